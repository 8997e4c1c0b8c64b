// SPDX-License-Identifier: Apache-2.0
// trajcore: a wide register kept in block RAM instead of flip-flops.
//
// For a register that is written whole and read long after (the STATUS
// snapshot of the samples: Axes*OutWidth bits sent a word at a time): on the
// iCE40 its bits take ceil(Width/16) SB_RAM40_4K blocks (256 x 16, one
// address used) and one logic cell, instead of Width logic cells.
//
// Contract: data_o is the value of the last write, from the second clock
// after it: a write in clock c (we_i high) is in the RAM after c, read into
// data_o after c+1 (one clock later than a flop's). data_o holds while we_i
// is high, so the RAM is never read and written in the same clock (the
// iCE40's block RAM leaves such a read undefined; `no_rw_check` tells Yosys
// that no collision logic is needed). After reset data_o is undefined until
// the first write has been read, as a flop without reset would be.
`default_nettype none
`include "traj_check.svh"

module traj_hold_ram #(
  parameter int Width = 16  // bits, >= 1
) (
  input  logic             clk_i,
  input  logic             we_i,
  input  logic [Width-1:0] data_i,
  output logic [Width-1:0] data_o
);

  `TRAJ_PARAM_CHECK(g_bad_width, Width >= 1, "traj_hold_ram: Width must be >= 1")

  // two words, one used: an index that is a signal keeps Yosys from turning
  // the memory into flops (it does for a constant index)
  logic addr;
  (* ram_style = "block", no_rw_check *) logic [Width-1:0] mem [0:1];
  assign addr = 1'b0;

  always_ff @(posedge clk_i) begin
    if (we_i) mem[addr] <= data_i;
    else data_o <= mem[addr];
  end

endmodule

`default_nettype wire
