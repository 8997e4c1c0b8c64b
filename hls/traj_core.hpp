// SPDX-License-Identifier: Apache-2.0
// trajcore hls: the core, one segment stream for both sampling engines.
// Cycle-accurate model of rtl/traj_core.sv: it instantiates the
// forward-difference engine (hls/traj_fd_engine.hpp) and the BCU generator
// (hls/traj_bcu_gen.hpp) and adds a router and an output selector.
//
// Segment stream: one ChunkWidth-bit word stream (AXI4-Stream tdata, tvalid,
// tready; behind a 2-entry register slice, so s_axis_tready is a flop, and so
// is each engine's tvalid: fd_v_q/bcu_v_q = out_v_q && kind of the word in
// the slice's output register, kept from the next-state values, a
// re-encoding for timing that leaves the cycle schedule unchanged) with a
// 1-bit tuser = segment kind (0: forward differences, 1: BCU),
// sampled on the FIRST word of every segment (later words' tuser is ignored;
// the host keeps it constant within a segment). The words of a segment are
// exactly those of the engine's own stream format, so a segment has a fixed
// length per kind: FD HdrWords + Axes*(Degree+1)*Width/ChunkWidth words, BCU
// 1 + 4*Axes*Digits words. The router counts them and forwards each segment
// to its engine, in stream order, waiting (tready low) while that engine
// cannot take it. The FD engine takes a segment only when it has none; the BCU
// generator takes the next one while it plays (up to three of its segments in
// flight: playing, prepared, loading), so up to four segments are in flight.
// The next segment of the other kind is loaded while the current one plays.
//
// Ticks go to the engine that owns the current segment: the oldest in flight.
// In flight: the number of BCU segments (0..3), whether an FD segment is (at
// most one), and how many of the BCU segments are older than it; a segment is
// counted when its first word is accepted and dropped on its engine's
// seg_done (each engine finishes its segments in order). The routing looks at this cycle's pop and push,
// so a tick arriving with the seg_done of the previous segment already goes
// to the next one. With nothing in flight, ticks go to the engine of the last
// segment (which then reports underrun as it does alone).
//
// Output: the engines' registered outputs, combined (no extra latency:
// tick_i -> sample_valid_o is 2 clocks, as for each engine):
//   underrun_o / seg_done_o = OR of the engines'; tick_err_o = OR of the
//   engines' and a sticky core flag: a segment ended while its engine still
//   held a tick and the next segment in flight belongs to the other engine
//   (that tick would be served out of order; held by the same engine it is
//   served, in order, by that engine's next segment, as when the BCU plays
//   segments back to back at one sample per clock);
//   sample_valid_o = a real sample from either engine, or an underrun once
//   the core has emitted a sample since reset;
//   sample_o = the sample of the engine that emitted last (sel_q). On an
//   underrun the output therefore holds the last sample (or, if the BCU was
//   last, its end value, as the generator alone): it never jumps to a stale
//   value of the other engine.
// Both engines' samples have the same width (OutWidth = Width - GuardBits, the
// BCU is instantiated with it and checks its rounded sample fits) and, by the
// hosts' convention, the same LSB 2^-F (traj::fd::Format::frac_bits ==
// traj::bcu::Format::frac_bits; tb/core checks it).
//
// Requirements for exact, tick-for-tick play: FD segments have K >= 1 (the
// compiler refuses K = 0), the stream is not starved, and ticks are at least
// kMinTickSpacing clocks apart: the BCU's start latency at MaxDepth plus the
// register slice (2), which covers a BCU segment after an FD one of K = 1 and
// an FD reload (HdrWords + Regs*Chunks + 2 clocks). Within a run of BCU
// segments ticks may come on every clock (the generator's guarantee: once a
// segment has started, and across segments of K >= Bcu::kBackToBack(d_next)).
#pragma once
#include <cstdint>
#include <type_traits>

#include "traj_bcu_gen.hpp"
#include "traj_common.hpp"
#include "traj_fd_engine.hpp"
#include "traj_fd_tm.hpp"

