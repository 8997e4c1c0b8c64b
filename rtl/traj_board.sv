// trajcore: the portable board logic under the board tops (rtl/board/*_top.sv):
// host link with the segment FIFO (traj_link), the FD engine, the servo tick
// generator and the step/dir generator. The tops add the PLL, the resets,
// the input synchronisers and the pins.
//
//   rx_i (synchronised) -> traj_link -> segment words -> FD engine
//   traj_link CONFIG (tick period, run) -> traj_tick_gen -> tick -> engine, link
//   engine samples -> traj_step_gen (CONFIG shift, pulse, setup, enable) -> pins
//   engine status (underrun, tick_err, samples, segment starts) -> traj_link STATUS
//
// * seg_start (segments played): the first real sample after reset or after a
//   seg_done.
// * STATUS "tick error" (flag bit 3) = the engine's tick_err or the step
//   generator's err (a sample before the previous one was prepared, a step
//   rate above one per clock, pulses that cannot keep up).
// * The step generator interpolates over the tick period in use: the CONFIG
//   period, or the measured period of the external tick; periods of 2^16
//   clocks and more are clamped to 2^16-1 (2.18 ms at 30 MHz, 1.09 ms at
//   60 MHz: the steps of a longer tick come in its first 2^16-1 clocks; the
//   count stays exact; the edge timing bound holds to 1 ms ticks), an
//   external tick not measured yet counts as 1 clock (the steps of a tick at
//   once).
// * FD engine (FdTimeMux): 1 = traj_fd_tm (one adder, registers in block RAM;
//   the UP5K's size), 0 = traj_fd_engine (all registers in flops). Both take
//   the same stream and give the same samples per tick. traj_fd_tm's sample_o
//   changes during its pass, so the link's STATUS reads a copy registered at
//   sample_valid (the step generator reads sample_o while it holds: from
//   sample_valid until the next tick).
// * enable_o is high when CONFIG enables the outputs (drivers with an
//   active-low enable need an inverter or the top's inversion).
`default_nettype none
`include "traj_check.svh"

