// trajcore: narrow-pin wrapper of traj_fd_tm (the time-multiplexed FD engine)
// for iCE40 synthesis and place-and-route measurements, the same wrapper as
// traj_fd_synth_top around traj_fd_engine (so the figures compare).
//
// The engine's segment stream is ChunkWidth bits wide and its sample bus is
// Axes*OutWidth bits: more pins than an SG48 package has. This wrapper
//   * assembles stream words from bytes (traj_byte_words: byte_valid_i/byte_i,
//     LS byte first; byte_ready_o is back-pressure),
//   * registers the servo strobe and the reset,
//   * folds every sample bit into an 8-bit register and registers the status
//     flags (traj_sample_fold), so that no engine output can be optimised away:
//     SampleRam = 0: the parallel sample_o (Axes*OutWidth flops in the engine,
//     folded); SampleRam = 1: the engine's sample RAM read port, its address
//     from registered pins (sample_addr_i), its word folded (the sample flops
//     are unused and removed: the build for word-serial consumers).
// Everything is registered at the pins so that measured Fmax is the core's.
`default_nettype none
`include "traj_check.svh"

module traj_fd_tm_synth_top #(
  parameter int Axes       = 3,
  parameter int Degree     = 3,
  parameter int Width      = 64,
  parameter int ChunkWidth = 16,
  parameter int GuardBits  = 32,
  parameter int TickClocks = 240,
  parameter int SampleRam  = 0,  // 0: the parallel sample_o, 1: the sample RAM read port
  // derived, do not override
  parameter int SampleAddrWidth = ($clog2(Axes) + $clog2(Width / ChunkWidth) > 0) ? $clog2(Axes) + $clog2(Width / ChunkWidth) : 1
) (
  input  logic       clk_i,
  input  logic       rst_ni,
  input  logic [7:0] byte_i,
  input  logic       byte_valid_i,
  output logic       byte_ready_o,
  input  logic       tick_i,
  input  logic [SampleAddrWidth-1:0] sample_addr_i,  // SampleRam: the word read
  output logic [7:0] fold_o,
  output logic       sample_valid_o,
  output logic       underrun_o,
  output logic       seg_done_o,
  output logic       tick_err_o
);
  localparam int OutWidth = Width - GuardBits;

  `TRAJ_PARAM_CHECK(g_bad_sample_ram, SampleRam == 0 || SampleRam == 1,
                    "traj_fd_tm_synth_top: SampleRam must be 0 or 1")


  logic                     rst_nq, tick_q;
  logic [SampleAddrWidth-1:0] sample_addr_q;
  /* verilator lint_off UNUSEDSIGNAL */
  logic [ChunkWidth-1:0]    sample_word;  // read in one mode only (SampleRam)
  /* verilator lint_on UNUSEDSIGNAL */
  logic [ChunkWidth-1:0]    word;
  logic                     word_valid, word_ready;
  logic                     sample_valid, underrun, seg_done, tick_err;
  /* verilator lint_off UNUSEDSIGNAL */
  logic [Axes*OutWidth-1:0] sample;
  logic [Axes*OutWidth-1:0] sample_we, sample_wd;  // (the engine's own sample flops)
  /* verilator lint_on UNUSEDSIGNAL */
  /* verilator lint_off UNUSEDSIGNAL */
  logic                     word_user;  // the engine's stream has no side band
  /* verilator lint_on UNUSEDSIGNAL */

  always_ff @(posedge clk_i) begin
    rst_nq <= rst_ni;
    tick_q <= tick_i;
    sample_addr_q <= (SampleRam != 0) ? sample_addr_i : '0;
  end

  traj_byte_words #(.WordWidth(ChunkWidth), .UserWidth(1)) u_bytes (
    .clk_i, .rst_ni(rst_nq),
    .byte_i, .user_i(1'b0), .byte_valid_i, .byte_ready_o,
    .m_axis_tdata(word), .m_axis_tuser(word_user), .m_axis_tvalid(word_valid),
    .m_axis_tready(word_ready)
  );

  traj_fd_tm #(
    .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth), .GuardBits(GuardBits),
    .TickClocks(TickClocks)
  ) u_engine (
    .clk_i, .rst_ni(rst_nq),
    .s_axis_tdata(word), .s_axis_tvalid(word_valid), .s_axis_tready(word_ready),
    .tick_i(tick_q),
    .sample_valid_o(sample_valid), .sample_o(sample), .sample_we_o(sample_we), .sample_wd_o(sample_wd),
    .sample_addr_i(sample_addr_q), .sample_word_o(sample_word),
    .underrun_o(underrun), .seg_done_o(seg_done), .tick_err_o(tick_err)
  );

  localparam int FoldWidth = (SampleRam != 0) ? ChunkWidth : Axes * OutWidth;
  logic [FoldWidth-1:0] fold_in;
  if (SampleRam != 0) begin : g_fold_word
    assign fold_in = FoldWidth'(sample_word);  // the word at sample_valid
  end else begin : g_fold_sample
    assign fold_in = FoldWidth'(sample);
  end

  traj_sample_fold #(.SampleWidth(FoldWidth)) u_fold (
    .clk_i,
    .sample_valid_i(sample_valid), .sample_i(fold_in),
    .underrun_i(underrun), .seg_done_i(seg_done), .tick_err_i(tick_err),
    .fold_o, .sample_valid_o, .underrun_o, .seg_done_o, .tick_err_o
  );
endmodule

`default_nettype wire
