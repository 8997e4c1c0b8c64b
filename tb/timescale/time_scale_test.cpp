// SPDX-License-Identifier: Apache-2.0
// The time-scale reference (host/timescale): its S-curve against a
// breadth-first search of every integer ramp, and the butterfly re-timed by
// hold, override and starvation at random servo ticks, checked on the output
// samples by a finite-difference check of its own against the machine's
// limits and against the unscaled engine samples (the same points re-timed).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <queue>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "job/job.hpp"
#include "input/path_json.hpp"
#include "report/report.hpp"
#include "test_seed.hpp"
#include "timescale/time_scale.hpp"
#include "scaled_butterfly.hpp"

namespace {

using namespace traj;
using timescale::IntBounds;
using timescale::SCurve;

// The fewest servo ticks from rest at s0 to rest at target, every ramp
// (k changes by -1, 0, +1; |k| <= m; 0 <= S <= hi) searched breadth first.
int fewest_ticks(int64_t s0, int64_t target, int64_t m, int64_t hi) {
  const int64_t span = 2 * m + 1;
  std::vector<int> dist((hi + 1) * span, -1);
  auto id = [&](int64_t s, int64_t k) { return static_cast<size_t>(s * span + (k + m)); };
  std::queue<std::pair<int64_t, int64_t>> q;
  dist[id(s0, 0)] = 0;
  q.push({s0, 0});
  while (!q.empty()) {
    const auto [s, k] = q.front();
    q.pop();
    if (s == target && k == 0) return dist[id(s, k)];
    for (int dk = -1; dk <= 1; ++dk) {
      const int64_t k2 = k + dk, s2 = s + k2;
      if (k2 < -m || k2 > m || s2 < 0 || s2 > hi || dist[id(s2, k2)] >= 0) continue;
      dist[id(s2, k2)] = dist[id(s, k)] + 1;
      q.push({s2, k2});
    }
  }
  return -1;
}

TEST(SCurve, RestToRestInTheFewestTicks) {
  // the greedy curve against the search, every start and target
  for (int64_t m : {1, 2, 3, 5, 8}) {
    IntBounds b;
    b.m = m;
    b.s_max = 120;
    for (int64_t s0 = 0; s0 <= 120; s0 += 7)
      for (int64_t t = 0; t <= 120; t += 5) {
        SCurve c(b, s0);
        c.set_target(t);
        int n = 0;
        while (!c.at_rest() && n < 10000) {
          c.step();
          ++n;
        }
        ASSERT_TRUE(c.at_rest()) << "m " << m << " from " << s0 << " to " << t;
        ASSERT_EQ(n, fewest_ticks(s0, t, m, 120)) << "m " << m << " from " << s0 << " to " << t;
      }
  }
}

// stop_ticks_bound (the hardware unit's clock bound rests on it) against the
// curve's own stops: from every state random targets lead to, one step
// toward the target (as the unit's check takes it first), then to rest at 0.
TEST(SCurve, StopsWithinTheTickBound) {
  std::mt19937_64 rng(test::env_seed(8));
  double worst = 0;
  for (int run = 0; run < 60; ++run) {
    IntBounds b;
    b.m = 1 + static_cast<int64_t>(rng() % (run % 3 == 0 ? 4 : 300));
    b.s_max = 1 + static_cast<int64_t>(rng() % (int64_t(1) << (4 + run % 17)));
    const int64_t bound = stop_ticks_bound(b);
    SCurve c(b, static_cast<int64_t>(rng() % (b.s_max + 1)));
    for (int t = 0; t < 2000; ++t) {
      if (rng() % 40 == 0) c.set_target(rng() % 3 == 0 ? b.s_max : static_cast<int64_t>(rng() % (b.s_max + 1)));
      c.step();
      SCurve stop = c;
      stop.step();
      stop.set_target(0);
      int64_t n = 1;
      while (!stop.at_rest() && n <= bound + 1) {
        stop.step();
        ++n;
      }
      ASSERT_LE(n, bound) << "m " << b.m << " s_max " << b.s_max << " from S " << c.s() << " k " << c.k();
      worst = std::max(worst, static_cast<double>(n) / static_cast<double>(bound));
    }
  }
  std::printf("  longest stop: %.2f of stop_ticks_bound\n", worst);
}

TEST(SCurve, TargetsChangedAnyTimeStayWithinTheBounds) {
  std::mt19937_64 rng(test::env_seed(7));
  for (int run = 0; run < 200; ++run) {
    IntBounds b;
    b.m = 1 + static_cast<int64_t>(rng() % 40);
    b.s_max = 1 + static_cast<int64_t>(rng() % 5000);
    SCurve c(b, static_cast<int64_t>(rng() % (b.s_max + 1)));
    int64_t lo = c.s(), hi = c.s();  // the hull of the start and every target
    for (int t = 0; t < 3000; ++t) {
      if (rng() % 50 == 0) {
        c.set_target(static_cast<int64_t>(rng() % (b.s_max + 1)));
        lo = std::min(lo, c.target());
        hi = std::max(hi, c.target());
      }
      const int64_t k0 = c.k();
      c.step();
      ASSERT_LE(std::abs(c.k() - k0), 1);
      ASSERT_LE(std::abs(c.k()), b.m);
      ASSERT_GE(c.s(), lo) << "run " << run << " tick " << t;
      ASSERT_LE(c.s(), hi) << "run " << run << " tick " << t;
    }
    // and it lands
    int n = 0;
    while (!c.at_rest() && n < 100000) {
      c.step();
      ++n;
    }
    ASSERT_TRUE(c.at_rest());
  }
}

// What a scenario did, and the worst ratios of the output's sample
// differences to the limits.
struct Outcome {
  double worst = 0;
  std::string worst_what;
  uint64_t servo_ticks = 0, starved_holds = 0;
  bool ended_on_last = false, held_still = false;
};

struct Event {
  uint64_t at;           // servo tick
  enum Kind { kHold, kResume, kOverride, kPause } kind;
  double value = 0;      // override s; pause length in servo ticks
};

// ramp_gain_log2 > 0: ramps 2^g times faster in rate and in accel than the
// derived bounds (to show that the check finds what they prevent)
Outcome play(const Butterfly& bf, const std::vector<Event>& events, double s_max, uint64_t link_per_tick,
             int ramp_gain_log2 = 0) {
  const double H = 1e-3;
  const int n = static_cast<int>(std::lround(H / bf.h));
  timescale::OutputError err{bf.h, H, bf.lsb};
  const auto rb = timescale::derive_ramp_bounds(bf.peaks, bf.limits, s_max, err);
  auto ib = timescale::integer_bounds(rb, H);
  ib.m <<= ramp_gain_log2;
  ib.scale_bits -= ramp_gain_log2;
  ib.s_max >>= ramp_gain_log2;
  timescale::TimeScaler ts(ib, n, 3);
  Outcome o;
  std::vector<std::vector<double>> out;  // units
  uint64_t received = std::min<uint64_t>(bf.n, link_per_tick ? 4 * n : bf.n), paused_until = 0;
  size_t next = 0;
  bool held = false;
  uint64_t events_postponed = 0;
  static bool shown = false;
  if (!shown && ramp_gain_log2 == 0) {
    shown = true;
    std::printf("  ramp bounds: |ds/dt| <= %.3f /s, |d2s/dt2| <= %.1f /s^2; integer: scale bits %d, m %lld\n", rb.rate,
                rb.accel, ib.scale_bits, static_cast<long long>(ib.m));
  }
  for (uint64_t t = 0; t < 200000; ++t) {
    while (next < events.size() && events[next].at <= t) {
      const Event& e = events[next++];
      if (e.kind == Event::kHold) ts.hold(held = true);
      if (e.kind == Event::kResume) {
        if (ts.s() != 0) {  // resume once the hold stands still
          ++events_postponed;
          --next;
          break;
        }
        ts.hold(held = false);
      }
      if (e.kind == Event::kOverride) ts.set_override(static_cast<int64_t>(std::ldexp(e.value, ib.scale_bits)));
      if (e.kind == Event::kPause) paused_until = t + static_cast<uint64_t>(e.value);
    }
    if (link_per_tick && t >= paused_until) received = std::min<uint64_t>(bf.n, received + link_per_tick);
    const auto y = ts.tick(bf.samples, received, received == bf.n);
    std::vector<double> yu(3);
    for (int a = 0; a < 3; ++a) yu[a] = static_cast<double>(y[a]) * bf.lsb;
    out.push_back(yu);
    // every output lies between the two engine samples around it (the same
    // points re-timed; per axis, the interpolation rounded down)
    const uint64_t e = ts.engine_index();
    for (int a = 0; a < 3; ++a) {
      const int64_t y0 = bf.samples[e * 3 + a], y1 = e + 1 < bf.n ? bf.samples[(e + 1) * 3 + a] : y0;
      EXPECT_GE(y[a], std::min(y0, y1)) << "tick " << t;
      EXPECT_LE(y[a], std::max(y0, y1)) << "tick " << t;
    }
    if (held && ts.s() == 0 && out.size() >= 2) o.held_still = o.held_still || out[out.size() - 2] == yu;
    if (received == bf.n && e + 1 >= bf.n && ts.s() >= 0 && t > 10) {
      o.ended_on_last = true;
      for (int a = 0; a < 3; ++a) o.ended_on_last = o.ended_on_last && y[a] == bf.samples[(bf.n - 1) * 3 + a];
      // a few still ticks after the end
      for (int i = 0; i < 3; ++i) out.push_back(yu);
      break;
    }
  }
  o.servo_ticks = out.size();
  o.starved_holds = ts.starved_holds();
  // sample differences at H against the machine's limits
  const char* names[3] = {"x", "y", "z"};
  for (size_t i = 3; i < out.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      const double d1 = out[i][a] - out[i - 1][a], d1p = out[i - 1][a] - out[i - 2][a], d1pp = out[i - 2][a] - out[i - 3][a];
      const double r[3] = {std::fabs(d1) / H / bf.limits[a].v, std::fabs(d1 - d1p) / (H * H) / bf.limits[a].a,
                           std::fabs(d1 - 2 * d1p + d1pp) / (H * H * H) / bf.limits[a].j};
      const char* what[3] = {"v", "a", "j"};
      for (int q = 0; q < 3; ++q)
        if (r[q] > o.worst) {
          o.worst = r[q];
          o.worst_what = std::string(what[q]) + "_" + names[a] + " at servo tick " + std::to_string(i);
        }
    }
  return o;
}

TEST(TimeScaleButterfly, UnscaledPlaysTheEngineSamples) {
  const Butterfly& bf = butterfly();
  const Outcome o = play(bf, {}, 1.0, 0);
  std::printf("  unscaled: %llu servo ticks, worst %.4f of a limit (%s)\n",
              static_cast<unsigned long long>(o.servo_ticks), o.worst, o.worst_what.c_str());
  EXPECT_TRUE(o.ended_on_last);
  EXPECT_LE(o.worst, 1.0) << o.worst_what;
}

TEST(TimeScaleButterfly, HoldAndOverrideAtRandomTicksKeepEveryLimit) {
  const Butterfly& bf = butterfly();
  const uint64_t seed = test::env_seed(1);
  std::mt19937_64 rng(seed);
  const uint64_t motion_ticks = bf.n * 20 / 1000;  // servo ticks at s = 1
  for (int run = 0; run < 6; ++run) {
    std::vector<Event> ev;
    uint64_t t = rng() % (motion_ticks / 2);
    ev.push_back({t, Event::kHold});
    t += 50 + rng() % 1500;
    ev.push_back({t, Event::kResume});
    t += rng() % 2000;
    ev.push_back({t, Event::kOverride, 0.2 + 0.8 * std::uniform_real_distribution<double>(0, 1)(rng)});
    t += rng() % 3000;
    ev.push_back({t, Event::kOverride, 1.0});
    const Outcome o = play(bf, ev, 1.0, 0);
    std::printf("  seed %llu run %d: hold at %llu, %llu servo ticks, worst %.4f of a limit (%s)\n",
                static_cast<unsigned long long>(seed), run, static_cast<unsigned long long>(ev[0].at),
                static_cast<unsigned long long>(o.servo_ticks), o.worst, o.worst_what.c_str());
    EXPECT_TRUE(o.ended_on_last) << "run " << run;
    EXPECT_TRUE(o.held_still) << "run " << run << ": the hold came to a standstill";
    EXPECT_LE(o.worst, 1.0) << "run " << run << ": " << o.worst_what;
  }
}

TEST(TimeScaleButterfly, OverrideAboveOneWithinTheLimits) {
  // s_max 1.2 (the bounds are derived for it; 1.5 leaves no jerk headroom
  // and is refused): 120 % from a random tick, a hold, back to 120 %
  const Butterfly& bf = butterfly();
  EXPECT_THROW(play(bf, {}, 1.5, 0), std::invalid_argument);
  std::mt19937_64 rng(test::env_seed(5));
  for (int run = 0; run < 3; ++run) {
    const uint64_t t0 = rng() % 3000, t1 = t0 + 500 + rng() % 3000;
    const Outcome o = play(bf, {{t0, Event::kOverride, 1.2}, {t1, Event::kHold}, {t1 + 300, Event::kResume}}, 1.2, 0);
    std::printf("  120 %% from %llu, hold at %llu: %llu servo ticks, worst %.4f of a limit (%s)\n",
                static_cast<unsigned long long>(t0), static_cast<unsigned long long>(t1),
                static_cast<unsigned long long>(o.servo_ticks), o.worst, o.worst_what.c_str());
    EXPECT_TRUE(o.ended_on_last);
    EXPECT_LE(o.worst, 1.0) << o.worst_what;
  }
}

TEST(TimeScaleButterfly, RampsFasterThanTheBoundsBreakALimit) {
  // the same holds with ramps 16 times faster: the output check sees the
  // acceleration or jerk the derivation keeps out
  const Butterfly& bf = butterfly();
  double worst = 0;
  for (uint64_t at : {2474u, 3339u, 4328u, 2235u}) {
    const Outcome o = play(bf, {{at, Event::kHold}, {at + 400, Event::kResume}}, 1.0, 0, 4);
    std::printf("  16x ramps, hold at %llu: worst %.3f of a limit (%s)\n", static_cast<unsigned long long>(at), o.worst,
                o.worst_what.c_str());
    worst = std::max(worst, o.worst);
  }
  EXPECT_GT(worst, 1.0);
}

TEST(TimeScaleButterfly, StarvedLinkStopsOnThePathWithinTheLimits) {
  // the link delivers 30 engine samples per servo tick (n = 50 are played at
  // s = 1), with pauses: the unit holds by itself before the data runs out
  // and resumes when enough has arrived
  const Butterfly& bf = butterfly();
  std::mt19937_64 rng(test::env_seed(3));
  std::vector<Event> ev;
  for (uint64_t t = 500; t < 9000; t += 1500 + rng() % 1000) ev.push_back({t, Event::kPause, 200.0 + rng() % 800});
  const Outcome o = play(bf, ev, 1.0, 30);
  std::printf("  starved: %llu servo ticks, %llu automatic holds, worst %.4f of a limit (%s)\n",
              static_cast<unsigned long long>(o.servo_ticks), static_cast<unsigned long long>(o.starved_holds), o.worst,
              o.worst_what.c_str());
  EXPECT_GT(o.starved_holds, 0u);
  EXPECT_TRUE(o.ended_on_last);
  EXPECT_LE(o.worst, 1.0) << o.worst_what;
}

TEST(TimeScaleBounds, NoHeadroomIsRefusedNamingTheAxis) {
  std::vector<timescale::AxisKinematics> plan = {{100, 2000, 40000}, {100, 3000, 40000}};
  std::vector<timescale::AxisKinematics> lim = {{200, 3000, 50000}, {200, 3000, 50000}};
  const timescale::OutputError err{20e-6, 1e-3, std::ldexp(1.0, -32)};
  try {
    timescale::derive_ramp_bounds(plan, lim, 1.0, err);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("axis Y"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("acceleration"), std::string::npos) << e.what();
  }
  plan[1].a = 2000;
  const auto b = timescale::derive_ramp_bounds(plan, lim, 1.0, err);
  // the bounds hold for every axis (the conditions, evaluated here)
  for (size_t a = 0; a < plan.size(); ++a) {
    const double e = err.of_axis(plan[a]), H = 1e-3;
    EXPECT_LE(plan[a].a + plan[a].v * b.rate + 4 * e / (H * H), lim[a].a * (1 + 1e-12));
    EXPECT_LE(plan[a].j + 3 * plan[a].a * b.rate + plan[a].v * b.accel + 8 * e / (H * H * H), lim[a].j * (1 + 1e-12));
  }
  EXPECT_GT(b.rate, 0);
  EXPECT_GT(b.accel, 0);
}

}  // namespace
