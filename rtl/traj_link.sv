// trajcore: the board's host link: UART receiver and transmitter, the
// protocol of rtl/board/LINK.md (traj_link_proto) and the segment FIFO
// (traj_seg_fifo) feeding the FD engine. Mirrored by hls/traj_link.hpp.
//
// Contract with the board top:
//   * rx_i is synchronised to clk_i by the board (two flops); tx_o is a flop.
//   * m_axis_*: the FD engine's segment word stream (K, then the registers,
//     exactly traj_fd_engine's s_axis order); tvalid is a flop and the data
//     hold until taken; a segment starts only while playing (run_o) and then
//     leaves whole.
//   * tick_i: the servo strobe (one cycle per tick): counts the ticks played
//     and the status period; eng_tick_i: the engine's tick (tick_i without
//     time scaling), keeps segment starts away from it.
//   * time scaling (LINK.md): scale_*_o, hold_o, stop_o, end_o, resume_o to
//     the board's traj_time_scale, stored_o/stored_k_o (the K of each record
//     stored) for its count of engine ticks ahead; scale_s_i, starved_*,
//     ahead_i, held_i for STATUS.
//   * seg_start_i: one cycle when a segment's first sample leaves the engine
//     (segments played).
//   * underrun_i: the engine's underrun_o (a tick found no segment), at most
//     2 cycles after its tick; the link tells a STOP, the end of the job and a
//     real underrun (counted, halted until RESUME) apart.
//   * tick_err_i: the engine's sticky tick_err_o (STATUS flag bit 3).
//   * sample_i: the engine's sample_o, axis a at [a*OutWidth +: OutWidth].
//   * run_o: ticks may be given to the engine (playing, not halted); the first
//     tick must follow run_o's rise by at least 3 cycles (the first segment
//     reaches the engine by then).
//   * tick_period_o (clocks; 0 = external tick input), step_shift_o (6 bits per
//     axis), pulse_o, setup_o (clocks), enable_o: the applied CONFIG; they
//     change only on a good CONFIG frame, which is refused while playing.
`default_nettype none
`include "traj_check.svh"

