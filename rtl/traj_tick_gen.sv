// trajcore: servo tick generator.
//
// Mirrors hls/traj_tick_gen.hpp cycle for cycle. One strobe per tick on
// tick_o (one cycle high), the engines' tick contract:
//   * period_i != 0: internal tick every period_i clocks while run_i is high.
//     The first tick comes period_i clocks after run_i rises; a change of
//     period_i takes effect at the next tick. period_i = 1 would be a level
//     (a tick in every cycle), which the engines' contract forbids: the host
//     link refuses tick periods below the engine's update time.
//   * period_i == 0: the external tick tick_ext_i (asynchronous) passes a
//     2-flop synchroniser and a rising-edge detector: one strobe per rising
//     edge while run_i is high, whatever the pulse width.
//   * period_o is the tick period in clocks: period_i, or for the external
//     tick the clocks between its last two rising edges (0 until two edges
//     have been seen since reset; ExtWidth bits, at most 2^ExtWidth - 1: a
//     longer or stopped external tick reads as that), for the step
//     generator.
// Latency: tick_ext_i high before clock edge c -> tick_o high in the cycle
// after edge c+2 (2 synchroniser flops, the output flop; the edge detector's
// flop runs beside them).
`default_nettype none
`include "traj_check.svh"

module traj_tick_gen #(
  parameter int PeriodWidth = 32,          // width of the period input and counter, 2..32
  parameter int ExtWidth    = PeriodWidth  // width of the external period's measurement, 2..PeriodWidth
) (
  input  logic                   clk_i,
  input  logic                   rst_ni,
  input  logic                   run_i,       // ticks only while high
  input  logic [PeriodWidth-1:0] period_i,    // tick period in clocks; 0: external tick
  input  logic                   tick_ext_i,  // external tick, asynchronous
  output logic                   tick_o,      // one-cycle strobe per tick
  output logic [PeriodWidth-1:0] period_o     // period in use (measured for the external tick)
);

  `TRAJ_PARAM_CHECK(g_bad_width, PeriodWidth >= 2 && PeriodWidth <= 32,
                    "traj_tick_gen: PeriodWidth must be 2..32")
  `TRAJ_PARAM_CHECK(g_bad_ext, ExtWidth >= 2 && ExtWidth <= PeriodWidth,
                    "traj_tick_gen: ExtWidth must be 2..PeriodWidth")

  logic                   ext_meta_q, ext_sync_q, ext_prev_q;  // synchroniser, edge detector
  logic [PeriodWidth-1:0] cnt_q;       // internal: clocks to the next tick (reloaded with period_i: one decrementer)
  logic [ExtWidth-1:0]    ext_cnt_q;   // external: clocks since the last edge (saturating)
  logic [ExtWidth-1:0]    ext_per_q;   // external: clocks between the last two edges
  logic                   ext_seen_q;  // an external edge has been seen since reset
  logic                   tick_q;

  logic internal, ext_rise, int_tick, ext_tick;
  assign internal = (period_i != '0);
  assign ext_rise = ext_sync_q && !ext_prev_q;
  assign int_tick = run_i && internal && (cnt_q == PeriodWidth'(1));
  assign ext_tick = run_i && !internal && ext_rise;

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      ext_meta_q <= 1'b0;
      ext_sync_q <= 1'b0;
      ext_prev_q <= 1'b0;
      cnt_q      <= PeriodWidth'(1);
      ext_cnt_q  <= '0;
      ext_per_q  <= '0;
      ext_seen_q <= 1'b0;
      tick_q     <= 1'b0;
    end else begin
      ext_meta_q <= tick_ext_i;
      ext_sync_q <= ext_meta_q;
      ext_prev_q <= ext_sync_q;
      if (!run_i || cnt_q == PeriodWidth'(1)) cnt_q <= period_i;
      else                       cnt_q <= cnt_q - 1'b1;
      if (ext_rise) begin
        ext_cnt_q  <= ExtWidth'(1);
        ext_seen_q <= 1'b1;
        if (ext_seen_q) ext_per_q <= ext_cnt_q;
      end else if (ext_cnt_q != '1) begin
        ext_cnt_q <= ext_cnt_q + 1'b1;  // saturates: a stopped external tick
      end
      tick_q <= int_tick || ext_tick;
    end
  end

`ifdef FORMAL
  logic f_past_valid = 1'b0;
  logic f_past2 = 1'b0;  // two cycles since reset
  always_ff @(posedge clk_i) begin
    f_past_valid <= 1'b1;
    f_past2 <= rst_ni && $past(rst_ni) && f_past_valid;
  end
  always_comb if (!f_past_valid) assume (!rst_ni);
  always_ff @(posedge clk_i) begin
    if (f_past_valid && $past(rst_ni)) begin
      // one strobe = one tick: never two in a row, unless the period is 1 or
      // changes between them
      if ($past(tick_q) && tick_q && f_past2)
        assert ($past(period_i, 2) == PeriodWidth'(1) || $past(period_i, 2) != $past(period_i));
      // the external tick strobes only on a rising edge of the synchronised input
      if (tick_q && $past(period_i) == '0) assert ($past(ext_sync_q) && !$past(ext_prev_q) && $past(run_i));
      if (tick_q) assert ($past(run_i));
    end
  end
`endif

  assign tick_o   = tick_q;
  assign period_o = internal ? period_i : PeriodWidth'(ext_per_q);

endmodule

`default_nettype wire
