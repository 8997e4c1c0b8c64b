// SPDX-License-Identifier: Apache-2.0
// trajcore: the core, one segment stream for both sampling engines
// (traj_fd_engine, or with FdTimeMux traj_fd_tm, and traj_bcu_gen). Mirrors
// hls/traj_core.hpp cycle for cycle; the full description is there and in
// rtl/README.md. In short:
//   * one ChunkWidth-bit AXI4-Stream segment input behind a register slice
//     (traj_skid: s_axis_tready is a flop), and a register slice in front of
//     each engine (an engine's tready reaches its slice and the segment
//     count, never the router's forwarding); s_axis_tuser = segment kind
//     (0 = forward differences, 1 = BCU), sampled on the first word of every
//     segment. Segment lengths are fixed per kind (each engine's own format),
//     so the router counts words and forwards each segment, in order, to its
//     engine (back-pressure while that engine cannot take it). The next
//     segment of the other kind loads while the current one plays; the BCU
//     generator also takes its own next segments while it plays.
//   * ticks go to the engine owning the oldest segment in flight (counted
//     the clock after its engine takes the segment's first word, dropped on
//     its engine's seg_done, seen in the same cycle: up to 3 BCU segments and
//     1 FD segment, with the number of BCU segments older than the FD one),
//     else to the engine of the last segment. Within a run of BCU segments ticks may come
//     on every clock. Tick contract per engine: the FD engine takes a tick on
//     a rising edge of its tick (high two cycles in a row = one tick and
//     tick_err); the BCU generator takes one tick per cycle its tick is high
//     (its one-sample-per-clock rate). The core counts FD ticks as the FD
//     engine does.
//   * one sample output, same ports and latency as the engines: the
//     sample of the engine that emitted last; on an underrun it holds.
`default_nettype none
`include "traj_check.svh"

