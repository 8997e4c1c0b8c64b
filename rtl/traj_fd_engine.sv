// SPDX-License-Identifier: Apache-2.0
// trajcore: forward-difference sampling engine.
//
// Mirrors hls/traj_fd_engine.hpp cycle for cycle; see that file for the full
// description. In short:
//   * per axis Degree+1 registers r[0..Degree] of Width bits; r[0] is the
//     position (GuardBits below the output LSB), r[i] the i-th forward difference;
//   * one tick: r[i] <- r[i] + r[i+1] (old values), additions only;
//   * the carry chain is cut into Width/ChunkWidth chunks: an update takes that
//     many cycles, each rotating every register right by ChunkWidth with the
//     chunk sum entering at the top (no chunk-select multiplexers);
//   * segment input is a ChunkWidth-bit word stream: header (K, 32 bits, in
//     ceil(32/ChunkWidth) words, least significant first),
//     then registers axis-major, r[0] first, least significant chunk first,
//     shifted into the same rotate chain;
//   * tick contract: one strobe = one tick. A tick is a cycle with tick_i high
//     after a cycle with tick_i low (a rising edge; tick_i is never sampled as
//     a level). tick_i high in two consecutive cycles violates the contract:
//     it is one tick and sets the sticky tick_err. The tick is latched; a tick
//     with no active segment raises underrun and the output holds (never
//     jumps); a tick while one is pending also sets tick_err.
`default_nettype none
`include "traj_check.svh"