module traj_link #(
  parameter int ClkHz         = 48_000_000,  // clk_i in Hz
  parameter int Baud          = 1_000_000,   // UART bit rate (ClkHz/Baud >= 8)
  parameter int Axes          = 3,           // FD engine parameters, as traj_fd_engine
  parameter int Degree        = 3,
  parameter int Width         = 64,
  parameter int ChunkWidth    = 16,
  parameter int GuardBits     = 32,
  parameter int FifoDepth     = 4096,        // FIFO RAM words (16384: one UP5K SPRAM)
  parameter int MinTickPeriod = 256,         // smallest CONFIG tick period in clocks
  parameter int ScaleWidth    = 0,           // SW of the board's time-scale unit (0: none)
  parameter int SnapRam       = 0,           // 1: the STATUS snapshot of the samples in block RAM (traj_link_proto)
  parameter int CountRam      = 0,           // 1: the STATUS counters in block RAM (traj_link_proto)
  // derived, do not override
  parameter int OutWidth      = Width - GuardBits
) (
  input  logic                     clk_i,
  input  logic                     rst_ni,
  input  logic                     rx_i,
  output logic                     tx_o,
  // segment words to the FD engine
  output logic [ChunkWidth-1:0]    m_axis_tdata,
  output logic                     m_axis_tvalid,
  input  logic                     m_axis_tready,
  // board
  input  logic                     tick_i,
  input  logic                     eng_tick_i,
  input  logic                     seg_start_i,
  input  logic                     underrun_i,
  input  logic                     tick_err_i,
  input  logic [Axes*OutWidth-1:0] sample_i,
  input  logic [31:0]              scale_s_i,
  input  logic [15:0]              starved_count_i,
  input  logic [31:0]              ahead_i,
  input  logic                     starved_i,
  input  logic                     held_i,
  output logic                     run_o,
  output logic [31:0]              tick_period_o,
  output logic [Axes*6-1:0]        step_shift_o,
  output logic [15:0]              pulse_o,
  output logic [15:0]              setup_o,
  output logic                     enable_o,
  output logic [31:0]              scale_m_o,
  output logic [31:0]              scale_s_max_o,
  output logic [31:0]              scale_override_o,
  output logic [5:0]               scale_shift_o,
  output logic                     scale_auto_o,
  output logic                     hold_o,
  output logic                     stop_o,
  output logic                     end_o,
  output logic                     resume_o,
  output logic                     stored_o,     // a record stored, its K in stored_k_o
  output logic [31:0]              stored_k_o,
  output logic                     cleared_o     // the FIFO cleared (RESET)
);

  localparam int HdrWords = (ChunkWidth < 32) ? 32 / ChunkWidth : 1;
  localparam int SegWords = HdrWords + Axes * (Degree + 1) * Width / ChunkWidth;

  `TRAJ_PARAM_CHECK(g_bad_derived, OutWidth == Width - GuardBits,
                    "traj_link: OutWidth is derived; do not override it")

  logic [7:0]            rx_data, tx_data;
  logic                  rx_valid, rx_err, tx_valid, tx_ready;
  logic                  fifo_wr, fifo_commit, fifo_rollback, fifo_clear, fifo_release, fifo_busy;
  logic [ChunkWidth-1:0] fifo_wr_data;
  logic [15:0]           fifo_level, fifo_credits;

  traj_uart_rx #(.ClkHz(ClkHz), .Baud(Baud)) u_rx (
    .clk_i, .rst_ni, .rx_i, .data_o(rx_data), .valid_o(rx_valid), .err_o(rx_err)
  );

  traj_link_proto #(
    .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth), .GuardBits(GuardBits),
    .MinTickPeriod(MinTickPeriod), .ClkHz(ClkHz), .ScaleWidth(ScaleWidth), .SnapRam(SnapRam), .CountRam(CountRam)
  ) u_proto (
    .clk_i, .rst_ni,
    .rx_data_i(rx_data), .rx_valid_i(rx_valid), .rx_err_i(rx_err),
    .tx_tdata_o(tx_data), .tx_tvalid_o(tx_valid), .tx_tready_i(tx_ready),
    .fifo_wr_o(fifo_wr), .fifo_wr_data_o(fifo_wr_data), .fifo_commit_o(fifo_commit),
    .fifo_rollback_o(fifo_rollback), .fifo_clear_o(fifo_clear), .release_o(fifo_release),
    .fifo_level_i(fifo_level), .fifo_credits_i(fifo_credits), .fifo_busy_i(fifo_busy),
    .tick_i, .eng_tick_i, .seg_start_i, .underrun_i, .tick_err_i, .sample_i,
    .scale_s_i, .starved_count_i, .ahead_i, .starved_i, .held_i,
    .run_o, .tick_period_o, .step_shift_o, .pulse_o, .setup_o, .enable_o,
    .scale_m_o, .scale_s_max_o, .scale_override_o, .scale_shift_o, .scale_auto_o,
    .hold_o, .stop_o, .end_o, .resume_o, .stored_k_o
  );
  assign stored_o  = fifo_commit;
  assign cleared_o = fifo_clear;

  traj_seg_fifo #(.ChunkWidth(ChunkWidth), .SegWords(SegWords), .Depth(FifoDepth)) u_fifo (
    .clk_i, .rst_ni,
    .wr_i(fifo_wr), .wr_data_i(fifo_wr_data), .commit_i(fifo_commit), .rollback_i(fifo_rollback),
    .clear_i(fifo_clear), .release_i(fifo_release),
    .m_axis_tdata, .m_axis_tvalid, .m_axis_tready,
    .level_o(fifo_level), .credits_o(fifo_credits), .busy_o(fifo_busy)
  );

  traj_uart_tx #(.ClkHz(ClkHz), .Baud(Baud)) u_tx (
    .clk_i, .rst_ni, .s_tdata(tx_data), .s_tvalid(tx_valid), .s_tready(tx_ready), .tx_o
  );

endmodule

`default_nettype wire