namespace traj {

template <int Axes, int Degree, int Width, int ChunkWidth, int GuardBits, int CtrlWidth,
          int BcuGuardBits, int MaxDepth, bool FdTimeMux = false>
class Core {
 public:
  static constexpr int kAxes = Axes;
  static constexpr int kOutWidth = Width - GuardBits;
  // FdTimeMux: the time-multiplexed FD engine (the RTL's traj_fd_tm): the same
  // stream, ticks and samples, answered after its pass over the registers
  using Fd = std::conditional_t<FdTimeMux, FdTm<Axes, Degree, Width, ChunkWidth, GuardBits>,
                                FdEngine<Axes, Degree, Width, ChunkWidth, GuardBits>>;
  using Bcu = BcuGen<Axes, ChunkWidth, CtrlWidth, BcuGuardBits, kOutWidth, MaxDepth>;
  static constexpr int kFdWords = Fd::kWords;
  static constexpr int kBcuWords = Bcu::kSegWords;
  static constexpr int kFdTickSpacing = FdTimeMux ? FdTm<Axes, Degree, Width, ChunkWidth, GuardBits>::kMinTickClocks + 2
                                                  : Fd::kWords + 2;
  static constexpr int kMinTickSpacing =
      Bcu::kStartLatencyMax + 2 > kFdTickSpacing ? Bcu::kStartLatencyMax + 2 : kFdTickSpacing;
  static_assert(Fd::kOutWidth == Bcu::kOutWidth, "engine output widths differ");
  // Clocks from a tick to its sample at the core's output, ticks at least
  // kMinTickSpacing apart: 2 (the BCU and the parallel FD engine), or the
  // time-multiplexed FD engine's pass + 2.
  static constexpr int answer_clocks(bool bcu, bool last_tick) { return bcu ? 2 : Fd::answer_clocks(last_tick); }

  enum Kind : uint8_t { kFd = 0, kBcu = 1 };

  struct In {
    bool rst_n = true;
    u128 tdata = 0;
    bool tuser = false;  // segment kind, sampled on the first word
    bool tvalid = false;
    bool tick = false;
  };

  // State (the RTL's flops, same names, same order). Router: control, all
  // reset. Input slice: valid bits reset, data not.
  struct Regs {
    // router and segments in flight
    bool in_seg_q = false;              // a segment is being forwarded
    bool kind_q = false;                // its kind
    bool last_kind_q = false;           // kind of the last segment finished
    bool sel_q = false;                 // engine that emitted the last sample
    bool primed_q = false;              // a sample has been emitted since reset
    int nb_q = 0;                       // BCU segments in flight (0..3)
    int fpos_q = 0;                     // BCU segments in flight older than the FD one
    bool fdf_q = false;                 // an FD segment is in flight
    int rem_q = 0;                      // words of the forwarded segment still to come
    int pend_fd_q = 0, pend_bcu_q = 0;  // ticks routed to an engine not yet answered (0..3)
    bool fd_tick_q = false;             // fd_tick of the previous cycle: the FD engine takes rising edges only
    bool err_q = false;                 // sticky: a segment ended with a tick still pending
    // input register slice
    bool out_v_q = false, sk_v_q = false, out_u_q = false, sk_u_q = false;
    bool fd_v_q = false, bcu_v_q = false;  // out_v_q && the out word's kind is FD / BCU
    u128 out_d_q = 0, sk_d_q = 0;
  };

  // Combinational view of one cycle (needs the inputs: tready depends on tuser
  // on a segment's first word).
  struct Comb {
    bool kind_now, tready, accept, push, pop_b, pop_f, fdf1, owner1, last1, tick_kind, sel_now;
    int nb1, fpos1;  // after this cycle's pops
  };