module traj_fd_engine #(
  parameter int Axes       = 3,   // axes in lockstep, 1..8
  parameter int Degree     = 3,   // polynomial degree, 1..7 (Degree+1 registers per axis)
  parameter int Width      = 64,  // register width, multiple of ChunkWidth, <= 128
  parameter int ChunkWidth = 16,  // carry-chain chunk and stream word width: 16, 32 or 64
  parameter int GuardBits  = 32,  // register bits below the output LSB, 0..Width-2
  // derived, do not override
  parameter int OutWidth   = Width - GuardBits
) (
  input  logic                     clk_i,
  input  logic                     rst_ni,
  // segment word stream
  input  logic [ChunkWidth-1:0]    s_axis_tdata,
  input  logic                     s_axis_tvalid,
  output logic                     s_axis_tready,
  // servo strobe
  input  logic                     tick_i,
  // samples: axis a in sample_o[a*OutWidth +: OutWidth], two's complement
  output logic                     sample_valid_o,
  output logic [Axes*OutWidth-1:0] sample_o,
  output logic                     underrun_o,
  output logic                     seg_done_o,
  output logic                     tick_err_o
);

  localparam int Chunks     = Width / ChunkWidth;
  localparam int Regs       = Axes * (Degree + 1);
  localparam int HdrWords   = (ChunkWidth < 32) ? 32 / ChunkWidth : 1;
  localparam int Words      = HdrWords + Regs * Chunks;
  localparam int CountWidth = 32;
  localparam int WcntWidth  = $clog2(Words);
  localparam int PhaseWidth = (Chunks > 1) ? $clog2(Chunks) : 1;

  // ---------------------------------------------------------------------
  // Elaboration-time parameter checks.
  // ---------------------------------------------------------------------
  `TRAJ_PARAM_CHECK(g_bad_axes, Axes >= 1 && Axes <= 8,
                    "traj_fd_engine: Axes must be 1..8")
  `TRAJ_PARAM_CHECK(g_bad_degree, Degree >= 1 && Degree <= 7,
                    "traj_fd_engine: Degree must be 1..7")
  `TRAJ_PARAM_CHECK(g_bad_chunk, ChunkWidth == 16 || ChunkWidth == 32 || ChunkWidth == 64,
                    "traj_fd_engine: ChunkWidth must be 16, 32 or 64")
  `TRAJ_PARAM_CHECK(g_bad_width, Width >= ChunkWidth && Width <= 128 && Width % ChunkWidth == 0,
                    "traj_fd_engine: Width must be a multiple of ChunkWidth, at most 128")
  `TRAJ_PARAM_CHECK(g_bad_guard, GuardBits >= 0 && GuardBits <= Width - 2,
                    "traj_fd_engine: GuardBits must be 0..Width-2")
  `TRAJ_PARAM_CHECK(g_bad_outwidth, OutWidth == Width - GuardBits,
                    "traj_fd_engine: OutWidth is derived (Width-GuardBits); do not override it")

  // ---------------------------------------------------------------------
  // State. Datapath (reg_q, carry_q, sample_q, count_q) is not reset.
  // ---------------------------------------------------------------------
  logic [Width-1:0]      reg_q [Regs];
  logic [Regs-1:0]       carry_q;
  logic [CountWidth-1:0] count_q;
  logic                  active_q, primed_q, busy_q, last_tick_q;
  logic                  tick_q, tick_err_q;
  logic                  tick_in_q;  // tick_i of the previous cycle (edge detection)
  logic                  hdr_q;      // == (wcnt_q < HdrWords), kept as a flop for timing
  logic                  cnt_one_q;  // == (count_q == 1), kept as a flop for timing
  logic [WcntWidth-1:0]  wcnt_q;
  logic [PhaseWidth-1:0] phase_q;
  logic                  sample_valid_q, underrun_q, seg_done_q;
  logic [Axes*OutWidth-1:0] sample_q;

  // ---------------------------------------------------------------------
  // Control decode (mirrors FdEngine::clock).
  // ---------------------------------------------------------------------
  logic ready, accept, header, in_header, load_shift, wcnt_zero, consume, run, step, last_phase;
  logic count_is_one;
  logic tick_new;   // a new tick: tick_i rises
  logic tick_held;  // tick_i high for a second cycle: contract violation

  assign tick_new  = tick_i && !tick_in_q;
  assign tick_held = tick_i && tick_in_q;

  assign ready        = !active_q && !busy_q;
  assign accept       = s_axis_tvalid && ready;
  assign wcnt_zero    = (wcnt_q == '0);
  assign in_header    = hdr_q;
  assign header       = accept && in_header;
  assign load_shift   = accept && !in_header;
  assign consume      = tick_q && !busy_q && wcnt_zero && !accept;
  // == consume && active_q: an active segment implies no load in progress
  // (ready is low, so no accept, and wcnt_q is 0).
  assign run          = tick_q && active_q && !busy_q;
  assign step         = run || busy_q;
  assign count_is_one = cnt_one_q;
  if (Chunks == 1) begin : g_one_chunk
    assign last_phase = step;
  end else begin : g_chunks
    assign last_phase = busy_q && (phase_q == PhaseWidth'(Chunks - 1));
  end

  // ---------------------------------------------------------------------
  // Register chain: load shift or one chunk of the update.
  // ---------------------------------------------------------------------
  for (genvar n = 0; n < Regs; n++) begin : g_reg
    localparam int I = n % (Degree + 1);  // register index within its axis
    logic [ChunkWidth-1:0] chain_in;
    logic [ChunkWidth-1:0] top_d;
    logic                  carry_d;

    if (n == Regs - 1) begin : g_chain_top
      assign chain_in = s_axis_tdata;
    end else begin : g_chain_mid
      assign chain_in = reg_q[n+1][ChunkWidth-1:0];
    end

    if (I == Degree) begin : g_const
      // The highest difference is constant within a segment: rotate only.
      assign top_d   = reg_q[n][ChunkWidth-1:0];
      assign carry_d = 1'b0;
      /* verilator lint_off UNUSEDSIGNAL */
      logic unused_carry;  // carry_q of the constant register is never read
      assign unused_carry = carry_q[n];
      /* verilator lint_on UNUSEDSIGNAL */
    end else begin : g_acc
      logic [ChunkWidth:0] sum;
      // carry_q is 0 at the start of every update (cleared by the last
      // phase and by reset), so it enters the chain ungated.
      assign sum     = {1'b0, reg_q[n][ChunkWidth-1:0]} + {1'b0, reg_q[n+1][ChunkWidth-1:0]}
                     + {{ChunkWidth{1'b0}}, carry_q[n]};
      assign top_d   = sum[ChunkWidth-1:0];
      assign carry_d = sum[ChunkWidth];
    end

    // Rotate right by one chunk with a new top chunk (load or sum).
    logic [Width-1:0] load_d, step_d;
    if (Chunks == 1) begin : g_whole
      assign load_d = chain_in;
      assign step_d = top_d;
    end else begin : g_rotate
      assign load_d = {chain_in, reg_q[n][Width-1:ChunkWidth]};
      assign step_d = {top_d, reg_q[n][Width-1:ChunkWidth]};
    end

    always_ff @(posedge clk_i) begin
      if (load_shift) begin
        reg_q[n] <= load_d;
      end else if (step) begin
        reg_q[n] <= step_d;
      end
    end
    always_ff @(posedge clk_i) begin
      if (!rst_ni || (step && last_phase)) begin
        carry_q[n] <= 1'b0;
      end else if (step) begin
        carry_q[n] <= carry_d;
      end
    end
  end

  // ---------------------------------------------------------------------
  // Control registers.
  // ---------------------------------------------------------------------
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      active_q       <= 1'b0;
      primed_q       <= 1'b0;
      wcnt_q         <= '0;
      hdr_q          <= 1'b1;
      busy_q         <= 1'b0;
      phase_q        <= '0;
      tick_q         <= 1'b0;
      tick_in_q      <= 1'b0;
      tick_err_q     <= 1'b0;
      sample_valid_q <= 1'b0;
      underrun_q     <= 1'b0;
      seg_done_q     <= 1'b0;
    end else begin
      // Segment load.
      if (accept) begin
        if (wcnt_q == WcntWidth'(Words - 1)) begin
          wcnt_q   <= '0;
          hdr_q    <= 1'b1;
          active_q <= (count_q != '0);
        end else begin
          wcnt_q <= wcnt_q + 1'b1;
          if (wcnt_q == WcntWidth'(HdrWords - 1)) hdr_q <= 1'b0;
        end
      end
      // Update sequencing.
      if (step) begin
        if (last_phase) begin
          busy_q  <= 1'b0;
          phase_q <= '0;
          if (run ? count_is_one : last_tick_q) active_q <= 1'b0;
        end else begin
          busy_q  <= 1'b1;
          phase_q <= busy_q ? phase_q + 1'b1 : PhaseWidth'(1);
        end
      end
      // Tick handling.
      tick_in_q      <= tick_i;
      tick_q         <= (tick_q && !consume) || tick_new;
      tick_err_q     <= tick_err_q || (tick_new && tick_q && !consume) || tick_held;
      sample_valid_q <= consume && (active_q || primed_q);
      // primed: a real sample has left since reset (a K = 0 segment emits
      // none), so an underrun repeats a sample that was output, never the
      // unreset register
      primed_q       <= primed_q || run;
      underrun_q     <= consume && !active_q;
      seg_done_q     <= run && count_is_one;
    end
  end

  // Count and samples: datapath, not reset.
  logic [CountWidth-1:0] count_hdr;  // count_q after taking one header word
  if (ChunkWidth < 32) begin : g_hdr_shift
    assign count_hdr = {s_axis_tdata, count_q[CountWidth-1:ChunkWidth]};
  end else begin : g_hdr_word
    assign count_hdr = s_axis_tdata[CountWidth-1:0];
    if (ChunkWidth > 32) begin : g_hdr_unused
      /* verilator lint_off UNUSEDSIGNAL */
      logic [ChunkWidth-CountWidth-1:0] unused_hdr;  // header bits above K are reserved
      assign unused_hdr = s_axis_tdata[ChunkWidth-1:CountWidth];
      /* verilator lint_on UNUSEDSIGNAL */
    end
  end

  always_ff @(posedge clk_i) begin
    if (header) begin
      count_q   <= count_hdr;
      cnt_one_q <= (count_hdr == CountWidth'(1));
    end else if (run) begin
      count_q   <= count_q - 1'b1;
      cnt_one_q <= (count_q == CountWidth'(2));
    end
    if (run) begin
      last_tick_q <= count_is_one;
    end
  end

  for (genvar a = 0; a < Axes; a++) begin : g_out
    always_ff @(posedge clk_i) begin
      if (run) begin
        sample_q[a*OutWidth +: OutWidth] <= reg_q[a*(Degree+1)][Width-1:GuardBits];
      end
    end
  end


`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Formal properties (yosys -formal): bounded model checking from reset and
  // temporal induction, run by scripts/formal.sh (the rtl.formal.* tests).
  // ---------------------------------------------------------------------
  logic f_past_valid = 1'b0;
  logic f_cnt_valid = 1'b0;  // count_q holds a value written by a header word
  logic f_emitted = 1'b0;    // a sample of an active segment has left since reset
  always_ff @(posedge clk_i) begin
    f_past_valid <= 1'b1;
    f_emitted <= rst_ni && (f_emitted || run);
    if (!rst_ni) f_cnt_valid <= f_cnt_valid;
    if (header) f_cnt_valid <= 1'b1;
  end
  always_comb begin
    if (!f_past_valid) assume (!rst_ni);
  end
  always_ff @(posedge clk_i) begin
    if (f_past_valid) begin
      // reset clears every control output and state
      if (!$past(rst_ni)) begin
        assert (!sample_valid_q && !underrun_q && !seg_done_q && !tick_err_q);
        assert (!active_q && !busy_q && !primed_q && wcnt_q == '0 && !tick_q);
      end
      // tick_err is sticky until reset
      if ($past(rst_ni) && $past(tick_err_q)) assert (tick_err_q);
      // tick contract: one strobe = one tick. tick_i high in two consecutive
      // cycles is one tick (no second pending tick) and sets tick_err.
      if ($past(rst_ni) && $past(tick_i) && $past(tick_in_q)) begin
        assert (tick_err_q);
        assert (tick_q == ($past(tick_q) && !$past(consume)));
      end
      if ($past(rst_ni) && $past(tick_i) && !$past(tick_in_q)) assert (tick_q);
      if ($past(rst_ni)) assert (tick_in_q == $past(tick_i));
      // the output never moves except with a sample of an active segment:
      // underrun, idle, loading and reset hold it (no jump)
      if (!$past(run)) assert (sample_q == $past(sample_q));
      // a segment-done pulse comes with its sample, never with an underrun
      if (seg_done_q) assert (sample_valid_q && !underrun_q);
      if (underrun_q) assert (sample_valid_q == $past(primed_q));
      // a valid sample is one the engine has output since reset: never the
      // unreset sample register (e.g. after a K = 0 first segment)
      if (sample_valid_q) assert (f_emitted);
    end
    if (f_past_valid) begin
      // registered decodes equal what they stand for (the timing fixes)
      assert (hdr_q == (32'(wcnt_q) < 32'(HdrWords)));
      if (f_cnt_valid) assert (cnt_one_q == (count_q == CountWidth'(1)));
      // state bounds and consistency
      assert (32'(wcnt_q) < 32'(Words));
      if (Chunks > 1) assert (32'(phase_q) < 32'(Chunks));
      if (busy_q) assert (active_q);
      if (active_q) assert (wcnt_q == '0);
      if (active_q && !busy_q) assert (count_q != '0);
      assert (s_axis_tready == (!active_q && !busy_q));
      // supporting invariants (make the properties inductive)
      if (busy_q) assert (last_tick_q == (count_q == '0));
      if (active_q || primed_q || 32'(wcnt_q) >= 32'(HdrWords)) assert (f_cnt_valid);
      if (!busy_q) assert (carry_q == '0);
      assert (primed_q == f_emitted);
    end
  end
`endif

  assign s_axis_tready  = ready;
  assign sample_valid_o = sample_valid_q;
  assign sample_o       = sample_q;
  assign underrun_o     = underrun_q;
  assign seg_done_o     = seg_done_q;
  assign tick_err_o     = tick_err_q;

endmodule

`default_nettype wire
