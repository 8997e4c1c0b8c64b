// trajcore: BCU generator. Samples a cubic Bernstein polynomial per axis at
// t = j/2^d, j = 0..2^d-1, in increasing time order, one sample per tick, by
// depth-first de Casteljau mid-subdivision (traj_bcu, scaled form) with an
// explicit stack. Mirrors hls/traj_bcu_gen.hpp cycle for cycle; the full
// description (arithmetic, schedule, timing, interface rules) is there and in
// tb/bcu/README.md. In short:
//   * W = CtrlWidth + 3*MaxDepth bits per coefficient; after loading, values
//     are multiplied by 8^(MaxDepth-d) (PRE), so every leaf is 8^MaxDepth times
//     the exact value: the output is one fixed bit slice, rounded once, half up.
//   * one BCU, shared by the axes: cur_q is a ring of Axes quaternions that
//     rotates by one quaternion per cycle through the BCU (DESC) or the stack
//     read port (POP).
//   * stack: MaxDepth*Axes entries of 4*W bits, one write port, synchronous
//     read: block RAM. Entry lvl*Axes+a = right half pushed by axis a at lvl.
//   * ticks at least MinTickSpacing = 3 + 4*Axes*Words + MaxDepth*Axes clocks
//     apart are always served with latency 2 (tick_i -> sample_valid_o).
`default_nettype none
`include "traj_check.svh"

