// SPDX-License-Identifier: Apache-2.0
// hls BCU and BCU generator: exactness against GMP rationals (d = 0..16),
// schedule/timing, interface rules (underrun, tick_err, reset).
#include <gtest/gtest.h>

#include <cstdlib>
#include <gmpxx.h>
#include <random>

#include "test_seed.hpp"
#include "bcu/bcu_compiler.hpp"
#include "bcu_driver.hpp"
#include "traj_bcu.hpp"
#include "traj_bcu_gen.hpp"

using traj::i128;
using traj::u128;
namespace bcu = traj::bcu;

static uint64_t test_seed() { return traj::test::test_seed(20240611ull); }

// Random w-bit signed value, biased to the extremes now and then.
static mpz_class rand_ctrl(std::mt19937_64& rng, int w) {
  const int kind = static_cast<int>(rng() % 8);
  mpz_class lim = 1;
  lim <<= (w - 1);
  if (kind == 0) return lim - 1;
  if (kind == 1) return -lim;
  mpz_class v = 0;
  for (int k = 0; k < w; k += 64) {
    v <<= 64;
    v += static_cast<unsigned long>(rng());
  }
  v = v % (2 * lim);
  return v - lim;
}

// ---------------------------------------------------------------------------
// BCU unit: exact against the rational de Casteljau formula, outputs fit w+3.
// ---------------------------------------------------------------------------
static void check_bcu(const i128 v[4], int w) {
  u128 in[4];
  for (int k = 0; k < 4; ++k) in[k] = traj::wrap(static_cast<u128>(v[k]), w);
  const traj::BcuOut o = traj::bcu_split(in, w);
  const i128 A = v[0], B = v[1], C = v[2], D = v[3];
  const i128 l[4] = {8 * A, 4 * (A + B), 2 * (A + 2 * B + C), A + 3 * B + 3 * C + D};
  const i128 r[4] = {A + 3 * B + 3 * C + D, 2 * (B + 2 * C + D), 4 * (C + D), 8 * D};
  for (int k = 0; k < 4; ++k) {
    ASSERT_EQ(traj::sext(o.l[k], w + 3), l[k]) << "w=" << w << " L" << k;
    ASSERT_EQ(traj::sext(o.r[k], w + 3), r[k]) << "w=" << w << " R" << k;
  }
}

TEST(BcuUnit, ExhaustiveWidth4) {
  i128 v[4];
  for (int a = -8; a < 8; ++a)
    for (int b = -8; b < 8; ++b)
      for (int c = -8; c < 8; ++c)
        for (int d = -8; d < 8; ++d) {
          v[0] = a, v[1] = b, v[2] = c, v[3] = d;
          check_bcu(v, 4);
        }
}

TEST(BcuUnit, RandomWidths) {
  std::mt19937_64 rng(test_seed());
  for (int w : {8, 17, 32, 63, 64, 100, 125}) {
    for (int n = 0; n < 20000; ++n) {
      i128 v[4];
      for (int k = 0; k < 4; ++k) {
        const int kind = static_cast<int>(rng() % 6);
        const i128 lim = static_cast<i128>(u128(1) << (w - 1));
        if (kind == 0) v[k] = lim - 1;
        else if (kind == 1) v[k] = -lim;
        else v[k] = traj::sext((u128(rng()) << 64) | rng(), w);
      }
      check_bcu(v, w);
    }
  }
}

