// trajcore: BCU generator. Samples a cubic Bernstein polynomial per axis at
// t = j/2^d, j = 0..2^d-1, in increasing time order, one sample per tick, by
// depth-first de Casteljau mid-subdivision (scaled form, seed 000) with an
// explicit stack. Mirrors hls/traj_bcu_gen.hpp cycle for cycle; the full
// description (arithmetic, schedule, timing, interface rules) is there and in
// tb/bcu/README.md. In short:
//   * values are WP = Digits*ChunkWidth bits (Digits = ceil((CtrlWidth +
//     3*MaxDepth)/ChunkWidth)), sent by the host pre-scaled by 8^(MaxDepth-d),
//     so every leaf is 8^MaxDepth times the exact value: the output is one
//     fixed bit slice, rounded once, half up.
//   * digit-serial datapath: four lanes (A, B, C, D) rotate by one ChunkWidth
//     digit per cycle through a 2-stage pipelined BCU whose adders are
//     ChunkWidth bits wide with saved carries (as traj_fd_engine): no carry
//     chain longer than ChunkWidth, no chunk-select multiplexer.
//   * stack: MaxDepth*Axes*Digits entries of 4 digits, one write port,
//     synchronous read: block RAM.
//   * ticks at least MinTickSpacing = 3 + 4*N + MaxDepth*(N+2) clocks apart
//     (N = Axes*Digits) are always served with latency 2.
`default_nettype none
`include "traj_check.svh"

