// SPDX-License-Identifier: Apache-2.0
// trajcore: time-scale unit (feed override, feed hold, a stop on the path
// when data runs out). Mirrors hls/traj_time_scale.hpp cycle for cycle; the
// method is there and in host/timescale/README.md (the exact reference and
// the ramp bounds that keep every axis within its limits). In short, per
// servo tick (tick_i, one strobe = one tick):
//   * s = S 2^-sb, its rate k (|k| <= m_i) changes by -1, 0 or +1 and S by
//     the new k, toward the target (0 while held or starved, else the
//     override clamped to s_max_i); b = |k| (|k| - 1) / 2 is kept beside k;
//     a step takes 4 clocks, one adder or comparator deep each;
//   * unless end_i: one more tick at the target then a stop, simulated one
//     S-curve step per clock, must fit within the samples ahead
//     (sum << shift_i <= ahead), else the unit holds by itself (starved_o,
//     starved_count_o); starved, it resumes (auto_resume_i) when twice a tick
//     at the target and a stop from it fit;
//   * trajectory time phi (32.32 engine samples) += S << shift_i (the shift
//     a bit per clock, as ahead >> shift_i for the check); the engine
//     is ticked (eng_tick_o; the next strobe only after eng_valid_i) until
//     the window y0, y1 holds samples floor(phi) and floor(phi) + 1;
//   * sample_o = y0 + floor((y1 - y0) frac(phi)), 32 shift-add steps per axis.
// Contract: configuration inputs (m_i, s_max_i, override_i, shift_i,
// hold_i, auto_resume_i, end_i) are sampled when a servo tick is taken;
// avail_i (engine samples available beyond those ticked) when a servo tick
// is taken and before the window is primed; eng_sample_i with eng_valid_i.
// sample_valid_o is one strobe per servo tick taken (none before the first
// two samples are available). A servo tick while busy_o is dropped and sets
// err_o (sticky until reset); so does trajectory time passing the data ahead
// without end_i (cannot happen: the check keeps every stop within it).
// A servo tick takes at most timescale::unit_tick_clocks clocks
// (host/timescale/time_scale.hpp, from this schedule; 2^p engine ticks per
// servo tick at s = 1): 2 (shift_i + 1) + 4 (stop + 1) + (2^(p+1) + 2)
// (engine latency + 2) + 34 Axes + 10, with a stop of at most
// 3 m + (s_max + m^2) / m + 4 S-curve steps; checked on the hls model
// (time_scale_hls_test) and on the simulated board.
`default_nettype none
`include "traj_check.svh"

