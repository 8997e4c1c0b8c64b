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
// * StatusRam: the copies of the samples that only STATUS reads (the link's
//   snapshot of a frame, 1; also the board's copy above, 2) in block RAM
//   (traj_hold_ram, Axes*OutWidth/16 blocks each) instead of flops, for a
//   device short of logic cells (the UP5K). With 2 a STATUS frame reports
//   the samples of two clocks before it starts, not one. 3 also keeps the
//   link's six STATUS counters in block RAM (traj_link_proto CountRam).
// * enable_o is high when CONFIG enables the outputs (drivers with an
//   active-low enable need an inverter or the top's inversion).
// * TimeScale = 1: the time-scale unit (traj_time_scale: feed override, feed
//   hold, a stop on the path when data runs out; LINK.md) sits between the
//   servo tick and the engine when CONFIG enables it (m != 0): the unit ticks
//   the engine, reads its samples a word at a time through traj_fd_tm's
//   sample RAM port (so TimeScale needs FdTimeMux = 1 and GuardBits a
//   multiple of ChunkWidth), and the step generator and STATUS take its
//   interpolated output, which it presents at the next servo tick (a fixed
//   latency of one servo tick and Axes*OutWidth + 2 clocks). Its count of
//   engine ticks ahead (avail) is kept here (traj_ahead): + K of each record
//   stored (within 2 clocks), moved from the FIFO's share to the engine's as
//   a segment's header leaves the FIFO, - 1 per real engine sample; RESET
//   clears the FIFO's share. hold_i
//   (a button, synchronised by the top), FEED's hold and STOP hold; RESUME
//   lets a starved hold resume as auto-resume does. With the unit on, the
//   engine underruns only at the job's end (the unit ticks it once past the
//   last sample, END taken: the link's end of the job, told with the output
//   that follows); the board tells the link the end of a STOP (S at 0, at a
//   servo tick) by the same underrun input.
//   TimeScale = 0: no unit, hold_i unused, the link refuses time scaling.
// * UseDsp = 1 (a device with SB_MAC16 blocks: the UP5K): the step
//   generator's DDA sums in 2 Axes of them and two of the time-scale unit's
//   adders in two more (traj_add): the same sums in fewer logic cells.
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
  parameter int TimeScale     = 0,     // 1: the time-scale unit (below)
  parameter int ScaleWidth    = 20,    // SW of the time-scale unit (S, m, s_max)
  parameter int StatusRam     = 0,     // STATUS in block RAM: 1 the link's copy of the samples, 2 also the board's, 3 also the link's counters
  parameter int UseDsp        = 0,     // 1: adders in SB_MAC16 blocks (iCE40 UP5K: traj_step_gen, traj_time_scale)
  // derived, do not override
  parameter int OutWidth      = Width - GuardBits
) (
  input  logic            clk_i,
  input  logic            rst_ni,
  input  logic            rx_i,         // UART RX, synchronised to clk_i by the top
  output logic            tx_o,         // UART TX (a flop)
  input  logic            tick_ext_i,   // external servo tick, asynchronous
  input  logic            hold_i,       // feed hold (TimeScale), synchronised to clk_i by the top
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
  localparam int TsAddrW         = ($clog2(Axes) + $clog2(OutWidth / ChunkWidth) > 0) ?
                                   $clog2(Axes) + $clog2(OutWidth / ChunkWidth) : 1;

  `TRAJ_PARAM_CHECK(g_bad_derived, OutWidth == Width - GuardBits,
                    "traj_board: OutWidth is derived; do not override it")
  `TRAJ_PARAM_CHECK(g_bad_scale, (TimeScale == 0 || TimeScale == 1) && ScaleWidth >= 4 && ScaleWidth <= 24,
                    "traj_board: TimeScale must be 0 or 1, ScaleWidth 4..24")
  `TRAJ_PARAM_CHECK(g_bad_scale_engine, TimeScale == 0 || (FdTimeMux && GuardBits % ChunkWidth == 0),
                    "traj_board: TimeScale = 1 reads the samples through traj_fd_tm's sample RAM port: it needs FdTimeMux = 1 and GuardBits a multiple of ChunkWidth")
  `TRAJ_PARAM_CHECK(g_bad_status_ram, StatusRam >= 0 && StatusRam <= 3,
                    "traj_board: StatusRam must be 0, 1, 2 or 3")
  `TRAJ_PARAM_CHECK(g_bad_dsp, UseDsp == 0 || UseDsp == 1, "traj_board: UseDsp must be 0 or 1")
  `TRAJ_PARAM_CHECK(g_bad_min_tick, MinTickPeriod >= Axes * (StepPeriodWidth + StepFracBits + StepSubBits + 3) + 3,
                    "traj_board: MinTickPeriod must cover the step generator's preparation")

  // link <-> engine
  logic [ChunkWidth-1:0]    seg_tdata;
  logic                     seg_tvalid, seg_tready;
  logic                     run, enable;
  logic [31:0]              tick_period;
  logic [Axes*6-1:0]        step_shift;
  logic [15:0]              pulse, setup;
  // time scaling
  logic [31:0]              sc_m, sc_smax, sc_ovr, stored_k, ahead;
  logic [5:0]               sc_shift;
  logic                     sc_auto, link_hold, link_stop, link_end, link_resume, stored, cleared;
  logic                     eng_tick, link_underrun;
  // the output samples (the step generator's input), also read by the
  // simulated board (host/board/sim_board.cpp)
  logic                     out_valid /* verilator public_flat_rd */;
  logic [Axes*OutWidth-1:0] out_sample /* verilator public_flat_rd */;
  logic [31:0]              ts_s;
  logic [15:0]              ts_count;
  logic                     ts_starved, ts_held, ts_err;
  // engine
  logic                     tick, seg_done, tick_err;
  logic                     sample_valid /* verilator public_flat_rd */;  // the engine's (the simulated board times it)
  logic                     underrun /* verilator public_flat_rd */;      // with sample_valid: a held sample, no new one
  logic [Axes*OutWidth-1:0] sample, status_sample;
  logic [Axes*OutWidth-1:0] eng_we, eng_wd;  // traj_fd_tm's sample write port (the shared output register)
  logic [TsAddrW-1:0]       ts_word_addr;  // the unit's word of the engine's sample RAM
  logic [ChunkWidth-1:0]    ts_word;
  logic                     seg_start, new_seg_q;
  // tick and step generators
  logic [31:0]              period_used;
  logic [StepPeriodWidth-1:0] step_period_q;  // a flop: the clamp off the generator's paths
  logic                     step_err;
  logic [9:0]               beat_q;

  traj_link #(
    .ClkHz(ClkHz), .Baud(Baud), .Axes(Axes), .Degree(Degree), .Width(Width),
    .ChunkWidth(ChunkWidth), .GuardBits(GuardBits), .FifoDepth(FifoDepth),
    .MinTickPeriod(MinTickPeriod), .ScaleWidth((TimeScale != 0) ? ScaleWidth : 0), .SnapRam((StatusRam >= 1) ? 1 : 0),
    .CountRam((StatusRam >= 3) ? 1 : 0)
  ) u_link (
    .clk_i, .rst_ni, .rx_i, .tx_o,
    .m_axis_tdata(seg_tdata), .m_axis_tvalid(seg_tvalid), .m_axis_tready(seg_tready),
    .tick_i(tick), .eng_tick_i(eng_tick), .seg_start_i(seg_start), .underrun_i(link_underrun),
    .tick_err_i(tick_err || step_err || ts_err), .sample_i(status_sample),
    .scale_s_i(ts_s), .starved_count_i(ts_count), .ahead_i(ahead), .starved_i(ts_starved), .held_i(ts_held),
    .run_o(run), .tick_period_o(tick_period), .step_shift_o(step_shift),
    .pulse_o(pulse), .setup_o(setup), .enable_o(enable),
    .scale_m_o(sc_m), .scale_s_max_o(sc_smax), .scale_override_o(sc_ovr), .scale_shift_o(sc_shift),
    .scale_auto_o(sc_auto), .hold_o(link_hold), .stop_o(link_stop), .end_o(link_end),
    .resume_o(link_resume), .stored_o(stored), .stored_k_o(stored_k), .cleared_o(cleared)
  );

  if (FdTimeMux) begin : g_fd_tm
    logic [Axes*OutWidth-1:0] sample_hold_q;
    logic [ChunkWidth-1:0]    sample_word;  // the time-scale unit's window (the step generator takes sample_o whole)
    localparam int SampleAddrW = ($clog2(Axes) + $clog2(Width / ChunkWidth) > 0) ? $clog2(Axes) + $clog2(Width / ChunkWidth) : 1;
    logic [SampleAddrW-1:0]   sample_addr;
    if (TimeScale != 0) begin : g_word_addr
      // the unit's word {axis, w} of the sample is chunk GuardBits/ChunkWidth + w
      // of the axis's register r[0] in the sample RAM
      localparam int ChB    = $clog2(Width / ChunkWidth);
      localparam int WB     = $clog2(OutWidth / ChunkWidth);
      localparam int AxB    = $clog2(Axes);
      localparam int First  = GuardBits / ChunkWidth;
      logic [31:0] ax, w;
      assign ax = (AxB > 0) ? 32'(ts_word_addr) >> WB : 32'd0;
      assign w  = (WB > 0) ? 32'(ts_word_addr) & ((32'd1 << WB) - 32'd1) : 32'd0;
      assign sample_addr = SampleAddrW'((ax << ChB) | (32'(First) + w));
    end else begin : g_no_word_addr
      assign sample_addr = '0;
    end

    traj_fd_tm #(
      .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth), .GuardBits(GuardBits),
      .TickClocks(MinTickPeriod)
    ) u_engine (
      .clk_i, .rst_ni,
      .s_axis_tdata(seg_tdata), .s_axis_tvalid(seg_tvalid), .s_axis_tready(seg_tready),
      .tick_i(eng_tick),
      .sample_valid_o(sample_valid), .sample_o(sample), .sample_we_o(eng_we), .sample_wd_o(eng_wd),
      .sample_addr_i(sample_addr), .sample_word_o(sample_word),
      .underrun_o(underrun), .seg_done_o(seg_done), .tick_err_o(tick_err)
    );

    // datapath, not reset (as the engines' sample_o); in block RAM
    // (StatusRam >= 2) the copy follows a clock later (traj_hold_ram)
    if (StatusRam >= 2) begin : g_hold_ram
      traj_hold_ram #(.Width(Axes * OutWidth)) u_hold (
        .clk_i, .we_i(out_valid), .data_i(out_sample), .data_o(sample_hold_q)
      );
    end else begin : g_hold_flops
      always_ff @(posedge clk_i) begin
        if (out_valid) sample_hold_q <= out_sample;
      end
    end
    assign status_sample = sample_hold_q;
    assign ts_word       = sample_word;
  end else begin : g_fd_par
    traj_fd_engine #(
      .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth), .GuardBits(GuardBits)
    ) u_engine (
      .clk_i, .rst_ni,
      .s_axis_tdata(seg_tdata), .s_axis_tvalid(seg_tvalid), .s_axis_tready(seg_tready),
      .tick_i(eng_tick),
      .sample_valid_o(sample_valid), .sample_o(sample),
      .underrun_o(underrun), .seg_done_o(seg_done), .tick_err_o(tick_err)
    );
    assign status_sample = sample;
    assign ts_word       = '0;  // (TimeScale needs FdTimeMux)
    assign eng_we        = '0;
    assign eng_wd        = '0;
  end

  // -------------------------------------------------------------------
  // Time scaling: engine ticks ahead, the unit, the output.
  // -------------------------------------------------------------------

  if (TimeScale != 0) begin : g_scale
    localparam int HdrWords = (ChunkWidth < 32) ? 32 / ChunkWidth : 1;
    localparam int SegWords = HdrWords + Axes * (Degree + 1) * Width / ChunkWidth;
    localparam int WordBits = $clog2(SegWords + 1);
    logic [WordBits-1:0] word_q;      // words of the segment leaving the FIFO so far
    logic [31:0]         hdr_k;       // its K, as its header words pass
    logic                hdr_done, real_sample;
    if (ChunkWidth >= 32) begin : g_hdr1
      assign hdr_k = seg_tdata[31:0];
    end else begin : g_hdr2
      logic [15:0] hdr_lo_q;
      always_ff @(posedge clk_i) begin
        if (seg_tvalid && seg_tready && word_q == '0) hdr_lo_q <= seg_tdata[15:0];
      end
      assign hdr_k = {seg_tdata[15:0], hdr_lo_q};
    end
    assign hdr_done    = seg_tvalid && seg_tready && word_q == WordBits'(HdrWords - 1);
    assign real_sample = sample_valid && !underrun;
    always_ff @(posedge clk_i) begin
      if (!rst_ni) word_q <= '0;
      else if (seg_tvalid && seg_tready) word_q <= (word_q == WordBits'(SegWords - 1)) ? '0 : word_q + 1'b1;
    end
    // kept whole (a flop on the unit's avail_i, no adder after it); a store
    // is counted within 2 clocks (traj_ahead)
    traj_ahead #(.Width(32)) u_ahead (
      .clk_i, .rst_ni, .stored_i(stored), .stored_k_i(stored_k), .cleared_i(cleared),
      .hdr_done_i(hdr_done), .hdr_k_i(hdr_k), .real_i(real_sample), .ahead_o(ahead)
    );

    logic             scale_on, done_q, resume_q, ts_valid, ts_tick, ts_starved_q;
    // the unit's busy and engine strobe: the simulated board measures the
    // unit's servo tick and the engine's answer against the host's bounds
    logic             ts_busy /* verilator public_flat_rd */;
    logic             ts_eng_tick /* verilator public_flat_rd */;
    logic             under_q;
    /* verilator lint_off UNUSEDSIGNAL */
    logic             unused_wide;  // bits above ScaleWidth: the link refuses them
    assign unused_wide = ^{sc_smax, sc_ovr};
    /* verilator lint_on UNUSEDSIGNAL */
    logic [ScaleWidth-1:0] s_now;
    logic [Axes*OutWidth-1:0] ts_sample;
    logic                     ts_shift, ts_bit;
    logic [Axes*OutWidth-1:0] out_q;
    // CONFIG (m != 0 turns the unit on) is taken only while not playing: a
    // flop, off the paths of the ticks and of the output register's writes
    always_ff @(posedge clk_i) begin
      if (!rst_ni) scale_on <= 1'b0;
      else scale_on <= sc_m != '0;
    end
    assign ts_tick  = tick && scale_on;
    assign ts_held  = scale_on && (link_hold || hold_i || link_stop);

    traj_time_scale #(.Axes(Axes), .OutWidth(OutWidth), .SW(ScaleWidth), .WordWidth(ChunkWidth), .UseDsp(UseDsp)) u_scale (
      .clk_i, .rst_ni, .tick_i(ts_tick),
      .m_i(sc_m[ScaleWidth-1:0]), .s_max_i(sc_smax[ScaleWidth-1:0]), .override_i(sc_ovr[ScaleWidth-1:0]),
      .shift_i(sc_shift), .hold_i(ts_held), .auto_resume_i(sc_auto || resume_q), .end_i(link_end),
      .avail_i(ahead),
      .eng_tick_o(ts_eng_tick), .eng_valid_i(sample_valid), .eng_addr_o(ts_word_addr), .eng_word_i(ts_word),
      .sample_valid_o(ts_valid), .sample_o(ts_sample), .out_shift_o(ts_shift), .out_bit_o(ts_bit),
      .s_o(s_now), .starved_o(ts_starved_q),
      .starved_count_o(ts_count), .busy_o(ts_busy), .err_o(ts_err)
    );

    // RESUME lets a starved hold resume (once twice the stop fits) as
    // auto-resume does; done_q: a STOP has come to rest, to the link
    always_ff @(posedge clk_i) begin
      if (!rst_ni) begin
        resume_q <= 1'b0;
        done_q   <= 1'b0;
      end else begin
        if (link_resume) resume_q <= 1'b1;
        else if (!ts_starved_q) resume_q <= 1'b0;
        done_q <= ts_tick && !ts_busy && link_stop && s_now == '0;
      end
    end

    // The unit presents each servo tick's output at the next servo tick (the
    // step generator times its steps from each sample's arrival: a fixed
    // latency). The engine's underrun (with the unit on: the job's end)
    // reaches the link with the output that follows it, so that the last
    // sample reaches the step generator as playback stops.
    always_ff @(posedge clk_i) begin
      if (!rst_ni) under_q <= 1'b0;
      else under_q <= (under_q && !ts_valid) || (underrun && scale_on);
    end
    // One output register for both: the engine's write port fills it while
    // the unit is off, the unit's shift while it is on, the same writes as
    // their own sample_o flops (left to synthesis to drop). scale_on changes
    // only while not playing, and either side writes every bit between two
    // of its valid strobes, so at each out_valid out_q is what that side's
    // sample_o holds (what a multiplexer of the two would give), with no
    // second copy of the samples and no multiplexer.
    always_ff @(posedge clk_i) begin
      if (scale_on) begin
        if (ts_shift) out_q <= {ts_bit, out_q[Axes*OutWidth-1:1]};
      end else begin
        for (int i = 0; i < Axes * OutWidth; i++)
          if (eng_we[i]) out_q[i] <= eng_wd[i];
      end
    end
    /* verilator lint_off UNUSEDSIGNAL */
    logic unused_own;  // the engine's and the unit's own sample flops: out_q instead
    assign unused_own = ^{sample, ts_sample};
    /* verilator lint_on UNUSEDSIGNAL */
    assign eng_tick      = scale_on ? ts_eng_tick : tick;
    assign out_valid     = scale_on ? ts_valid : sample_valid;
    assign out_sample    = out_q;
    assign link_underrun = scale_on ? ((ts_valid && under_q) || done_q) : underrun;
    assign ts_s          = 32'(s_now);
    assign ts_starved    = ts_starved_q;
  end else begin : g_no_scale
    /* verilator lint_off UNUSEDSIGNAL */
    logic unused_scale;
    assign unused_scale = ^{sc_m, sc_smax, sc_ovr, sc_shift, sc_auto, link_hold, link_stop, link_end,
                            link_resume, hold_i, stored, stored_k, cleared, ts_word, ts_word_addr,
                            eng_we, eng_wd};
    /* verilator lint_on UNUSEDSIGNAL */
    assign eng_tick      = tick;
    assign out_valid     = sample_valid;
    assign out_sample    = sample;
    assign link_underrun = underrun;
    assign ts_s          = '0;
    assign ts_count      = '0;
    assign ahead         = '0;
    assign ts_starved    = 1'b0;
    assign ts_held       = 1'b0;
    assign ts_err        = 1'b0;
    assign ts_word_addr  = '0;
  end

  // the step generator takes the period clamped to 2^StepPeriodWidth - 1: an
  // external period measured to one bit more (saturating) clamps the same
  traj_tick_gen #(.PeriodWidth(32), .ExtWidth(StepPeriodWidth + 1)) u_tick (
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
    .DueWidth(8), .TimeWidth(16), .SubBits(StepSubBits), .UseDsp(UseDsp)
  ) u_step (
    .clk_i, .rst_ni,
    .shift_i(step_shift), .period_i(step_period_q), .pulse_i(pulse), .setup_i(setup),
    .enable_i(enable),
    .sample_valid_i(out_valid), .sample_i(out_sample),
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
  assign err_o       = tick_err || step_err || ts_err;
  assign heartbeat_o = beat_q[9];

endmodule

`default_nettype wire