module traj_bcu_gen #(
  parameter int Axes       = 3,   // axes in lockstep, 1..8
  parameter int ChunkWidth = 16,  // stream word and carry-chain digit width, 8..64
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
  localparam int W         = CtrlWidth + 3 * MaxDepth;         // value bits needed
  localparam int Digits    = (W + CW - 1) / CW;                 // digits per value
  localparam int WP        = Digits * CW;                       // datapath width
  localparam int N         = Axes * Digits;                     // digits per lane
  localparam int P         = 2;                                 // BCU pipeline latency
  localparam int R         = N + P;                             // ring positions per lane
  localparam int Shift     = 3 * MaxDepth + GuardBits;          // output rounding shift
  localparam int Narrow    = CtrlWidth - GuardBits + ((GuardBits > 0) ? 1 : 0);
  localparam int DepthBits = $clog2(MaxDepth + 1);
  localparam int Stack     = MaxDepth * N;
  localparam int AddrBits  = $clog2(Stack + 1);
  localparam int PcBits    = $clog2(R);
  localparam int LcBits    = (N > 1) ? $clog2(N) : 1;
  localparam int DgBits    = (Digits > 1) ? $clog2(Digits) : 1;
  localparam int LaneW     = R * CW;

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

  localparam logic [2:0] StIdle   = 3'd0;
  localparam logic [2:0] StLoad   = 3'd1;
  localparam logic [2:0] StSettle = 3'd2;
  localparam logic [2:0] StDesc   = 3'd3;
  localparam logic [2:0] StReady  = 3'd4;
  localparam logic [2:0] StPop    = 3'd5;

  // ---------------------------------------------------------------------
  // State. Control is reset; datapath (ring, pipeline, asm, rd, sample,
  // stack, pop address pipeline) is not.
  // ---------------------------------------------------------------------
  logic [2:0]           state_q, state_d;
  logic                 tick_q, tick_err_q, have_last_q, have_last_d;
  logic                 valid_q, valid_d, underrun_q, underrun_d, done_q, done_d;
  logic [DepthBits-1:0] depth_q, depth_d, lvl_q, lvl_d, pop_lvl_q;
  logic [PcBits-1:0]    pc_q, pc_d;
  logic [1:0]           wc_q, wc_d;
  logic [LcBits-1:0]    lc_q, lc_d;
  logic [DgBits-1:0]    dg_q, dg_d;
  logic                 pc_last_q;  // == (pc_q == R-1), a flop for timing
  logic [MaxDepth-1:0]  j_q, j_d;
  logic [AddrBits-1:0]  addr_q, addr_d, pop_base_q;

  logic [4*LaneW-1:0]       ring_q, ring_d;     // lane l position i at [(l*R+i)*CW +: CW]
  logic [3*CW-1:0]          asm_q, asm_d;
  logic [4*CW-1:0]          rd_q;
  logic [Axes*OutWidth-1:0] sample_q, sample_d;
  logic [4*CW-1:0]          stack_mem [2**AddrBits];

  logic accept, consume, mem_we, shift, ins_desc, ins_load, ins_pop;

  // ---------------------------------------------------------------------
  // Digit-serial BCU on the head digits (free running, latency 2).
  //   stage 1: s1 = A+B, s2 = B+C, s3 = C+D
  //   stage 2: t1 = s1+s2, t2 = s2+s3
  //   output : m = t1+t2; L = (A<<3, s1<<2, t1<<1, m), R = (m, t2<<1, s3<<2, D<<3)
  // Carries are saved per adder and cleared at the first digit of a value;
  // shifts take the top bits of the previous digit from small flops.
  // ---------------------------------------------------------------------
  logic [CW-1:0] hd_a, hd_b, hd_c, hd_d;
  assign hd_a = ring_q[(0 * R) * CW +: CW];
  assign hd_b = ring_q[(1 * R) * CW +: CW];
  assign hd_c = ring_q[(2 * R) * CW +: CW];
  assign hd_d = ring_q[(3 * R) * CW +: CW];

  logic          f0, f0_next;
  logic [CW:0]   s1_sum, s2_sum, s3_sum, t1_sum, t2_sum, m_sum;
  logic [CW-1:0] s1_q, s2_q, s3_q, a1_q, d1_q;
  logic          cs1_q, cs2_q, cs3_q, first1_q;
  logic [CW-1:0] t1_q, t2_q, a2_q, s12_q, s32_q, d2_q;
  logic          ct1_q, ct2_q, cm_q;
  logic [2:0]    ha_q, hd_q;
  logic [1:0]    hs1_q, hs3_q;
  logic          ht1_q, ht2_q;

  // Saved carries and shift bits are cleared when they are captured if the
  // digit that will use them is the first of a value, so no adder carry-in
  // and no shifted digit is gated (timing).
  assign f0      = (dg_q == '0);
  // == (dg_d == '0), from flops only (timing)
  assign f0_next = (state_q != StDesc) || pc_last_q || (dg_q == DgBits'(Digits - 1));
  assign s1_sum = {1'b0, hd_a} + {1'b0, hd_b} + {{CW{1'b0}}, cs1_q};
  assign s2_sum = {1'b0, hd_b} + {1'b0, hd_c} + {{CW{1'b0}}, cs2_q};
  assign s3_sum = {1'b0, hd_c} + {1'b0, hd_d} + {{CW{1'b0}}, cs3_q};
  assign t1_sum = {1'b0, s1_q} + {1'b0, s2_q} + {{CW{1'b0}}, ct1_q};
  assign t2_sum = {1'b0, s2_q} + {1'b0, s3_q} + {{CW{1'b0}}, ct2_q};
  assign m_sum  = {1'b0, t1_q} + {1'b0, t2_q} + {{CW{1'b0}}, cm_q};

  always_ff @(posedge clk_i) begin
    s1_q     <= s1_sum[CW-1:0];
    s2_q     <= s2_sum[CW-1:0];
    s3_q     <= s3_sum[CW-1:0];
    cs1_q    <= s1_sum[CW] && !f0_next;
    cs2_q    <= s2_sum[CW] && !f0_next;
    cs3_q    <= s3_sum[CW] && !f0_next;
    a1_q     <= hd_a;
    d1_q     <= hd_d;
    first1_q <= f0;
    t1_q     <= t1_sum[CW-1:0];
    t2_q     <= t2_sum[CW-1:0];
    ct1_q    <= t1_sum[CW] && !f0;
    ct2_q    <= t2_sum[CW] && !f0;
    a2_q     <= a1_q;
    s12_q    <= s1_q;
    s32_q    <= s3_q;
    d2_q     <= d1_q;
    cm_q     <= m_sum[CW] && !first1_q;
    ha_q     <= first1_q ? 3'b000 : a2_q[CW-1:CW-3];
    hs1_q    <= first1_q ? 2'b00 : s12_q[CW-1:CW-2];
    ht1_q    <= first1_q ? 1'b0 : t1_q[CW-1];
    ht2_q    <= first1_q ? 1'b0 : t2_q[CW-1];
    hs3_q    <= first1_q ? 2'b00 : s32_q[CW-1:CW-2];
    hd_q     <= first1_q ? 3'b000 : d2_q[CW-1:CW-3];
  end

  logic [4*CW-1:0] bcu_left, bcu_right;
  assign bcu_left  = {m_sum[CW-1:0], {t1_q[CW-2:0], ht1_q}, {s12_q[CW-3:0], hs1_q},
                      {a2_q[CW-4:0], ha_q}};
  assign bcu_right = {{d2_q[CW-4:0], hd_q}, {s32_q[CW-3:0], hs3_q}, {t2_q[CW-2:0], ht2_q},
                      m_sum[CW-1:0]};

  // ---------------------------------------------------------------------
  // Output rounding, once, half up: floor((x + 2^(Shift-1)) / 2^Shift), of
  // A (READY) and of D (IDLE: the end value of the last leaf) of every axis,
  // registered every cycle (rnd_a_q, rnd_d_q: the sum bits pack into the adders'
  // logic cells). The ring is static in SETTLE/READY and IDLE (no pass), and
  // a tick is processed only from the cycle after SETTLE, resp. in IDLE,
  // which is entered only from READY (or reset, with have_last_q clear), so
  // the registered values are those of the current ring. The sample is then
  // selected from flops (rsel_q == (state_q == StIdle)): no adder is in the
  // path to sample_q.
  // ---------------------------------------------------------------------
  logic                     rsel_q;
  logic [Axes*OutWidth-1:0] rnd_a_q, rnd_d_q, round_x;
  for (genvar a = 0; a < Axes; a++) begin : g_round
    // Bits of xa/xd below the rounding bit, and the sign copies of ha/hd
    // above the Narrow result bits, are not needed (the value fits Narrow bits).
    /* verilator lint_off UNUSEDSIGNAL */
    logic [WP-1:0]              xa, xd;
    logic signed [WP-Shift-1:0] ha, hd;
    /* verilator lint_on UNUSEDSIGNAL */
    logic [Narrow-1:0]          ra, rd;
    assign xa = ring_q[(0 * R + a * Digits) * CW +: WP];
    assign xd = ring_q[(3 * R + a * Digits) * CW +: WP];
    assign ha = xa[WP-1:Shift];
    assign hd = xd[WP-1:Shift];
    assign ra = Narrow'(ha) + {{(Narrow-1){1'b0}}, xa[Shift-1]};
    assign rd = Narrow'(hd) + {{(Narrow-1){1'b0}}, xd[Shift-1]};
    always_ff @(posedge clk_i) begin
      rnd_a_q[a*OutWidth +: OutWidth] <= OutWidth'($signed(ra));
      rnd_d_q[a*OutWidth +: OutWidth] <= OutWidth'($signed(rd));
    end
  end
  assign round_x = rsel_q ? rnd_d_q : rnd_a_q;

  // ---------------------------------------------------------------------
  // Pop address pipeline, three registers: the lowest zero bit of j (one-hot,
  // ~j & (j+1)), its index = trailing ones of j, p = depth-1-that, then p*N.
  // j only changes at a processed tick and READY comes at least R cycles later.
  // ---------------------------------------------------------------------
  logic [MaxDepth-1:0]  zero_oh_q;
  logic [DepthBits-1:0] tones;
  always_comb begin
    tones = '0;
    for (int i = 0; i < MaxDepth; i++) begin
      if (zero_oh_q[i]) tones = tones | DepthBits'(i);
    end
  end
  always_ff @(posedge clk_i) begin
    zero_oh_q  <= ~j_q & (j_q + 1'b1);
    pop_lvl_q  <= depth_q - 1'b1 - tones;
    pop_base_q <= AddrBits'(pop_lvl_q) * AddrBits'(N);
  end

  // Header word: depth, clamped to MaxDepth.
  logic [DepthBits-1:0] hdr_depth;
  // The comparison is constant when MaxDepth+1 is a power of two (no value of
  // the field exceeds MaxDepth); it is kept for every other MaxDepth.
  /* verilator lint_off CMPCONST */
  assign hdr_depth = (s_axis_tdata[DepthBits-1:0] > DepthBits'(MaxDepth))
                   ? DepthBits'(MaxDepth) : s_axis_tdata[DepthBits-1:0];
  /* verilator lint_on CMPCONST */

  // j == 2^d - 1 (the last leaf), registered: j and d are stable for many
  // cycles before READY (at least R after a tick, 4*N after a header).
  // Likewise the level compares of the pass ends (lvl changes at most once
  // per pass, R cycles apart).
  logic is_last_q, desc_last_q, lvl_eq_q;
  always_ff @(posedge clk_i) begin
    is_last_q   <= (j_q == ~({MaxDepth{1'b1}} << depth_q));
    desc_last_q <= (lvl_q + 1'b1 == depth_q);
    lvl_eq_q    <= (lvl_q == depth_q);
  end

  assign s_axis_tready = (state_q == StIdle) || (state_q == StLoad);
  assign accept        = s_axis_tready && s_axis_tvalid;

  // ---------------------------------------------------------------------
  // Next state (mirrors BcuGen::clock).
  // ---------------------------------------------------------------------
  always_comb begin
    state_d     = state_q;
    have_last_d = have_last_q;
    valid_d     = 1'b0;
    underrun_d  = 1'b0;
    done_d      = 1'b0;
    depth_d     = depth_q;
    lvl_d       = lvl_q;
    pc_d        = pc_q;
    wc_d        = wc_q;
    lc_d        = lc_q;
    j_d         = j_q;
    addr_d      = addr_q;
    asm_d       = asm_q;
    sample_d    = sample_q;
    consume     = 1'b0;
    mem_we      = 1'b0;
    shift       = 1'b0;
    ins_desc    = 1'b0;
    ins_load    = 1'b0;
    ins_pop     = 1'b0;

    unique case (state_q)
      StIdle: begin
        // Timing: only the state (and the tick) depend on accept. depth is
        // taken from every word offered in IDLE (the accepted header is the
        // last one), j, lvl and addr are cleared in every IDLE cycle (unused
        // there), and wc, lc and pc are always 0 in IDLE.
        depth_d = hdr_depth;
        j_d     = '0;
        lvl_d   = '0;
        addr_d  = '0;
        if (accept) begin
          state_d = StLoad;
        end else if (tick_q) begin
          consume    = 1'b1;
          underrun_d = 1'b1;
          if (have_last_q) begin
            valid_d  = 1'b1;
            sample_d = round_x;
          end
        end
      end
      StLoad: begin
        if (accept) begin
          if (wc_q == 2'd3) begin
            wc_d     = '0;
            shift    = 1'b1;
            ins_load = 1'b1;
            if (lc_q == LcBits'(N - 1)) begin
              lc_d    = '0;
              state_d = (depth_q == '0) ? StSettle : StDesc;
            end else begin
              lc_d = lc_q + 1'b1;
            end
          end else begin
            asm_d[wc_q*CW +: CW] = s_axis_tdata;
            wc_d                 = wc_q + 1'b1;
          end
        end
      end
      StDesc: begin
        shift    = 1'b1;
        ins_desc = 1'b1;
        if (pc_q >= PcBits'(P)) begin
          mem_we = 1'b1;
          addr_d = addr_q + 1'b1;
        end
        if (pc_last_q) begin
          pc_d  = '0;
          lvl_d = lvl_q + 1'b1;
          if (desc_last_q) state_d = StSettle;
        end else begin
          pc_d = pc_q + 1'b1;
        end
      end
      StSettle: begin
        // one cycle for the registered output rounding (rnd_a_q) to see the leaf
        state_d = StReady;
      end
      StReady: begin
        if (tick_q) begin
          consume  = 1'b1;
          valid_d  = 1'b1;
          sample_d = round_x;
          if (is_last_q) begin
            done_d      = 1'b1;
            have_last_d = 1'b1;
            state_d     = StIdle;
          end else begin
            lvl_d   = pop_lvl_q + 1'b1;
            addr_d  = pop_base_q;
            pc_d    = '0;
            j_d     = j_q + 1'b1;
            state_d = StPop;
          end
        end
      end
      StPop: begin
        shift   = 1'b1;
        ins_pop = 1'b1;
        if (pc_q < PcBits'(N)) addr_d = addr_q + 1'b1;
        if (pc_last_q) begin
          pc_d    = '0;
          state_d = lvl_eq_q ? StSettle : StDesc;
        end else begin
          pc_d = pc_q + 1'b1;
        end
      end
      default: begin
        state_d = StIdle;
      end
    endcase

    // digit index of the head digit (0 = first digit of a value)
    if (state_q == StDesc && !pc_last_q) begin
      dg_d = (dg_q == DgBits'(Digits - 1)) ? '0 : dg_q + 1'b1;
    end else begin
      dg_d = '0;
    end
  end

  // ---------------------------------------------------------------------
  // Ring: rotate every lane right by one digit; the new digits of a pass
  // enter at position N-1 (BCU output, load) or N (stack read data).
  // ---------------------------------------------------------------------
  logic [4*CW-1:0] load_quad;
  assign load_quad = {s_axis_tdata, asm_q};
  for (genvar l = 0; l < 4; l++) begin : g_lane
    logic [LaneW-1:0] lane, rot;
    assign lane = ring_q[l*LaneW +: LaneW];
    assign rot  = {lane[CW-1:0], lane[LaneW-1:CW]};
    always_comb begin
      ring_d[l*LaneW +: LaneW] = rot;
      if (ins_desc) ring_d[(l*R + N - 1)*CW +: CW] = bcu_left[l*CW +: CW];
      if (ins_load) ring_d[(l*R + N - 1)*CW +: CW] = load_quad[l*CW +: CW];
      if (ins_pop)  ring_d[(l*R + N)*CW +: CW]     = rd_q[l*CW +: CW];
    end
  end

  // ---------------------------------------------------------------------
  // Registers.
  // ---------------------------------------------------------------------
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      state_q     <= StIdle;
      tick_q      <= 1'b0;
      tick_err_q  <= 1'b0;
      have_last_q <= 1'b0;
      valid_q     <= 1'b0;
      underrun_q  <= 1'b0;
      done_q      <= 1'b0;
      depth_q     <= '0;
      lvl_q       <= '0;
      pc_q        <= '0;
      wc_q        <= '0;
      lc_q        <= '0;
      dg_q        <= '0;
      pc_last_q   <= 1'b0;
      j_q         <= '0;
      addr_q      <= '0;
      rsel_q      <= 1'b1;
    end else begin
      state_q     <= state_d;
      tick_q      <= (tick_q && !consume) || tick_i;
      tick_err_q  <= tick_err_q || (tick_i && tick_q && !consume);
      have_last_q <= have_last_d;
      valid_q     <= valid_d;
      underrun_q  <= underrun_d;
      done_q      <= done_d;
      depth_q     <= depth_d;
      lvl_q       <= lvl_d;
      pc_q        <= pc_d;
      wc_q        <= wc_d;
      lc_q        <= lc_d;
      dg_q        <= dg_d;
      pc_last_q   <= (pc_d == PcBits'(R - 1));
      j_q         <= j_d;
      addr_q      <= addr_d;
      rsel_q      <= (state_d == StIdle);
    end
  end

  always_ff @(posedge clk_i) begin
    if (shift) ring_q <= ring_d;
    asm_q    <= asm_d;
    sample_q <= sample_d;
  end

  // Stack: one write port, synchronous read (block RAM).
  always_ff @(posedge clk_i) begin
    if (mem_we) stack_mem[addr_q] <= bcu_right;
    rd_q <= stack_mem[addr_q];
  end

  assign sample_valid_o = valid_q;
  assign sample_o       = sample_q;
  assign underrun_o     = underrun_q;
  assign seg_done_o     = done_q;
  assign tick_err_o     = tick_err_q;

endmodule

`default_nettype wire
