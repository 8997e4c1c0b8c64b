// SPDX-License-Identifier: Apache-2.0
// traj_core (hls model, hls/traj_core.hpp) with both host compilers:
//   * a chained path of mixed FD and BCU segments (random cubic Bezier pieces,
//     G0-continuous), compiled by traj::fd::Compiler and traj::bcu, played
//     through the core model: every sample equals the hosts' exact prediction,
//     every tick is served exactly Core::answer_clocks later (2, or the
//     time-multiplexed FD engine's pass + 2; none lost or repeated, also
//     at kind switches), and at every switch the first sample of the new segment
//     is exactly the end sample the previous segment predicts (no jump);
//     every sample is within the stated bound of the double-precision path;
//   * the same path with idle cycles on the stream and sparser ticks;
//   * underrun after the last segment holds the output.
// Seed: env TRAJ_SEED (default 20240612), printed.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <gmpxx.h>
#include <random>
#include <string>
#include <vector>

#include "test_seed.hpp"
#include "bcu/bcu_compiler.hpp"
#include "fd/fd_compiler.hpp"
#include "traj_core.hpp"

namespace {
#ifndef C_FDTM
#define C_FDTM 0
#endif
using Core = traj::Core<C_AXES, C_DEGREE, C_WIDTH, C_CHUNK, C_GUARD, C_CTRL, C_BGUARD, C_DEPTH, C_FDTM != 0>;
constexpr int kF = 16;  // output LSB = 2^-16 mm, both engines
constexpr double kH = 1e-3;

uint64_t test_seed() { return traj::test::test_seed(20240612ull); }

traj::fd::Format fd_format() {
  return {C_AXES, C_DEGREE, C_WIDTH, C_CHUNK, C_GUARD, kF};
}
traj::bcu::Format bcu_format() {
  return {C_AXES, C_CHUNK, C_CTRL, C_BGUARD, Core::kOutWidth, C_DEPTH, kF};
}

struct Piece {
  bool bcu = false;
  int K = 0;
  int d = 0;  // BCU depth
  std::vector<std::array<double, 4>> b;         // [axis] Bezier control values (mm)
  std::vector<uint64_t> words;
  std::vector<std::vector<int64_t>> samples;    // [k][axis], k = 0..K (K: end sample)
  std::vector<double> extra_lsb;                // per axis: carried start offset (BCU after FD)
};

struct Path {
  std::vector<Piece> pieces;
  std::vector<std::vector<int64_t>> expect;     // every played sample in order
  std::vector<bool> done;                       // seg_done with it
  std::vector<bool> bcu;                        // played by the BCU
  size_t switches = 0;
};

double bez(const std::array<double, 4>& b, double u) {
  const double v = 1 - u;
  return v * v * v * b[0] + 3 * v * v * u * b[1] + 3 * v * u * u * b[2] + u * u * u * b[3];
}

// Build and compile a chained path of n pieces, kinds random (both present).
Path build_path(std::mt19937_64& rng, int n, int dmin = 4, int dmax = 8) {
  const traj::fd::Compiler fdc(fd_format());
  const traj::bcu::Format bf = bcu_format();
  const int Gf = C_GUARD, Gb = C_BGUARD;
  static_assert(C_GUARD >= C_BGUARD, "the FD register grid must be finer than the BCU grid");
  std::uniform_real_distribution<double> pos(-40.0, 40.0), step(-6.0, 6.0);
  Path p;
  std::vector<double> start(C_AXES);
  for (auto& s : start) s = pos(rng);
  // exact chaining state of the previous piece
  bool have_prev = false, prev_bcu = false;
  std::vector<mpz_class> prev_fd_end(C_AXES), prev_cD(C_AXES);
  for (int i = 0; i < n; ++i) {
    Piece pc;
    pc.bcu = (i % 5 == 3) ? !p.pieces.back().bcu : (rng() & 1);
    pc.b.resize(C_AXES);
    for (int a = 0; a < C_AXES; ++a) {
      pc.b[a][0] = start[a];
      for (int k = 1; k < 4; ++k) pc.b[a][k] = pc.b[a][k - 1] + step(rng);
      start[a] = pc.b[a][3];
    }
    pc.extra_lsb.assign(C_AXES, 0.0);
    if (pc.bcu) {
      const int d = dmin + static_cast<int>(rng() % (dmax - dmin + 1));  // K = 16..256 by default
      pc.K = 1 << d;
      pc.d = d;
      traj::bcu::Controls b(C_AXES, 4);
      for (int a = 0; a < C_AXES; ++a)
        for (int k = 0; k < 4; ++k) b(a, k) = pc.b[a][k];
      traj::bcu::Segment s = traj::bcu::compile_segment(b, d, bf);
      if (have_prev) {
        for (int a = 0; a < C_AXES; ++a) {
          mpz_class cA;
          if (prev_bcu) {
            cA = prev_cD[a];  // exact chaining, A = previous D
          } else {
            // FD end state rounded to the BCU control grid:
            // cA = floor(E / 2^(Gf-Gb)) - 2^(Gb-1), so that round(cA / 2^Gb) = floor(E / 2^Gf)
            mpz_fdiv_q_2exp(cA.get_mpz_t(), prev_fd_end[a].get_mpz_t(), Gf - Gb);
            if (Gb > 0) cA -= mpz_class(1) << (Gb - 1);
          }
          const mpz_class diff = cA - s.ctrl[a][0];
          pc.extra_lsb[a] = std::fabs(diff.get_d()) / std::ldexp(1.0, Gb);
          s.ctrl[a][0] = cA;
        }
      }
      pc.words = traj::bcu::stream_words(s.ctrl, d, bf);
      pc.samples.assign(pc.K + 1, std::vector<int64_t>(C_AXES));
      for (int j = 0; j <= pc.K; ++j)
        for (int a = 0; a < C_AXES; ++a)
          pc.samples[j][a] = traj::bcu::predict_sample(s.ctrl[a], d, j, Gb);
      for (int a = 0; a < C_AXES; ++a) prev_cD[a] = s.ctrl[a][3];
      prev_bcu = true;
    } else {
      pc.K = 50 + static_cast<int>(rng() % 250);
      traj::fd::PolySegment seg;
      seg.h = kH;
      seg.ticks = pc.K;
      const double T = pc.K * kH;
      seg.coef.resize(C_AXES);
      for (int a = 0; a < C_AXES; ++a) {
        const auto& bb = pc.b[a];
        const double p0 = bb[0], p1 = 3 * (bb[1] - bb[0]), p2 = 3 * (bb[0] - 2 * bb[1] + bb[2]),
                     p3 = bb[3] - 3 * bb[2] + 3 * bb[1] - bb[0];
        seg.coef[a] = {p0, p1 / T, p2 / (T * T), p3 / (T * T * T)};
      }
      std::vector<mpz_class> st(C_AXES);
      const std::vector<mpz_class>* sp = nullptr;
      if (have_prev) {
        for (int a = 0; a < C_AXES; ++a) {
          if (prev_bcu) {
            // BCU end value on the FD register grid, + 1/2 output LSB: the
            // engine's floor then gives exactly round(D).
            st[a] = prev_cD[a] * (mpz_class(1) << (Gf - Gb)) + (mpz_class(1) << (Gf - 1));
          } else {
            st[a] = prev_fd_end[a];
          }
        }
        sp = &st;
      }
      const traj::fd::Compiled c = fdc.compile(seg, sp, "piece " + std::to_string(i));
      pc.words = fdc.words(c);
      pc.samples.assign(pc.K + 1, std::vector<int64_t>(C_AXES));
      for (int k = 0; k <= pc.K; ++k)
        for (int a = 0; a < C_AXES; ++a) pc.samples[k][a] = fdc.sample_at(c, a, k).get_si();
      prev_fd_end = c.end;
      prev_bcu = false;
    }
    have_prev = true;
    for (int k = 0; k < pc.K; ++k) {
      p.expect.push_back(pc.samples[k]);
      p.done.push_back(k == pc.K - 1);
      p.bcu.push_back(pc.bcu);
    }
    if (!p.pieces.empty() && p.pieces.back().bcu != pc.bcu) ++p.switches;
    p.pieces.push_back(pc);
  }
  return p;
}

struct Played {
  std::vector<std::vector<int64_t>> samples;
  std::vector<bool> underrun, done;
  std::vector<uint64_t> cycle;
  std::vector<uint64_t> tick_cycle;
  bool tick_err = false;
};

// Stream the whole path (offer_pct % of cycles valid) and tick every `spacing`
// cycles from the first READY/active segment on, `extra` ticks after the end.
Played play_gaps(const Path& p, const std::vector<int>& gaps, int offer_pct, int extra, std::mt19937_64& rng);
Played play(const Path& p, int spacing, int offer_pct, int extra, std::mt19937_64& rng) {
  return play_gaps(p, std::vector<int>(p.expect.size() + extra, spacing), offer_pct, extra, rng);
}

// Tick k comes gaps[k] clocks after tick k-1 (gaps[0] unused).
Played play_gaps(const Path& p, const std::vector<int>& gaps, int offer_pct, int extra, std::mt19937_64& rng) {
  Core core;
  std::vector<std::pair<uint64_t, bool>> words;
  for (const auto& pc : p.pieces)
    for (uint64_t w : pc.words) words.push_back({w, pc.bcu});
  size_t wi = 0;
  Played out;
  const size_t want = p.expect.size() + extra;
  uint64_t cyc = 0, next_tick = 0;
  bool started = false;
  while (out.tick_cycle.size() < want || cyc < next_tick + 8) {
    Core::In in;
    in.tvalid = wi < words.size() && int(rng() % 100) < offer_pct;
    in.tdata = in.tvalid ? words[wi].first : 0;
    in.tuser = in.tvalid ? words[wi].second : false;
    if (!started) {  // first tick once the first segment is ready to play
      started = p.pieces[0].bcu ? core.bcu().state() == Core::Bcu::S_READY : core.fd().active();
      next_tick = cyc;
    }
    in.tick = started && cyc == next_tick && out.tick_cycle.size() < want;
    if (in.tick) {
      out.tick_cycle.push_back(cyc);
      if (out.tick_cycle.size() < gaps.size()) next_tick = cyc + gaps[out.tick_cycle.size()];
    }
    if (core.sample_valid() || core.underrun()) {
      std::vector<int64_t> v;
      for (int a = 0; a < C_AXES; ++a) v.push_back(core.sample(a));
      out.samples.push_back(v);
      out.underrun.push_back(core.underrun());
      out.done.push_back(core.seg_done());
      out.cycle.push_back(cyc);
    }
    out.tick_err |= core.tick_err();
    const bool acc = core.tready(in) && in.tvalid;
    core.clock(in);
    if (acc) ++wi;
    ++cyc;
    if (cyc > 400000000ull) break;
  }
  return out;
}

void check_path(const Path& p, const Played& got, bool strict_latency) {
  ASSERT_GE(got.samples.size(), p.expect.size());
  EXPECT_FALSE(got.tick_err);
  for (size_t k = 0; k < p.expect.size(); ++k) {
    ASSERT_FALSE(got.underrun[k]) << "tick " << k << " found no segment (lost at a switch?)";
    ASSERT_EQ(got.samples[k], p.expect[k]) << "sample " << k;
    ASSERT_EQ(got.done[k], p.done[k]) << "seg_done at " << k;
    if (strict_latency) {
      ASSERT_EQ(got.cycle[k], got.tick_cycle[k] + Core::answer_clocks(p.bcu[k], p.done[k])) << "tick " << k << " late";
    }
  }
  // after the last segment: underrun, output holds (FD: last sample; BCU: its end value)
  const Piece& last = p.pieces.back();
  for (size_t k = p.expect.size(); k < got.samples.size(); ++k) {
    EXPECT_TRUE(got.underrun[k]);
    if (last.bcu) EXPECT_EQ(got.samples[k], last.samples[last.K]);
    else EXPECT_EQ(got.samples[k], last.samples[last.K - 1]);
  }
}

}  // namespace

