// SPDX-License-Identifier: Apache-2.0
// trajcore: an adder, sum_o = a_i + b_i (+ ci_i with CarryIn = 1) modulo
// 2^Width, in logic cells or (UseDsp = 1) in an iCE40 UP5K DSP block.
//
// RegB = 1: b is a register of the adder, sum_o = a_i + b_q, with b_q taking
// b_i at a clock with be_i high (not reset; CarryIn 0). In the DSP form its
// low 32 bits are the block's own C/D input registers (CHOLD/DHOLD = !be_i):
// a register loaded from another register takes a logic cell per bit on the
// iCE40 (its flip-flop has no LUT of its own), the block's take none.
//
// UseDsp = 1: the SB_MAC16's 32-bit adder, combinational ({A, B} + {C, D},
// no register, carry in 0), takes the low 32 bits; the bits above are
// added in logic cells, with the carry into bit 32 recovered from the
// operands' and the sum's bit 31: carry = a31 b31 | (a31 ^ b31) !s31.
// A carry in goes in as one bit more below: {a, 1} + {b, ci} carries ci
// out of that bit (the block's own carry in is a constant or a cascade).
// The UP5K has eight such blocks, idle otherwise: a Width-bit adder there
// frees up to 32 logic cells (those of its sum bits; operands and sums that
// a register takes keep theirs). Only for a device with SB_MAC16 (the
// UP5K); simulation needs Yosys' model of the block (techlibs/ice40/
// cells_sim.v: tb/board/CMakeLists.txt proves the two forms equal).
`default_nettype none
`include "traj_check.svh"

