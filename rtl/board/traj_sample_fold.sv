// SPDX-License-Identifier: Apache-2.0
// trajcore: the output side of a board wrapper. XOR-folds every bit of a wide
// sample bus into an 8-bit register (so that synthesis keeps every sample bit
// of the core behind it) and registers the status flags, so that every output
// pin comes from a flop and the measured Fmax is the core's.
`default_nettype none

module traj_sample_fold #(
  parameter int SampleWidth = 96  // bits of the sample bus
) (
  input  logic                   clk_i,
  input  logic                   sample_valid_i,
  input  logic [SampleWidth-1:0] sample_i,
  input  logic                   underrun_i,
  input  logic                   seg_done_i,
  input  logic                   tick_err_i,
  output logic [7:0]             fold_o,
  output logic                   sample_valid_o,
  output logic                   underrun_o,
  output logic                   seg_done_o,
  output logic                   tick_err_o
);
  logic [7:0] fold_q, fold_d;
  logic       sample_valid_q, underrun_q, seg_done_q, tick_err_q;

  always_comb begin
    fold_d = fold_q;
    for (int b = 0; b < SampleWidth; b++) fold_d[b % 8] = fold_d[b % 8] ^ sample_i[b];
  end

  always_ff @(posedge clk_i) begin
    if (sample_valid_i) fold_q <= fold_d;
    sample_valid_q <= sample_valid_i;
    underrun_q     <= underrun_i;
    seg_done_q     <= seg_done_i;
    tick_err_q     <= tick_err_i;
  end

  assign fold_o         = fold_q;
  assign sample_valid_o = sample_valid_q;
  assign underrun_o     = underrun_q;
  assign seg_done_o     = seg_done_q;
  assign tick_err_o     = tick_err_q;
endmodule

`default_nettype wire
