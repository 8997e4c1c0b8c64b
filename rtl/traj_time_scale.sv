// SPDX-License-Identifier: Apache-2.0
// trajcore: time-scale unit (feed override, feed hold, a stop on the path
// when data runs out). Mirrors hls/traj_time_scale.hpp cycle for cycle; the
// method is there and in host/timescale/README.md (the exact reference and
// the ramp bounds that keep every axis within its limits). The datapath is
// narrow so that the unit fits beside the board logic: the S-curve's
// registers in flops, everything wide a bit per clock, the samples in block
// RAM. Per servo tick (tick_i, one strobe = one tick):
//   * s = S 2^-sb, its rate k (|k| <= m_i) changes by -1, 0 or +1 and S by
//     the new k, toward the target (0 while held or starved, else the
//     override clamped to s_max_i). k is a sign and a magnitude c, kept
//     beside x = c (c + 1) / 2: with a = |target - S|, moving toward the
//     target it goes up if c < m and a >= x + c + 1, holds if c = 0 or
//     a >= x, else goes down; moving away (or on the target) it goes down. A
//     step takes 4 clocks (a and c < m; the comparisons and the choice; c
//     and x; S), on the work copy (ws, wc, wks, wx) of the real curve (cs,
//     cc, cks, cx);
//   * unless end_i: one more tick at the target then a stop, simulated one
//     step per 4 clocks, must fit within the samples ahead, else the unit
//     holds by itself (starved_o, starved_count_o); starved, it resumes
//     (auto_resume_i) when twice a tick at the target and a stop from it
//     fit. "Fits": X 2^sh + frac <= av 2^32 (X the stop's travel, sh the
//     shift or one more; av the samples ahead), compared bit-serially, LSB
//     first, in NCmp = max(2 SW + 45, 65) clocks;
//   * trajectory time is kept as its fraction (frac, 32 bits; the window is
//     at its integer part): frac + S 2^shift is compared with
//     (av + end) 2^32 (past it: only at the end, clamped there), then
//     written back bit-serially: the fraction into frac, the integer part
//     (the engine ticks to do) into av;
//   * the engine is ticked (eng_tick_o; the next strobe only after
//     eng_valid_i) av times, av decremented bit-serially; before the last
//     tick its sample is copied a bit per clock into y0 (two 1-bit RAMs, y0a
//     and y0b); the sample after it (y1) stays in the engine's sample RAM,
//     read through its word port (eng_addr_o; eng_word_i is the word at the
//     address of the clock before);
//   * per axis y0 + floor((y1 - y0) frac / 2^32), a bit per clock in a
//     pipeline of three (the reads; a serial subtractor gives the
//     difference's bit, the bit of weight -2^OutWidth last; the product):
//     the difference's bits times the parallel frac (acc = (acc +/- d_j
//     frac) >> 1, product bit j out), and the product's bits 32 and up plus
//     y0's bits (a serial adder) go into the output RAM (rout).
//   * The output is presented at the next servo tick: rout shifted into
//     sample_o a bit per clock (Axes*OutWidth + 1 clocks), then
//     sample_valid_o (one strobe; none for the first servo tick taken).
//     out_shift_o / out_bit_o are that shift (sample_o takes
//     {out_bit_o, sample_o[N-1:1]} in a clock with out_shift_o high): a
//     register outside built from them follows sample_o exactly (traj_board
//     shares one with the engine's output).
// Contract: m_i, s_max_i and shift_i are held while running; override_i,
// hold_i, auto_resume_i, end_i and avail_i (engine samples available beyond
// those ticked) are sampled when a servo tick is taken (after the window is
// primed, at the first one); eng_word_i holds the engine's sample from
// eng_valid_i until the next eng_tick_o. A servo tick while busy_o is
// dropped and sets err_o (sticky until reset); so does trajectory time
// passing the data ahead without end_i (cannot happen: the check keeps every
// stop within it). A servo tick's work takes less than
// timescale::unit_tick_clocks clocks (host/timescale/time_scale.hpp, from
// this schedule; checked on the hls model and on the simulated board).
`default_nettype none
`include "traj_check.svh"

