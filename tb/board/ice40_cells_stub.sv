// Port-only stand-ins of the iCE40 primitives the board tops instantiate, for
// lint and elaboration (Verilator, Icarus, Yosys hierarchy -check) only;
// synthesis uses Yosys' own ice40 cell library. The ports the tops connect,
// named as in Yosys' techlibs/ice40/cells_sim.v (the unused PLL outputs
// PLLOUTCORE and SDO are left out).
`default_nettype none
/* verilator lint_off UNUSEDSIGNAL */
/* verilator lint_off UNUSEDPARAM */
/* verilator lint_off UNDRIVEN */
/* verilator lint_off DECLFILENAME */
/* verilator lint_off MULTITOP */
module SB_PLL40_PAD #(
  parameter FEEDBACK_PATH = "SIMPLE",
  parameter [3:0] DIVR = 4'b0000,
  parameter [6:0] DIVF = 7'b0000000,
  parameter [2:0] DIVQ = 3'b000,
  parameter [2:0] FILTER_RANGE = 3'b000
) (
  input  wire       PACKAGEPIN,
  output wire       PLLOUTGLOBAL,
  input  wire       EXTFEEDBACK,
  input  wire [7:0] DYNAMICDELAY,
  output wire       LOCK,
  input  wire       BYPASS,
  input  wire       RESETB,
  input  wire       LATCHINPUTVALUE,
  input  wire       SDI,
  input  wire       SCLK
);
endmodule

module SB_PLL40_CORE #(
  parameter FEEDBACK_PATH = "SIMPLE",
  parameter [3:0] DIVR = 4'b0000,
  parameter [6:0] DIVF = 7'b0000000,
  parameter [2:0] DIVQ = 3'b000,
  parameter [2:0] FILTER_RANGE = 3'b000
) (
  input  wire       REFERENCECLK,
  output wire       PLLOUTGLOBAL,
  input  wire       EXTFEEDBACK,
  input  wire [7:0] DYNAMICDELAY,
  output wire       LOCK,
  input  wire       BYPASS,
  input  wire       RESETB,
  input  wire       LATCHINPUTVALUE,
  input  wire       SDI,
  input  wire       SCLK
);
endmodule

module SB_IO #(
  parameter [5:0] PIN_TYPE = 6'b000000,
  parameter [0:0] PULLUP = 1'b0
) (
  input  wire PACKAGE_PIN,
  output wire D_IN_0
);
endmodule

// (rtl/traj_add.sv, UseDsp = 1: the iCEBreaker's step generator)
module SB_MAC16 #(
  parameter [0:0] C_REG = 1'b0,
  parameter [0:0] D_REG = 1'b0,
  parameter [1:0] TOPOUTPUT_SELECT = 2'd0,
  parameter [1:0] TOPADDSUB_LOWERINPUT = 2'd0,
  parameter [0:0] TOPADDSUB_UPPERINPUT = 1'b0,
  parameter [1:0] TOPADDSUB_CARRYSELECT = 2'd0,
  parameter [1:0] BOTOUTPUT_SELECT = 2'd0,
  parameter [1:0] BOTADDSUB_LOWERINPUT = 2'd0,
  parameter [0:0] BOTADDSUB_UPPERINPUT = 1'b0,
  parameter [1:0] BOTADDSUB_CARRYSELECT = 2'd0
) (
  input  wire        CLK, CE,
  input  wire [15:0] C, A, B, D,
  input  wire        AHOLD, BHOLD, CHOLD, DHOLD,
  input  wire        IRSTTOP, IRSTBOT, ORSTTOP, ORSTBOT,
  input  wire        OLOADTOP, OLOADBOT, ADDSUBTOP, ADDSUBBOT,
  input  wire        OHOLDTOP, OHOLDBOT,
  input  wire        CI, ACCUMCI, SIGNEXTIN,
  output wire [31:0] O,
  output wire        CO, ACCUMCO, SIGNEXTOUT
);
endmodule
/* verilator lint_on MULTITOP */
/* verilator lint_on DECLFILENAME */
/* verilator lint_on UNDRIVEN */
/* verilator lint_on UNUSEDPARAM */
/* verilator lint_on UNUSEDSIGNAL */
`default_nettype wire
