// SPDX-License-Identifier: Apache-2.0
// trajcore: BCU generator. Samples a cubic Bernstein polynomial per axis at
// t = j/2^d, j = 0..2^d-1, in increasing time order, ONE SAMPLE PER CLOCK once
// a segment has started, then holds the end value round(D). Mirrors
// hls/traj_bcu_gen.hpp cycle for cycle; the full description (method,
// exactness, schedule, timing rules) is there and in rtl/README.md. In short:
//   * the host sends every control value pre-scaled by 8^(MaxDepth-d); d
//     scaled mid-subdivisions along the left spine (digit-serial BCU, in place
//     in block RAM) give the first leaf (A, B, C, D), 8^MaxDepth times the
//     cubic on [0, 2^-d];
//   * one digit-serial pass turns it into exact integer forward differences
//     S0 = A + 2^(Shift-1), D1 = D - A, D2 = 6(B-2C+D), D3 = 6(D-3C+3B-A):
//     the leaf polynomial at every integer x is the sample at t = x/2^d, so
//     S += D1, D1 += D2, D2 += D3 gives every sample exactly (modulo 2^WF,
//     the true values fit) and the sample is a bit slice of S;
//   * the forward-difference stage is a skewed carry pipeline: C chunks of
//     ChunkWidth bits, the carry registered between chunks, chunk k one step
//     behind chunk k-1: one step per clock, no carry chain longer than
//     ChunkWidth; the next segment is loaded chunk by chunk behind the last
//     step of the current one (no gap).
`default_nettype none
`include "traj_check.svh"

