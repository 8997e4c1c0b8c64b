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
//     flags (traj_sample_fold), so that no engine output can be optimised away.
// Everything is registered at the pins so that measured Fmax is the core's.
`default_nettype none

module traj_fd_tm_synth_top #(
  parameter int Axes       = 3,
  parameter int Degree     = 3,
  parameter int Width      = 64,
  parameter int ChunkWidth = 16,
  parameter int GuardBits  = 32,
  parameter int TickClocks = 240
) (
  input  logic       clk_i,
  input  logic       rst_ni,
  input  logic [7:0] byte_i,
  input  logic       byte_valid_i,
  output logic       byte_ready_o,
  input  logic       tick_i,
  output logic [7:0] fold_o,
  output logic       sample_valid_o,
  output logic       underrun_o,
  output logic       seg_done_o,
  output logic       tick_err_o
);
  localparam int OutWidth = Width - GuardBits;


  logic                     rst_nq, tick_q;
  logic [ChunkWidth-1:0]    word;
  logic                     word_valid, word_ready;
  logic                     sample_valid, underrun, seg_done, tick_err;
  logic [Axes*OutWidth-1:0] sample;
  /* verilator lint_off UNUSEDSIGNAL */
  logic                     word_user;  // the engine's stream has no side band
  /* verilator lint_on UNUSEDSIGNAL */

  always_ff @(posedge clk_i) begin
    rst_nq <= rst_ni;
    tick_q <= tick_i;
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
    .sample_valid_o(sample_valid), .sample_o(sample),
    .underrun_o(underrun), .seg_done_o(seg_done), .tick_err_o(tick_err)
  );

  traj_sample_fold #(.SampleWidth(Axes * OutWidth)) u_fold (
    .clk_i,
    .sample_valid_i(sample_valid), .sample_i(sample),
    .underrun_i(underrun), .seg_done_i(seg_done), .tick_err_i(tick_err),
    .fold_o, .sample_valid_o, .underrun_o, .seg_done_o, .tick_err_o
  );
endmodule

`default_nettype wire
