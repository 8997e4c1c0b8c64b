// SPDX-License-Identifier: Apache-2.0
// plan::fine_windows_ok (per-segment bounds of the sampled tangential and
// normal quantities and chords at every engine tick) against a brute-force
// reference written apart from it: every tick window of the segment's
// samples, in long double, from the definitions of host/planner/README.md.
// Soundness: whatever it accepts, the reference finds within the limits.
// Use: it accepts what is well within them (not a check that refuses
// everything), also a segment that starts at rest. And job::engine_pieces:
// the pieces are the polynomial, tick by tick.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "input/path_json.hpp"
#include "job/job.hpp"
#include "planner/fine_check.hpp"
#include "test_seed.hpp"

namespace {

using namespace traj;
using plan::kMaxAxes;
using plan::TimeSegment;
using Pos = std::array<long double, kMaxAxes>;

// q(t) - q(0) of one axis, in long double.
long double travel_ld(const TimeSegment& s, int a, long double t) {
  long double v = 0;
  for (int j = s.degree; j >= 1; --j) v = v * t + s.coef[a][j];
  return v * t;
}

struct Worst {
  long double ratio = 0;  // largest value / limit
  std::string what;
};

// Every window the check covers: starts -2..K-1 (the tail holds ticks
// -3..-1); the same windows and thresholds as fit_segments at every tick.
Worst brute_force(const TimeSegment& s, int d, double h, const plan::Limits& L,
                  const std::vector<std::array<double, kMaxAxes>>& tail) {
  const long long K = s.K;
  const int hn = static_cast<int>(tail.size());
  auto pos = [&](long long k) {
    Pos p{};
    for (int a = 0; a < d; ++a)
      p[a] = k < 0 ? static_cast<long double>(tail[static_cast<size_t>(hn + k)][a]) : travel_ld(s, a, k * (long double)h);
    return p;
  };
  auto norm = [&](const Pos& v) {
    long double n = 0;
    for (int a = 0; a < d; ++a) n += v[a] * v[a];
    return std::sqrt(n);
  };
  auto diff = [&](const Pos& x, const Pos& y) {
    Pos r{};
    for (int a = 0; a < d; ++a) r[a] = x[a] - y[a];
    return r;
  };
  // the part of v normal to the direction of u (0 where u is shorter than `least`)
  auto normal = [&](const Pos& v, const Pos& u, long double least) -> long double {
    const long double un = norm(u);
    if (un <= least) return 0;
    long double dot = 0;
    for (int a = 0; a < d; ++a) dot += v[a] * u[a] / un;
    Pos r{};
    for (int a = 0; a < d; ++a) r[a] = v[a] - dot * u[a] / un;
    return norm(r);
  };
  Worst w;
  auto note = [&](long double value, double limit, const char* what, long long k) {
    if (value / limit > w.ratio) {
      w.ratio = value / limit;
      w.what = std::string(what) + " at tick " + std::to_string(k);
    }
  };
  const long double hh = h, min_chord = 1e-9L * L.feed * h;
  const long long first = -std::min<long long>(2, hn);
  for (long long k = first; k <= K - 1; ++k) {
    const Pos x0 = pos(k), x1 = pos(k + 1);
    if (k >= 0) note(norm(diff(x1, x0)) / hh, L.feed, "chord speed", k);
    if (k + 2 > K) continue;
    const Pos x2 = pos(k + 2);
    const long double s0 = norm(diff(x1, x0)) / hh, s1 = norm(diff(x2, x1)) / hh;
    Pos A{};
    for (int a = 0; a < d; ++a) A[a] = (x2[a] - 2 * x1[a] + x0[a]) / (hh * hh);
    if (k >= -1) {
      note(std::fabs(s1 - s0) / hh, L.a_tan, "tangential acceleration", k);
      note(normal(A, diff(x2, x0), 2 * min_chord), L.a_cen, "normal acceleration", k);
    }
    if (k + 3 > K || s.degree != 5) continue;
    const Pos x3 = pos(k + 3);
    const long double s2 = norm(diff(x3, x2)) / hh;
    Pos J{};
    for (int a = 0; a < d; ++a) J[a] = (x3[a] - 3 * x2[a] + 3 * x1[a] - x0[a]) / (hh * hh * hh);
    note(std::fabs(s2 - 2 * s1 + s0) / (hh * hh), L.j_tan, "tangential jerk", k);
    note(normal(J, diff(x2, x1), min_chord), L.j_cen, "normal jerk", k);
  }
  return w;
}

// The fitted positions of the last 3 ticks of `s`, relative to its end.
std::vector<std::array<double, kMaxAxes>> tail_of(const TimeSegment& s, int d, double h) {
  std::vector<std::array<double, kMaxAxes>> t;
  for (uint32_t k = s.K >= 3 ? s.K - 3 : 0; k < s.K; ++k) {
    std::array<double, kMaxAxes> q{};
    for (int a = 0; a < d; ++a) q[a] = s.travel(a, k * h) - s.travel(a, s.K * h);
    t.push_back(q);
  }
  return t;
}

// The segments of the butterfly planned at 20 us (fit on the 1 ms fit tick):
// each passed fine_windows_ok when it was fitted; the reference finds every
// window of every one within the limits.
TEST(FineCheck, EverySegmentOfAFineTickPlanKeepsTheLimitsAtEveryTick) {
  job::JobConfig cfg;
  cfg.machine.period = 20e-6;
  cfg.machine.choose_format(cfg.limits);
  cfg.engine_ticks = false;
  ASSERT_GT(cfg.machine.fit_ticks(), 1);
  const job::JobResult r = job::run_job(input::load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json"), cfg);
  const double h = cfg.machine.period;
  long double worst = 0;
  std::string what;
  std::vector<std::array<double, kMaxAxes>> tail;
  uint64_t ticks = 0;
  for (size_t i = 0; i + 1 < r.segments.size(); ++i) {  // the last is the one-tick hold
    const TimeSegment& s = r.segments[i];
    const Worst w = brute_force(s, 2, h, cfg.limits, tail);
    if (w.ratio > worst) {
      worst = w.ratio;
      what = "segment " + std::to_string(i) + ": " + w.what;
    }
    tail = tail_of(s, 2, h);
    ticks += s.K;
  }
  EXPECT_LE(worst, 1 + 1e-9L) << what;
  EXPECT_GT(worst, 0.5L);  // the reference measures something
  std::printf("  %zu segments, %llu ticks at 20 us: worst %.6Lf of its limit (%s)\n", r.segments.size(),
              static_cast<unsigned long long>(ticks), worst, what.c_str());
}

// Random quintic segments (a speed, an acceleration and a jerk in random
// directions, of random sizes): what the check accepts, the reference finds
// within the limits; of those the reference finds well within them (0.8),
// the check accepts most, so it is not a refusal of everything.
TEST(FineCheck, RandomSegmentsAcceptedOnlyWithinTheLimitsAndMostlyWhereWellWithin) {
  std::mt19937_64 rng(test::test_seed(7));
  std::uniform_real_distribution<double> U(-1, 1);
  plan::Limits L;
  L.feed = 100;
  const double h = 20e-6;
  int accepted = 0, well_within = 0, well_within_accepted = 0, checked = 0;
  for (int rep = 0; rep < 400; ++rep) {
    TimeSegment s;
    s.degree = 5;
    s.K = static_cast<uint32_t>(20 + rng() % 800);
    const int d = 2 + static_cast<int>(rng() % 2);
    const double scale = std::pow(10.0, U(rng));  // sizes from 1/10 to 10 times typical
    for (int a = 0; a < d; ++a) {
      s.coef[a][0] = 50 * U(rng);
      s.coef[a][1] = 30 * scale * U(rng);
      s.coef[a][2] = 300 * scale * U(rng);
      s.coef[a][3] = 3000 * scale * U(rng);
      s.coef[a][4] = 1e5 * scale * U(rng);
      s.coef[a][5] = 1e6 * scale * U(rng);
    }
    std::vector<std::array<double, kMaxAxes>> tail;
    const bool ok = plan::fine_windows_ok(s, d, h, L, tail);
    const Worst w = brute_force(s, d, h, L, tail);
    ++checked;
    if (ok) {
      ++accepted;
      EXPECT_LE(w.ratio, 1 + 1e-9L) << "rep " << rep << ": " << w.what;
    }
    if (w.ratio <= 0.8L) {
      ++well_within;
      well_within_accepted += ok;
    }
  }
  std::printf("  %d random segments: %d accepted; %d well within the limits, %d of them accepted\n", checked,
              accepted, well_within, well_within_accepted);
  ASSERT_GT(well_within, 40);
  EXPECT_GE(well_within_accepted, 0.9 * well_within);
  EXPECT_LT(accepted, checked);  // some are refused
}

// A segment that starts at rest and turns as it speeds up (the chord speed
// vanishes at its start: the direction is unknown there), with a tail at rest
// before it: accepted, and the reference agrees.
TEST(FineCheck, ASegmentFromRestIsAcceptedWhereTheLimitsHold) {
  plan::Limits L;
  const double h = 20e-6;
  TimeSegment s;
  s.degree = 5;
  s.K = 2000;
  // q = j t^3/6 along x plus a slower turn into y: rest at t = 0 (q' = q'' = 0)
  s.coef[0] = {10, 0, 0, 1500, -2e4, 1e5};
  s.coef[1] = {-5, 0, 0, 0, 800, -1e4};
  std::vector<std::array<double, kMaxAxes>> tail(3, std::array<double, kMaxAxes>{});
  plan::FineCheckStats st;
  EXPECT_TRUE(plan::fine_windows_ok(s, 2, h, L, tail, nullptr, &st));
  const Worst w = brute_force(s, 2, h, L, tail);
  EXPECT_LE(w.ratio, 1.0L) << w.what;
  EXPECT_GT(st.exact_windows, 0u);  // near the rest, window by window
  EXPECT_LT(st.exact_windows, 200u);  // ...and only there
  std::printf("  from rest: %zu intervals bounded, %zu windows one by one of %u; worst %.4Lf (%s)\n", st.intervals,
              st.exact_windows, s.K, w.ratio, w.what.c_str());
}

// Long polynomials in engine pieces: each piece is the polynomial from its
// start, tick by tick, to rounding; no piece longer than the limit; the
// pieces cover the segment tick for tick.
TEST(EnginePieces, PiecesAreThePolynomialTickByTick) {
  TimeSegment s;
  s.degree = 5;
  s.k0 = 1000;
  s.K = 40000;
  s.coef[0] = {120.5, 40, -300, 2000, -1e4, 3e4};
  s.coef[1] = {-7.25, -12, 150, -900, 4e3, -1e4};
  const double h = 1e-6;
  std::vector<TimeSegment> pieces;
  job::engine_pieces(s, 15000, h, pieces);
  ASSERT_EQ(pieces.size(), 3u);
  long long k = s.k0;
  for (const TimeSegment& p : pieces) {
    EXPECT_EQ(p.k0, k);
    EXPECT_LE(p.K, 15000u);
    for (uint32_t i = 0; i <= p.K; i += 97)
      for (int a = 0; a < 2; ++a) {
        long double want = 0;
        const long double t = static_cast<long double>(p.k0 - s.k0 + i) * h;
        for (int j = 5; j >= 0; --j) want = want * t + s.coef[a][j];
        EXPECT_NEAR(p.eval(a, i * h), static_cast<double>(want), 1e-12 * 128) << "piece at " << p.k0 << " tick " << i;
      }
    k += p.K;
  }
  EXPECT_EQ(k, s.k0 + s.K);
}

}  // namespace
