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

}  // namespace