  Comb comb(const In& in) const {
    Comb c{};
    const Regs& q = r_;
    (void)in;
    // kind of the word in the slice's output register, where it is valid
    // (== in_seg_q ? kind_q : out_u_q; the registered per-engine valids hold it)
    c.kind_now = q.bcu_v_q;
    c.tready = c.kind_now ? bcu_.tready() : fd_.outputs().tready;  // router side
    c.accept = (q.fd_v_q && fd_.outputs().tready) || (q.bcu_v_q && bcu_.tready());
    c.push = c.accept && !q.in_seg_q;
    c.pop_b = q.nb_q > 0 && bcu_.seg_done();
    c.pop_f = q.fdf_q && fd_.outputs().seg_done;
    // in flight after this cycle's pops, then the owner of the next tick
    c.nb1 = q.nb_q - (c.pop_b ? 1 : 0);
    c.fdf1 = q.fdf_q && !c.pop_f;
    c.fpos1 = (c.pop_b && q.fpos_q > 0) ? q.fpos_q - 1 : q.fpos_q;
    c.last1 = c.pop_b ? true : (c.pop_f ? false : q.last_kind_q);
    c.owner1 = c.fdf1 || c.nb1 > 0 || c.push;  // someone owns the next tick
    c.tick_kind = (c.fdf1 && c.fpos1 == 0) ? false
                  : c.nb1 > 0             ? true
                  : c.fdf1                ? false
                  : c.push                ? c.kind_now
                                          : c.last1;
    const auto fo = fd_.outputs();
    const bool fd_real = fo.sample_valid && !fo.underrun;
    const bool bcu_real = bcu_.sample_valid() && !bcu_.underrun();
    c.sel_now = fd_real ? false : (bcu_real ? true : q.sel_q);
    return c;
  }

  // Outputs of the current cycle.
  // s_axis_tready: registered (skid buffer), independent of the inputs.
  bool tready(const In& = In{}) const { return !r_.sk_v_q; }
  bool sample_valid() const {
    const auto fo = fd_.outputs();
    const bool fd_real = fo.sample_valid && !fo.underrun;
    const bool bcu_real = bcu_.sample_valid() && !bcu_.underrun();
    return fd_real || bcu_real || ((fo.underrun || bcu_.underrun()) && r_.primed_q);
  }
  bool sel_now() const {
    const auto fo = fd_.outputs();
    if (fo.sample_valid && !fo.underrun) return false;
    if (bcu_.sample_valid() && !bcu_.underrun()) return true;
    return r_.sel_q;
  }
  u128 sample_bits(int a) const { return sel_now() ? bcu_.sample_bits(a) : fd_.outputs().sample[a]; }
  int64_t sample(int a) const { return static_cast<int64_t>(sext(sample_bits(a), kOutWidth)); }
  bool underrun() const { return fd_.outputs().underrun || bcu_.underrun(); }
  bool seg_done() const { return fd_.outputs().seg_done || bcu_.seg_done(); }
  bool tick_err() const { return fd_.outputs().tick_err || bcu_.tick_err() || r_.err_q; }

  const Regs& regs() const { return r_; }
  const Fd& fd() const { return fd_; }
  const Bcu& bcu() const { return bcu_; }