module traj_bcu_gen #(
  parameter int Axes       = 3,   // axes in lockstep, 1..8
  parameter int ChunkWidth = 16,  // stream word and carry-chain chunk width, 8..64
  parameter int CtrlWidth  = 40,  // control value width, >= 2
  parameter int GuardBits  = 9,   // control bits below the output LSB, 0..CtrlWidth-2
  parameter int OutWidth   = 32,  // sample width, CtrlWidth-GuardBits+(GuardBits>0) .. 64
  parameter int MaxDepth   = 12   // largest depth d (K = 2^d samples), 1..30
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

  localparam int CW        = ChunkWidth;
  localparam int W         = CtrlWidth + 3 * MaxDepth;          // value bits needed
  localparam int Digits    = (W + CW - 1) / CW;                  // stream digits per value
  localparam int WP        = Digits * CW;                        // stream value width
  localparam int N         = Axes * Digits;                      // DESC pass slots
  localparam int C         = (W + 1 + CW - 1) / CW;              // FD chunks
  localparam int WF        = C * CW;                             // FD register width
  localparam int Ni        = Axes * C;                           // INIT pass slots
  localparam int L         = 5;                                  // read -> write latency
  localparam int Pp        = (N > L + 1) ? N : L + 1;            // DESC pass period
  localparam int Pi        = Ni + L + 1;                         // INIT + drain + hand-off
  localparam int Shift     = 3 * MaxDepth + GuardBits;           // output rounding shift
  localparam int Narrow    = CtrlWidth - GuardBits + ((GuardBits > 0) ? 1 : 0);
  localparam int DepthBits = $clog2(MaxDepth + 1);
  localparam int DgBits    = (C > 1) ? $clog2(C) : 1;
  localparam int AxBits    = (Axes > 1) ? $clog2(Axes) : 1;
  localparam int PcBits    = $clog2(((Pp > Pi) ? Pp : Pi) + 1);
  localparam int MemAB     = DgBits + 1;                         // {bank, digit}
  localparam int HalfDigit = (Shift - 1) / CW;                   // rounding constant 2^(Shift-1)
  localparam int HalfBit   = (Shift - 1) % CW;
  localparam int K0        = Shift / CW;                         // lowest chunk of the output slice

  // ---------------------------------------------------------------------
  // Elaboration-time parameter checks.
  // ---------------------------------------------------------------------
  `TRAJ_PARAM_CHECK(g_bad_axes, Axes >= 1 && Axes <= 8, "traj_bcu_gen: Axes must be 1..8")
  `TRAJ_PARAM_CHECK(g_bad_chunk, ChunkWidth >= 8 && ChunkWidth <= 64,
                    "traj_bcu_gen: ChunkWidth must be 8..64")
  `TRAJ_PARAM_CHECK(g_bad_depth, MaxDepth >= 1 && MaxDepth <= 30,
                    "traj_bcu_gen: MaxDepth must be 1..30")
  `TRAJ_PARAM_CHECK(g_bad_ctrl, CtrlWidth >= 2 && WP <= 128,
                    "traj_bcu_gen: CtrlWidth must be >= 2 with ceil((CtrlWidth+3*MaxDepth)/ChunkWidth)*ChunkWidth <= 128")
  `TRAJ_PARAM_CHECK(g_bad_guard, GuardBits >= 0 && GuardBits <= CtrlWidth - 2,
                    "traj_bcu_gen: GuardBits must be 0..CtrlWidth-2")
  `TRAJ_PARAM_CHECK(g_bad_out, OutWidth >= Narrow && OutWidth <= 64,
                    "traj_bcu_gen: OutWidth must be CtrlWidth-GuardBits+(GuardBits>0)..64")
  `TRAJ_PARAM_CHECK(g_bad_hdr, DepthBits <= ChunkWidth,
                    "traj_bcu_gen: the depth field must fit one stream word")

  // Prep FSM states (BcuGen::State). Only hardware states: whether a sample
  // is ready is a view of the model for test drivers, not a state.
  typedef enum logic [2:0] {StIdle, StLoad, StWaitx, StDesc, StInit} state_e;

  // ---------------------------------------------------------------------
  // State (BcuGen::Regs, same names, same order). Control is reset, the
  // datapath is not. The memories (mem) and the deskew registers (dsk_q)
  // are declared in their generate blocks.
  // ---------------------------------------------------------------------
  // prep FSM
  state_e               fsm_q;
  logic [DepthBits-1:0] depth_q;
  logic                 bank_q, nbank_q;     // bank of the segment in the FSM, of the next header
  logic [1:0]           wc_q;                // LOAD word counters: lane, digit, axis
  logic [DgBits-1:0]    wdg_q;
  logic [AxBits-1:0]    wax_q;
  logic [PcBits-1:0]    pc_q;                // pass cycle, DESC level, pass slot (digit, axis)
  logic [DepthBits-1:0] lvl_q;
  logic [DgBits-1:0]    sdg_q;
  logic [AxBits-1:0]    sax_q;
  // transfer into the forward-difference stage and the stage's tags
  logic                 xpend_q;             // a prepared segment waits, its chunk 0 in rd_q
  logic                 xbusy_q;             // its chunks 1..C-1 are being loaded
  logic                 xbank_q;
  logic [DepthBits-1:0] xdepth_q;
  logic [DgBits-1:0]    xk_q;                // RAM digit read for the transfer
  logic [DgBits-1:0]    xk1_q;               // == xk_q + 1 (timing: no adder before the RAM address)
  logic                 frem_q;              // the feeding segment has steps left to enter
  logic                 need_end_q;          // its last step entered, the end tag not yet
  logic [MaxDepth-1:0]  fcnt_q;              // steps left to enter after the next one
  logic [C-1:0]         tag_v_q, tag_last_q, tag_end_q;  // tag of chunk k's step
  // the start flag is used below the top only (chunk k loads where it is at k-1)
  /* verilator lint_off UNUSEDSIGNAL */
  logic [C-1:0]         tag_start_q;
  /* verilator lint_on UNUSEDSIGNAL */
  // == |tag_v_q[C-2:0], |tag_start_q[C-2:0] (0 if C == 1), registered for timing
  /* verilator lint_off UNUSEDSIGNAL */
  logic                 vlo_q, slo_q;
  /* verilator lint_on UNUSEDSIGNAL */
  // digit-serial pipeline slots: rs (RAM output), hs (head), s1, s2 (stages)
  logic                 rs_v_q, rs_first_q, rs_init_q, rs_ext_q;
  logic                 hs_v_q, hs_first_q, hs_init_q;
  logic                 s1_v_q, s1_first_q, s1_init_q;
  logic                 s2_v_q, s2_init_q;
  logic [4*Axes-1:0]    we_q;                // RAM write enables, lane l, axis a at [l*Axes + a]
  // ticks and outputs
  logic                 tick_q, tick_err_q, valid_q, underrun_q, done_q;
  // ---- datapath (not reset) ----
  logic [AxBits-1:0]    rs_ax_q, hs_ax_q, s1_ax_q, s2_ax_q;
  logic [DgBits-1:0]    rs_dg_q, hs_dg_q, s1_dg_q, s2_dg_q;
  logic                 rs_bank_q, hs_bank_q, s1_bank_q, s2_bank_q;
  logic [4*Axes*CW-1:0] rd_q;                // RAM outputs, lane l, axis a at [(l*Axes + a)*CW +: CW]
  logic [MemAB-1:0]     waddr_q;
  logic [4*CW-1:0]      wdata_q;
  logic [4*CW-1:0]      hd_q;                // axis-multiplexed head digits A, B, C, D
  // stage 1
  logic [CW-1:0]        s1_q, s2_q, s3_q, a1_q, e1_q, e2_q, e3_q;
  logic                 cs1_q, cs2_q, cs3_q, ce1_q, ce2_q, ce3_q;
  // stage 2
  logic [CW-1:0]        t1_q, t2_q, a2_q, s12_q, u_q, y1_q, y2_q, e1d_q;
  logic                 ct1_q, ct2_q, cu_q, cy1_q, cy2_q;
  logic [1:0]           he1_q;               // top bits of the previous e1 digit
  logic [3:0]           he2_q;               // top bits of the previous e2 digit
  // output stage
  logic                 cm_q, cs0_q, cd2_q, cd3_q;
  logic [2:0]           ha_q;
  logic [1:0]           hs1_q;
  logic                 ht1_q;
  logic [1:0]           hu_q;
  // forward-difference stage: axis a, chunk k at [(a*C + k)*CW +: CW], carries at [a*C + k]
  logic [Axes*WF-1:0]   fs_q, f1_q, f2_q, f3_q;
  logic [Axes*C-1:0]    cs_q, c1_q, c2_q;
  logic [Axes*OutWidth-1:0] sample_q;

  // ---------------------------------------------------------------------
  // Stream input and forward-difference stage control: advance, ticks,
  // entering tag.
  // ---------------------------------------------------------------------
  logic accept;
  logic top_v, top_end, newer, proc, under, consume, adv;
  logic adv_t_q, adv_n_q;  // adv with a tick, without one (timing copies)
  logic enter_start, ent_v, ent_last, ent_end, xfer_step;
  assign s_axis_tready = (fsm_q == StIdle) || (fsm_q == StLoad);
  assign accept        = s_axis_tready && s_axis_tvalid;
  assign top_v   = tag_v_q[C-1];
  assign top_end = tag_end_q[C-1];
  if (C > 1) begin : g_newer
    assign newer     = xpend_q || vlo_q;
    assign xfer_step = adv && (enter_start || slo_q);
  end else begin : g_newer1
    assign newer     = xpend_q;
    assign xfer_step = adv && enter_start;
  end
  assign proc    = tick_q && top_v;
  assign under   = tick_q && !top_v && (fsm_q == StIdle) && !s_axis_tvalid && !newer;
  assign consume = proc || under;
  // adv = top_v ? proc : (top_end ? newer : 1), re-encoded for timing (it
  // enables the whole forward-difference stage): its values with and without
  // a tick are flops kept from the next state (below), so adv is one LUT
  assign adv     = tick_q ? adv_t_q : adv_n_q;
  // entering tag: the next step of the feeding segment, else the pending
  // segment's start, else (once) the end tag, else a bubble
  assign enter_start = !frem_q && xpend_q;
  assign ent_v       = frem_q || xpend_q;
  assign ent_last    = frem_q ? (fcnt_q == '0) : (xdepth_q == '0);
  assign ent_end     = !frem_q && !xpend_q && need_end_q;

  // ---------------------------------------------------------------------
  // Prep FSM: IDLE (header) -> LOAD (4N words) -> WAITX (transfer over) ->
  // DESC (d passes) -> INIT (one pass, hand-off) -> IDLE.
  // ---------------------------------------------------------------------
  logic [DepthBits-1:0] hdr_depth;
  // The comparison is constant when MaxDepth+1 is a power of two (no value of
  // the field exceeds MaxDepth); it is kept for every other MaxDepth.
  /* verilator lint_off CMPCONST */
  assign hdr_depth = (s_axis_tdata[DepthBits-1:0] > DepthBits'(MaxDepth))
                   ? DepthBits'(MaxDepth) : s_axis_tdata[DepthBits-1:0];
  /* verilator lint_on CMPCONST */

  logic              pass_on, pass_init, issue, hand_off;
  logic [DgBits-1:0] dpass_last;
  assign pass_on    = (fsm_q == StDesc) || (fsm_q == StInit);
  assign pass_init  = (fsm_q == StInit);
  assign dpass_last = pass_init ? DgBits'(C - 1) : DgBits'(Digits - 1);
  // pc_q below the pass's slots (Ni for INIT, else N) and pc_q at the
  // pass's last clock (period Pi for INIT, else Pp) are kept in flops from
  // the next state (pc_lt_q, pc_end_q: timing copies, proved equal below)
  logic pc_lt_q, pc_end_q;
  assign issue      = pass_on && pc_lt_q;  // a pass slot is read this cycle
  assign hand_off   = pass_init && pc_end_q;

  state_e               fsm_d;
  logic [DepthBits-1:0] depth_d, lvl_d;
  logic                 bank_d, nbank_d;
  logic [1:0]           wc_d;
  logic [DgBits-1:0]    wdg_d, sdg_d;
  logic [AxBits-1:0]    wax_d, sax_d;
  logic [PcBits-1:0]    pc_d;
  always_comb begin
    fsm_d   = fsm_q;
    depth_d = depth_q;
    bank_d  = bank_q;
    nbank_d = nbank_q;
    wc_d    = wc_q;
    wdg_d   = wdg_q;
    wax_d   = wax_q;
    pc_d    = pc_q;
    lvl_d   = lvl_q;
    sdg_d   = sdg_q;
    sax_d   = sax_q;
    case (fsm_q)
      StIdle: begin
        if (accept) begin
          depth_d = hdr_depth;
          bank_d  = nbank_q;
          nbank_d = !nbank_q;
          wc_d    = '0;
          wdg_d   = '0;
          wax_d   = '0;
          fsm_d   = StLoad;
        end
      end
      StLoad: begin
        if (accept) begin
          wc_d = wc_q + 1'b1;
          if (wc_q == 2'd3) begin
            if (wdg_q == DgBits'(Digits - 1)) begin
              wdg_d = '0;
              if (wax_q == AxBits'(Axes - 1)) begin
                wax_d = '0;
                fsm_d = StWaitx;
              end else begin
                wax_d = wax_q + 1'b1;
              end
            end else begin
              wdg_d = wdg_q + 1'b1;
            end
          end
        end
      end
      StWaitx: begin
        if (!xpend_q && !xbusy_q) begin
          if (depth_q == '0) fsm_d = StInit;
          else               fsm_d = StDesc;
          pc_d  = '0;
          lvl_d = '0;
          sdg_d = '0;
          sax_d = '0;
        end
      end
      StDesc, StInit: begin
        if (issue) begin
          if (sdg_q == dpass_last) begin
            sdg_d = '0;
            sax_d = sax_q + 1'b1;
          end else begin
            sdg_d = sdg_q + 1'b1;
          end
        end
        if (pc_end_q) begin
          pc_d  = '0;
          sdg_d = '0;
          sax_d = '0;
          if (pass_init) begin
            fsm_d = StIdle;
          end else begin
            lvl_d = lvl_q + 1'b1;
            if (lvl_top_q) fsm_d = StInit;
          end
        end else begin
          pc_d = pc_q + 1'b1;
        end
      end
      default: begin
        fsm_d = StIdle;
      end
    endcase
  end

  // Their next values from how pc moves: to 0 (a pass starts: below the
  // slots, at the end only for a one-clock period: Pp = 1, Pi >= 2), up by
  // one within a pass (below: still below unless at the last slot; at the
  // end: one clock before it), else held (pass_init does not change either).
  // lvl_top_q: in DESC, lvl_q + 1 == depth_q (its last pass), kept from how
  // lvl moves there: 0 from WAITX (depth fixed), + 1 at a DESC pass's end
  // (a timing copy, proved equal below)
  logic pc_zero, pc_inc, pass_init_d, lvl_top_q;
  always_ff @(posedge clk_i) begin
    if (!rst_ni) lvl_top_q <= 1'b0;
    else if (fsm_q == StWaitx) lvl_top_q <= (depth_q == DepthBits'(1));
    else if (fsm_q == StDesc && pc_end_q) lvl_top_q <= ({1'b0, lvl_q} + (DepthBits + 1)'(2) == {1'b0, depth_q});
  end
  assign pc_zero     = ((fsm_q == StWaitx) && !xpend_q && !xbusy_q) || (pass_on && pc_end_q);
  assign pc_inc      = pass_on && !pc_end_q;
  assign pass_init_d = (fsm_d == StInit);
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      pc_lt_q  <= 1'b1;       // pc 0 < N (N >= 1)
      pc_end_q <= (Pp == 1);  // pc 0 == Pp - 1
    end else if (pc_zero) begin
      pc_lt_q  <= 1'b1;
      pc_end_q <= (Pp == 1) && !pass_init_d;
    end else if (pc_inc) begin
      pc_lt_q  <= pc_lt_q && (pc_q != (pass_init ? PcBits'(Ni - 1) : PcBits'(N - 1)));
      pc_end_q <= pc_q == (pass_init ? PcBits'(Pi - 2) : PcBits'(Pp - 2));
    end
  end

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      fsm_q   <= StIdle;
      depth_q <= '0;
      bank_q  <= 1'b0;
      nbank_q <= 1'b0;
      wc_q    <= '0;
      wdg_q   <= '0;
      wax_q   <= '0;
      pc_q    <= '0;
      lvl_q   <= '0;
      sdg_q   <= '0;
      sax_q   <= '0;
    end else begin
      fsm_q   <= fsm_d;
      depth_q <= depth_d;
      bank_q  <= bank_d;
      nbank_q <= nbank_d;
      wc_q    <= wc_d;
      wdg_q   <= wdg_d;
      wax_q   <= wax_d;
      pc_q    <= pc_d;
      lvl_q   <= lvl_d;
      sdg_q   <= sdg_d;
      sax_q   <= sax_d;
    end
  end

  // ---------------------------------------------------------------------
  // Transfer and tags: the hand-off makes the prepared segment pending; at
  // an advance the tags shift up by one chunk with the entering tag at 0,
  // and chunk k of a new segment loads where its start tag arrives (chunk
  // 0: as it enters), the RAM reading chunk k+1 in the same cycle.
  // ---------------------------------------------------------------------
  logic [C-1:0] tag_v_d, tag_start_d, tag_last_d, tag_end_d;
  logic         vlo_d, slo_d;  // the ORs of the tags below the top, after an advance
  if (C > 1) begin : g_tag
    assign tag_v_d     = {tag_v_q[C-2:0], ent_v};
    assign tag_start_d = {tag_start_q[C-2:0], enter_start};
    assign tag_last_d  = {tag_last_q[C-2:0], ent_v && ent_last};
    assign tag_end_d   = {tag_end_q[C-2:0], ent_end};
  end else begin : g_tag1
    assign tag_v_d     = ent_v;
    assign tag_start_d = enter_start;
    assign tag_last_d  = ent_v && ent_last;
    assign tag_end_d   = ent_end;
  end
  if (C > 2) begin : g_lo
    assign vlo_d = ent_v || (|tag_v_q[C-3:0]);
    assign slo_d = enter_start || (|tag_start_q[C-3:0]);
  end else if (C == 2) begin : g_lo2
    assign vlo_d = ent_v;
    assign slo_d = enter_start;
  end else begin : g_lo1
    assign vlo_d = 1'b0;
    assign slo_d = 1'b0;
  end

  // the next top tag, pending flag and newer: adv's copies from them
  logic top_v_n, top_end_n, xpend_n, newer_n;
  assign top_v_n   = adv ? tag_v_d[C-1] : top_v;
  assign top_end_n = adv ? tag_end_d[C-1] : top_end;
  assign xpend_n   = (adv && !frem_q && xpend_q) ? 1'b0 : (hand_off || xpend_q);
  if (C > 1) begin : g_newer_n
    assign newer_n = xpend_n || (adv ? vlo_d : vlo_q);
  end else begin : g_newer_n1
    assign newer_n = xpend_n;
  end
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      adv_t_q <= 1'b1;
      adv_n_q <= 1'b1;
    end else begin
      adv_t_q <= !(!top_v_n && top_end_n && !newer_n);
      adv_n_q <= !top_v_n && (!top_end_n || newer_n);
    end
  end

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      xpend_q     <= 1'b0;
      xbusy_q     <= 1'b0;
      xbank_q     <= 1'b0;
      xdepth_q    <= '0;
      xk_q        <= '0;
      xk1_q       <= DgBits'(1);
      frem_q      <= 1'b0;
      need_end_q  <= 1'b0;
      fcnt_q      <= '0;
      tag_v_q     <= '0;
      tag_start_q <= '0;
      tag_last_q  <= '0;
      tag_end_q   <= '0;
      vlo_q       <= 1'b0;
      slo_q       <= 1'b0;
    end else begin
      if (hand_off) begin
        xpend_q  <= 1'b1;
        xbank_q  <= bank_q;
        xdepth_q <= depth_q;
        xk_q     <= '0;
        xk1_q    <= DgBits'(1);
      end
      if (adv) begin
        if (frem_q) begin
          frem_q     <= (fcnt_q != '0);
          fcnt_q     <= fcnt_q - 1'b1;
          need_end_q <= (fcnt_q == '0);
        end else if (xpend_q) begin
          frem_q     <= (xdepth_q != '0);
          // steps left after the one after this: 2^d - 2
          fcnt_q     <= MaxDepth'((64'd1 << xdepth_q) - 64'd2);
          need_end_q <= (xdepth_q == '0);
          xpend_q    <= 1'b0;
          xbusy_q    <= 1'b1;
        end else begin
          need_end_q <= 1'b0;
        end
        if (xfer_step) begin
          if (xk_q == DgBits'(C - 1)) begin
            xbusy_q <= 1'b0;
          end else begin
            xk_q  <= xk1_q;
            xk1_q <= xk1_q + 1'b1;
          end
        end
        tag_v_q     <= tag_v_d;
        tag_start_q <= tag_start_d;
        tag_last_q  <= tag_last_d;
        tag_end_q   <= tag_end_d;
        vlo_q       <= vlo_d;
        slo_q       <= slo_d;
      end
    end
  end

  // ---------------------------------------------------------------------
  // Block RAM: one memory per (lane, axis), address {bank, digit}; one
  // registered write port (LOAD words, pass results), one synchronous read
  // port (passes, transfer), shared address for all memories. Read every
  // cycle (no enable: no fan-out of a late enable to the read registers): a
  // pass's slot (digit 0 in its other cycles, so the hand-off cycle reads
  // chunk 0), else the transfer's chunk xk, or xk+1 when chunk xk loads in
  // this cycle.
  // ---------------------------------------------------------------------
  logic              rd_bank;
  logic [DgBits-1:0] rd_dg, rd_dg_hold;
  logic [MemAB-1:0]  rd_addr;
  assign rd_bank = pass_on ? bank_q : xbank_q;
  // A transfer step never falls in a pass (WAITX: passes start only when no
  // transfer is pending or running; proved under FORMAL below), so the late
  // xfer_step selects in the last LUT level only: the pass/idle choice is
  // made from flops in parallel.
  assign rd_dg_hold = pass_on ? sdg_q : xk_q;  // sdg_q = 0 between slots
  assign rd_dg      = xfer_step ? xk1_q : rd_dg_hold;
  assign rd_addr    = {rd_bank, rd_dg};
  for (genvar l = 0; l < 4; l++) begin : g_mem_l
    for (genvar a = 0; a < Axes; a++) begin : g_mem_a
      // A read never needs the word written in the same cycle (a pass reads a
      // digit at least L+1 cycles after writing it; LOAD writes the other
      // bank): no read/write collision logic.
      (* no_rw_check *) logic [CW-1:0] mem [2**MemAB];
      always_ff @(posedge clk_i) begin
        if (we_q[l*Axes + a]) mem[waddr_q] <= wdata_q[l*CW +: CW];
        rd_q[(l*Axes + a)*CW +: CW] <= mem[rd_addr];
      end
    end
  end

  // ---------------------------------------------------------------------
  // Digit-serial pipeline: rd -> hd -> stage 1 -> stage 2 -> write register.
  // Slot flags: v (write back), first (first digit of a value, or a bubble),
  // init (INIT pass), ext (sign-fill digit), ax, dg, bank.
  // ---------------------------------------------------------------------
  logic is_first, is_ext;
  assign is_first = (sdg_q == '0);
  assign is_ext   = pass_init && (32'(sdg_q) >= Digits);

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      rs_v_q <= 1'b0; rs_first_q <= 1'b1; rs_init_q <= 1'b0; rs_ext_q <= 1'b0;
      hs_v_q <= 1'b0; hs_first_q <= 1'b1; hs_init_q <= 1'b0;
      s1_v_q <= 1'b0; s1_first_q <= 1'b1; s1_init_q <= 1'b0;
      s2_v_q <= 1'b0; s2_init_q <= 1'b0;
    end else begin
      rs_v_q     <= issue;
      rs_first_q <= !issue || is_first;
      rs_init_q  <= issue && pass_init;
      rs_ext_q   <= issue && is_ext;
      hs_v_q     <= rs_v_q;
      hs_first_q <= rs_first_q;
      hs_init_q  <= rs_init_q;
      s1_v_q     <= hs_v_q;
      s1_first_q <= hs_first_q;
      s1_init_q  <= hs_init_q;
      s2_v_q     <= s1_v_q;
      s2_init_q  <= s1_init_q;
    end
  end
  always_ff @(posedge clk_i) begin
    rs_ax_q   <= issue ? sax_q : '0;
    rs_dg_q   <= issue ? sdg_q : '0;
    rs_bank_q <= issue && bank_q;
    hs_ax_q   <= rs_ax_q;   hs_dg_q <= rs_dg_q;   hs_bank_q <= rs_bank_q;
    s1_ax_q   <= hs_ax_q;   s1_dg_q <= hs_dg_q;   s1_bank_q <= hs_bank_q;
    s2_ax_q   <= s1_ax_q;   s2_dg_q <= s1_dg_q;   s2_bank_q <= s1_bank_q;
  end

  // hd: axis multiplexer (or the sign fill of the previous digit). An OR of
  // decoded words per lane: an indexed part-select would elaborate into an
  // index adder and a shifter across all lanes (timing).
  logic [4*CW-1:0] rd_ax;
  always_comb begin
    rd_ax = '0;
    for (int l = 0; l < 4; l++)
      for (int a = 0; a < Axes; a++)
        if (32'(rs_ax_q) == a) rd_ax[l*CW +: CW] = rd_ax[l*CW +: CW] | rd_q[(l*Axes + a)*CW +: CW];
  end
  always_ff @(posedge clk_i) begin
    for (int l = 0; l < 4; l++) begin
      if (rs_ext_q) hd_q[l*CW +: CW] <= {CW{hd_q[l*CW + CW - 1]}};
      else          hd_q[l*CW +: CW] <= rd_ax[l*CW +: CW];
    end
  end

  // stage 1: BCU s1=A+B, s2=B+C, s3=C+D; INIT e1=D-A, e2=B-C, e3=D-C.
  // Saved carries: cleared (set, for a subtraction) when the digit that will
  // use them (slot rs, next in hd) starts a value.
  logic [CW-1:0] hd_a, hd_b, hd_c, hd_d;
  assign hd_a = hd_q[0*CW +: CW];
  assign hd_b = hd_q[1*CW +: CW];
  assign hd_c = hd_q[2*CW +: CW];
  assign hd_d = hd_q[3*CW +: CW];
  logic [CW:0] s1_sum, s2_sum, s3_sum, e1_sum, e2_sum, e3_sum;
  assign s1_sum = {1'b0, hd_a} + {1'b0, hd_b} + {{CW{1'b0}}, cs1_q};
  assign s2_sum = {1'b0, hd_b} + {1'b0, hd_c} + {{CW{1'b0}}, cs2_q};
  assign s3_sum = {1'b0, hd_c} + {1'b0, hd_d} + {{CW{1'b0}}, cs3_q};
  assign e1_sum = {1'b0, hd_d} + {1'b0, ~hd_a} + {{CW{1'b0}}, ce1_q};
  assign e2_sum = {1'b0, hd_b} + {1'b0, ~hd_c} + {{CW{1'b0}}, ce2_q};
  assign e3_sum = {1'b0, hd_d} + {1'b0, ~hd_c} + {{CW{1'b0}}, ce3_q};
  always_ff @(posedge clk_i) begin
    s1_q  <= s1_sum[CW-1:0];
    s2_q  <= s2_sum[CW-1:0];
    s3_q  <= s3_sum[CW-1:0];
    a1_q  <= hd_a;
    e1_q  <= e1_sum[CW-1:0];
    e2_q  <= e2_sum[CW-1:0];
    e3_q  <= e3_sum[CW-1:0];
    cs1_q <= s1_sum[CW] && !rs_first_q;
    cs2_q <= s2_sum[CW] && !rs_first_q;
    cs3_q <= s3_sum[CW] && !rs_first_q;
    ce1_q <= e1_sum[CW] || rs_first_q;
    ce2_q <= e2_sum[CW] || rs_first_q;
    ce3_q <= e3_sum[CW] || rs_first_q;
  end

  // stage 2: BCU t1=s1+s2, t2=s2+s3; INIT u=e2+e3, y1=6*e1, y2=18*e2.
  logic [CW:0] t1_sum, t2_sum, u_sum, y1_sum, y2_sum;
  assign t1_sum = {1'b0, s1_q} + {1'b0, s2_q} + {{CW{1'b0}}, ct1_q};
  assign t2_sum = {1'b0, s2_q} + {1'b0, s3_q} + {{CW{1'b0}}, ct2_q};
  assign u_sum  = {1'b0, e2_q} + {1'b0, e3_q} + {{CW{1'b0}}, cu_q};
  assign y1_sum = {1'b0, e1_q[CW-3:0], he1_q} + {1'b0, e1_q[CW-2:0], he1_q[1]} + {{CW{1'b0}}, cy1_q};
  assign y2_sum = {1'b0, e2_q[CW-5:0], he2_q} + {1'b0, e2_q[CW-2:0], he2_q[3]} + {{CW{1'b0}}, cy2_q};
  always_ff @(posedge clk_i) begin
    t1_q  <= t1_sum[CW-1:0];
    t2_q  <= t2_sum[CW-1:0];
    a2_q  <= a1_q;
    s12_q <= s1_q;
    u_q   <= u_sum[CW-1:0];
    y1_q  <= y1_sum[CW-1:0];
    y2_q  <= y2_sum[CW-1:0];
    e1d_q <= e1_q;
    ct1_q <= t1_sum[CW] && !hs_first_q;
    ct2_q <= t2_sum[CW] && !hs_first_q;
    cu_q  <= u_sum[CW] && !hs_first_q;
    cy1_q <= y1_sum[CW] && !hs_first_q;
    cy2_q <= y2_sum[CW] && !hs_first_q;
    he1_q <= hs_first_q ? 2'b00 : e1_q[CW-1:CW-2];
    he2_q <= hs_first_q ? 4'b0000 : e2_q[CW-1:CW-4];
  end

  // output stage: BCU m = t1+t2, L = (A<<3, s1<<2, t1<<1, m);
  // INIT S0 = A + half, D1 = e1, D2 = (u<<2)+(u<<1), D3 = y1+y2.
  logic [CW:0]   m_sum, s0_sum, dd2_sum, dd3_sum;
  logic [CW-1:0] half_dig;
  assign half_dig = (32'(s2_dg_q) == HalfDigit) ? CW'(1) << HalfBit : '0;
  assign m_sum   = {1'b0, t1_q} + {1'b0, t2_q} + {{CW{1'b0}}, cm_q};
  assign s0_sum  = {1'b0, a2_q} + {1'b0, half_dig} + {{CW{1'b0}}, cs0_q};
  assign dd2_sum = {1'b0, u_q[CW-3:0], hu_q} + {1'b0, u_q[CW-2:0], hu_q[1]} + {{CW{1'b0}}, cd2_q};
  assign dd3_sum = {1'b0, y1_q} + {1'b0, y2_q} + {{CW{1'b0}}, cd3_q};
  always_ff @(posedge clk_i) begin
    cm_q  <= m_sum[CW] && !s1_first_q;
    cs0_q <= s0_sum[CW] && !s1_first_q;
    cd2_q <= dd2_sum[CW] && !s1_first_q;
    cd3_q <= dd3_sum[CW] && !s1_first_q;
    ha_q  <= s1_first_q ? 3'b000 : a2_q[CW-1:CW-3];
    hs1_q <= s1_first_q ? 2'b00 : s12_q[CW-1:CW-2];
    ht1_q <= s1_first_q ? 1'b0 : t1_q[CW-1];
    hu_q  <= s1_first_q ? 2'b00 : u_q[CW-1:CW-2];
  end

  // write register: LOAD word (one lane) or pass result (4 lanes)
  logic             wl_we;
  logic [MemAB-1:0] wl_addr;
  assign wl_we   = (fsm_q == StLoad) && accept;
  assign wl_addr = {bank_q, wdg_q};
  always_ff @(posedge clk_i) begin
    if (wl_we) begin
      wdata_q <= {4{s_axis_tdata}};
      waddr_q <= wl_addr;
    end else if (s2_init_q) begin
      wdata_q <= {dd3_sum[CW-1:0], dd2_sum[CW-1:0], e1d_q, s0_sum[CW-1:0]};
      waddr_q <= {s2_bank_q, s2_dg_q};
    end else begin
      wdata_q <= {m_sum[CW-1:0], {t1_q[CW-2:0], ht1_q}, {s12_q[CW-3:0], hs1_q}, {a2_q[CW-4:0], ha_q}};
      waddr_q <= {s2_bank_q, s2_dg_q};
    end
  end
  always_ff @(posedge clk_i) begin
    for (int l = 0; l < 4; l++) begin
      for (int a = 0; a < Axes; a++) begin
        if (!rst_ni) begin
          we_q[l*Axes + a] <= 1'b0;
        end else if (wl_we) begin
          we_q[l*Axes + a] <= (wc_q == 2'(l)) && (32'(wax_q) == a);
        end else begin
          we_q[l*Axes + a] <= s2_v_q && (32'(s2_ax_q) == a);
        end
      end
    end
  end

  // ---------------------------------------------------------------------
  // Forward-difference stage: per axis S, D1, D2, D3 of C chunks; chunk k
  // adds with the registered carry of chunk k-1 (one step behind it). All
  // chunks advance together (adv); chunk k loads the new segment where the
  // start tag reaches it (chunk 0: as it enters).
  // ---------------------------------------------------------------------
  logic [Axes*WF-1:0] fs_d, f1_d, f2_d, f3_d;
  logic [Axes*C-1:0]  cs_d, c1_d, c2_d;
  logic [C-1:0]       load_k;
  if (C > 1) begin : g_load
    assign load_k = {tag_start_q[C-2:0], enter_start};
  end else begin : g_load1
    assign load_k = enter_start;
  end
  for (genvar a = 0; a < Axes; a++) begin : g_fd_a
    for (genvar k = 0; k < C; k++) begin : g_fd_k
      localparam int I = a * C + k;
      logic          ci_s, ci_1, ci_2;
      logic [CW:0]   ns, n1, n2;
      logic [CW-1:0] ld_s, ld_1, ld_2, ld_3;
      if (k == 0) begin : g_c0
        assign ci_s = 1'b0;
        assign ci_1 = 1'b0;
        assign ci_2 = 1'b0;
      end else begin : g_cn
        assign ci_s = cs_q[I-1];
        assign ci_1 = c1_q[I-1];
        assign ci_2 = c2_q[I-1];
      end
      assign ld_s = rd_q[(0*Axes + a)*CW +: CW];
      assign ld_1 = rd_q[(1*Axes + a)*CW +: CW];
      assign ld_2 = rd_q[(2*Axes + a)*CW +: CW];
      assign ld_3 = rd_q[(3*Axes + a)*CW +: CW];
      assign ns = {1'b0, fs_q[I*CW +: CW]} + {1'b0, f1_q[I*CW +: CW]} + {{CW{1'b0}}, ci_s};
      assign n1 = {1'b0, f1_q[I*CW +: CW]} + {1'b0, f2_q[I*CW +: CW]} + {{CW{1'b0}}, ci_1};
      assign n2 = {1'b0, f2_q[I*CW +: CW]} + {1'b0, f3_q[I*CW +: CW]} + {{CW{1'b0}}, ci_2};
      assign cs_d[I] = ns[CW];
      assign c1_d[I] = n1[CW];
      assign c2_d[I] = n2[CW];
      assign fs_d[I*CW +: CW] = load_k[k] ? ld_s : ns[CW-1:0];
      assign f1_d[I*CW +: CW] = load_k[k] ? ld_1 : n1[CW-1:0];
      assign f2_d[I*CW +: CW] = load_k[k] ? ld_2 : n2[CW-1:0];
      assign f3_d[I*CW +: CW] = load_k[k] ? ld_3 : f3_q[I*CW +: CW];
    end
  end
  always_ff @(posedge clk_i) begin
    if (adv) begin
      fs_q <= fs_d;
      f1_q <= f1_d;
      f2_q <= f2_d;
      f3_q <= f3_d;
      cs_q <= cs_d;
      c1_q <= c1_d;
      c2_q <= c2_d;
    end
  end

  // Deskew: chunk k (K0 <= k < C-1) waits C-1-k advances, so the slice of
  // the top step is complete; the sample is that slice (no adder).
  logic [Axes*OutWidth-1:0] top_sample;
  for (genvar a = 0; a < Axes; a++) begin : g_out
    // Bits of the step below the slice and above it are not needed.
    /* verilator lint_off UNUSEDSIGNAL */
    logic [WF-1:0] top_val;
    /* verilator lint_on UNUSEDSIGNAL */
    logic [Narrow-1:0] slice;
    assign top_val[(C-1)*CW +: CW] = fs_q[(a*C + C - 1)*CW +: CW];
    for (genvar k = 0; k < C - 1; k++) begin : g_dsk
      if (k < K0) begin : g_low
        assign top_val[k*CW +: CW] = '0;
      end else begin : g_del
        localparam int D = C - 1 - k;
        logic [D*CW-1:0] dsk_q;  // stage i (i advances old) at [i*CW +: CW]
        if (D > 1) begin : g_multi
          always_ff @(posedge clk_i) begin
            if (adv) dsk_q <= {dsk_q[(D-1)*CW-1:0], fs_q[(a*C + k)*CW +: CW]};
          end
        end else begin : g_one
          always_ff @(posedge clk_i) begin
            if (adv) dsk_q <= fs_q[(a*C + k)*CW +: CW];
          end
        end
        assign top_val[k*CW +: CW] = dsk_q[(D-1)*CW +: CW];
      end
    end
    assign slice = top_val[Shift +: Narrow];
    assign top_sample[a*OutWidth +: OutWidth] = OutWidth'($signed(slice));
  end

  // ---------------------------------------------------------------------
  // Ticks and output registers.
  // ---------------------------------------------------------------------
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      tick_q     <= 1'b0;
      tick_err_q <= 1'b0;
      valid_q    <= 1'b0;
      underrun_q <= 1'b0;
      done_q     <= 1'b0;
    end else begin
      tick_q     <= (tick_q && !consume) || tick_i;
      tick_err_q <= tick_err_q || (tick_i && tick_q && !consume);
      valid_q    <= consume && (proc || top_end);
      underrun_q <= under;
      done_q     <= proc && tag_last_q[C-1];
    end
  end
  // Loaded whenever a tick is pending and the top holds a sample or the end
  // value (timing: no stream or FSM term in this wide enable). If the tick is
  // not answered in this cycle (it waits for a newer segment), sample_q may
  // take the end value before the next sample_valid_o; sample_o is defined
  // with sample_valid_o, and every value emitted with it is unchanged.
  always_ff @(posedge clk_i) begin
    if (tick_q && (top_v || top_end)) sample_q <= top_sample;
  end

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Formal properties (scripts/formal.sh: yosys-smtbmc + z3, bounded
  // from reset and induction). The timing copies equal their definitions,
  // and the read-address shortcut (rd_dg) is exact: no transfer step in a
  // pass.
  // ---------------------------------------------------------------------
  logic f_past_valid = 1'b0;
  always_ff @(posedge clk_i) f_past_valid <= 1'b1;
  always_comb begin
    if (!f_past_valid) assume (!rst_ni);
  end
  always_ff @(posedge clk_i) begin
    if (f_past_valid) begin
      // timing copies
      assert (xk1_q == xk_q + 1'b1);
      assert (pc_lt_q == (pc_q < (pass_init ? PcBits'(Ni) : PcBits'(N))));
      assert (pc_end_q == (pc_q == (pass_init ? PcBits'(Pi - 1) : PcBits'(Pp - 1))));
      if (fsm_q == StDesc) assert (lvl_top_q == (lvl_q + 1'b1 == depth_q) && lvl_q < depth_q);
      // (inductive with: pc is 0 outside a pass and within its period in one)
      if (!pass_on) assert (pc_q == '0);
      else assert (pc_q <= (pass_init ? PcBits'(Pi - 1) : PcBits'(Pp - 1)));
      assert (adv_t_q == !(!top_v && top_end && !newer));
      assert (adv_n_q == (!top_v && (!top_end || newer)));
      if (C > 1) begin
        assert (vlo_q == |(tag_v_q & C'((64'd1 << (C - 1)) - 64'd1)));
        assert (slo_q == |(tag_start_q & C'((64'd1 << (C - 1)) - 64'd1)));
      end else begin
        assert (!vlo_q && !slo_q);
      end
      // no transfer step in a pass (rd_dg selects xk1_q over the pass digit)
      assert (!(pass_on && xfer_step));
      // supporting invariants (make the properties inductive): the transfer
      // runs while its start tag is below the top, chunk k+1 is read while
      // the start tag is at k, a pending segment waits with chunk 0 read,
      // and no pass runs while a transfer is pending or running
      assert (!(xpend_q && xbusy_q));
      if (xpend_q) assert (xk_q == '0);
      if (pass_on) assert (!xpend_q && !xbusy_q);
      if (C > 1) begin
        assert (xbusy_q == slo_q);
      end else begin
        assert (!xbusy_q);
      end
      for (int p = 0; p < C - 1; p++) begin
        if (tag_start_q[p]) assert (32'(xk_q) == p + 1);
      end
    end
  end
`endif

  // ---------------------------------------------------------------------
  // Outputs (s_axis_tready is decoded from the FSM state above).
  // ---------------------------------------------------------------------
  assign sample_valid_o = valid_q;
  assign sample_o       = sample_q;
  assign underrun_o     = underrun_q;
  assign seg_done_o     = done_q;
  assign tick_err_o     = tick_err_q;

endmodule

`default_nettype wire
