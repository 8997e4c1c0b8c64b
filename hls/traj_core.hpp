// SPDX-License-Identifier: Apache-2.0
// trajcore hls: the core, one segment stream for both sampling engines.
// Cycle-accurate model of rtl/traj_core.sv: it instantiates the
// forward-difference engine (hls/traj_fd_engine.hpp, or with FdTimeMux the
// time-multiplexed one, hls/traj_fd_tm.hpp) and the BCU generator
// (hls/traj_bcu_gen.hpp) and adds a router and an output selector.
//
// Segment stream: one ChunkWidth-bit word stream (AXI4-Stream tdata, tvalid,
// tready) with a 1-bit tuser = segment kind (0: forward differences, 1: BCU),
// sampled on the FIRST word of every segment (later words' tuser is ignored;
// the host keeps it constant within a segment). The words of a segment are
// exactly those of the engine's own stream format, so a segment has a fixed
// length per kind: FD HdrWords + Axes*(Degree+1)*Width/ChunkWidth words, BCU
// 1 + 4*Axes*Digits words. The router counts them and forwards each segment
// to its engine, in stream order, waiting (tready low) while that engine
// cannot take it. Register slices (hls/traj_skid.hpp) cut every handshake
// path: one in front of the router (s_axis_tready is a flop) and one in front
// of each engine (an engine's tready reaches its slice and the segment count,
// not the router); the router's per-engine valids fd_v_q/bcu_v_q are the
// input slice's valid and the word's kind, registered from the next state.
// The FD engine takes a segment only when it has none; the BCU generator
// takes the next one while it plays (up to three of its segments in flight:
// playing, prepared, loading), so up to four segments are in flight.
// The next segment of the other kind is loaded while the current one plays.
//
// Ticks go to the engine that owns the current segment: the oldest in flight.
// In flight: the number of BCU segments (0..3), whether an FD segment is (at
// most one), and how many of the BCU segments are older than it; a segment is
// counted the clock after its engine takes its first word (marked by the
// router in the engine's slice) and dropped on its engine's seg_done (each
// engine finishes its segments in order; first words reach the engines in
// stream order, at most one per clock, because a segment has more words than
// a slice holds). The routing looks at this cycle's pops, so a tick arriving
// with the seg_done of the previous segment already goes to the next one. With nothing in flight, ticks go to the engine of the last
// segment (which then reports underrun as it does alone).
//
// Output: the engines' registered outputs, combined (no extra latency:
// tick_i -> sample_valid_o as for each engine, answer_clocks):
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
// two register slices (3), which covers a BCU segment after an FD one of K = 1
// and an FD reload (HdrWords + Regs*Chunks + 3 clocks; with FdTimeMux the
// time-multiplexed engine's kMinTickClocks + 3). Within a run of BCU
// segments ticks may come on every clock (the generator's guarantee: once a
// segment has started, and across segments of K >= Bcu::kBackToBack(d_next)).
#pragma once
#include <cstdint>
#include <type_traits>