module traj_time_scale #(
  parameter int Axes     = 3,   // 1..8
  parameter int OutWidth = 48,  // sample width, 8..64
  parameter int SW       = 16   // width of S (s = S 2^-sb), 4..24
) (
  input  logic                     clk_i,
  input  logic                     rst_ni,
  input  logic                     tick_i,         // servo strobe
  input  logic [SW-1:0]            m_i,            // rate bound, >= 1
  input  logic [SW-1:0]            s_max_i,
  input  logic [SW-1:0]            override_i,
  input  logic [5:0]               shift_i,        // 32 - sb + p, <= 40
  input  logic                     hold_i,
  input  logic                     auto_resume_i,
  input  logic                     end_i,          // every sample of the trajectory is available
  input  logic [31:0]              avail_i,        // samples available beyond those ticked
  // engine
  output logic                     eng_tick_o,
  input  logic                     eng_valid_i,
  input  logic [Axes*OutWidth-1:0] eng_sample_i,
  // output
  output logic                     sample_valid_o,
  output logic [Axes*OutWidth-1:0] sample_o,
  output logic [SW-1:0]            s_o,
  output logic                     starved_o,
  output logic [15:0]              starved_count_o,
  output logic                     busy_o,
  output logic                     err_o
);
  `TRAJ_PARAM_CHECK(g_bad_axes, Axes >= 1 && Axes <= 8, "traj_time_scale: Axes must be 1..8")
  `TRAJ_PARAM_CHECK(g_bad_out, OutWidth >= 8 && OutWidth <= 64, "traj_time_scale: OutWidth must be 8..64")
  `TRAJ_PARAM_CHECK(g_bad_sw, SW >= 4 && SW <= 24, "traj_time_scale: SW must be 4..24")

  localparam int KW   = SW + 1;        // k, two's complement
  localparam int BW   = 2 * SW;        // b = |k| (|k| - 1) / 2
  localparam int CW   = SW + 3;        // e = target - S and e - k, two's complement
  localparam int SumW = 2 * SW + 2;    // the stop's travel (sum of S)
  localparam int LW   = 66;            // ahead, the increment: 34-bit index . 32-bit fraction
  localparam int AccW = OutWidth + 2;  // the product's accumulator, signed
  localparam int AxW  = (Axes > 1) ? $clog2(Axes) : 1;

  typedef enum logic [4:0] {
    StIdle, StPrime, StPrimeWait, StTick, StAhead, StShr, StA, StA2, StB, StC, StDecide, StShl, StPhi, StAdv,
    StAdvWait, StMulD, StMul, StMulW, StOut
  } state_e;
  // the S-curve step in flight: the stop's first, its next, the tick's own
  typedef enum logic [1:0] {MdFirst, MdLoop, MdReal} mode_e;

  // Whether S, moving at k (after the change), can land exactly e ahead: the
  // shortest stop from k covers need = |k| (|k| - 1) / 2 (ne = -e, computed
  // a stage earlier). Signs are tested
  // on the sign bits and magnitudes compared unsigned (no reliance on signed
  // semantics in functions, which tools treat differently).
  function automatic logic land(input logic [CW-1:0] e, input logic [CW-1:0] ne, input logic [KW-1:0] k,
                                input logic [BW-1:0] need);
    logic big;  // need >= 2^(CW-1) > |e|
    big = |need[BW-1:CW-1];
    if (k == '0) land = 1'b1;
    else if (big) land = 1'b0;
    else if (!k[KW-1]) land = !e[CW-1] && e >= need[CW-1:0];
    else land = (e[CW-1] || e == '0) && ne >= need[CW-1:0];
  endfunction

  // ---------------------------------------------------------------------
  // State (hls TimeScale, same names).
  // ---------------------------------------------------------------------
  state_e        st_q;
  mode_e         mode_q;
  logic          eng_tick_q, valid_q, err_q;
  logic          primed_q, fill_q, starved_q, resume_q, end_q;
  logic [SW-1:0] cur_s_q, sim_s_q, tgt_q, sim_tgt_q;
  logic [KW-1:0] cur_k_q, sim_k_q;
  logic [BW-1:0] cur_b_q, sim_b_q;
  // the step's stage registers
  logic [SW-1:0] pa_s_q;
  logic [KW-1:0] pa_k_q, pa_up_q, pa_dir_q, pb_k_q;
  logic [CW-1:0] pa_e_q, pa_eup_q, pa_ek_q, pa_neup_q, pa_nek_q;
  logic [BW-1:0] pa_b_q, pa_bu_q, pa_bd_q, pb_b_q;
  logic          pa_pos_q, pa_away_q, pa_upok_q;
  logic [SumW-1:0] sum_q;
  logic [31:0]   last_q;   // the last sample's index
  logic [LW-1:0] room_q, inc_q;
  logic          room_none_q;  // no sample ahead: room is 0
  logic [LW:0]   phisum_q;
  logic [63:0]   phi_q;
  logic [5:0]    sc_q;     // shift steps left
  logic [31:0]   w_q;      // engine sample index of y0
  logic [15:0]   cnt_q;
  logic [Axes*OutWidth-1:0] y0_q, y1_q, out_q;
  logic [AxW-1:0] ax_q;
  logic [4:0]    bit_q;
  logic signed [AccW-1:0] d_q, acc_q;

  // ---------------------------------------------------------------------
  // Combinational helpers (each one adder or comparator deep).
  // ---------------------------------------------------------------------
  logic [SW-1:0] ov, a_s, a_t;
  logic [KW-1:0] a_k, a_abs, a_dir;
  logic [BW-1:0] a_b;
  logic [CW-1:0] a_e;
  logic          a_epos;
  logic [33:0]   last_sum;
  logic [CW-1:0] b_eup, b_ek;
  logic [KW-1:0] b_nk;
  logic [BW-1:0] b_nb;
  logic [SW-1:0] c_ns;
  logic [32:0]   idx_diff;  // last - index(phi), for the time ahead
  logic          frac_nz;
  logic          phi_over;  // phisum > last << 32
  logic          phi_behind;  // last << 32 < phi
  logic [OutWidth-1:0] y0a, y1a;
  logic signed [AccW-1:0] y0s, acc_sum;

  assign ov = (override_i > s_max_i) ? s_max_i : override_i;
  // the last sample phi may reach: the last available one at the end, else
  // the one before it (the window at phi needs the sample after phi's)
  assign last_sum = {2'b00, w_q} + {33'd0, end_i} + {2'b00, avail_i};

  // stage A inputs: the curve stepped and its target
  always_comb begin
    a_s = cur_s_q;
    a_k = cur_k_q;
    a_b = cur_b_q;
    a_t = tgt_q;
    if (mode_q == MdFirst) a_t = sim_tgt_q;
    if (mode_q == MdLoop) begin
      a_s = sim_s_q;
      a_k = sim_k_q;
      a_b = sim_b_q;
      a_t = '0;
    end
  end
  assign a_e    = {{(CW - SW){1'b0}}, a_t} - {{(CW - SW){1'b0}}, a_s};
  assign a_epos = !a_e[CW-1] && (a_e != '0);
  assign a_abs  = a_k[KW-1] ? -a_k : a_k;
  assign a_dir  = a_epos ? KW'(1) : '1;  // +1 or -1

  // stage B: the choice
  assign b_eup = pa_e_q - {{(CW - KW){pa_up_q[KW-1]}}, pa_up_q};  // registered in StA2
  assign b_ek  = pa_e_q - {{(CW - KW){pa_k_q[KW-1]}}, pa_k_q};
  logic land_up, land_k;  // (outside the always_comb: Icarus takes no constant selects there)
  assign land_up = land(pa_eup_q, pa_neup_q, pa_up_q, pa_bu_q);
  assign land_k  = land(pa_ek_q, pa_nek_q, pa_k_q, pa_b_q);
  always_comb begin
    b_nk = pa_k_q;
    b_nb = pa_b_q;
    if (pa_away_q) begin
      b_nk = pa_pos_q ? pa_k_q - KW'(1) : pa_k_q + KW'(1);
      b_nb = pa_bd_q;
    end else if (pa_e_q != '0) begin
      if (pa_upok_q && land_up) begin
        b_nk = pa_up_q;
        b_nb = pa_bu_q;
      end else if (!land_k) begin
        b_nk = pa_k_q - pa_dir_q;
        b_nb = pa_bd_q;
      end
    end
  end
  // stage C: the move
  assign c_ns = pa_s_q + SW'(pb_k_q);

  assign idx_diff = {1'b0, last_q} - {1'b0, phi_q[63:32]} - 33'(phi_q[31:0] != '0);
  assign frac_nz  = phi_q[31:0] != '0;
  assign phi_over = (phisum_q[LW:32] > {3'b000, last_q}) ||
                    (phisum_q[LW:32] == {3'b000, last_q} && phisum_q[31:0] != '0);
  assign phi_behind = (phi_q[63:32] > last_q) || (phi_q[63:32] == last_q && phi_q[31:0] != '0);

  // the axis in work is always at the bottom of the window registers: they
  // rotate by one axis after each axis's output (no axis multiplexer)
  assign y0a     = y0_q[OutWidth-1:0];
  assign y1a     = y1_q[OutWidth-1:0];
  assign y0s     = $signed({{(AccW - OutWidth){y0a[OutWidth-1]}}, y0a});
  assign acc_sum = acc_q + (phi_q[{1'b0, bit_q}] ? d_q : '0);

  // ---------------------------------------------------------------------
  // The FSM (hls TimeScale::clock).
  // ---------------------------------------------------------------------
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      st_q       <= StIdle;
      mode_q     <= MdReal;
      eng_tick_q <= 1'b0;
      valid_q    <= 1'b0;
      err_q      <= 1'b0;
      primed_q   <= 1'b0;
      fill_q     <= 1'b0;
      starved_q  <= 1'b0;
      resume_q   <= 1'b0;
      end_q      <= 1'b0;
      cur_s_q    <= '0;
      cur_k_q    <= '0;
      cur_b_q    <= '0;
      phi_q      <= '0;
      w_q        <= '0;
      cnt_q      <= '0;
    end else begin
      eng_tick_q <= 1'b0;
      valid_q    <= 1'b0;
      if (tick_i && st_q != StIdle) err_q <= 1'b1;
      case (st_q)
        StIdle: begin
          if (tick_i) begin
            if (primed_q) st_q <= StTick;
            else if (avail_i >= 32'd2) st_q <= StPrime;
          end
        end
        StPrime: begin
          eng_tick_q <= 1'b1;
          st_q       <= StPrimeWait;
        end
        StPrimeWait: begin
          if (eng_valid_i) begin
            fill_q <= !fill_q;
            if (!fill_q) begin
              st_q <= StPrime;
            end else begin
              primed_q <= 1'b1;
              st_q     <= StTick;
            end
          end
        end
        StTick: begin
          end_q  <= end_i;
          // the last sample's index, saturated at 2^32 - 1 (the index is 32
          // bits: 2^32 engine ticks a program, 24 hours at 20 us)
          last_q <= (last_sum > 34'hFFFF_FFFF) ? 32'hFFFF_FFFF : last_sum[31:0];
          sc_q   <= shift_i;
          tgt_q  <= (hold_i || (starved_q && !end_i)) ? '0 : ov;
          mode_q <= MdReal;
          if (end_i) begin
            st_q <= StA;
          end else if (!starved_q) begin
            resume_q  <= 1'b0;
            sim_tgt_q <= hold_i ? '0 : ov;
            st_q      <= StAhead;
          end else if (auto_resume_i && !hold_i) begin
            resume_q  <= 1'b1;
            sim_tgt_q <= ov;
            // twice a tick at the target and a stop from it (S = target,
            // k = 0: the stop's start below)
            sum_q     <= SumW'(ov);
            st_q      <= StAhead;
          end else begin
            st_q <= StA;
          end
        end
        StAhead: begin
          // (last << 32) - phi, or 0: index and fraction apart
          // (0 when the last sample is not ahead: room_none_q, a comparison
          // beside the subtraction, applied where room is used)
          room_q      <= {1'b0, idx_diff, frac_nz ? 32'(-phi_q[31:0]) : 32'd0};
          room_none_q <= last_q <= phi_q[63:32];
          st_q <= StShr;
        end
        StShr: begin
          if (sc_q == '0) begin
            mode_q <= resume_q ? MdLoop : MdFirst;
            st_q   <= StA;
          end else begin
            room_q <= room_q >> 1;
            sc_q   <= sc_q - 6'd1;
          end
        end
        StA: st_q <= StA2;
        StA2: st_q <= StB;
        StB: st_q <= StC;
        StC: begin
          if (mode_q == MdReal) begin
            cur_s_q <= c_ns;
            cur_k_q <= pb_k_q;
            cur_b_q <= pb_b_q;
            inc_q   <= LW'(c_ns);
            sc_q    <= shift_i;
            st_q    <= StShl;
          end else begin
            sum_q  <= ((mode_q == MdFirst) ? '0 : sum_q) + SumW'(c_ns);
            mode_q <= MdLoop;
            st_q   <= (c_ns == '0 && pb_k_q == '0) ? StDecide : StA;  // the stop ends at rest
          end
        end
        StDecide: begin
          // sum << shift > ahead  <=>  sum > floor(ahead / 2^shift)
          if (!resume_q) begin
            if (room_none_q || (room_q[LW-1:SumW] == '0 && sum_q > room_q[SumW-1:0])) begin
              starved_q <= 1'b1;
              cnt_q     <= cnt_q + 16'd1;
              tgt_q     <= '0;
            end
          end else if (!room_none_q && (room_q[LW-1:SumW+1] != '0 || sum_q <= room_q[SumW:1])) begin  // twice fits
            starved_q <= 1'b0;
            tgt_q     <= ov;
          end
          mode_q <= MdReal;
          st_q   <= StA;
        end
        StShl: begin
          if (sc_q == '0) begin
            phisum_q <= {3'b000, phi_q} + {1'b0, inc_q};
            st_q     <= StPhi;
          end else begin
            inc_q <= inc_q << 1;
            sc_q  <= sc_q - 6'd1;
          end
        end
        StPhi: begin
          if (phi_over) begin
            // at the trajectory's end; without end_i it cannot happen (the
            // check keeps every stop within the data): err_o. Never back
            // (a last sample behind phi: only after end_i fell, which the
            // contract excludes while a job plays)
            if (!phi_behind) phi_q <= {last_q, 32'd0};
            if (!end_q) err_q <= 1'b1;
          end else begin
            phi_q <= phisum_q[63:0];
          end
          st_q <= StAdv;
        end
        StAdv: begin
          if (w_q < phi_q[63:32]) begin
            eng_tick_q <= 1'b1;
            st_q       <= StAdvWait;
          end else begin
            st_q <= StMulD;
          end
        end
        StAdvWait: begin
          if (eng_valid_i) begin
            w_q  <= w_q + 32'd1;
            st_q <= StAdv;
          end
        end
        StMulD: st_q <= StMul;
        StMul: if (bit_q == 5'd31) st_q <= StMulW;
        StMulW: st_q <= (32'(ax_q) == Axes - 1) ? StOut : StMulD;
        StOut: begin
          valid_q <= 1'b1;
          st_q    <= StIdle;
        end
        default: st_q <= StIdle;
      endcase
    end
  end

  // Datapath (not reset): the step's stages, the stop's curve, the window,
  // the product, the output.
  always_ff @(posedge clk_i) begin
    if (st_q == StA) begin
      pa_s_q    <= a_s;
      pa_k_q    <= a_k;
      pa_b_q    <= a_b;
      pa_e_q    <= a_e;
      pa_pos_q  <= !a_k[KW-1] && (a_k != '0);
      pa_away_q <= (a_k != '0) && ((a_e == '0) || (a_epos != (!a_k[KW-1] && (a_k != '0))));
      pa_dir_q  <= a_dir;
      pa_up_q   <= a_k + a_dir;
      pa_bu_q   <= a_b + BW'(a_abs);
      pa_bd_q   <= a_b - BW'(a_abs) + BW'(1);
      pa_upok_q <= {1'b0, a_abs} + 1'b1 <= {1'b0, KW'(m_i)};
    end
    if (st_q == StA2) begin
      pa_eup_q  <= b_eup;
      pa_ek_q   <= b_ek;
      pa_neup_q <= {{(CW - KW){pa_up_q[KW-1]}}, pa_up_q} - pa_e_q;  // -(e - up)
      pa_nek_q  <= {{(CW - KW){pa_k_q[KW-1]}}, pa_k_q} - pa_e_q;
    end
    if (st_q == StB) begin
      pb_k_q <= b_nk;
      pb_b_q <= b_nb;
    end
    if (st_q == StC && mode_q != MdReal) begin
      sim_s_q <= c_ns;
      sim_k_q <= pb_k_q;
      sim_b_q <= pb_b_q;
    end else if (st_q == StTick && !end_i && starved_q && auto_resume_i && !hold_i) begin
      sim_s_q <= ov;  // the resume check's stop starts at the target, at rest in k
      sim_k_q <= '0;
      sim_b_q <= '0;
    end
    if (st_q == StAdv) ax_q <= '0;
    if (st_q == StMulD) begin
      d_q   <= $signed({{(AccW - OutWidth){y1a[OutWidth-1]}}, y1a}) - y0s;
      acc_q <= '0;
      bit_q <= '0;
    end
    if (st_q == StMul) begin
      acc_q <= acc_sum >>> 1;  // floor
      if (bit_q != 5'd31) bit_q <= bit_q + 5'd1;
    end
    if (st_q == StMulW && 32'(ax_q) != Axes - 1) ax_q <= ax_q + 1'b1;
  end

  // The window takes the engine's samples; at each axis's output it rotates
  // by one axis, and the output shifts the axis's sample in at the top.
  logic [OutWidth-1:0] mul_out;
  logic                take;
  assign mul_out = OutWidth'(y0s + acc_q);
  assign take    = (st_q == StPrimeWait || st_q == StAdvWait) && eng_valid_i;
  if (Axes == 1) begin : g_one_axis
    always_ff @(posedge clk_i) begin
      if (take) begin
        y0_q <= y1_q;
        y1_q <= eng_sample_i;
      end
      if (st_q == StMulW) out_q <= mul_out;
    end
  end else begin : g_rotate
    always_ff @(posedge clk_i) begin
      if (take) begin
        y0_q <= y1_q;
        y1_q <= eng_sample_i;
      end else if (st_q == StMulW) begin
        y0_q <= {y0_q[OutWidth-1:0], y0_q[Axes*OutWidth-1:OutWidth]};
        y1_q <= {y1_q[OutWidth-1:0], y1_q[Axes*OutWidth-1:OutWidth]};
      end
      if (st_q == StMulW) out_q <= {mul_out, out_q[Axes*OutWidth-1:OutWidth]};
    end
  end

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Formal properties (scripts/formal.sh: BMC from reset and induction).
  // ---------------------------------------------------------------------
  logic f_past_valid = 1'b0;
  logic signed [KW:0] f_k, f_kp, f_m;
  logic [SW-1:0] f_m_q;
  always_ff @(posedge clk_i) begin
    f_past_valid <= 1'b1;
    f_kp         <= f_k;
    f_m_q        <= m_i;
  end
  // the configuration is held while running; shift_i within its contract
  always_comb begin
    if (!f_past_valid) assume (!rst_ni);
    assume (m_i != '0);
    assume (shift_i <= 6'd40);
    if (f_past_valid) assume (m_i == f_m_q);
  end
  assign f_k = $signed({cur_k_q[KW-1], cur_k_q});
  assign f_m = $signed({1'b0, KW'(m_i)});
  always_ff @(posedge clk_i) begin
    if (f_past_valid) begin
      if (!$past(rst_ni)) begin
        assert (st_q == StIdle && !eng_tick_q && !valid_q && !err_q && !primed_q && !starved_q);
        assert (cur_s_q == '0 && cur_k_q == '0 && phi_q == '0 && w_q == '0 && cnt_q == '0);
      end else begin
        // err_o is sticky; a servo tick while busy sets it
        if ($past(err_q)) assert (err_q);
        if ($past(tick_i) && $past(st_q) != StIdle) assert (err_q);
        // S and k move only at the end of a step of the tick's own, k by at
        // most one; phi only after the shift that follows it
        if (!($past(st_q) == StC && $past(mode_q) == MdReal)) assert (cur_s_q == $past(cur_s_q) && cur_k_q == $past(cur_k_q));
        if ($past(st_q) == StC) assert (f_k - f_kp <= 1 && f_kp - f_k <= 1);
        if ($past(st_q) != StPhi) assert (phi_q == $past(phi_q));
        // trajectory time never moves back (below the index's top: a program
        // of 2^32 - 1 engine samples is the unit's limit)
        if ($past(st_q) == StPhi && $past(w_q) != '1) assert (phi_q >= $past(phi_q));
        // supporting invariants: the window is at phi's index outside the
        // advance
        if (st_q != StAdv && st_q != StAdvWait && w_q != '1) assert (w_q == phi_q[63:32]);
        if (st_q == StAdv && w_q != '1) assert (w_q <= phi_q[63:32]);
        if (st_q == StAdvWait && w_q != '1) assert (w_q < phi_q[63:32]);
        // from the tick on, the last sample phi may reach is not behind it;
        // the sum is phi plus the increment
        if ((st_q == StAhead || st_q == StShr || st_q == StA || st_q == StB || st_q == StC ||
             st_q == StDecide || st_q == StShl || st_q == StPhi) && w_q != '1)
          assert (last_q >= phi_q[63:32]);
        if (st_q == StPhi) assert (phisum_q >= {3'b000, phi_q});
      end
      // |k| <= m (m held): the step never exceeds it (the stage registers
      // hold a curve within it too)
      assert (f_k <= f_m && -f_k <= f_m);
      if (st_q == StA2 || st_q == StB || st_q == StC) begin
        assert ($signed({pa_k_q[KW-1], pa_k_q}) <= f_m && -$signed({pa_k_q[KW-1], pa_k_q}) <= f_m);
        assert (pa_dir_q == KW'(1) || pa_dir_q == '1);
        assert (pa_upok_q == ((pa_k_q[KW-1] ? -pa_k_q : pa_k_q) + 1'b1 <= KW'(m_i)));
        assert (pa_up_q == pa_k_q + pa_dir_q);
        assert (pa_pos_q == (!pa_k_q[KW-1] && pa_k_q != '0));
        assert (!pa_away_q || pa_k_q != '0);
      end
      if (st_q == StC) assert ($signed({pb_k_q[KW-1], pb_k_q}) <= f_m && -$signed({pb_k_q[KW-1], pb_k_q}) <= f_m);
      // the simulated stop's rate too: from a step, or 0 for the resume check
      if (resume_q && (st_q == StAhead || st_q == StShr)) assert (sim_k_q == '0);
      if (st_q == StA && mode_q == MdLoop)
        assert ($signed({sim_k_q[KW-1], sim_k_q}) <= f_m && -$signed({sim_k_q[KW-1], sim_k_q}) <= f_m);
      if (st_q == StC && mode_q == MdReal) assert (pa_k_q == cur_k_q);
      // strobes: one cycle each; an engine tick only into a wait state that
      // holds until the engine's answer (one tick outstanding at most)
      if (eng_tick_q) assert (st_q == StPrimeWait || st_q == StAdvWait);
      if (valid_q) assert (st_q == StIdle);
      if ($past(rst_ni) && $past(eng_tick_q)) assert (!eng_tick_q);
      if ($past(rst_ni) && $past(valid_q)) assert (!valid_q);
      if ($past(rst_ni) && valid_q) assert ($past(st_q) == StOut);
      assert (mode_q != 2'd3);
    end
  end
`endif

  assign eng_tick_o      = eng_tick_q;
  assign sample_valid_o  = valid_q;
  assign sample_o        = out_q;
  assign s_o             = cur_s_q;
  assign starved_o       = starved_q;
  assign starved_count_o = cnt_q;
  assign busy_o          = st_q != StIdle;
  assign err_o           = err_q;
endmodule

`default_nettype wire