// ---------------------------------------------------------------------------
// Generator exactness: every sample == floor(exact + 1/2), exact from GMP mpq
// sum of Bernstein terms at t = j/2^d, for d = 0..16; error <= 1/2 LSB for
// every d (it does not grow with depth).
// ---------------------------------------------------------------------------
namespace {
constexpr int kAx = 3, kChunk = 32, kCtrl = 71, kGuard = 8, kOut = 64, kMaxD = 16;
using BigGen = traj::BcuGen<kAx, kChunk, kCtrl, kGuard, kOut, kMaxD>;

bcu::Format big_format() { return {kAx, kChunk, kCtrl, kGuard, kOut, kMaxD, 0}; }

// Run one segment to completion with a tick on EVERY clock from the first
// ready sample on (the 1 sample/clock guarantee), then one underrun tick;
// returns the samples, end value last. Every tick must be answered exactly 2
// clocks later, with no gap.
template <class Gen>
std::vector<std::vector<int64_t>> run_fast(const std::vector<uint64_t>& words, int depth) {
  bcu::test::Driver<Gen> drv;
  drv.words = words;
  const size_t K = size_t(1) << depth;
  size_t guard = 0;
  while (drv.gen.state() != Gen::S_READY && ++guard < 100000) drv.step(false);
  const uint64_t t0 = drv.cycle;
  for (size_t j = 0; j < K; ++j) drv.step(true);       // K ticks on consecutive clocks
  while (drv.gen.state() != Gen::S_IDLE && ++guard < 100000) drv.step(false);
  drv.step(true);                                      // end value (underrun)
  for (int k = 0; k < 4; ++k) drv.step(false);
  std::vector<std::vector<int64_t>> out;
  EXPECT_EQ(drv.events.size(), K + 1);
  for (size_t i = 0; i < drv.events.size(); ++i) {
    const auto& e = drv.events[i];
    EXPECT_TRUE(e.valid);
    if (i < K) {
      EXPECT_EQ(e.cycle, t0 + i + 2) << "sample " << i << " not at one per clock";
      EXPECT_FALSE(e.underrun);
      EXPECT_EQ(e.done, i == K - 1);
    } else {
      EXPECT_TRUE(e.underrun);
    }
    out.push_back(e.sample);
  }
  EXPECT_FALSE(drv.gen.tick_err());
  return out;
}
}  // namespace

TEST(BcuGen, ExactAgainstRationalsDepth0To16) {
  std::mt19937_64 rng(test_seed() + 1);
  const bcu::Format f = big_format();
  for (int d = 0; d <= kMaxD; ++d) {
    const int reps = d <= 10 ? 4 : (d <= 13 ? 2 : 1);
    for (int rep = 0; rep < reps; ++rep) {
      std::vector<std::vector<mpz_class>> c(kAx, std::vector<mpz_class>(4));
      for (int a = 0; a < kAx; ++a)
        for (int i = 0; i < 4; ++i) c[a][i] = rand_ctrl(rng, kCtrl);
      if (rep == 0 && d == kMaxD) {  // worst-case growth: alternating extremes
        mpz_class lim = 1;
        lim <<= (kCtrl - 1);
        c[0] = {lim - 1, -lim, lim - 1, -lim};
        c[1] = {-lim, lim - 1, -lim, lim - 1};
      }
      const auto words = bcu::stream_words(c, d, f);
      const auto got = run_fast<BigGen>(words, d);
      const int K = 1 << d;
      ASSERT_EQ(got.size(), size_t(K) + 1) << "d=" << d;
      const mpz_class half_den = mpz_class(1) << kGuard;  // control LSB = 2^-G output LSB
      mpq_class max_err = 0;
      for (int j = 0; j <= K; ++j) {
        const mpq_class t(j, K);
        const mpq_class u = 1 - t;
        for (int a = 0; a < kAx; ++a) {
          mpq_class v = u * u * u * c[a][0] + 3 * u * u * t * c[a][1] + 3 * u * t * t * c[a][2] +
                        t * t * t * c[a][3];
          v /= half_den;  // in output LSBs
          mpq_class vr = v + mpq_class(1, 2);
          mpz_class fl;
          mpz_fdiv_q(fl.get_mpz_t(), vr.get_num_mpz_t(), vr.get_den_mpz_t());
          ASSERT_EQ(mpz_class(static_cast<long>(got[j][a])), fl)
              << "d=" << d << " rep=" << rep << " j=" << j << " axis=" << a;
          ASSERT_EQ(got[j][a], bcu::predict_sample(c[a], d, j, kGuard));
          mpq_class e = abs(mpq_class(static_cast<long>(got[j][a])) - v);
          if (e > max_err) max_err = e;
        }
      }
      EXPECT_LE(max_err, mpq_class(1, 2)) << "d=" << d;
    }
  }
}