TEST(Core, FormatsOfBothEnginesAreEqual) {
  EXPECT_EQ(fd_format().out_width(), bcu_format().out_width);
  EXPECT_EQ(fd_format().frac_bits, bcu_format().frac_bits);
  EXPECT_EQ(Core::Fd::kOutWidth, Core::Bcu::kOutWidth);
  EXPECT_GE(C_GUARD, C_BGUARD);
}

TEST(Core, MixedChainedPathExactAtMinTickSpacing) {
  std::mt19937_64 rng(test_seed());
  const Path p = build_path(rng, 24);
  ASSERT_GE(p.switches, 6u);
  const Played got = play(p, Core::kMinTickSpacing, 100, 3, rng);
  check_path(p, got, true);

  // Continuity across kinds: the first sample of every piece is exactly the
  // end sample predicted by the previous piece, and no step between two
  // consecutive samples exceeds the path's speed bound (+2 LSB of rounding).
  const double lsb = std::ldexp(1.0, -kF);
  size_t k0 = 0;
  for (size_t i = 0; i < p.pieces.size(); ++i) {
    const Piece& pc = p.pieces[i];
    if (i > 0) {
      const Piece& pr = p.pieces[i - 1];
      EXPECT_EQ(pc.samples[0], pr.samples[pr.K]) << "piece " << i << (pc.bcu ? " (BCU)" : " (FD)")
                                                  << " after " << (pr.bcu ? "BCU" : "FD");
    }
    for (int a = 0; a < C_AXES; ++a) {
      double vmax = 0;  // max |dx/dk| per tick from the control polygon
      for (int k = 0; k < 3; ++k) vmax = std::max(vmax, 3 * std::fabs(pc.b[a][k + 1] - pc.b[a][k]));
      vmax /= pc.K;
      for (int k = 0; k < pc.K; ++k) {
        const size_t g = k0 + k;
        if (g + 1 < p.expect.size()) {
          const double stepl = std::fabs(double(p.expect[g + 1][a] - p.expect[g][a]));
          EXPECT_LE(stepl, vmax / lsb + 2) << "jump at sample " << g << " axis " << a;
        }
        // within the stated bound of the double-precision path
        const double x = bez(pc.b[a], double(k) / pc.K);
        const double err = std::fabs(double(pc.samples[k][a]) - x / lsb);
        if (pc.bcu) {
          const double u = 1.0 - double(k) / pc.K;
          const double bound = traj::bcu::error_bound(bcu_format(), 200.0) / lsb +
                               pc.extra_lsb[a] * u * u * u;
          EXPECT_LE(err, bound) << "piece " << i << " k " << k << " axis " << a;
          // the carried offset is the FD end error rounded to the BCU grid
          EXPECT_LE(pc.extra_lsb[a], 0.25 + std::ldexp(1.0, -C_BGUARD) + 1e-6);
        } else {
          EXPECT_LE(err, 1.0 + 1e-6) << "piece " << i << " k " << k << " axis " << a;  // 1/2 + tol
        }
      }
    }
    k0 += pc.K;
  }
  std::printf("  %zu pieces, %zu kind switches, %zu samples, all exact\n", p.pieces.size(), p.switches,
              p.expect.size());
}

