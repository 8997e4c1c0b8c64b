// SPDX-License-Identifier: Apache-2.0
// trajcore: the engine ticks stored ahead of those played, for the time-scale
// unit (its avail_i) and STATUS (traj_board, TimeScale = 1).
//
//   ahead = fifo_k + the samples of the segments in the engine not yet played
//   fifo_k = K of the segments stored, not yet left the FIFO
//
// Events: stored_i (a record stored, its K in stored_k_i), cleared_i (RESET
// emptied the FIFO: its share leaves ahead), hdr_done_i (a segment's header
// left the FIFO, its K in hdr_k_i: moved from fifo_k to the engine's share,
// ahead unchanged), real_i (an engine sample played: ahead - 1). The plain
// form adds up to four operands a clock (two adders for each count); here
// each count has one adder, because a store waits (pend_q) for a clock
// without hdr_done_i, real_i and cleared_i, and is then added to both:
//   fifo_k' = (cleared ? 0 : fifo_k) + (a store ? K : hdr_done ? ~hdr_k : 0) + hdr_done
//   ahead'  = ahead + (a store ? K : cleared ? ~fifo_k : real ? ~0 : 0) + (cleared && !real)
// (-x = ~x + 1; cleared with real: - fifo_k - 1 = + ~fifo_k). So ahead is the
// plain count less a store's K for the clocks it waits: never more than the
// data stored (the unit's stops stay within it), exact once it is added. A
// store waits while the clocks it meets carry the other events: hdr_done_i
// comes once per segment read (at least its words apart), real_i once per
// engine tick, so a store waits at most 2 clocks on the board.
// Contract: stored_i and cleared_i are never high together (the link's
// verdicts of two frames); stored_k_i holds from stored_i until the next
// store (the link's register of the record's K: the next record's K bytes
// come long after); hdr_k_i is valid with hdr_done_i.
`default_nettype none
`include "traj_check.svh"

module traj_ahead #(
  parameter int Width = 32  // 2..32
) (
  input  logic             clk_i,
  input  logic             rst_ni,
  input  logic             stored_i,
  input  logic [Width-1:0] stored_k_i,
  input  logic             cleared_i,
  input  logic             hdr_done_i,
  input  logic [Width-1:0] hdr_k_i,
  input  logic             real_i,
  output logic [Width-1:0] ahead_o
);

  `TRAJ_PARAM_CHECK(g_bad_width, Width >= 2 && Width <= 32, "traj_ahead: Width must be 2..32")

  logic [Width-1:0] fifo_k_q, ahead_q;
  logic             pend_q;  // a store not yet added (its K: stored_k_i)
  logic             add_k;   // a store is added this clock

  assign add_k = (stored_i || pend_q) && !hdr_done_i && !real_i && !cleared_i;

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      fifo_k_q <= '0;
      ahead_q  <= '0;
      pend_q   <= 1'b0;
    end else begin
      // a store waiting at RESET was in the FIFO that RESET empties
      pend_q   <= (stored_i || (pend_q && !cleared_i)) && !add_k;
      fifo_k_q <= (cleared_i ? '0 : fifo_k_q) + (add_k ? stored_k_i : hdr_done_i ? ~hdr_k_i : '0)
                + Width'(hdr_done_i);
      ahead_q  <= ahead_q + (add_k ? stored_k_i : cleared_i ? ~fifo_k_q : real_i ? '1 : '0)
                + Width'(cleared_i && !real_i);
    end
  end

  assign ahead_o = ahead_q;

`ifdef FORMAL
  // The plain form (every event in its own clock's sums) beside this one:
  // this one is the plain count less the K of a waiting store, and a store
  // waits only while the clocks carry other events.
  logic f_past_valid = 1'b0;
  logic [Width-1:0] f_fifo_k_q, f_ahead_q, f_k_q;
  logic f_h1_q, f_h2_q, f_r1_q, f_r2_q, f_p1_q, f_p2_q;  // the last two clocks' hdr_done, real, pend
  always_ff @(posedge clk_i) begin
    f_past_valid <= 1'b1;
    f_k_q  <= stored_k_i;
    f_h1_q <= hdr_done_i;
    f_h2_q <= f_h1_q;
    f_r1_q <= real_i;
    f_r2_q <= f_r1_q;
    f_p1_q <= pend_q;
    f_p2_q <= f_p1_q;
    if (!rst_ni) begin
      f_fifo_k_q <= '0;
      f_ahead_q  <= '0;
    end else begin
      f_fifo_k_q <= (cleared_i ? '0 : f_fifo_k_q) + (stored_i ? stored_k_i : '0) - (hdr_done_i ? hdr_k_i : '0);
      f_ahead_q  <= f_ahead_q - (cleared_i ? f_fifo_k_q : '0) + (stored_i ? stored_k_i : '0) - Width'(real_i);
    end
  end
  always_comb begin
    if (!f_past_valid) assume (!rst_ni);
    assume (!(stored_i && cleared_i));
    // the contract: K holds while its store waits, no store meanwhile
    if (f_past_valid && pend_q) assume (stored_k_i == f_k_q && !stored_i);
    // the events' spacing on the board (a segment's words, an engine
    // tick): at least 3 clocks
    if (f_past_valid && (f_h1_q || f_h2_q)) assume (!hdr_done_i);
    if (f_past_valid && (f_r1_q || f_r2_q)) assume (!real_i);
    if (f_past_valid && rst_ni) begin
      assert (fifo_k_q == f_fifo_k_q - (pend_q ? stored_k_i : '0));
      assert (ahead_q == f_ahead_q - (pend_q ? stored_k_i : '0));
      // a store waits at most 2 clocks (an hdr_done and a real_i in turn)
      assert (!(pend_q && f_p1_q && f_p2_q));
    end
  end
`endif

endmodule

`default_nettype wire