// ---------------------------------------------------------------------------
// Timing.
// ---------------------------------------------------------------------------
namespace {
using MidGen = traj::BcuGen<3, 32, 40, 9, 32, 12>;
bcu::Format mid_format() { return {3, 32, 40, 9, 32, 12, 8}; }
// the defaults of the synthesised generator (16-bit chunks)
using DefGen = traj::BcuGen<3, 16, 40, 9, 32, 12>;
bcu::Format def_format() {
  bcu::Format f = mid_format();
  f.chunk_width = 16;
  return f;
}

// Queue chained segments of the given depths; returns expected samples and
// seg_done flags in play order.
struct Queued {
  std::vector<std::vector<int64_t>> expect;
  std::vector<bool> done;
};
template <class Gen>
Queued queue_segments(bcu::test::Driver<Gen>& drv, const std::vector<int>& depths, const bcu::Format& f,
                      std::mt19937_64& rng) {
  Queued qd;
  std::vector<mpz_class> prevD(Gen::kAxes);
  for (size_t s = 0; s < depths.size(); ++s) {
    std::vector<std::vector<mpz_class>> c(Gen::kAxes, std::vector<mpz_class>(4));
    for (int a = 0; a < Gen::kAxes; ++a) {
      for (int i = 0; i < 4; ++i) c[a][i] = rand_ctrl(rng, f.ctrl_width);
      if (s > 0) c[a][0] = prevD[a];  // chaining: A = previous D exactly
      prevD[a] = c[a][3];
    }
    const int d = depths[s];
    const auto w = bcu::stream_words(c, d, f);
    drv.words.insert(drv.words.end(), w.begin(), w.end());
    for (int j = 0; j < (1 << d); ++j) {
      std::vector<int64_t> v;
      for (int a = 0; a < Gen::kAxes; ++a) v.push_back(bcu::predict_sample(c[a], d, j, f.guard_bits));
      qd.expect.push_back(v);
      qd.done.push_back(j == (1 << d) - 1);
    }
  }
  return qd;
}

// Tick every `spacing` clocks from the first ready sample on; true when every
// tick was answered 2 clocks later by the right sample (no underrun, no
// tick_err). `exact` asserts the samples.
template <class Gen>
bool play_uniform(bcu::test::Driver<Gen>& drv, const Queued& qd, int spacing, bool assert_all,
                  int64_t first_tick = -1) {
  if (first_tick >= 0) {
    while (drv.cycle < uint64_t(first_tick)) drv.step(false);
  } else {
    while (drv.gen.state() != Gen::S_READY) drv.step(false);
  }
  std::vector<uint64_t> tick_cycles;
  for (uint64_t c = 0; tick_cycles.size() < qd.expect.size(); ++c) {
    const bool tick = (c % spacing) == 0;
    if (tick) tick_cycles.push_back(drv.cycle);
    drv.step(tick);
  }
  for (int k = 0; k < 4; ++k) drv.step(false);
  bool ok = !drv.gen.tick_err() && drv.events.size() == qd.expect.size();
  for (size_t k = 0; ok && k < qd.expect.size(); ++k) {
    const auto& e = drv.events[k];
    ok = e.valid && !e.underrun && e.cycle == tick_cycles[k] + 2 && e.done == qd.done[k] && e.sample == qd.expect[k];
    if (assert_all) {
      EXPECT_TRUE(ok) << "tick " << k << " (cycle " << tick_cycles[k] << "): valid " << e.valid << " underrun "
                      << e.underrun << " answered at " << e.cycle;
    }
  }
  if (assert_all) {
    EXPECT_FALSE(drv.gen.tick_err());
  }
  return ok;
}
}  // namespace

TEST(BcuGen, TimingConstantsAtTheDefaults) {
  // 3 axes, 16-bit chunks, CtrlWidth 40, MaxDepth 12: W = 76, 5 digits, 5 FD chunks
  EXPECT_EQ(DefGen::kN, 15);
  EXPECT_EQ(DefGen::kC, 5);
  EXPECT_EQ(DefGen::kPp, 15);
  EXPECT_EQ(DefGen::kPi, 21);
  EXPECT_EQ(DefGen::kStartLatency(12), 1 + 60 + 1 + 180 + 21 + 5);
  EXPECT_EQ(DefGen::kMinTickSpacing, 263);
  EXPECT_EQ(DefGen::kRunTickSpacing, 1);
}