module traj_core #(
  parameter int Axes         = 3,   // axes in lockstep, 1..8 (both engines)
  parameter int Degree       = 3,   // FD polynomial degree, 1..7
  parameter int Width        = 64,  // FD register width, multiple of ChunkWidth, <= 128
  parameter int ChunkWidth   = 16,  // stream word and carry-chain width: 16, 32 or 64
  parameter int GuardBits    = 32,  // FD register bits below the output LSB
  parameter int CtrlWidth    = 40,  // BCU control value width
  parameter int BcuGuardBits = 9,   // BCU control bits below the output LSB
  parameter int MaxDepth     = 12,  // BCU largest depth d (K = 2^d)
  parameter int FdTimeMux    = 0,   // FD engine: 1 = traj_fd_tm (one adder, registers in block RAM)
  // derived, do not override: the common sample width of both engines
  parameter int OutWidth     = Width - GuardBits
) (
  input  logic                     clk_i,
  input  logic                     rst_ni,
  // segment word stream; tuser = kind (0 FD, 1 BCU), sampled on the first word
  input  logic [ChunkWidth-1:0]    s_axis_tdata,
  input  logic                     s_axis_tuser,
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

  // Segment lengths in words (the engines' stream formats).
  localparam int FdHdrWords = (ChunkWidth < 32) ? 32 / ChunkWidth : 1;
  localparam int FdWords    = FdHdrWords + Axes * (Degree + 1) * (Width / ChunkWidth);
  localparam int BcuDigits  = (CtrlWidth + 3 * MaxDepth + ChunkWidth - 1) / ChunkWidth;
  localparam int BcuWords   = 1 + 4 * Axes * BcuDigits;
  localparam int MaxWords   = (FdWords > BcuWords) ? FdWords : BcuWords;
  localparam int RemBits    = $clog2(MaxWords);
  localparam int BcuNarrow  = CtrlWidth - BcuGuardBits + ((BcuGuardBits > 0) ? 1 : 0);

  // The engines check their own parameters; the core checks the shared format.
  `TRAJ_PARAM_CHECK(g_bad_outwidth, OutWidth == Width - GuardBits,
                    "traj_core: OutWidth is derived (Width-GuardBits); do not override it")
  `TRAJ_PARAM_CHECK(g_bad_fdtm, FdTimeMux == 0 || FdTimeMux == 1, "traj_core: FdTimeMux must be 0 or 1")
  `TRAJ_PARAM_CHECK(g_bad_bcu_fit, BcuNarrow <= OutWidth,
                    "traj_core: the BCU sample (CtrlWidth-BcuGuardBits+1 bits) must fit the FD output width")

  // ---------------------------------------------------------------------
  // State (Core::Regs, same names, same order) and signals, declared before
  // use. Router: control, all reset. Input slice: valid bits reset, data not.
  // ---------------------------------------------------------------------
  // router and segments in flight
  logic               in_seg_q, kind_q, last_kind_q, sel_q, primed_q;
  logic [1:0]         nb_q, fpos_q;
  logic               fdf_q;
  logic [RemBits-1:0] rem_q;
  logic [1:0]         pend_fd_q, pend_bcu_q;
  logic               fd_tick_q;  // fd_tick of the previous cycle: the FD engine takes rising edges only
  logic               err_q;
  // input register slice (u_in) and the kind of the word in it, registered
  logic                  out_v_d, out_u_d, fd_v_q, bcu_v_q;
  logic [ChunkWidth-1:0] out_d_q;
  /* verilator lint_off UNUSEDSIGNAL */
  // slice outputs the core does not read: the input slice's valid and kind
  // (re-encoded in fd_v_q/bcu_v_q) and its next word's data, the engine
  // slices' next state
  logic                  out_v_q, out_u_q, fd_nv, bcu_nv;
  logic [ChunkWidth-1:0] out_dd;
  logic [ChunkWidth:0]   fd_nd, bcu_nd;
  /* verilator lint_on UNUSEDSIGNAL */
  // the engines' register slices (u_fd_in, u_bcu_in)
  logic                  fd_in_ready, bcu_in_ready, fd_first, bcu_first;
  logic [ChunkWidth-1:0] fd_tdata, bcu_tdata;
  // engine ports
  logic                     fd_tvalid, fd_tready, fd_tick;
  logic                     fd_valid, fd_underrun, fd_done, fd_err;
  logic [Axes*OutWidth-1:0] fd_sample;
  logic                     bcu_tvalid, bcu_tready, bcu_tick;
  logic                     bcu_valid, bcu_underrun, bcu_done, bcu_err;
  logic [Axes*OutWidth-1:0] bcu_sample;
  // next-state decode
  logic       in_seg_d, kind_d, kind_nx;
  logic       accept, first, push, push_b, push_q, push_b_q, pop_b, pop_f, owner1, last1, tick_kind;
  logic [1:0] nb1, fpos1, pf, pb;
  logic       fdf1;
  logic       sel_now, fd_real, bcu_real;

  // ---------------------------------------------------------------------
  // Router and segments in flight: nb_q BCU segments (playing, prepared,
  // loading: 0..3), fdf_q an FD segment (at most one), fpos_q BCU segments
  // older than it. Counted the clock after its engine takes a segment's first
  // word, dropped on its engine's seg_done (each engine finishes in order).
  // State is control: all reset.
  // ---------------------------------------------------------------------
  assign accept        = (fd_v_q && fd_in_ready) || (bcu_v_q && bcu_in_ready);
  // a segment's first word: the router marks it (first), and the segment is
  // counted in flight the clock after its engine takes that word (push,
  // registered: push_q; a tick then cannot find the segment loaded yet)
  assign first         = accept && !in_seg_q;
  assign push_b        = bcu_tvalid && bcu_tready && bcu_first;
  assign push          = (fd_tvalid && fd_tready && fd_first) || push_b;
  assign pop_b         = (nb_q != 2'd0) && bcu_done;
  assign pop_f         = fdf_q && fd_done;
  assign nb1           = nb_q - {1'b0, pop_b};
  assign fdf1          = fdf_q && !pop_f;
  assign fpos1         = (pop_b && fpos_q != 2'd0) ? fpos_q - 1'b1 : fpos_q;
  assign last1         = pop_b ? 1'b1 : (pop_f ? 1'b0 : last_kind_q);
  assign owner1        = fdf1 || (nb1 != 2'd0) || push_q;
  always_comb begin
    if (fdf1 && fpos1 == 2'd0) tick_kind = 1'b0;
    else if (nb1 != 2'd0)      tick_kind = 1'b1;
    else if (fdf1)             tick_kind = 1'b0;
    else if (push_q)           tick_kind = push_b_q;
    else                       tick_kind = last1;
  end

  assign fd_tick    = tick_i && !tick_kind;
  assign bcu_tick   = tick_i && tick_kind;

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      in_seg_q    <= 1'b0;
      kind_q      <= 1'b0;
      rem_q       <= '0;
      nb_q        <= '0;
      fdf_q       <= 1'b0;
      fpos_q      <= '0;
      last_kind_q <= 1'b0;
      push_q      <= 1'b0;
      push_b_q    <= 1'b0;
      sel_q       <= 1'b0;
      primed_q    <= 1'b0;
      pend_fd_q   <= '0;
      fd_tick_q   <= 1'b0;
      pend_bcu_q  <= '0;
      err_q       <= 1'b0;
    end else begin
      in_seg_q <= in_seg_d;
      kind_q   <= kind_d;
      if (accept) begin
        rem_q <= in_seg_q ? rem_q - 1'b1
                          : (bcu_v_q ? RemBits'(BcuWords - 1) : RemBits'(FdWords - 1));
      end
      last_kind_q <= last1;
      nb_q        <= nb1 + {1'b0, push_b_q};
      fdf_q       <= fdf1 || (push_q && !push_b_q);
      fpos_q      <= (push_q && !push_b_q) ? nb1 : fpos1;
      push_q      <= push;
      push_b_q    <= push_b;
      sel_q      <= sel_now;
      primed_q   <= primed_q || fd_real || bcu_real;
      fd_tick_q  <= fd_tick;
      pend_fd_q  <= pf + {1'b0, fd_tick && !fd_tick_q};
      pend_bcu_q <= pb + {1'b0, bcu_tick};
      if ((pop_b && pb != 2'd0 && owner1 && !tick_kind) || (pop_f && pf != 2'd0 && owner1 && tick_kind))
        err_q <= 1'b1;
    end
  end

  // Pending ticks per engine: +1 per routed tick, -1 per answer (every
  // processed tick gives sample_valid or underrun one cycle later). If the
  // owner of a finished segment still holds a tick while the next segment in
  // flight is the other engine's, that tick would be served out of order:
  // sticky error, reported on tick_err_o.
  assign pf = pend_fd_q - {1'b0, fd_valid || fd_underrun};
  assign pb = pend_bcu_q - {1'b0, bcu_valid || bcu_underrun};

  // ---------------------------------------------------------------------
  // Input register slice: s_axis_tready is a flop; the router sees its
  // output. Per-engine valid, registered (timing): fd_v_q/bcu_v_q hold
  // exactly out_v_q && kind of the word in the slice's output (in_seg_q ?
  // kind_q : out_u_q), computed from the next-state values, so the kind
  // decode is off the router's handshake path. This is a re-encoding, not a
  // new pipeline stage. Where out_v_q is known to be set (accept, first) the
  // word's kind is bcu_v_q.
  // ---------------------------------------------------------------------
  traj_skid #(.Width(ChunkWidth + 1)) u_in (
    .clk_i, .rst_ni,
    .data_i({s_axis_tuser, s_axis_tdata}), .valid_i(s_axis_tvalid), .ready_o(s_axis_tready),
    .data_o({out_u_q, out_d_q}), .valid_o(out_v_q), .ready_i(accept),
    .valid_d_o(out_v_d), .data_d_o({out_u_d, out_dd})
  );
  assign in_seg_d = accept ? (!in_seg_q || rem_q != RemBits'(1)) : in_seg_q;
  assign kind_d   = first ? bcu_v_q : kind_q;
  assign kind_nx  = in_seg_d ? kind_d : out_u_d;
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      fd_v_q  <= 1'b0;
      bcu_v_q <= 1'b0;
    end else begin
      fd_v_q  <= out_v_d && !kind_nx;
      bcu_v_q <= out_v_d && kind_nx;
    end
  end

  // ---------------------------------------------------------------------
  // The engines' register slices: the router hands a word to the slice of
  // its kind, with a bit that marks a segment's first word; the engine's
  // tready reaches no further than its slice and the segment count (the
  // slices' readies and the engines' tvalids are flops).
  // ---------------------------------------------------------------------
  traj_skid #(.Width(ChunkWidth + 1)) u_fd_in (
    .clk_i, .rst_ni,
    .data_i({!in_seg_q, out_d_q}), .valid_i(fd_v_q), .ready_o(fd_in_ready),
    .data_o({fd_first, fd_tdata}), .valid_o(fd_tvalid), .ready_i(fd_tready),
    .valid_d_o(fd_nv), .data_d_o(fd_nd)
  );
  traj_skid #(.Width(ChunkWidth + 1)) u_bcu_in (
    .clk_i, .rst_ni,
    .data_i({!in_seg_q, out_d_q}), .valid_i(bcu_v_q), .ready_o(bcu_in_ready),
    .data_o({bcu_first, bcu_tdata}), .valid_o(bcu_tvalid), .ready_i(bcu_tready),
    .valid_d_o(bcu_nv), .data_d_o(bcu_nd)
  );

  // ---------------------------------------------------------------------
  // Engines: each takes the words of its slice.
  // ---------------------------------------------------------------------

  // The two FD engines take the same stream and ticks and give the same
  // samples; traj_fd_tm answers a tick after its pass over the registers
  // (Axes*Chunks*(Degree+1) + 2 clocks) instead of 2.
  if (FdTimeMux != 0) begin : g_fd_tm
    localparam int Chunks   = Width / ChunkWidth;
    localparam int SampleAW = ($clog2(Axes) + $clog2(Chunks) > 0) ? $clog2(Axes) + $clog2(Chunks) : 1;
    localparam int TmTick   = Axes * Chunks * (Degree + 2) + FdHdrWords + 1;  // its MinTickClocks
    logic [SampleAW-1:0] sample_addr;
    /* verilator lint_off UNUSEDSIGNAL */
    logic [ChunkWidth-1:0] sample_word;  // the core outputs sample_o whole
    logic [Axes*OutWidth-1:0] sample_we, sample_wd;  // (the engine's own sample flops)
    /* verilator lint_on UNUSEDSIGNAL */
    assign sample_addr = '0;
    traj_fd_tm #(
      .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth), .GuardBits(GuardBits),
      .TickClocks(TmTick)
    ) u_fd (
      .clk_i, .rst_ni,
      .s_axis_tdata(fd_tdata), .s_axis_tvalid(fd_tvalid), .s_axis_tready(fd_tready),
      .tick_i(fd_tick),
      .sample_valid_o(fd_valid), .sample_o(fd_sample), .sample_we_o(sample_we), .sample_wd_o(sample_wd),
      .sample_addr_i(sample_addr), .sample_word_o(sample_word),
      .underrun_o(fd_underrun), .seg_done_o(fd_done), .tick_err_o(fd_err)
    );
  end else begin : g_fd
    traj_fd_engine #(
      .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth), .GuardBits(GuardBits)
    ) u_fd (
      .clk_i, .rst_ni,
      .s_axis_tdata(fd_tdata), .s_axis_tvalid(fd_tvalid), .s_axis_tready(fd_tready),
      .tick_i(fd_tick),
      .sample_valid_o(fd_valid), .sample_o(fd_sample),
      .underrun_o(fd_underrun), .seg_done_o(fd_done), .tick_err_o(fd_err)
    );
  end

  traj_bcu_gen #(
    .Axes(Axes), .ChunkWidth(ChunkWidth), .CtrlWidth(CtrlWidth), .GuardBits(BcuGuardBits),
    .OutWidth(OutWidth), .MaxDepth(MaxDepth)
  ) u_bcu (
    .clk_i, .rst_ni,
    .s_axis_tdata(bcu_tdata), .s_axis_tvalid(bcu_tvalid), .s_axis_tready(bcu_tready),
    .tick_i(bcu_tick),
    .sample_valid_o(bcu_valid), .sample_o(bcu_sample),
    .underrun_o(bcu_underrun), .seg_done_o(bcu_done), .tick_err_o(bcu_err)
  );

  // ---------------------------------------------------------------------
  // Output: the engine that emitted last.
  // ---------------------------------------------------------------------
  assign fd_real  = fd_valid && !fd_underrun;
  assign bcu_real = bcu_valid && !bcu_underrun;
  assign sel_now  = fd_real ? 1'b0 : (bcu_real ? 1'b1 : sel_q);

  assign sample_valid_o = fd_real || bcu_real || ((fd_underrun || bcu_underrun) && primed_q);
  assign sample_o       = sel_now ? bcu_sample : fd_sample;
  assign underrun_o     = fd_underrun || bcu_underrun;
  assign seg_done_o     = fd_done || bcu_done;
  assign tick_err_o     = fd_err || bcu_err || err_q;

endmodule

`default_nettype wire