module traj_time_scale #(
  parameter int Axes      = 3,   // 1..8
  parameter int OutWidth  = 48,  // sample width, 8..64
  parameter int SW        = 16,  // width of S (s = S 2^-sb), 4..24
  parameter int WordWidth = 16,  // the engine's sample RAM word: 8, 16 or 32, divides OutWidth
  parameter int UseDsp    = 0,   // 1: two adders (sum + S, the product's) in SB_MAC16 blocks (iCE40 UP5K; traj_add)
  // derived, do not override
  parameter int EngAddrWidth = ($clog2(Axes) + $clog2(OutWidth / WordWidth) > 0) ?
                               $clog2(Axes) + $clog2(OutWidth / WordWidth) : 1
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
  // engine: its tick, its answer, its sample RAM read port ({axis, word})
  output logic                     eng_tick_o,
  input  logic                     eng_valid_i,
  output logic [EngAddrWidth-1:0]  eng_addr_o,
  input  logic [WordWidth-1:0]     eng_word_i,
  // output
  output logic                     sample_valid_o,
  output logic [Axes*OutWidth-1:0] sample_o,
  output logic                     out_shift_o,    // sample_o's shift (above)
  output logic                     out_bit_o,
  output logic [SW-1:0]            s_o,
  output logic                     starved_o,
  output logic [15:0]              starved_count_o,
  output logic                     busy_o,
  output logic                     err_o
);
  `TRAJ_PARAM_CHECK(g_bad_axes, Axes >= 1 && Axes <= 8, "traj_time_scale: Axes must be 1..8")
  `TRAJ_PARAM_CHECK(g_bad_out, OutWidth >= 8 && OutWidth <= 64, "traj_time_scale: OutWidth must be 8..64")
  `TRAJ_PARAM_CHECK(g_bad_sw, SW >= 4 && SW <= 24, "traj_time_scale: SW must be 4..24")
  `TRAJ_PARAM_CHECK(g_bad_dsp, UseDsp == 0 || UseDsp == 1, "traj_time_scale: UseDsp must be 0 or 1")
  `TRAJ_PARAM_CHECK(g_bad_word, (WordWidth == 8 || WordWidth == 16 || WordWidth == 32) && OutWidth % WordWidth == 0,
                    "traj_time_scale: WordWidth must be 8, 16 or 32 and divide OutWidth")
  `TRAJ_PARAM_CHECK(g_bad_eaddr, EngAddrWidth == (($clog2(Axes) + $clog2(OutWidth / WordWidth) > 0) ?
                                                  $clog2(Axes) + $clog2(OutWidth / WordWidth) : 1),
                    "traj_time_scale: EngAddrWidth is derived; do not override it")

  localparam int XW    = 2 * SW - 1;   // x = c (c + 1) / 2, c < 2^SW
  localparam int SumW  = 2 * SW + 3;   // the stop's travel: (stop + 1) S values
  localparam int AW    = 33;           // av: avail (+ end), the engine ticks to do
  localparam int NCmp  = (SumW + 42 > 65) ? SumW + 42 : 65;  // serial pass: X 2^41 + frac, (av + 1) 2^32
  localparam int NMul  = 32 + OutWidth;  // product bits to the output's top bit
  localparam int NDec  = AW;
  localparam int N     = Axes * OutWidth;
  localparam int BB    = $clog2(OutWidth);
  localparam int AxB   = $clog2(Axes);
  localparam int AxW   = (AxB > 0) ? AxB : 1;
  localparam int RamAW = AxB + BB;
  localparam int WB    = $clog2(OutWidth / WordWidth);
  localparam int WBit  = $clog2(WordWidth);

  typedef enum logic [4:0] {
    StIdle, StPrime, StPrimeWait, StCopy, StLatch, StReadout, StPlan, StS1, StS2, StS3, StS4, StCommit, StPass,
    StPassEnd, StAdv, StDec, StAdvTick, StAdvWait, StMul
  } state_e;
  typedef enum logic [1:0] {MdFirst, MdLoop, MdReal} mode_e;       // the check's first step, its stop's, the tick's own
  typedef enum logic [1:0] {PkCheck, PkPhiCmp, PkPhiApply} pass_e;

  // ---------------------------------------------------------------------
  // State (hls TimeScale, same names).
  // ---------------------------------------------------------------------
  state_e          st_q;
  logic            eng_tick_q, valid_q, err_q;
  logic            primed_q, fill_q, have_q, starved_q;
  logic [15:0]     cnt_q;
  // the tick's configuration
  logic            end_q, hold_q, aut_q;
  logic [SW-1:0]   ov_q;
  // the S-curve: the real one, the work copy, the step's stage registers
  logic [SW-1:0]   cs_q, cc_q;
  logic [XW-1:0]   cx_q;
  logic            cks_q;
  logic [SW-1:0]   ws_q, wc_q;
  logic [XW-1:0]   wx_q;
  logic            wks_q;
  mode_e           mode_q;
  logic            tz_q, resume_q, pend_q;
  logic [SW-1:0]   a_q;
  logic [SW:0]     y_q;
  logic            es_q, ez_q, upok_q, up_q, dn_q;
  logic [SumW-1:0] sum_q;
  // trajectory time and the serial passes
  logic [31:0]     frac_q;
  logic [AW-1:0]   av_q;
  pass_e           pk_q;
  logic [6:0]      i_q;
  logic [5:0]      dl_q;
  logic            c1_q, c2_q, gt_q, zacc_q, fnz_q, snz_q;
  logic            za_q, extra_q;
  // walks over the samples, the product
  logic [AxW-1:0]  ax_q, pax_q;
  logic [6:0]      j_q;
  logic            pv_q, fin_q;
  logic signed [32:0] acc_q;
  logic            bor_q, oc_q, dq_q, sg_q, dv_q;
  logic [6:0]      jd_q;
  logic [N-1:0]    out_q;
  logic            out_shift;  // out_q takes rout_q from the top
  // RAMs (1 bit wide, {axis, bit}) and their registered read ports
  logic            y0a_q, y0b_q, rout_q;

  // ---------------------------------------------------------------------
  // Combinational helpers.
  // ---------------------------------------------------------------------
  assign out_shift = st_q == StReadout && pv_q;
  // the sample bit of this clock's walk or product index, clamped to the
  // top bit (sign extension)
  logic [BB-1:0]   cbit;
  assign cbit = (i_q < 7'(OutWidth)) ? i_q[BB-1:0] : BB'(OutWidth - 1);
  logic [RamAW-1:0] ra, rb, ro;
  assign ra = RamAW'({ax_q, cbit});
  assign rb = RamAW'({ax_q, BB'(i_q - 7'd33)});  // for jd_q = i_q - 2
  assign ro = RamAW'({ax_q, i_q[BB-1:0]});
  if (WB > 0) begin : g_eaddr_words
    assign eng_addr_o = EngAddrWidth'({ax_q, cbit[BB-1:WBit]});
  end else begin : g_eaddr_axis
    assign eng_addr_o = EngAddrWidth'(ax_q);
  end

  // S-curve step: S1 (a = |t - S|, c < m), S2 (the comparisons on x),
  // S3 (x +/- , c +/- 1), S4 (S +/- c)
  logic [SW-1:0]   tgt, s1_d2;
  logic [SW:0]     s1_d1;
  assign tgt   = (mode_q == MdLoop || tz_q) ? '0 : ov_q;
  assign s1_d1 = {1'b0, tgt} - {1'b0, ws_q};  // t - S (its sign: S above the target)
  assign s1_d2 = ws_q - tgt;
  // x + c + 1 (S2: the comparison; S3: up), or x - c (S3: down); XW + 1
  // bits (x + c + 1 reaches 2^XW at c = 2^SW - 1). The choice is registered
  // in S2, so that S3's adder mode is a flop.
  logic            xsub;
  logic [XW:0]     xa;
  assign xsub = dn_q;  // set in S2 for S3 only
  assign xa   = {1'b0, wx_q} + (xsub ? ~{1'b0, XW'(wc_q)} : {1'b0, XW'(wc_q)}) + 1'b1;
  // a >= x and a >= x + c + 1 (a < 2^SW): x's top bits 0, then a compare of
  // the low bits (x + c + 1's low bits and their carry out: y_q, from S1,
  // where the adder adds; xa[SW] is that carry when x's top bits are 0)
  logic            xhz, s2_lk, s2_lu, s2_away, s2_up, s2_dn;
  assign xhz     = wx_q[XW-1:SW] == '0;
  assign s2_lk   = wc_q == '0 || (xhz && a_q >= wx_q[SW-1:0]);
  assign s2_lu   = xhz && !y_q[SW] && a_q >= y_q[SW-1:0];
  assign s2_away = wc_q != '0 && (ez_q || es_q != wks_q);
  assign s2_up   = !s2_away && !ez_q && upok_q && s2_lu;
  assign s2_dn   = s2_away || (!ez_q && !s2_up && !s2_lk);

  // the stop's travel + S (S1), or S alone (the move's X: the commit, the
  // apply pass; sum is 0 there, after the plan or a pass)
  logic [SumW-1:0] sadd;
  traj_add #(.Width(SumW), .UseDsp(UseDsp)) u_sadd (
    .clk_i, .be_i(1'b0), .a_i(sum_q), .b_i(SumW'(ws_q)), .ci_i(1'b0), .sum_o(sadd)
  );

  // serial pass: the bits of X 2^sh + frac (l) and (av + cin) 2^32 (r)
  logic            xb, in_f, in_a, fb, ab, pl, pr, apply, na;
  assign xb    = dl_q == '0 && sum_q[0];
  assign in_f  = i_q < 7'd32;
  assign in_a  = i_q >= 7'd32 && i_q < 7'(32 + AW);
  assign fb    = in_f && frac_q[0];
  assign ab    = in_a && av_q[0];
  assign pl    = xb ^ fb ^ c1_q;
  assign pr    = i_q >= 7'd32 && (ab ^ c2_q);
  assign apply = pk_q == PkPhiApply;
  assign na    = apply ? pl : ab;
  // decrement of av: bit, next zero accumulation
  logic            db, dzacc;
  assign db    = av_q[0] ^ c1_q;
  assign dzacc = zacc_q || db;

  // product, a pipeline of three: the reads of bit i (counter i_q); the
  // difference's bit j_q (serial subtractor, into dq_q); the product with
  // dq_q (acc +/- d frac), its bit jd_q, and the output bit jd_q - 32
  logic [WBit-1:0] jw;  // the bit of j_q (clamped to the sign) in its word
  logic            y1b, dj, pb;
  logic signed [33:0] mt;
  assign jw  = (j_q < 7'(OutWidth)) ? j_q[WBit-1:0] : WBit'(OutWidth - 1);
  assign y1b = eng_word_i[jw];
  assign dj  = j_q <= 7'(OutWidth) && (y1b ^ y0a_q ^ bor_q);
  // acc + d frac, or acc - frac at the sign bit: frac's bits inverted and a
  // carry in (one adder)
  logic            msub;
  assign msub = dq_q && sg_q;
  traj_add #(.Width(34), .CarryIn(1), .UseDsp(UseDsp)) u_mt (
    .clk_i, .be_i(1'b0),
    .a_i({acc_q[32], acc_q}), .b_i({2'b00, dq_q ? frac_q : 32'd0} ^ {34{msub}}), .ci_i(msub), .sum_o(mt)
  );
  assign pb   = mt[0];
  logic            ob;
  assign ob = y0b_q ^ pb ^ oc_q;

  // walk (copy, readout): the last clock, and the next address
  logic            walk_end;
  assign walk_end = fin_q;

  // ---------------------------------------------------------------------
  // Control (reset): the FSM, flags, the real curve, frac, the count.
  // ---------------------------------------------------------------------
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      st_q       <= StIdle;
      eng_tick_q <= 1'b0;
      valid_q    <= 1'b0;
      err_q      <= 1'b0;
      primed_q   <= 1'b0;
      fill_q     <= 1'b0;
      have_q     <= 1'b0;
      starved_q  <= 1'b0;
      cs_q       <= '0;
      cc_q       <= '0;
      cks_q      <= 1'b0;
      cx_q       <= '0;
      frac_q     <= '0;
      cnt_q      <= '0;
    end else begin
      eng_tick_q <= 1'b0;
      valid_q    <= 1'b0;
      if (tick_i && st_q != StIdle) err_q <= 1'b1;
      case (st_q)
        StIdle: begin
          if (tick_i) begin
            if (primed_q) st_q <= StLatch;
            else if (avail_i[31:1] != '0) st_q <= StPrime;  // two samples to prime the window
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
              st_q <= StCopy;
            end else begin
              primed_q <= 1'b1;
              st_q     <= StLatch;
            end
          end
        end
        StCopy: if (walk_end) st_q <= primed_q ? StAdvTick : StPrime;
        StLatch: st_q <= have_q ? StReadout : StPlan;
        StReadout: begin
          if (walk_end) begin
            valid_q <= 1'b1;
            st_q    <= StPlan;
          end
        end
        StPlan: st_q <= StS1;
        StS1: st_q <= (pend_q && ws_q == '0 && wc_q == '0) ? StPass : StS2;
        StS2: st_q <= StS3;
        StS3: st_q <= StS4;
        StS4: st_q <= (mode_q == MdReal) ? StCommit : StS1;
        StCommit: begin
          cs_q  <= ws_q;
          cc_q  <= wc_q;
          cks_q <= wks_q;
          cx_q  <= wx_q;
          st_q  <= StPass;
        end
        StPass: begin
          if (in_f) frac_q <= {apply ? pl : fb, frac_q[31:1]};
          if (i_q == 7'(NCmp - 1)) st_q <= StPassEnd;
        end
        StPassEnd: begin
          case (pk_q)
            PkCheck: begin
              if (!resume_q && (!zacc_q ? snz_q : gt_q)) begin  // a stop from the next tick would pass the data
                starved_q <= 1'b1;
                cnt_q     <= cnt_q + 16'd1;
              end else if (resume_q && (!zacc_q ? !snz_q : !gt_q)) begin  // twice fits
                starved_q <= 1'b0;
              end
              st_q <= StS1;
            end
            PkPhiCmp: begin
              if (gt_q) begin
                // at the trajectory's end (without end_i it cannot happen);
                // never back (a last sample behind phi: after end_i fell)
                if (!end_q) err_q <= 1'b1;
                if (!(!zacc_q && !end_q && fnz_q)) frac_q <= '0;
                st_q <= StAdv;
              end else begin
                st_q <= StPass;
              end
            end
            default: st_q <= StAdv;
          endcase
        end
        StAdv: begin
          if (za_q) st_q <= extra_q ? StCopy : StMul;
          else st_q <= StDec;
        end
        StDec: begin
          if (i_q == 7'(NDec - 1)) st_q <= (!dzacc && !extra_q) ? StCopy : StAdvTick;
        end
        StAdvTick: begin
          eng_tick_q <= 1'b1;
          st_q       <= StAdvWait;
        end
        StAdvWait: if (eng_valid_i) st_q <= StAdv;
        StMul: begin
          if (fin_q && !pv_q && 32'(ax_q) == Axes - 1) begin
            have_q <= 1'b1;
            st_q   <= StIdle;
          end
        end
        default: st_q <= StIdle;
      endcase
    end
  end

  // ---------------------------------------------------------------------
  // Datapath (not reset): the configuration, the work curve and its stages,
  // the passes, the walks, the product, the output.
  // ---------------------------------------------------------------------
  always_ff @(posedge clk_i) begin
    case (st_q)
      StPrimeWait: begin
        if (eng_valid_i && !fill_q) begin
          ax_q  <= '0;
          i_q   <= '0;
          pv_q  <= 1'b0;
          fin_q <= 1'b0;
        end
      end
      StCopy, StReadout: begin
        if (out_shift) out_q <= {rout_q, out_q[N-1:1]};
        if (fin_q) begin
          pv_q <= 1'b0;
        end else begin
          pv_q  <= 1'b1;
          pax_q <= ax_q;
          j_q   <= i_q;
          if (i_q == 7'(OutWidth - 1)) begin
            i_q <= '0;
            if (32'(ax_q) == Axes - 1) fin_q <= 1'b1;
            else ax_q <= ax_q + 1'b1;
          end else begin
            i_q <= i_q + 7'd1;
          end
        end
      end
      StLatch: begin
        end_q  <= end_i;
        hold_q <= hold_i;
        aut_q  <= auto_resume_i;
        ov_q   <= (override_i > s_max_i) ? s_max_i : override_i;
        av_q   <= {1'b0, avail_i};
        ax_q   <= '0;
        i_q    <= '0;
        pv_q   <= 1'b0;
        fin_q  <= 1'b0;
      end
      StPlan: begin
        tz_q   <= hold_q || (starved_q && !end_q);
        pend_q <= 1'b0;
        sum_q  <= '0;  // (a serial pass also leaves it 0: the commit adds S to it)
        if (!end_q && !starved_q) begin
          resume_q <= 1'b0;
          ws_q     <= cs_q;
          wc_q     <= cc_q;
          wks_q    <= cks_q;
          wx_q     <= cx_q;
          mode_q   <= MdFirst;
        end else if (!end_q && aut_q && !hold_q) begin
          resume_q <= 1'b1;
          ws_q     <= ov_q;  // its travel starts with this S (S1 adds it)
          wc_q     <= '0;
          wks_q    <= 1'b0;
          wx_q     <= '0;
          pend_q   <= 1'b1;
          mode_q   <= MdLoop;
        end else begin
          ws_q     <= cs_q;
          wc_q     <= cc_q;
          wks_q    <= cks_q;
          wx_q     <= cx_q;
          mode_q   <= MdReal;
        end
      end
      StS1: begin
        if (pend_q) begin
          sum_q  <= sadd;
          pend_q <= 1'b0;
        end
        es_q   <= s1_d1[SW];
        ez_q   <= s1_d1 == '0;
        a_q    <= s1_d1[SW] ? s1_d2 : s1_d1[SW-1:0];
        upok_q <= wc_q < m_i;
        y_q    <= {xa[SW] ^ wx_q[SW], xa[SW-1:0]};  // the low sum's carry out: xa[SW] less x's bit SW
        if (pend_q && ws_q == '0 && wc_q == '0) begin  // the stop is at rest: its travel against the data
          pk_q   <= PkCheck;
          i_q    <= '0;
          dl_q   <= resume_q ? shift_i + 6'd1 : shift_i;
          c1_q   <= 1'b0;
          c2_q   <= 1'b0;
          gt_q   <= 1'b0;
          zacc_q <= 1'b0;
          fnz_q  <= 1'b0;
          snz_q  <= 1'b0;
        end
      end
      StS2: up_q <= s2_up;
      StS3: begin
        if (up_q) begin
          wx_q  <= xa[XW-1:0];
          wc_q  <= wc_q + SW'(1);
          wks_q <= es_q;
        end else if (dn_q) begin
          wx_q  <= xa[XW-1:0];
          wc_q  <= wc_q - SW'(1);
        end
      end
      StS4: begin
        ws_q <= wks_q ? ws_q - wc_q : ws_q + wc_q;
        if (mode_q != MdReal) begin
          pend_q <= 1'b1;
          mode_q <= MdLoop;
        end
      end
      StCommit: begin
        sum_q  <= sadd;  // X of the move: S
        pk_q   <= PkPhiCmp;
        i_q    <= '0;
        dl_q   <= shift_i;
        c1_q   <= 1'b0;
        c2_q   <= end_q;
        gt_q   <= 1'b0;
        zacc_q <= 1'b0;
        fnz_q  <= 1'b0;
        snz_q  <= 1'b0;
      end
      StPass: begin
        if (dl_q == '0) sum_q <= sum_q >> 1;
        else dl_q <= dl_q - 6'd1;
        c1_q <= (xb && fb) || (c1_q && (xb || fb));
        if (i_q >= 7'd32) c2_q <= ab && c2_q;
        if (pl != pr) gt_q <= pl;
        snz_q <= snz_q || xb;
        fnz_q <= fnz_q || fb;
        if (in_a) begin
          av_q   <= {na, av_q[AW-1:1]};
          zacc_q <= zacc_q || na;
        end
        i_q <= i_q + 7'd1;
      end
      StPassEnd: begin
        case (pk_q)
          PkCheck: begin
            if (!resume_q && (!zacc_q ? snz_q : gt_q)) tz_q <= 1'b1;
            else if (resume_q && (!zacc_q ? !snz_q : !gt_q)) tz_q <= 1'b0;
            ws_q   <= cs_q;
            wc_q   <= cc_q;
            wks_q  <= cks_q;
            wx_q   <= cx_q;
            mode_q <= MdReal;
          end
          PkPhiCmp: begin
            if (gt_q) begin
              if (!zacc_q && !end_q && fnz_q) begin
                av_q    <= '0;
                za_q    <= 1'b1;
                extra_q <= 1'b0;
              end else begin
                za_q    <= !zacc_q;
                extra_q <= end_q;
              end
            end else begin
              sum_q  <= sadd;  // S again (the pass shifted it out)
              pk_q   <= PkPhiApply;
              i_q    <= '0;
              dl_q   <= shift_i;
              c1_q   <= 1'b0;
              c2_q   <= end_q;
              gt_q   <= 1'b0;
              zacc_q <= 1'b0;
              fnz_q  <= 1'b0;
              snz_q  <= 1'b0;
            end
          end
          default: begin
            za_q    <= !zacc_q;
            extra_q <= 1'b0;
          end
        endcase
      end
      StAdv: begin
        if (za_q) begin
          ax_q  <= '0;
          i_q   <= '0;
          pv_q  <= 1'b0;
          fin_q <= 1'b0;
          if (extra_q) begin
            extra_q <= 1'b0;
          end else begin
            acc_q <= '0;
            bor_q <= 1'b0;
            oc_q  <= 1'b0;
            dv_q  <= 1'b0;
          end
        end else begin
          i_q    <= '0;
          c1_q   <= 1'b1;  // the decrement's borrow
          zacc_q <= 1'b0;
        end
      end
      StDec: begin
        c1_q   <= !av_q[0] && c1_q;
        av_q   <= {db, av_q[AW-1:1]};
        zacc_q <= dzacc;
        if (i_q == 7'(NDec - 1)) begin
          za_q  <= !dzacc;
          i_q   <= '0;  // the copy's walk (when this is the advance's last tick)
          ax_q  <= '0;
          pv_q  <= 1'b0;
          fin_q <= 1'b0;
        end else begin
          i_q <= i_q + 7'd1;
        end
      end
      StMul: begin
        if (dv_q) begin
          acc_q <= mt[33:1];  // floor
          if (jd_q >= 7'd32) oc_q <= (y0b_q && pb) || (oc_q && (y0b_q || pb));
        end
        dv_q <= pv_q;
        if (pv_q) begin
          dq_q <= dj;
          if (j_q < 7'(OutWidth)) bor_q <= (!y1b && y0a_q) || (!(y1b ^ y0a_q) && bor_q);
          sg_q <= j_q == 7'(OutWidth);  // the difference's sign bit: weight -2^OutWidth
          jd_q <= j_q;
        end
        if (!fin_q) begin
          pv_q <= 1'b1;
          j_q  <= i_q;
          if (i_q == 7'(NMul - 1)) fin_q <= 1'b1;
          i_q <= i_q + 7'd1;
        end else if (pv_q) begin
          pv_q <= 1'b0;
        end else if (32'(ax_q) != Axes - 1) begin
          ax_q  <= ax_q + 1'b1;
          i_q   <= '0;
          fin_q <= 1'b0;
          acc_q <= '0;
          bor_q <= 1'b0;
          oc_q  <= 1'b0;
        end
      end
      default: ;
    endcase
  end

  // RAMs: y0 twice (the copy writes both; the product reads bit j from y0a
  // and bit j - 32 from y0b), the output (the product writes it, the
  // readout reads it). No RAM is read and written at one address in one
  // clock (the copy and the readout only write or only read them; the
  // product reads y0 and writes rout).
  logic            y0_we, rout_we;
  logic [RamAW-1:0] y0_wa, rout_wa;
  logic            y0_wd;
  assign y0_we   = st_q == StCopy && pv_q;
  assign y0_wa   = RamAW'({pax_q, j_q[BB-1:0]});
  assign y0_wd   = eng_word_i[WBit'(j_q)];
  // the choice "down": high in S3 only (the x adder's mode)
  always_ff @(posedge clk_i) begin
    if (!rst_ni) dn_q <= 1'b0;
    else dn_q <= st_q == StS2 && s2_dn;
  end

  assign rout_we = st_q == StMul && dv_q && jd_q >= 7'd32;
  assign rout_wa = RamAW'({ax_q, BB'(jd_q - 7'd32)});
  (* no_rw_check *) logic y0a_mem [2**RamAW];
  (* no_rw_check *) logic y0b_mem [2**RamAW];
  (* no_rw_check *) logic rout_mem [2**RamAW];
  always_ff @(posedge clk_i) begin
    if (y0_we) begin
      y0a_mem[y0_wa] <= y0_wd;
      y0b_mem[y0_wa] <= y0_wd;
    end
    if (rout_we) rout_mem[rout_wa] <= ob;
    y0a_q  <= y0a_mem[ra];
    y0b_q  <= y0b_mem[rb];
    rout_q <= rout_mem[ro];
  end

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Formal properties (scripts/formal.sh: BMC from reset and induction).
  // ---------------------------------------------------------------------
  logic f_past_valid = 1'b0;
  logic [SW-1:0] f_m_q, f_smax_q;
  logic [5:0]    f_shift_q;
  always_ff @(posedge clk_i) begin
    f_past_valid <= 1'b1;
    f_m_q        <= m_i;
    f_smax_q     <= s_max_i;
    f_shift_q    <= shift_i;
  end
  // the configuration held while running; shift_i within its contract
  always_comb begin
    if (!f_past_valid) assume (!rst_ni);
    assume (m_i != '0);
    assume (shift_i <= 6'd40);
    if (f_past_valid) assume (m_i == f_m_q && s_max_i == f_smax_q && shift_i == f_shift_q);
  end
  // k as a signed number, and x = c (c + 1) / 2 of a magnitude
  function automatic logic signed [SW+1:0] f_k(input logic ks, input logic [SW-1:0] c);
    f_k = ks ? -$signed({2'b00, c}) : $signed({2'b00, c});
  endfunction
  function automatic logic [2*SW-1:0] f_tri(input logic [SW-1:0] c);
    f_tri = ({SW'(0), c} * ({SW'(0), c} + 1'b1)) >> 1;
  endfunction
  logic f_step, f_real;  // in a step (the work curve valid); of the tick's own curve
  assign f_step = st_q == StS1 || st_q == StS2 || st_q == StS3 || st_q == StS4 || st_q == StCommit;
  assign f_real = mode_q == MdReal;
  always_ff @(posedge clk_i) begin
    if (f_past_valid) begin
      if (!$past(rst_ni)) begin
        assert (st_q == StIdle && !eng_tick_q && !valid_q && !err_q && !primed_q && !have_q && !starved_q);
        assert (cs_q == '0 && cc_q == '0 && cx_q == '0 && frac_q == '0 && cnt_q == '0);
      end else begin
        // err_o is sticky; a servo tick while busy sets it
        if ($past(err_q)) assert (err_q);
        if ($past(tick_i) && $past(st_q) != StIdle) assert (err_q);
        // the real curve moves only at the commit of the tick's own step, k
        // by at most one; trajectory time only in the serial passes
        if ($past(st_q) != StCommit) assert (cs_q == $past(cs_q) && cc_q == $past(cc_q) && cks_q == $past(cks_q));
        if ($past(st_q) == StCommit)
          assert (f_k(cks_q, cc_q) - f_k($past(cks_q), $past(cc_q)) <= 1 &&
                  f_k($past(cks_q), $past(cc_q)) - f_k(cks_q, cc_q) <= 1);
        if ($past(st_q) != StPass && $past(st_q) != StPassEnd) assert (frac_q == $past(frac_q));
        // strobes: one cycle each; an engine tick only into a state that
        // waits for its answer (one tick outstanding); an output only at the
        // end of a readout
        if ($past(eng_tick_q)) assert (!eng_tick_q);
        if ($past(valid_q)) assert (!valid_q);
        if (valid_q) assert ($past(st_q) == StReadout && st_q == StPlan);
      end
      if (eng_tick_q) assert (st_q == StPrimeWait || st_q == StAdvWait);
      // |k| <= m (m held), and x = c (c + 1) / 2, for the real curve always
      // and for the work curve through a step
      assert (cc_q <= m_i);
      assert ({SW'(0), cx_q} == f_tri(cc_q));
      if (f_step) begin
        assert (wc_q <= m_i);
        assert ({SW'(0), wx_q} == f_tri(wc_q));
      end
      // the tick's own step starts from the real curve and moves k by at
      // most one
      if (f_real && (st_q == StS1 || st_q == StS2 || st_q == StS3))
        assert (ws_q == cs_q && wc_q == cc_q && wks_q == cks_q && wx_q == cx_q);
      if (f_real && (st_q == StS4 || st_q == StCommit))
        assert (f_k(wks_q, wc_q) - f_k(cks_q, cc_q) <= 1 && f_k(cks_q, cc_q) - f_k(wks_q, wc_q) <= 1);
      // supporting invariants: the stage registers of a step
      if (st_q == StS2 || st_q == StS3) assert (upok_q == (wc_q < m_i));
      if (st_q != StS3) assert (!dn_q);
      if (st_q == StS3) begin
        assert (!(up_q && dn_q));
        if (up_q) assert (wc_q < m_i && (wc_q == '0 || es_q == wks_q));
        if (dn_q) assert (wc_q != '0);
      end
      assert (st_q <= StMul);
      if (f_step) assert (mode_q != 2'd3);
      if (st_q == StPass || st_q == StPassEnd) assert (pk_q != 2'd3);
    end
  end
`endif

  assign eng_tick_o      = eng_tick_q;
  assign sample_valid_o  = valid_q;
  assign sample_o        = out_q;
  assign out_shift_o     = out_shift;
  assign out_bit_o       = rout_q;
  assign s_o             = cs_q;
  assign starved_o       = starved_q;
  assign starved_count_o = cnt_q;
  assign busy_o          = st_q != StIdle;
  assign err_o           = err_q;
endmodule

`default_nettype wire
