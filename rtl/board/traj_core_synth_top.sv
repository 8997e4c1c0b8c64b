// SPDX-License-Identifier: Apache-2.0
// trajcore: narrow-pin wrapper of traj_core (FD engine + BCU generator behind
// one segment stream) for iCE40 synthesis and place-and-route measurements.
//
// The core's segment stream is ChunkWidth bits wide and its sample bus is
// Axes*OutWidth bits: more pins than an SG48 package has. This wrapper
//   * assembles stream words from bytes (traj_byte_words: byte_valid_i/byte_i,
//     LS byte first; byte_ready_o is back-pressure); kind_i (segment kind,
//     tuser) is taken with every byte, the word's kind is that of its last byte,
//   * registers the servo strobe and the reset,
//   * folds every sample bit into an 8-bit register and registers the status
//     flags (traj_sample_fold), so that no core output can be optimised away.
// Everything is registered at the pins, so the measured Fmax is the core's.
`default_nettype none

module traj_core_synth_top #(
  parameter int Axes         = 3,   // axes in lockstep
  parameter int Degree       = 3,   // FD degree
  parameter int Width        = 64,  // FD register width
  parameter int ChunkWidth   = 16,  // stream word width, multiple of 8
  parameter int GuardBits    = 32,  // FD guard bits
  parameter int CtrlWidth    = 40,  // BCU control value width
  parameter int BcuGuardBits = 9,   // BCU control bits below the output LSB
  parameter int MaxDepth     = 12,  // BCU largest depth (K = 4096)
  parameter int FdTimeMux    = 0    // FD engine: 1 = traj_fd_tm
) (
  input  logic       clk_i,
  input  logic       rst_ni,
  input  logic [7:0] byte_i,
  input  logic       byte_valid_i,
  input  logic       kind_i,
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
  logic                     word_kind, word_valid, word_ready;
  logic                     sample_valid, underrun, seg_done, tick_err;
  logic [Axes*OutWidth-1:0] sample;

  always_ff @(posedge clk_i) begin
    rst_nq <= rst_ni;
    tick_q <= tick_i;
  end

  traj_byte_words #(.WordWidth(ChunkWidth), .UserWidth(1)) u_bytes (
    .clk_i, .rst_ni(rst_nq),
    .byte_i, .user_i(kind_i), .byte_valid_i, .byte_ready_o,
    .m_axis_tdata(word), .m_axis_tuser(word_kind), .m_axis_tvalid(word_valid),
    .m_axis_tready(word_ready)
  );

  traj_core #(
    .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth), .GuardBits(GuardBits),
    .CtrlWidth(CtrlWidth), .BcuGuardBits(BcuGuardBits), .MaxDepth(MaxDepth),
    .FdTimeMux(FdTimeMux)
  ) u_core (
    .clk_i, .rst_ni(rst_nq),
    .s_axis_tdata(word), .s_axis_tuser(word_kind), .s_axis_tvalid(word_valid),
    .s_axis_tready(word_ready),
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