module traj_add #(
  parameter int Width   = 32,  // 1..64
  parameter int CarryIn = 0,   // 1: ci_i is added (else ignored)
  parameter int UseDsp  = 0,   // 1: the low 32 bits in an SB_MAC16 (iCE40 UP5K)
  parameter int RegB    = 0    // 1: b_i is registered at be_i (sum_o = a_i + the register)
) (
  input  logic             clk_i,  // (RegB = 1 only)
  input  logic             be_i,   // b's register takes b_i (RegB = 1 only)
  input  logic [Width-1:0] a_i,
  input  logic [Width-1:0] b_i,
  input  logic             ci_i,
  output logic [Width-1:0] sum_o
);

  `TRAJ_PARAM_CHECK(g_bad_width, Width >= 1 && Width <= 64, "traj_add: Width must be 1..64")
  `TRAJ_PARAM_CHECK(g_bad_ci, CarryIn == 0 || CarryIn == 1, "traj_add: CarryIn must be 0 or 1")
  `TRAJ_PARAM_CHECK(g_bad_dsp, UseDsp == 0 || UseDsp == 1, "traj_add: UseDsp must be 0 or 1")
  `TRAJ_PARAM_CHECK(g_bad_regb, RegB == 0 || RegB == 1, "traj_add: RegB must be 0 or 1")
  // (the DSP form takes a carry in as y's bit 0: with RegB it would be registered too)
  `TRAJ_PARAM_CHECK(g_bad_regb_ci, RegB == 0 || CarryIn == 0, "traj_add: RegB = 1 needs CarryIn = 0")

  /* verilator lint_off UNUSEDSIGNAL */
  logic clk, be;  // (not read with RegB = 0)
  /* verilator lint_on UNUSEDSIGNAL */
  assign clk = clk_i;
  assign be  = be_i;

  if (UseDsp == 0) begin : g_lc
    /* verilator lint_off UNUSEDSIGNAL */
    logic ci;  // (not read with CarryIn = 0)
    /* verilator lint_on UNUSEDSIGNAL */
    logic [Width-1:0] b;
    assign ci = ci_i;
    if (RegB != 0) begin : g_reg
      logic [Width-1:0] b_q;
      always_ff @(posedge clk) if (be) b_q <= b_i;
      assign b = b_q;
    end else begin : g_comb
      assign b = b_i;
    end
    assign sum_o = a_i + b + Width'(CarryIn != 0 && ci);
  end else begin : g_dsp
    localparam int XW = Width + CarryIn;        // the operands with the carry's bit
    localparam int LW = (XW < 32) ? XW : 32;    // bits in the DSP
    logic [XW-1:0] x, y;
    logic [31:0]   x32, y32;
    /* verilator lint_off UNUSEDSIGNAL */
    logic [XW-1:0] s;                       // (bit 0 the carry's bit with CarryIn = 1)
    logic [31:0]   o32;                     // (bits XW and up unused below 32)
    logic          co, accum_co, sign_ext;  // the block's carry and cascade outputs, not used
    logic          ci;                      // (not read with CarryIn = 0)
    /* verilator lint_on UNUSEDSIGNAL */
    assign ci = ci_i;
    if (CarryIn != 0) begin : g_ci
      assign x = {a_i, 1'b1};
      assign y = {b_i, ci};
    end else begin : g_no_ci
      assign x = a_i;
      assign y = b_i;
    end
    assign x32 = 32'(x[LW-1:0]);
    assign y32 = 32'(y[LW-1:0]);
    // O = {A, B} + {C, D}: both halves add their inputs (LOWERINPUT 0: A / B,
    // UPPERINPUT 1: C / D), the top half takes the bottom's carry
    // (TOPADDSUB_CARRYSELECT 2), outputs unregistered (OUTPUT_SELECT 0);
    // C and D registered with RegB = 1 (CE 1, hold unless be_i)
    SB_MAC16 #(
      .C_REG(RegB[0]), .D_REG(RegB[0]),
      .TOPADDSUB_LOWERINPUT(2'd0), .TOPADDSUB_UPPERINPUT(1'b1), .TOPADDSUB_CARRYSELECT(2'd2),
      .TOPOUTPUT_SELECT(2'd0),
      .BOTADDSUB_LOWERINPUT(2'd0), .BOTADDSUB_UPPERINPUT(1'b1), .BOTADDSUB_CARRYSELECT(2'd0),
      .BOTOUTPUT_SELECT(2'd0)
    ) u_mac (
      .CLK(RegB != 0 ? clk : 1'b0), .CE(RegB != 0),
      .A(x32[31:16]), .B(x32[15:0]), .C(y32[31:16]), .D(y32[15:0]),
      .AHOLD(1'b0), .BHOLD(1'b0), .CHOLD(!be), .DHOLD(!be),
      .IRSTTOP(1'b0), .IRSTBOT(1'b0), .ORSTTOP(1'b0), .ORSTBOT(1'b0),
      .OLOADTOP(1'b0), .OLOADBOT(1'b0), .ADDSUBTOP(1'b0), .ADDSUBBOT(1'b0),
      .OHOLDTOP(1'b0), .OHOLDBOT(1'b0),
      .CI(1'b0), .ACCUMCI(1'b0), .SIGNEXTIN(1'b0),
      .O(o32), .CO(co), .ACCUMCO(accum_co), .SIGNEXTOUT(sign_ext)
    );
    if (XW <= 32) begin : g_fits
      assign s = o32[XW-1:0];
    end else begin : g_upper
      logic c32;
      logic [XW-1:31] yh;  // y's bits above the block and bit 31 (the carry's)
      if (RegB != 0) begin : g_yreg
        logic [XW-1:31] yh_q;  // with RegB = 1 a register of logic cells (the block registers its 32)
        always_ff @(posedge clk) if (be) yh_q <= y[XW-1:31];
        assign yh = yh_q;
      end else begin : g_ycomb
        assign yh = y[XW-1:31];
      end
      assign c32 = (x[31] && yh[31]) || ((x[31] ^ yh[31]) && !o32[31]);
      assign s   = {x[XW-1:32] + yh[XW-1:32] + (XW-32)'(c32), o32};
    end
    assign sum_o = s[XW-1:CarryIn];
  end

endmodule

`default_nettype wire
