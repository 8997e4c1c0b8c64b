// SPDX-License-Identifier: Apache-2.0
// Equivalence of traj_add's two forms: the logic-cell adder (UseDsp = 0) and
// the SB_MAC16 form (UseDsp = 1, simulated by Yosys' model of the block,
// techlibs/ice40/cells_sim.v), proved for every input by `sat -prove-asserts`
// (tb/board/CMakeLists.txt, rtl.equiv.traj_add.*).
//
// RegB = 1 (b registered at be): both forms start from zero registers and
// are compared over 3 clocks of any inputs (`sat -seq 3 -set-init-zero`).
// That covers every state either form can be in: its registers hold zero or
// the b of the last clock with be, both reached within one clock, and the
// clocks after check every a, ci and b against each.
`default_nettype none

module traj_add_equiv #(
  parameter int Width   = 34,
  parameter int CarryIn = 0,
  parameter int RegB    = 0
) (
  input  logic             clk,
  input  logic             be,
  input  logic [Width-1:0] a,
  input  logic [Width-1:0] b,
  input  logic             ci,
  output logic             same
);
  logic [Width-1:0] s_lc, s_dsp;
  traj_add #(.Width(Width), .CarryIn(CarryIn), .UseDsp(0), .RegB(RegB)) u_lc (
    .clk_i(clk), .be_i(be), .a_i(a), .b_i(b), .ci_i(ci), .sum_o(s_lc)
  );
  traj_add #(.Width(Width), .CarryIn(CarryIn), .UseDsp(1), .RegB(RegB)) u_dsp (
    .clk_i(clk), .be_i(be), .a_i(a), .b_i(b), .ci_i(ci), .sum_o(s_dsp)
  );
  assign same = s_lc == s_dsp;
  always_comb assert (same);
endmodule

`default_nettype wire