TEST(Core, MixedChainedPathWithIdleStream) {
  std::mt19937_64 rng(test_seed() + 1);
  const Path p = build_path(rng, 16);
  // stream valid 60 % of cycles: loading takes longer, ticks 3x the minimum
  const Played got = play(p, 3 * Core::kMinTickSpacing, 60, 2, rng);
  check_path(p, got, true);
}

TEST(Core, BcuRunsAtOneSamplePerClock) {
  // Mixed chained path with long BCU pieces (K = 512..2048): ticks on every
  // clock within a BCU piece and from a BCU piece into the next one (K >=
  // Bcu::kBackToBack(d_next): no gap), kMinTickSpacing before FD samples and
  // at the first sample after an FD piece. Every tick answered on time.
  std::mt19937_64 rng(test_seed() + 3);
  const Path p = build_path(rng, 14, 9, 11);
  std::vector<int> gaps;
  size_t bcu_run_ticks = 0;
  for (size_t i = 0; i < p.pieces.size(); ++i) {
    const Piece& pc = p.pieces[i];
    for (int k = 0; k < pc.K; ++k) {
      bool run = pc.bcu && k > 0;
      if (pc.bcu && k == 0 && i > 0) {
        const Piece& pr = p.pieces[i - 1];
        run = pr.bcu && pr.K >= Core::Bcu::kBackToBack(pc.d);
      }
      gaps.push_back(run ? 1 : Core::kMinTickSpacing);
      bcu_run_ticks += run;
    }
  }
  for (int e = 0; e < 2; ++e) gaps.push_back(Core::kMinTickSpacing);
  const Played got = play_gaps(p, gaps, 100, 2, rng);
  check_path(p, got, true);
  EXPECT_GT(bcu_run_ticks, p.expect.size() / 2);
  std::printf("  %zu samples, %zu of them on consecutive clocks (BCU runs)\n", p.expect.size(), bcu_run_ticks);
}

TEST(Core, FarBelowMinTickSpacingTicksAreLate) {
  // Sanity: ticks on every clock for FD segments too (the FD engine needs
  // Chunks clocks per tick): ticks are late or lost.
  std::mt19937_64 rng(test_seed() + 2);
  const Path p = build_path(rng, 8);
  const Played got = play(p, 1, 100, 0, rng);
  bool late = got.tick_err;
  for (size_t k = 0; k < got.samples.size() && k < got.tick_cycle.size() && k < p.expect.size(); ++k)
    late |= got.underrun[k] || got.cycle[k] != got.tick_cycle[k] + Core::answer_clocks(p.bcu[k], p.done[k]);
  EXPECT_TRUE(late);
}
