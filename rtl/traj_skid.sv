// SPDX-License-Identifier: Apache-2.0
// trajcore: register slice (2-entry skid buffer) for a valid/ready stream.
// Mirrors hls/traj_skid.hpp cycle for cycle.
//
// Both sides see only flops: ready_o is low exactly when the skid register
// is full, valid_o and data_o are registers. So a consumer's ready_i reaches
// no further than this slice's own state, and a producer's valid_i no
// further than its data registers: a slice between two blocks cuts every
// combinational path of their handshake.
// Contract (AXI4-Stream): a word is taken from the input when valid_i &&
// ready_o, given to the output when valid_o && ready_i; valid_o and data_o
// hold until taken; words leave in order, none lost or repeated. Latency 1
// (an empty slice shows a word the clock after it is taken); throughput one
// word per clock. valid_d_o and data_d_o are the next state of valid_o and
// data_o (for registered re-encodings of the output beside the slice).
// Reset clears the valid bits; the data registers keep their value.
`default_nettype none
`include "traj_check.svh"

module traj_skid #(
  parameter int Width = 16  // data bits, >= 1
) (
  input  logic             clk_i,
  input  logic             rst_ni,
  input  logic [Width-1:0] data_i,
  input  logic             valid_i,
  output logic             ready_o,
  output logic [Width-1:0] data_o,
  output logic             valid_o,
  input  logic             ready_i,
  output logic             valid_d_o,
  output logic [Width-1:0] data_d_o
);
  `TRAJ_PARAM_CHECK(g_bad_width, Width >= 1, "traj_skid: Width must be at least 1")

  logic             out_v_q, sk_v_q, load_out;
  logic [Width-1:0] out_d_q, sk_d_q;

  // the output register loads when it is empty or its word is taken: from
  // the skid register if that holds a word, else from the input
  assign load_out  = !out_v_q || ready_i;
  assign valid_d_o = load_out ? (sk_v_q || valid_i) : 1'b1;
  assign data_d_o  = (load_out && sk_v_q) ? sk_d_q : ((load_out && valid_i) ? data_i : out_d_q);

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      out_v_q <= 1'b0;
      sk_v_q  <= 1'b0;
    end else begin
      out_v_q <= valid_d_o;
      if (load_out) sk_v_q <= 1'b0;
      else if (valid_i && !sk_v_q) sk_v_q <= 1'b1;
    end
  end
  always_ff @(posedge clk_i) begin
    out_d_q <= data_d_o;
    if (!load_out && valid_i && !sk_v_q) sk_d_q <= data_i;
  end

  assign ready_o = !sk_v_q;
  assign valid_o = out_v_q;
  assign data_o  = out_d_q;

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Formal properties (scripts/formal.sh: BMC from reset and induction).
  // ---------------------------------------------------------------------
  logic f_past_valid = 1'b0;
  always_ff @(posedge clk_i) f_past_valid <= 1'b1;
  always_comb if (!f_past_valid) assume (!rst_ni);
  always_ff @(posedge clk_i) begin
    if (f_past_valid) begin
      if (!$past(rst_ni)) begin
        assert (!out_v_q && !sk_v_q);
      end else begin
        // the output holds until taken
        if ($past(out_v_q) && !$past(ready_i)) assert (out_v_q && out_d_q == $past(out_d_q));
        // a word taken at the input is in the slice the clock after
        if ($past(valid_i) && !$past(sk_v_q)) begin
          if ($past(out_v_q) && !$past(ready_i)) assert (sk_v_q && sk_d_q == $past(data_i));
          else if (!$past(sk_v_q)) assert (out_v_q && out_d_q == $past(data_i));
        end
        // the skid word goes out next, before any newer one
        if ($past(sk_v_q) && (!$past(out_v_q) || $past(ready_i))) assert (out_v_q && out_d_q == $past(sk_d_q));
      end
      // the skid register is used only behind a full output
      if (sk_v_q) assert (out_v_q);
    end
  end
`endif
endmodule

`default_nettype wire
