// SPDX-License-Identifier: Apache-2.0
// The time-scale unit's hls model (hls/traj_time_scale.hpp) against the exact
// reference (host/timescale): every output sample, S and the automatic-hold
// count equal at every servo tick, with holds, overrides and a starved link.
#include <gtest/gtest.h>

#include <cstdio>

#include "test_seed.hpp"
#include "time_scale_bench.hpp"

namespace {

using namespace traj::tsbench;

void expect_same(const Scenario& sc, const char* what) {
  Unit u;
  uint64_t outs = 0, starved = 0;
  const std::string why = run_scenario(sc, [&](const Unit::In& in) {
    const Unit::Out o = u.outputs();
    u.clock(in);
    return o;
  }, &outs, &starved);
  std::printf("  %s (seed %llu): %llu servo ticks, %llu automatic holds\n", what,
              static_cast<unsigned long long>(sc.seed), static_cast<unsigned long long>(outs),
              static_cast<unsigned long long>(starved));
  EXPECT_EQ(why, "") << what;
  EXPECT_GT(outs, 100u) << what;
}

TEST(TimeScaleHls, PlainRunIsTheReference) {
  Scenario sc;
  sc.seed = traj::test::env_seed(1);
  expect_same(sc, "plain");
}

TEST(TimeScaleHls, HoldsAndOverridesAreTheReference) {
  for (uint64_t seed : {traj::test::env_seed(2), uint64_t{3}}) {
    Scenario sc;
    sc.seed = seed;
    sc.hold_every = 97;
    sc.hold_len = 40;
    sc.override_every = 53;
    expect_same(sc, "holds and overrides");
  }
}

TEST(TimeScaleHls, StarvedLinkIsTheReference) {
  Scenario sc;
  sc.seed = traj::test::env_seed(4);
  sc.link_per_tick = 11;  // 16 needed at s = 1
  sc.pause_every = 150;
  sc.pause_len = 60;
  sc.override_every = 71;
  uint64_t starved = 0;
  Unit u;
  const std::string why = run_scenario(sc, [&](const Unit::In& in) {
    const Unit::Out o = u.outputs();
    u.clock(in);
    return o;
  }, nullptr, &starved);
  EXPECT_EQ(why, "");
  EXPECT_GT(starved, 3u);
}

// The servo period of the scenarios is timescale::unit_tick_clocks
// (run_scenario): a servo tick whose work took longer would find the unit
// busy and fail them with err_o. Here across rate bounds (fast and slow
// ramps, so short and long stops), engine latencies, holds, overrides and
// starvation; the longest run of busy clocks is below the bound.
TEST(TimeScaleHls, ServoTickWithinTheClockBound) {
  struct Case {
    traj::timescale::IntBounds b;
    int p, latency;
  };
  const Case cases[] = {{{10, 12, 1536}, 4, 3}, {{14, 95, 19660}, 3, 40}, {{12, 1, 5000}, 2, 7}, {{8, 200, 511}, 5, 1}};
  for (const Case& c : cases) {
    Scenario sc;
    sc.seed = traj::test::env_seed(5);
    sc.b = c.b;
    sc.p = c.p;
    sc.engine_latency = c.latency;
    sc.hold_every = 89;
    sc.hold_len = 30;
    sc.override_every = 41;
    sc.link_per_tick = (uint64_t(1) << c.p) - 1;
    sc.pause_every = 300;
    sc.pause_len = 40;
    sc.max_servo_ticks = 4000;
    Unit u;
    uint64_t busy = 0;
    const std::string why = run_scenario(sc, [&](const Unit::In& in) {
      const Unit::Out o = u.outputs();
      u.clock(in);
      return o;
    }, nullptr, nullptr, &busy);
    const uint64_t bound = traj::timescale::unit_tick_clocks(c.b, c.p, kAxes, c.latency, kOutWidth, kSW);
    std::printf("  sb %d m %lld s_max %lld p %d engine latency %d: longest servo tick's work %llu clocks, bound %llu\n",
                c.b.scale_bits, static_cast<long long>(c.b.m), static_cast<long long>(c.b.s_max), c.p, c.latency,
                static_cast<unsigned long long>(busy), static_cast<unsigned long long>(bound));
    EXPECT_EQ(why, "");
    EXPECT_LT(busy, bound);
    EXPECT_GT(busy, 0u);
  }
}

}  // namespace
