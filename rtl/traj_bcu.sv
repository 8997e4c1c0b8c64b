// SPDX-License-Identifier: Apache-2.0
// trajcore: BCU (Basic Calculation Unit), one de Casteljau mid-subdivision of
// a cubic Bernstein polynomial in the scaled form ([BCU], eq. 8).
// Mirrors hls/traj_bcu.hpp (traj::bcu_split). Purely combinational.
//
//   L = ( 8A, 4(A+B), 2(A+2B+C), A+3B+3C+D )
//   R = ( A+3B+3C+D, 2(B+2C+D), 4(C+D), 8D )
//
// Bit growth: exactly 3 bits per level. Every output is a non-negative
// combination of the inputs with weights summing to 8, so any InWidth-bit
// inputs give outputs that fit InWidth+3 bits: nothing is rounded or lost.
// Six adders; the factors 2, 4, 8 are wiring.
`default_nettype none
`include "traj_check.svh"

module traj_bcu #(
  parameter int InWidth  = 16,           // input coefficient width (two's complement), >= 2
  parameter int OutWidth = InWidth + 3   // derived: InWidth + 3 (checked), do not override
) (
  input  logic [4*InWidth-1:0]  coef_i,   // {D, C, B, A}, A in [InWidth-1:0]
  output logic [4*OutWidth-1:0] left_o,   // {D_l, C_l, B_l, A_l}, 8x the left half
  output logic [4*OutWidth-1:0] right_o   // {D_r, C_r, B_r, A_r}, 8x the right half
);

  `TRAJ_PARAM_CHECK(g_bad_inwidth, InWidth >= 2, "traj_bcu: InWidth must be >= 2")
  `TRAJ_PARAM_CHECK(g_bad_growth, OutWidth == InWidth + 3,
                    "traj_bcu: OutWidth must be InWidth+3 (3 bits of growth per level)")

  logic signed [OutWidth-1:0] a, b, c, d, s1, s2, s3, t1, t2, m;

  assign a  = OutWidth'($signed(coef_i[0*InWidth +: InWidth]));
  assign b  = OutWidth'($signed(coef_i[1*InWidth +: InWidth]));
  assign c  = OutWidth'($signed(coef_i[2*InWidth +: InWidth]));
  assign d  = OutWidth'($signed(coef_i[3*InWidth +: InWidth]));
  assign s1 = a + b;
  assign s2 = b + c;
  assign s3 = c + d;
  assign t1 = s1 + s2;
  assign t2 = s2 + s3;
  assign m  = t1 + t2;

  assign left_o  = {m, t1 <<< 1, s1 <<< 2, a <<< 3};
  assign right_o = {d <<< 3, s3 <<< 2, t2 <<< 1, m};

endmodule

`default_nettype wire