module traj_board #(
  parameter int ClkHz         = 30_000_000,
  parameter int Baud          = 1_000_000,
  parameter int Axes          = 3,
  parameter int Degree        = 5,
  parameter int Width         = 96,
  parameter int ChunkWidth    = 16,
  parameter int GuardBits     = 48,
  parameter int FifoDepth     = 16384,
  parameter int MinTickPeriod = 256,
  parameter bit FdTimeMux     = 1'b1,
  // derived, do not override
  parameter int OutWidth      = Width - GuardBits
) (
  input  logic            clk_i,
  input  logic            rst_ni,
  input  logic            rx_i,         // UART RX, synchronised to clk_i by the top
  output logic            tx_o,         // UART TX (a flop)
  input  logic            tick_ext_i,   // external servo tick, asynchronous
  output logic [Axes-1:0] step_o,
  output logic [Axes-1:0] dir_o,
  output logic            enable_o,
  output logic            run_o,        // playing (status LED)
  output logic            err_o,        // tick or step error (status LED)
  output logic            heartbeat_o   // toggles every 1024 ticks (status LED)
);

  localparam int StepPeriodWidth = 16;
  localparam int StepFracBits    = 12;  // 1/4096 step: edges within 4.5 us at 1 ms (rtl/README.md)
  localparam int StepSubBits     = 3;   // up to 8 quadratic sub-chords per tick

  `TRAJ_PARAM_CHECK(g_bad_derived, OutWidth == Width - GuardBits,
                    "traj_board: OutWidth is derived; do not override it")
  `TRAJ_PARAM_CHECK(g_bad_min_tick, MinTickPeriod >= Axes * (StepPeriodWidth + StepFracBits + StepSubBits + 3) + 3,
                    "traj_board: MinTickPeriod must cover the step generator's preparation")

  // link <-> engine
  logic [ChunkWidth-1:0]    seg_tdata;
  logic                     seg_tvalid, seg_tready;
  logic                     run, enable;
  logic [31:0]              tick_period;
  logic [Axes*6-1:0]        step_shift;
  logic [15:0]              pulse, setup;
  // engine
  logic                     tick, sample_valid, underrun, seg_done, tick_err;
  logic [Axes*OutWidth-1:0] sample, status_sample;
  logic                     seg_start, new_seg_q;
  // tick and step generators
  logic [31:0]              period_used;
  logic [StepPeriodWidth-1:0] step_period_q;  // a flop: the clamp off the generator's paths
  logic                     step_err;
  logic [9:0]               beat_q;

  traj_link #(
    .ClkHz(ClkHz), .Baud(Baud), .Axes(Axes), .Degree(Degree), .Width(Width),
    .ChunkWidth(ChunkWidth), .GuardBits(GuardBits), .FifoDepth(FifoDepth),
    .MinTickPeriod(MinTickPeriod)
  ) u_link (
    .clk_i, .rst_ni, .rx_i, .tx_o,
    .m_axis_tdata(seg_tdata), .m_axis_tvalid(seg_tvalid), .m_axis_tready(seg_tready),
    .tick_i(tick), .seg_start_i(seg_start), .underrun_i(underrun),
    .tick_err_i(tick_err || step_err), .sample_i(status_sample),
    .run_o(run), .tick_period_o(tick_period), .step_shift_o(step_shift),
    .pulse_o(pulse), .setup_o(setup), .enable_o(enable)
  );

  if (FdTimeMux) begin : g_fd_tm
    logic [Axes*OutWidth-1:0] sample_hold_q;
    /* verilator lint_off UNUSEDSIGNAL */
    logic [ChunkWidth-1:0]    sample_word;  // the step generator takes sample_o whole
    /* verilator lint_on UNUSEDSIGNAL */
    localparam int SampleAddrW = ($clog2(Axes) + $clog2(Width / ChunkWidth) > 0) ? $clog2(Axes) + $clog2(Width / ChunkWidth) : 1;
    logic [SampleAddrW-1:0]   sample_addr;
    assign sample_addr = '0;

    traj_fd_tm #(
      .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth), .GuardBits(GuardBits),
      .TickClocks(MinTickPeriod)
    ) u_engine (
      .clk_i, .rst_ni,
      .s_axis_tdata(seg_tdata), .s_axis_tvalid(seg_tvalid), .s_axis_tready(seg_tready),
      .tick_i(tick),
      .sample_valid_o(sample_valid), .sample_o(sample),
      .sample_addr_i(sample_addr), .sample_word_o(sample_word),
      .underrun_o(underrun), .seg_done_o(seg_done), .tick_err_o(tick_err)
    );

    // datapath, not reset (as the engines' sample_o)
    always_ff @(posedge clk_i) begin
      if (sample_valid) sample_hold_q <= sample;
    end
    assign status_sample = sample_hold_q;
  end else begin : g_fd_par
    traj_fd_engine #(
      .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth), .GuardBits(GuardBits)
    ) u_engine (
      .clk_i, .rst_ni,
      .s_axis_tdata(seg_tdata), .s_axis_tvalid(seg_tvalid), .s_axis_tready(seg_tready),
      .tick_i(tick),
      .sample_valid_o(sample_valid), .sample_o(sample),
      .underrun_o(underrun), .seg_done_o(seg_done), .tick_err_o(tick_err)
    );
    assign status_sample = sample;
  end

  traj_tick_gen #(.PeriodWidth(32)) u_tick (
    .clk_i, .rst_ni, .run_i(run), .period_i(tick_period), .tick_ext_i,
    .tick_o(tick), .period_o(period_used)
  );

  // 0 (an external tick not measured yet): 1, all steps of a tick at once;
  // datapath, not reset (the generator takes it with a sample, long after)
  always_ff @(posedge clk_i) begin
    step_period_q <= (period_used[31:StepPeriodWidth] != '0) ? '1
                   : (period_used == '0) ? StepPeriodWidth'(1) : period_used[StepPeriodWidth-1:0];
  end

  traj_step_gen #(
    .Axes(Axes), .OutWidth(OutWidth), .FracBits(StepFracBits), .PeriodWidth(StepPeriodWidth),
    .DueWidth(8), .TimeWidth(16), .SubBits(StepSubBits)
  ) u_step (
    .clk_i, .rst_ni,
    .shift_i(step_shift), .period_i(step_period_q), .pulse_i(pulse), .setup_i(setup),
    .enable_i(enable),
    .sample_valid_i(sample_valid), .sample_i(sample),
    .step_o, .dir_o, .enable_o, .err_o(step_err)
  );

  // segments played: the first real sample after reset or a seg_done
  assign seg_start = sample_valid && !underrun && new_seg_q;
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      new_seg_q <= 1'b1;
      beat_q    <= '0;
    end else begin
      if (seg_done)       new_seg_q <= 1'b1;
      else if (seg_start) new_seg_q <= 1'b0;
      if (tick) beat_q <= beat_q + 1'b1;
    end
  end

  assign run_o       = run;
  assign err_o       = tick_err || step_err;
  assign heartbeat_o = beat_q[9];

endmodule

`default_nettype wire