module traj_bcu_gen #(
  parameter int Axes       = 3,   // axes in lockstep, 1..8
  parameter int ChunkWidth = 32,  // stream word width, 8..64
  parameter int CtrlWidth  = 40,  // control value width, >= 2, CtrlWidth+3*MaxDepth <= 128
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

  localparam int W         = CtrlWidth + 3 * MaxDepth;         // datapath width
  localparam int Words     = (CtrlWidth + ChunkWidth - 1) / ChunkWidth;
  localparam int AsmWidth  = Words * ChunkWidth;
  localparam int Shift     = 3 * MaxDepth + GuardBits;         // output rounding shift
  localparam int Narrow    = CtrlWidth - GuardBits + ((GuardBits > 0) ? 1 : 0);
  localparam int DepthBits = $clog2(MaxDepth + 1);
  localparam int Stack     = MaxDepth * Axes;
  localparam int AddrBits  = $clog2(Stack + 1);
  localparam int AxBits    = $clog2(Axes + 1);
  localparam int VcBits    = $clog2(4 * Axes);
  localparam int WcBits    = (Words > 1) ? $clog2(Words) : 1;
  localparam int QW        = 4 * W;                            // one quaternion
  // Minimum tick spacing (clocks), see the header: 3 + 4*Axes*Words + MaxDepth*Axes.

  // ---------------------------------------------------------------------
  // Elaboration-time parameter checks.
  // ---------------------------------------------------------------------
  `TRAJ_PARAM_CHECK(g_bad_axes, Axes >= 1 && Axes <= 8, "traj_bcu_gen: Axes must be 1..8")
  `TRAJ_PARAM_CHECK(g_bad_chunk, ChunkWidth >= 8 && ChunkWidth <= 64,
                    "traj_bcu_gen: ChunkWidth must be 8..64")
  `TRAJ_PARAM_CHECK(g_bad_depth, MaxDepth >= 1 && MaxDepth <= 30,
                    "traj_bcu_gen: MaxDepth must be 1..30")
  `TRAJ_PARAM_CHECK(g_bad_ctrl, CtrlWidth >= 2 && CtrlWidth + 3 * MaxDepth <= 128,
                    "traj_bcu_gen: CtrlWidth must be >= 2 with CtrlWidth+3*MaxDepth <= 128")
  `TRAJ_PARAM_CHECK(g_bad_guard, GuardBits >= 0 && GuardBits <= CtrlWidth - 2,
                    "traj_bcu_gen: GuardBits must be 0..CtrlWidth-2")
  `TRAJ_PARAM_CHECK(g_bad_out, OutWidth >= Narrow && OutWidth <= 64,
                    "traj_bcu_gen: OutWidth must be CtrlWidth-GuardBits+(GuardBits>0)..64")
  `TRAJ_PARAM_CHECK(g_bad_hdr, DepthBits <= ChunkWidth,
                    "traj_bcu_gen: the depth field must fit one stream word")

  localparam logic [2:0] StIdle  = 3'd0;
  localparam logic [2:0] StLoad  = 3'd1;
  localparam logic [2:0] StPre   = 3'd2;
  localparam logic [2:0] StDesc  = 3'd3;
  localparam logic [2:0] StReady = 3'd4;
  localparam logic [2:0] StPop   = 3'd5;

  // ---------------------------------------------------------------------
  // State. Control is reset; datapath (cur, asm, rd, sample, last, stack) not.
  // ---------------------------------------------------------------------
  logic [2:0]           state_q, state_d;
  logic                 tick_q, tick_err_q, have_last_q, have_last_d;
  logic                 valid_q, valid_d, underrun_q, underrun_d, done_q, done_d;
  logic [DepthBits-1:0] depth_q, depth_d, cnt_q, cnt_d, lvl_q, lvl_d, pidx_q, pidx_d;
  logic [AxBits-1:0]    ax_q, ax_d;
  logic [WcBits-1:0]    wc_q, wc_d;
  logic [VcBits-1:0]    vc_q, vc_d;
  logic [MaxDepth-1:0]  j_q, j_d;
  logic [AddrBits-1:0]  addr_q, addr_d;   // stack address: lvl*Axes+ax (DESC), pidx*Axes+ax (POP)

  logic [Axes*QW-1:0]        cur_q, cur_d;
  logic [AsmWidth-1:0]       asm_q, asm_d;
  logic [QW-1:0]             rd_q;
  logic [Axes*OutWidth-1:0]  sample_q, sample_d, last_q, last_d;
  logic [QW-1:0]             stack_mem [2**AddrBits];

  logic                 accept, consume, mem_we;

  // ---------------------------------------------------------------------
  // The BCU on the head quaternion (axis at ring position 0). Its inputs are
  // at effective level <= MaxDepth-1, so they fit W-3 bits.
  // ---------------------------------------------------------------------
  logic [4*(W-3)-1:0] bcu_in;
  logic [QW-1:0]      bcu_left, bcu_right;
  for (genvar k = 0; k < 4; k++) begin : g_bcu_in
    assign bcu_in[k*(W-3) +: W-3] = cur_q[k*W +: W-3];
  end
  traj_bcu #(.InWidth(W - 3)) u_bcu (
    .coef_i(bcu_in), .left_o(bcu_left), .right_o(bcu_right)
  );

  // ---------------------------------------------------------------------
  // Output rounding, once, half up: floor((x + 2^(Shift-1)) / 2^Shift).
  // ---------------------------------------------------------------------
  logic [Axes*OutWidth-1:0] round_a, round_d;
  for (genvar a = 0; a < Axes; a++) begin : g_round
    logic [W-1:0]               xa, xd;
    logic signed [W-Shift-1:0]  ha, hd;
    logic [Narrow-1:0]          ra, rd;
    assign xa = cur_q[(4*a+0)*W +: W];
    assign xd = cur_q[(4*a+3)*W +: W];
    assign ha = xa[W-1:Shift];
    assign hd = xd[W-1:Shift];
    assign ra = Narrow'(ha) + {{(Narrow-1){1'b0}}, xa[Shift-1]};
    assign rd = Narrow'(hd) + {{(Narrow-1){1'b0}}, xd[Shift-1]};
    assign round_a[a*OutWidth +: OutWidth] = OutWidth'($signed(ra));
    assign round_d[a*OutWidth +: OutWidth] = OutWidth'($signed(rd));
  end

  // ---------------------------------------------------------------------
  // Trailing ones of j: the next leaf is the right half pushed at level
  // depth-1-trailing_ones(j).
  // ---------------------------------------------------------------------
  logic [DepthBits-1:0] tones, pop_idx;
  always_comb begin
    logic stop;
    stop  = 1'b0;
    tones = '0;
    for (int i = 0; i < MaxDepth; i++) begin
      if (!stop) begin
        if (j_q[i]) tones = tones + 1'b1;
        else stop = 1'b1;
      end
    end
  end

  assign pop_idx = depth_q - 1'b1 - tones;

  // Header word: depth, clamped to MaxDepth.
  logic [DepthBits-1:0] hdr_depth;
  // The comparison is constant when MaxDepth+1 is a power of two (no value of
  // the field exceeds MaxDepth); it is kept for every other MaxDepth.
  /* verilator lint_off CMPCONST */
  assign hdr_depth = (s_axis_tdata[DepthBits-1:0] > DepthBits'(MaxDepth))
                   ? DepthBits'(MaxDepth) : s_axis_tdata[DepthBits-1:0];
  /* verilator lint_on CMPCONST */

  // Completed control value (sign-extended to W).
  logic [W-1:0] load_val;
  assign load_val = W'($signed(asm_d[CtrlWidth-1:0]));

  // last sample index of the segment: 2^d - 1
  logic [MaxDepth-1:0] last_j;
  assign last_j = MaxDepth'((MaxDepth+1)'(1) << depth_q) - 1'b1;

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
    cnt_d       = cnt_q;
    lvl_d       = lvl_q;
    pidx_d      = pidx_q;
    ax_d        = ax_q;
    wc_d        = wc_q;
    vc_d        = vc_q;
    j_d         = j_q;
    addr_d      = addr_q;
    cur_d       = cur_q;
    asm_d       = (asm_q >> ChunkWidth) | (AsmWidth'(s_axis_tdata) << ((Words - 1) * ChunkWidth));
    sample_d    = sample_q;
    last_d      = last_q;
    consume     = 1'b0;
    mem_we      = 1'b0;

    unique case (state_q)
      StIdle: begin
        if (accept) begin
          depth_d = hdr_depth;
          cnt_d   = DepthBits'(MaxDepth) - hdr_depth;
          wc_d    = '0;
          vc_d    = '0;
          j_d     = '0;
          lvl_d   = '0;
          ax_d    = '0;
          addr_d  = '0;
          state_d = StLoad;
        end else if (tick_q) begin
          consume    = 1'b1;
          underrun_d = 1'b1;
          if (have_last_q) begin
            valid_d  = 1'b1;
            sample_d = last_q;
          end
        end
      end
      StLoad: begin
        if (accept) begin
          if (wc_q == WcBits'(Words - 1)) begin
            wc_d  = '0;
            cur_d = (cur_q >> W) | ((Axes*QW)'(load_val) << ((4 * Axes - 1) * W));
            if (vc_q == VcBits'(4 * Axes - 1)) begin
              vc_d    = '0;
              state_d = StPre;
            end else begin
              vc_d = vc_q + 1'b1;
            end
          end else begin
            wc_d = wc_q + 1'b1;
          end
        end
      end
      StPre: begin
        if (cnt_q != '0) begin
          cnt_d = cnt_q - 1'b1;
          for (int v = 0; v < 4 * Axes; v++) begin
            cur_d[v*W +: W] = {cur_q[v*W +: W-3], 3'b000};
          end
        end else begin
          state_d = (depth_q == '0) ? StReady : StDesc;
        end
      end
      StDesc: begin
        cur_d  = (cur_q >> QW) | ((Axes*QW)'(bcu_left) << ((Axes - 1) * QW));
        mem_we = 1'b1;
        addr_d = addr_q + 1'b1;
        if (ax_q == AxBits'(Axes - 1)) begin
          ax_d  = '0;
          lvl_d = lvl_q + 1'b1;
          if (lvl_q + 1'b1 == depth_q) state_d = StReady;
        end else begin
          ax_d = ax_q + 1'b1;
        end
      end
      StReady: begin
        if (tick_q) begin
          consume  = 1'b1;
          valid_d  = 1'b1;
          sample_d = round_a;
          if (j_q == last_j) begin
            done_d      = 1'b1;
            have_last_d = 1'b1;
            last_d      = round_d;
            state_d     = StIdle;
          end else begin
            pidx_d  = pop_idx;
            lvl_d   = depth_q - tones;
            addr_d  = AddrBits'(pop_idx) * AddrBits'(Axes);
            ax_d    = '0;
            j_d     = j_q + 1'b1;
            state_d = StPop;
          end
        end
      end
      StPop: begin
        if (ax_q != '0) begin
          cur_d = (cur_q >> QW) | ((Axes*QW)'(rd_q) << ((Axes - 1) * QW));
        end
        if (ax_q == AxBits'(Axes)) begin
          ax_d    = '0;
          state_d = (lvl_q == depth_q) ? StReady : StDesc;
        end else begin
          ax_d   = ax_q + 1'b1;
          addr_d = addr_q + 1'b1;
        end
      end
      default: begin
        state_d = StIdle;
      end
    endcase
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
      cnt_q       <= '0;
      lvl_q       <= '0;
      pidx_q      <= '0;
      ax_q        <= '0;
      wc_q        <= '0;
      vc_q        <= '0;
      j_q         <= '0;
      addr_q      <= '0;
    end else begin
      state_q     <= state_d;
      tick_q      <= (tick_q && !consume) || tick_i;
      tick_err_q  <= tick_err_q || (tick_i && tick_q && !consume);
      have_last_q <= have_last_d;
      valid_q     <= valid_d;
      underrun_q  <= underrun_d;
      done_q      <= done_d;
      depth_q     <= depth_d;
      cnt_q       <= cnt_d;
      lvl_q       <= lvl_d;
      pidx_q      <= pidx_d;
      ax_q        <= ax_d;
      wc_q        <= wc_d;
      vc_q        <= vc_d;
      j_q         <= j_d;
      addr_q      <= addr_d;
    end
  end

  always_ff @(posedge clk_i) begin
    cur_q    <= cur_d;
    sample_q <= sample_d;
    last_q   <= last_d;
    if (accept && state_q == StLoad) asm_q <= asm_d;
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
