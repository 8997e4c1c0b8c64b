// trajcore: iCEBreaker (iCE40UP5K-SG48) board top. Pins: constraints/icebreaker.pcf.
//
//   12 MHz oscillator -> SB_PLL40_PAD -> ClkHz core clock: 30 MHz (icepll -i
//   12 -o 30: DIVR 0, DIVF 79, DIVQ 5, FILTER_RANGE 1), with the time-scale
//   unit 24 MHz (icepll -i 12 -o 24: DIVF 63)
//   reset: power-on, PLL lock, user button BTN_N (traj_reset_sync)
//   feed hold (TimeScale = 1): button BTN1 of the snap-off PMOD2 section
//   (active high, the section's own pull-down; 2-flop synchroniser)
//   UART to the FTDI FT2232H channel B: rx_i (2-flop synchroniser), tx_o
//   PMOD1A: step/dir of 3 axes, the drivers' enable, the external tick input
//   LEDs: green = playing (blinks with the ticks), red = tick or step error
// Inputs have the iCE40 pull-ups on (SB_IO PULLUP): an unplugged PMOD tick
// input stays high (no edges), the button and RX idle high. BTN1 has none
// (the board pulls it down; with the PMOD2 section snapped off, wire it back
// or tie the pin low).
// The portable logic is traj_board (host link, segment FIFO in SPRAM, the
// time-multiplexed FD engine traj_fd_tm in the main job's format, tick and
// step generators; the step generator's DDA sums in 6 of the UP5K's 8 DSP
// blocks, with TimeScale = 1 two of the unit's adders in the other 2).
// TimeScale = 1 adds the time-scale unit (feed override, feed hold, a stop
// on the path when data runs out) with SW = 16 (CONFIG's m, s_max and
// override below 2^16) at a 24 MHz core clock: that build fills 98 % of the
// UP5K's logic cells and does not reach 30 MHz (rtl/README.md, "Boards and
// bitstreams"). The default is 0: no time scaling (the link refuses it),
// BTN1 unused, 30 MHz.
`default_nettype none
`include "traj_check.svh"

module traj_icebreaker_top #(
  parameter int TimeScale = 0,           // 1: the time-scale unit (SW 16, 24 MHz, above)
  parameter int ClkHz     = (TimeScale != 0) ? 24_000_000 : 30_000_000,  // 24 or 30 MHz: the PLL below
  parameter int Baud      = 1_000_000
) (
  input  logic       clk_i,       // 35: 12 MHz oscillator
  input  logic       btn_ni,      // 10: user button BTN_N
  input  logic       hold_i,      // 20: BTN1 (snap-off PMOD2), feed hold
  input  logic       rx_i,        // 6: FTDI channel B TXD -> FPGA
  output logic       tx_o,        // 9: FPGA -> FTDI channel B RXD
  input  logic       tick_ext_i,  // PMOD1A pin 10
  output logic [2:0] step_o,      // PMOD1A pins 1, 3, 7
  output logic [2:0] dir_o,       // PMOD1A pins 2, 4, 8
  output logic       enable_o,    // PMOD1A pin 9
  output logic       led_red_no,  // 11: LEDR_N
  output logic       led_green_no // 37: LEDG_N
);

  logic clk, lock, rst_n;
  logic btn_pin, rx_pin, tick_pin;
  logic [1:0] rx_q;
  logic hold;  // the hold button, synchronised
  logic run, err, beat;

  `TRAJ_PARAM_CHECK(g_bad_clk, ClkHz == 24_000_000 || ClkHz == 30_000_000,
                    "traj_icebreaker_top: ClkHz must be 24 or 30 MHz (the PLL's settings)")
  `TRAJ_PARAM_CHECK(g_bad_ts, TimeScale == 0 || TimeScale == 1, "traj_icebreaker_top: TimeScale must be 0 or 1")

  SB_PLL40_PAD #(
    .FEEDBACK_PATH("SIMPLE"),
    .DIVR(4'b0000),
    .DIVF((ClkHz == 24_000_000) ? 7'd63 : 7'd79),  // 12 MHz * (DIVF + 1) / 2^DIVQ
    .DIVQ(3'b101),
    .FILTER_RANGE(3'b001)
  ) u_pll (
    .PACKAGEPIN(clk_i),
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

  // inputs with pull-ups (PIN_TYPE 000001: simple input)
  SB_IO #(.PIN_TYPE(6'b000001), .PULLUP(1'b1)) u_btn  (.PACKAGE_PIN(btn_ni),     .D_IN_0(btn_pin));
  SB_IO #(.PIN_TYPE(6'b000001), .PULLUP(1'b1)) u_rx   (.PACKAGE_PIN(rx_i),       .D_IN_0(rx_pin));
  SB_IO #(.PIN_TYPE(6'b000001), .PULLUP(1'b1)) u_tick (.PACKAGE_PIN(tick_ext_i), .D_IN_0(tick_pin));

  traj_reset_sync u_rst (.clk_i(clk), .lock_i(lock), .btn_ni(btn_pin), .rst_no(rst_n));

  always_ff @(posedge clk) rx_q <= {rx_q[0], rx_pin};  // synchroniser (settled before reset ends)
  // the hold button (TimeScale = 1 only): a 2-flop synchroniser (a level,
  // held by a person; the unit samples it once per servo tick); without the
  // unit the pin has no buffer (nothing reads it)
  if (TimeScale != 0) begin : g_hold
    logic       hold_pin;
    logic [1:0] hold_q;
    SB_IO #(.PIN_TYPE(6'b000001), .PULLUP(1'b0)) u_hold (.PACKAGE_PIN(hold_i), .D_IN_0(hold_pin));
    always_ff @(posedge clk) hold_q <= {hold_q[0], hold_pin};
    assign hold = hold_q[1];
  end else begin : g_no_hold
    /* verilator lint_off UNUSEDSIGNAL */
    logic unused_hold;
    assign unused_hold = hold_i;  // BTN1 has no use without the unit
    /* verilator lint_on UNUSEDSIGNAL */
    assign hold = 1'b0;
  end

  traj_board #(
    .ClkHz(ClkHz), .Baud(Baud), .Axes(3), .Degree(5), .Width(96), .ChunkWidth(16), .GuardBits(48),
    .FifoDepth(16384), .FdTimeMux(1'b1), .TimeScale(TimeScale), .ScaleWidth(16), .StatusRam(3),
    .UseDsp(1)
  ) u_board (
    .clk_i(clk), .rst_ni(rst_n), .rx_i(rx_q[1]), .tx_o,
    .tick_ext_i(tick_pin),
    .hold_i(hold),
    .step_o, .dir_o, .enable_o,
    .run_o(run), .err_o(err), .heartbeat_o(beat)
  );

  assign led_green_no = !(run && !beat);
  assign led_red_no   = !err;

endmodule

`default_nettype wire
