// trajcore: iCE40-HX8K Breakout Board (iCE40HX8K-CT256) board top. Pins:
// constraints/hx8k_breakout.pcf.
//
//   12 MHz oscillator (ball J3) -> SB_PLL40_CORE -> ClkHz core clock
//   (icepll -i 12 -o 60: DIVR 0, DIVF 79, DIVQ 4, FILTER_RANGE 1)
//   reset: power-on, PLL lock, and an optional button to ground on header J2
//   (the board has no user button; traj_reset_sync)
//   feed hold: an optional button to ground on header J2 (2-flop
//   synchroniser; pressed = held, as FEED's hold)
//   UART to the FTDI FT2232H channel B: rx_i (2-flop synchroniser), tx_o
//   header J2: step/dir of 3 axes, the drivers' enable, the external tick input
//   LEDs D2..D5: playing, error, heartbeat (ticks), outputs enabled
// Inputs on header J2 have the iCE40 pull-ups on (SB_IO PULLUP): nothing on
// the board pulls them (an open button input reads released).
// The portable logic is traj_board (host link, segment FIFO in block RAM,
// the time-multiplexed FD engine traj_fd_tm in the main job's format, the
// time-scale unit (feed override, feed hold, a stop on the path when data
// runs out), tick and step generators).
`default_nettype none

module traj_hx8k_top #(
  parameter int ClkHz = 60_000_000,  // must match the PLL settings below
  parameter int Baud  = 1_000_000
) (
  input  logic       clk_i,       // J3: 12 MHz oscillator
  input  logic       btn_ni,      // J2 (C6): optional reset button to ground
  input  logic       hold_ni,     // J2 (C7): optional feed-hold button to ground
  input  logic       rx_i,        // B10: FTDI channel B TXD -> FPGA
  output logic       tx_o,        // B12: FPGA -> FTDI channel B RXD
  input  logic       tick_ext_i,  // J2 (A11)
  output logic [2:0] step_o,      // J2 (A5, A6, B8)
  output logic [2:0] dir_o,       // J2 (B6, B7, A9)
  output logic       enable_o,    // J2 (A10)
  output logic [3:0] led_o        // D2..D5: run, error, heartbeat, enable
);

  logic clk, lock, rst_n;
  logic btn_pin, hold_pin, tick_pin;
  logic [1:0] rx_q, hold_q;
  logic run, err, beat;

  SB_PLL40_CORE #(
    .FEEDBACK_PATH("SIMPLE"),
    .DIVR(4'b0000),
    .DIVF(7'b1001111),
    .DIVQ(3'b100),
    .FILTER_RANGE(3'b001)
  ) u_pll (
    .REFERENCECLK(clk_i),
    .PLLOUTGLOBAL(clk),
    .EXTFEEDBACK(1'b0),
    .DYNAMICDELAY(8'h00),
    .LOCK(lock),
    .BYPASS(1'b0),
    .RESETB(1'b1),
    .LATCHINPUTVALUE(1'b0),
    .SDI(1'b0),
    .SCLK(1'b0)
  );

  // header inputs with pull-ups (PIN_TYPE 000001: simple input)
  SB_IO #(.PIN_TYPE(6'b000001), .PULLUP(1'b1)) u_btn  (.PACKAGE_PIN(btn_ni),     .D_IN_0(btn_pin));
  SB_IO #(.PIN_TYPE(6'b000001), .PULLUP(1'b1)) u_hold (.PACKAGE_PIN(hold_ni),    .D_IN_0(hold_pin));
  SB_IO #(.PIN_TYPE(6'b000001), .PULLUP(1'b1)) u_tick (.PACKAGE_PIN(tick_ext_i), .D_IN_0(tick_pin));

  traj_reset_sync u_rst (.clk_i(clk), .lock_i(lock), .btn_ni(btn_pin), .rst_no(rst_n));

  always_ff @(posedge clk) rx_q <= {rx_q[0], rx_i};  // synchroniser (FTDI drives RX)
  // the hold button: a 2-flop synchroniser (a level, held by a person; the
  // unit samples it once per servo tick)
  always_ff @(posedge clk) hold_q <= {hold_q[0], hold_pin};

  traj_board #(
    .ClkHz(ClkHz), .Baud(Baud), .Axes(3), .Degree(5), .Width(96), .ChunkWidth(16), .GuardBits(48),
    .FifoDepth(4096), .FdTimeMux(1'b1), .TimeScale(1), .ScaleWidth(20), .StatusRam(1)
  ) u_board (
    .clk_i(clk), .rst_ni(rst_n), .rx_i(rx_q[1]), .tx_o,
    .tick_ext_i(tick_pin),
    .hold_i(!hold_q[1]),
    .step_o, .dir_o, .enable_o,
    .run_o(run), .err_o(err), .heartbeat_o(beat)
  );

  assign led_o = {enable_o, beat, err, run};

endmodule

`default_nettype wire