  void clock(const In& in) {
    const Comb c = comb(in);
    const Regs& q = r_;
    Regs n = r_;

    // -------------------------------------------------------------------
    // Router and segments in flight: nb_q BCU segments (playing, prepared,
    // loading: 0..3), fdf_q an FD segment (at most one), fpos_q BCU segments
    // older than it. Counted on a segment's first word, dropped on its
    // engine's seg_done (each engine finishes in order).
    // -------------------------------------------------------------------
    const bool fd_tick = in.tick && !c.tick_kind;
    const bool bcu_tick = in.tick && c.tick_kind;
    if (c.accept) {
      if (!q.in_seg_q) {
        n.in_seg_q = true;
        n.kind_q = c.kind_now;
        n.rem_q = (c.kind_now ? kBcuWords : kFdWords) - 1;
      } else {
        n.rem_q = q.rem_q - 1;
        if (q.rem_q == 1) n.in_seg_q = false;
      }
    }
    // finish (seg_done of their engine), then start
    n.last_kind_q = c.last1;
    n.nb_q = (c.nb1 + ((c.push && c.kind_now) ? 1 : 0)) & 3;
    n.fdf_q = c.fdf1 || (c.push && !c.kind_now);
    n.fpos_q = (c.push && !c.kind_now) ? c.nb1 : c.fpos1;
    // output selection
    const auto fo = fd_.outputs();
    n.sel_q = c.sel_now;
    n.primed_q = q.primed_q || (fo.sample_valid && !fo.underrun) ||
                 (bcu_.sample_valid() && !bcu_.underrun());
    // Pending ticks per engine: +1 per routed tick, -1 per answer (every
    // processed tick gives sample_valid or underrun one cycle later). If the
    // owner of a finished segment still holds a tick while the next segment
    // in flight is the other engine's, that tick would be served out of
    // order: sticky error, reported on tick_err.
    const int pf = q.pend_fd_q - ((fo.sample_valid || fo.underrun) ? 1 : 0);
    const int pb = q.pend_bcu_q - ((bcu_.sample_valid() || bcu_.underrun()) ? 1 : 0);
    n.fd_tick_q = fd_tick;
    n.pend_fd_q = (pf + ((fd_tick && !q.fd_tick_q) ? 1 : 0)) & 3;
    n.pend_bcu_q = (pb + (bcu_tick ? 1 : 0)) & 3;
    if ((c.pop_b && pb > 0 && c.owner1 && !c.tick_kind) || (c.pop_f && pf > 0 && c.owner1 && c.tick_kind))
      n.err_q = true;

    // -------------------------------------------------------------------
    // Input register slice (skid buffer): s_axis_tready is a flop; the router
    // sees out_*. Valid bits are reset, data is not. Per-engine valid,
    // registered (timing): the next out word's kind, from the next state.
    // -------------------------------------------------------------------
    if (!q.out_v_q || c.accept) {
      if (q.sk_v_q) {
        n.out_v_q = true;
        n.out_d_q = q.sk_d_q;
        n.out_u_q = q.sk_u_q;
        n.sk_v_q = false;
      } else {
        n.out_v_q = in.tvalid;
        if (in.tvalid) {
          n.out_d_q = in.tdata;
          n.out_u_q = in.tuser;
        }
      }
    } else if (in.tvalid && !q.sk_v_q) {
      n.sk_v_q = true;
      n.sk_d_q = in.tdata;
      n.sk_u_q = in.tuser;
    }
    const bool kind_nx = n.in_seg_q ? n.kind_q : n.out_u_q;
    n.fd_v_q = n.out_v_q && !kind_nx;
    n.bcu_v_q = n.out_v_q && kind_nx;

    // -------------------------------------------------------------------
    // Engines: each takes the slice's word when its registered valid is set.
    // -------------------------------------------------------------------
    typename Fd::In fi;
    fi.rst_n = in.rst_n;
    fi.tdata = static_cast<uint64_t>(q.out_d_q);
    fi.tvalid = q.fd_v_q;
    fi.tick = fd_tick;
    typename Bcu::In bi;
    bi.rst_n = in.rst_n;
    bi.tdata = q.out_d_q;
    bi.tvalid = q.bcu_v_q;
    bi.tick = bcu_tick;
    fd_.clock(fi);
    bcu_.clock(bi);

    if (!in.rst_n) {  // control only: the slice data registers keep their value
      const u128 od = n.out_d_q, sd = n.sk_d_q;
      const bool ou = n.out_u_q, su = n.sk_u_q;
      n = Regs{};
      n.out_d_q = od;
      n.sk_d_q = sd;
      n.out_u_q = ou;
      n.sk_u_q = su;
    }
    r_ = n;
  }

 private:
  Regs r_{};
  Fd fd_;
  Bcu bcu_;
};

}  // namespace traj