TEST(BcuGen, OneSamplePerClockAcrossSegments) {
  // Chained segments, ticks on EVERY clock from the first ready sample on,
  // stream always offered: every segment with at least kBackToBack(d_next)
  // samples hands over to the next with no gap, so all of them play at one
  // sample per clock, latency 2, exact, seg_done with each K-th sample.
  std::mt19937_64 rng(test_seed() + 2);
  for (int variant = 0; variant < 2; ++variant) {
    bcu::test::Driver<DefGen> drv;
    std::vector<int> depths;
    if (variant == 0) {
      depths = {12, 9, 9, 12, 10, 12, 9};
    } else {
      for (int s = 0; s < 8; ++s) depths.push_back(9 + static_cast<int>(rng() % 4));
    }
    depths.push_back(3);  // the last may be short: nothing follows it
    for (size_t s = 0; s + 1 < depths.size(); ++s)
      ASSERT_GE(1 << depths[s], DefGen::kBackToBack(depths[s + 1])) << "test setup";
    const Queued qd = queue_segments(drv, depths, def_format(), rng);
    ASSERT_TRUE(play_uniform(drv, qd, 1, true));
  }
}

TEST(BcuGen, BackToBackRuleIsExact) {
  // A segment started from idle (stream never starved), ticks on every clock:
  // the next segment (depth dn) follows with no gap iff K >= kBackToBack(dn).
  std::mt19937_64 rng(test_seed() + 5);
  int gaps = 0, seamless = 0;
  for (int ds = 4; ds <= 9; ++ds) {
    for (int dn : {0, 3, 8, 12}) {
      bcu::test::Driver<DefGen> drv;
      const Queued qd = queue_segments(drv, {ds, dn}, def_format(), rng);
      const bool ok = play_uniform(drv, qd, 1, false);
      EXPECT_EQ(ok, (1 << ds) >= DefGen::kBackToBack(dn)) << "ds " << ds << " dn " << dn;
      (ok ? seamless : gaps)++;
    }
  }
  EXPECT_GT(gaps, 0);
  EXPECT_GT(seamless, 0);
}

TEST(BcuGen, StartLatencyIsExact) {
  // header offered at cycle 0 (accepted at once), stream never starved: the
  // first sample is ready at kStartLatency(d): a tick at kStartLatency(d)-1
  // is answered 2 clocks later, one a clock earlier only 3 clocks later.
  std::mt19937_64 rng(test_seed() + 6);
  for (int d : {0, 1, 5, 12}) {
    for (int early = 0; early <= 1; ++early) {
      bcu::test::Driver<DefGen> drv;
      const Queued qd = queue_segments(drv, {d}, def_format(), rng);
      const uint64_t t = DefGen::kStartLatency(d) - 1 - early;
      while (drv.cycle < t) drv.step(false);
      drv.step(true);
      for (int k = 0; k < 4; ++k) drv.step(false);
      ASSERT_FALSE(drv.events.empty()) << d;
      EXPECT_EQ(drv.events[0].cycle, t + 2 + early) << "d " << d;
      EXPECT_EQ(drv.events[0].sample, qd.expect[0]);
    }
  }
}

TEST(BcuGen, MinTickSpacingBackToBack) {
  // Uniform ticks kMinTickSpacing apart serve every mix of
  // depths, with latency 2, exactly; the stream is always offered.
  std::mt19937_64 rng(test_seed() + 2);
  bcu::test::Driver<MidGen> drv;
  const Queued qd = queue_segments(drv, {12, 0, 1, 5, 12, 3, 2, 12, 7, 0, 12, 0, 0, 12}, mid_format(), rng);
  ASSERT_TRUE(play_uniform(drv, qd, MidGen::kMinTickSpacing, true));
}

TEST(BcuGen, MinTickSpacingIsTight) {
  // One clock less fails for a depth-0 segment followed by a depth-MaxDepth
  // one, the first tick answered as soon as the first sample is ready.
  std::mt19937_64 rng(test_seed() + 3);
  const int64_t t0 = MidGen::kStartLatency(0) - 1;
  {
    bcu::test::Driver<MidGen> drv;
    const Queued qd = queue_segments(drv, {0, 12}, mid_format(), rng);
    EXPECT_TRUE(play_uniform(drv, qd, MidGen::kMinTickSpacing, false, t0));
  }
  {
    bcu::test::Driver<MidGen> drv;
    const Queued qd = queue_segments(drv, {0, 12}, mid_format(), rng);
    EXPECT_FALSE(play_uniform(drv, qd, MidGen::kMinTickSpacing - 1, false, t0));
  }
}