#include "traj_bcu_gen.hpp"
#include "traj_common.hpp"
#include "traj_fd_engine.hpp"
#include "traj_fd_tm.hpp"
#include "traj_skid.hpp"

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
  // the engines' own spacing and the two register slices in front of them
  static constexpr int kFdTickSpacing = FdTimeMux ? FdTm<Axes, Degree, Width, ChunkWidth, GuardBits>::kMinTickClocks + 3
                                                  : Fd::kWords + 3;
  static constexpr int kMinTickSpacing =
      Bcu::kStartLatencyMax + 3 > kFdTickSpacing ? Bcu::kStartLatencyMax + 3 : kFdTickSpacing;
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
    bool push_q = false, push_b_q = false;  // an engine took a segment's first word (the BCU) last clock
    bool err_q = false;                 // sticky: a segment ended with a tick still pending
    // the input slice's output word is valid and of kind FD / BCU
    bool fd_v_q = false, bcu_v_q = false;
  };

  // Combinational view of one cycle (needs the inputs: tready depends on tuser
  // on a segment's first word).
  struct Comb {
    bool kind_now, tready, accept, first, push, push_b, pop_b, pop_f, fdf1, owner1, last1, tick_kind, sel_now;
    int nb1, fpos1;  // after this cycle's pops
  };

  Comb comb(const In& in) const {
    Comb c{};
    const Regs& q = r_;
    (void)in;
    // kind of the word in the slice's output register, where it is valid
    // (== in_seg_q ? kind_q : out_u_q; the registered per-engine valids hold it)
    c.kind_now = q.bcu_v_q;
    c.tready = c.kind_now ? bcu_in_.ready() : fd_in_.ready();  // router side
    c.accept = (q.fd_v_q && fd_in_.ready()) || (q.bcu_v_q && bcu_in_.ready());
    // a segment's first word: the router marks it (first), and the segment
    // is counted in flight the clock after its engine takes that word (push,
    // registered: push_q)
    c.first = c.accept && !q.in_seg_q;
    const bool fd_first = ((fd_in_.data() >> ChunkWidth) & 1) != 0;
    const bool bcu_first = ((bcu_in_.data() >> ChunkWidth) & 1) != 0;
    c.push_b = bcu_in_.valid() && bcu_.tready() && bcu_first;
    c.push = (fd_in_.valid() && fd_.outputs().tready && fd_first) || c.push_b;
    c.pop_b = q.nb_q > 0 && bcu_.seg_done();
    c.pop_f = q.fdf_q && fd_.outputs().seg_done;
    // in flight after this cycle's pops, then the owner of the next tick
    c.nb1 = q.nb_q - (c.pop_b ? 1 : 0);
    c.fdf1 = q.fdf_q && !c.pop_f;
    c.fpos1 = (c.pop_b && q.fpos_q > 0) ? q.fpos_q - 1 : q.fpos_q;
    c.last1 = c.pop_b ? true : (c.pop_f ? false : q.last_kind_q);
    c.owner1 = c.fdf1 || c.nb1 > 0 || q.push_q;  // someone owns the next tick
    c.tick_kind = (c.fdf1 && c.fpos1 == 0) ? false
                  : c.nb1 > 0             ? true
                  : c.fdf1                ? false
                  : q.push_q              ? q.push_b_q
                                          : c.last1;
    const auto fo = fd_.outputs();
    const bool fd_real = fo.sample_valid && !fo.underrun;
    const bool bcu_real = bcu_.sample_valid() && !bcu_.underrun();
    c.sel_now = fd_real ? false : (bcu_real ? true : q.sel_q);
    return c;
  }

  // Outputs of the current cycle.
  // s_axis_tready: registered (skid buffer), independent of the inputs.
  bool tready(const In& = In{}) const { return in_.ready(); }
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
  const Skid& in_slice() const { return in_; }

  void clock(const In& in) {
    const Comb c = comb(in);
    const Regs& q = r_;
    Regs n = r_;

    // -------------------------------------------------------------------
    // Router and segments in flight: nb_q BCU segments (playing, prepared,
    // loading: 0..3), fdf_q an FD segment (at most one), fpos_q BCU segments
    // older than it. Counted the clock after its engine takes a segment's
    // first word, dropped on its engine's seg_done (each engine finishes in
    // order).
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
    n.nb_q = (c.nb1 + (q.push_b_q ? 1 : 0)) & 3;
    n.fdf_q = c.fdf1 || (q.push_q && !q.push_b_q);
    n.fpos_q = (q.push_q && !q.push_b_q) ? c.nb1 : c.fpos1;
    n.push_q = c.push;
    n.push_b_q = c.push_b;
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
    // Input register slice: s_axis_tready is a flop; the router sees its
    // output. Per-engine valid, registered (timing): the next output word's
    // kind, from the next state.
    // -------------------------------------------------------------------
    const u128 data_mask = ~u128(0) >> (128 - ChunkWidth);
    const u128 in_word = (u128(in.tuser ? 1 : 0) << ChunkWidth) | (in.tdata & data_mask);
    const Skid::Next nx = in_.next(in.tvalid, in_word, c.accept);
    const bool out_u_d = ((nx.data >> ChunkWidth) & 1) != 0;
    const bool kind_nx = n.in_seg_q ? n.kind_q : out_u_d;
    n.fd_v_q = nx.valid && !kind_nx;
    n.bcu_v_q = nx.valid && kind_nx;

    // -------------------------------------------------------------------
    // The engines' register slices take the router's word; each engine
    // takes the words of its slice.
    // -------------------------------------------------------------------
    const u128 out_d = (u128(q.in_seg_q ? 0 : 1) << ChunkWidth) | (in_.data() & data_mask);  // {first, word}
    const bool fd_ready = fd_.outputs().tready, bcu_ready = bcu_.tready();
    typename Fd::In fi;
    fi.rst_n = in.rst_n;
    fi.tdata = static_cast<uint64_t>(fd_in_.data() & data_mask);
    fi.tvalid = fd_in_.valid();
    fi.tick = fd_tick;
    typename Bcu::In bi;
    bi.rst_n = in.rst_n;
    bi.tdata = bcu_in_.data() & data_mask;
    bi.tvalid = bcu_in_.valid();
    bi.tick = bcu_tick;
    fd_.clock(fi);
    bcu_.clock(bi);
    fd_in_.clock(in.rst_n, q.fd_v_q, out_d, fd_ready);
    bcu_in_.clock(in.rst_n, q.bcu_v_q, out_d, bcu_ready);
    in_.clock(in.rst_n, in.tvalid, in_word, c.accept);

    if (!in.rst_n) n = Regs{};  // control only (the slices keep their data)
    r_ = n;
  }

 private:
  Regs r_{};
  Skid in_, fd_in_, bcu_in_;  // input slice ({tuser, tdata}), the engines' slices
  Fd fd_;
  Bcu bcu_;
};

}  // namespace traj
