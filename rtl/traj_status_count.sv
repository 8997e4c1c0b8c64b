// SPDX-License-Identifier: Apache-2.0
// trajcore: the host link's STATUS counters in block RAM (traj_link_proto
// with CountRam = 1; mirrors hls/traj_status_count.hpp cycle for cycle).
//
// N 32-bit counters of one-cycle events in one block RAM with one adder, in
// place of N counters in flip-flops (32 logic cells each). Counter k is word
// k: each clock one word is read (cr_q) and the word read the clock before
// (cw_q) is written back plus the events counted since its own last write
// (pend_q, 2 bits per counter), so each counter is written every N clocks.
// The first round after reset writes the events alone (clr_q): the RAM is
// not reset.
// Contract: no ev_i bit is high in two consecutive cycles (the link's
// strobes are one cycle, its received bytes at most every other cycle), so
// a counter has at most ceil(N/2) = 3 events pending. want_i (a strobe, not
// while wait_o) asks for counter k_i: wait_o is high from the next clock
// until that counter's next write, when ld_o strobes with sum_o, the value
// written: the count of every event before that clock. That takes 1 to N
// clocks.
`default_nettype none
`include "traj_check.svh"

module traj_status_count #(
  parameter int N = 6  // counters, 2..6 (at most 3 events pending each)
) (
  input  logic         clk_i,
  input  logic         rst_ni,
  input  logic [N-1:0] ev_i,
  input  logic         want_i,
  input  logic [2:0]   k_i,
  output logic         wait_o,
  output logic         ld_o,
  output logic [31:0]  sum_o
);
  `TRAJ_PARAM_CHECK(g_bad_n, N >= 2 && N <= 6, "traj_status_count: N must be 2..6")

  (* ram_style = "block", no_rw_check *) logic [31:0] mem [0:7];
  logic [2:0]  cr_q, cw_q, ck_q;
  logic        cwv_q, clr_q, wait_q;
  logic [15:0] pend_q;  // 2 bits per counter (the rest unused, 0)
  logic [1:0]  pw_q;    // pend_q of cw_q, taken a clock early (off the adder's path)
  logic [31:0] rd_q;    // the RAM's read register
  logic [7:0]  ev;

  assign ev = 8'(ev_i);

  always_ff @(posedge clk_i) begin
    rd_q <= mem[cr_q];
    if (cwv_q) mem[cw_q] <= sum_o;
  end

  // datapath: what pend_q of cr_q becomes (cr_q is not the word written back
  // now); the counter asked for
  always_ff @(posedge clk_i) begin
    pw_q <= pend_q[{cr_q, 1'b0} +: 2] + {1'b0, ev[cr_q]};
    if (want_i) ck_q <= k_i;
  end

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      cr_q   <= '0;
      cw_q   <= '0;
      cwv_q  <= 1'b0;
      clr_q  <= 1'b1;
      wait_q <= 1'b0;
      pend_q <= '0;
    end else begin
      for (int k = 0; k < N; k++)
        pend_q[2*k +: 2] <= ((cwv_q && cw_q == 3'(k)) ? 2'd0 : pend_q[2*k +: 2]) + {1'b0, ev[k]};
      if (cwv_q && cw_q == 3'(N - 1)) clr_q <= 1'b0;
      cwv_q <= 1'b1;
      cw_q  <= cr_q;
      cr_q  <= (cr_q == 3'(N - 1)) ? 3'd0 : cr_q + 1'b1;
      if (want_i) wait_q <= 1'b1;
      else if (ld_o) wait_q <= 1'b0;
    end
  end

  assign sum_o  = (clr_q ? 32'h0 : rd_q) + {30'h0, pw_q};
  assign ld_o   = wait_q && cwv_q && (cw_q == ck_q);
  assign wait_o = wait_q;

`ifdef FORMAL
  // Every value written back is the count of the events before it, as flops
  // would hold it (f_n); no event is lost in pend_q; the schedule's state.
  logic            f_past_valid = 1'b0;
  logic [N-1:0]    f_ev_q;
  logic [8*32-1:0] f_n;
  always_ff @(posedge clk_i) begin
    f_past_valid <= 1'b1;
    f_ev_q <= ev_i;
    for (int k = 0; k < 8; k++) begin
      if (!rst_ni || k >= N) f_n[k*32 +: 32] <= '0;
      else if (ev[k]) f_n[k*32 +: 32] <= f_n[k*32 +: 32] + 1'b1;
    end
  end
  always_comb begin
    if (!f_past_valid) assume (!rst_ni);
    if (f_past_valid) assume ((ev_i & f_ev_q) == '0);
    if (wait_q) assume (!want_i);
    if (want_i) assume (32'(k_i) < N);
  end
  always_ff @(posedge clk_i) begin
    if (f_past_valid && rst_ni) begin
      assert (cr_q < 3'(N) && cw_q < 3'(N));
      if (cwv_q) begin
        assert (cr_q == ((cw_q == 3'(N - 1)) ? 3'd0 : cw_q + 3'd1));
        assert (pw_q == pend_q[{cw_q, 1'b0} +: 2]);
        assert (sum_o == f_n[32*cw_q +: 32]);
      end
      if (!cwv_q) assert (clr_q && cr_q == 3'd0);
      for (int k = 0; k < N; k++) begin
        if (ev[k] && !(cwv_q && cw_q == 3'(k))) assert (pend_q[2*k +: 2] != 2'd3);
        // the RAM word of a counter already written holds its count less
        // the events pending (so the next write is right)
        if (!clr_q && !(cwv_q && cw_q == 3'(k)))
          assert (mem[k] + 32'(pend_q[2*k +: 2]) == f_n[32*k +: 32]);
      end
      if (wait_q) assert (32'(ck_q) < N);
    end
  end
`endif

endmodule

`default_nettype wire