// ---------------------------------------------------------------------------
// Interface rules.
// ---------------------------------------------------------------------------
TEST(BcuGen, UnderrunBeforeAndAfterSegments) {
  const bcu::Format f = mid_format();
  bcu::test::Driver<MidGen> drv;
  // before any segment: underrun without sample_valid
  drv.step(true);
  drv.step(false);
  drv.step(false);
  ASSERT_EQ(drv.events.size(), 1u);
  EXPECT_TRUE(drv.events[0].underrun);
  EXPECT_FALSE(drv.events[0].valid);
  // one segment d=2, then two underrun ticks: both emit the end value D
  std::vector<std::vector<mpz_class>> c = {{100, 200, -300, 4000}, {-5, 6, 7, -8000}, {0, 0, 0, 1}};
  drv.words = bcu::stream_words(c, 2, f);
  drv.wi = 0;
  for (int k = 0; k < 403; ++k) drv.step(k < 400 && k % 50 == 49);
  ASSERT_EQ(drv.events.size(), 1u + 4 + 4);
  for (int j = 0; j < 4; ++j) {
    const auto& e = drv.events[1 + j];
    EXPECT_TRUE(e.valid && !e.underrun);
    EXPECT_EQ(e.done, j == 3);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(e.sample[a], bcu::predict_sample(c[a], 2, j, 9));
  }
  for (int k = 5; k < 9; ++k) {
    const auto& e = drv.events[k];
    EXPECT_TRUE(e.valid && e.underrun && !e.done);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(e.sample[a], bcu::predict_sample(c[a], 2, 4, 9));
  }
  EXPECT_FALSE(drv.gen.tick_err());
}

TEST(BcuGen, TickErrIsSticky) {
  bcu::test::Driver<MidGen> drv;
  const bcu::Format f = mid_format();
  std::vector<std::vector<mpz_class>> c(3, std::vector<mpz_class>{1, 2, 3, 4});
  drv.words = bcu::stream_words(c, 3, f);
  drv.step(false);  // header accepted
  drv.step(true);   // tick pending during LOAD
  drv.step(true);   // second tick while pending -> error
  EXPECT_TRUE(drv.gen.tick_err());
  for (int k = 0; k < 300; ++k) drv.step(false);
  EXPECT_TRUE(drv.gen.tick_err());
  drv.step(false, true, false);  // reset clears it
  EXPECT_FALSE(drv.gen.tick_err());
}

TEST(BcuGen, ResetMidSegment) {
  std::mt19937_64 rng(test_seed() + 4);
  const bcu::Format f = mid_format();
  bcu::test::Driver<MidGen> drv;
  std::vector<std::vector<mpz_class>> c(3, std::vector<mpz_class>(4));
  for (auto& r : c)
    for (auto& v : r) v = rand_ctrl(rng, 40);
  drv.words = bcu::stream_words(c, 6, f);
  for (int k = 0; k < 400; ++k) drv.step(k % 70 == 0);
  ASSERT_GT(drv.events.size(), 2u);
  drv.step(false, true, false);  // reset
  EXPECT_EQ(drv.gen.state(), MidGen::S_IDLE);
  // after reset with no segment: underrun without valid
  drv.events.clear();
  drv.wi = drv.words.size();
  drv.step(true);
  drv.step(false);
  drv.step(false);
  ASSERT_EQ(drv.events.size(), 1u);
  EXPECT_FALSE(drv.events[0].valid);
  // a fresh segment plays correctly
  drv.words = bcu::stream_words(c, 6, f);
  drv.wi = 0;
  drv.events.clear();
  for (int k = 0; k < 64 * 70 + 200; ++k) drv.step(k % 70 == 69);
  ASSERT_GE(drv.events.size(), 64u);
  for (int j = 0; j < 64; ++j)
    for (int a = 0; a < 3; ++a)
      ASSERT_EQ(drv.events[j].sample[a], bcu::predict_sample(c[a], 6, j, 9)) << j;
}
