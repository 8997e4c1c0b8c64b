// The tick generator: Verilated RTL (rtl/traj_tick_gen.sv) against the hls
// model (hls/traj_tick_gen.hpp) on every cycle (tick_o, period_o), and
// independent checks of what it must do: one strobe per internal period, one
// strobe per rising edge of the external tick whatever its width, none while
// run is low. Seeds: TRAJ_SEED=<n> reruns one. Built twice: at the default
// widths and with TRAJ_TICK_EXT_WIDTH (the RTL's ExtWidth, -G), where the
// external periods of these tests saturate.
#include <gtest/gtest.h>
#include <verilated.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <random>
#include <string>

#include "Vtraj_tick_gen.h"
#include "test_seed.hpp"
#include "traj_tick_gen.hpp"

namespace {

#ifndef TRAJ_TICK_EXT_WIDTH
#define TRAJ_TICK_EXT_WIDTH 32
#endif
constexpr int kExtWidth = TRAJ_TICK_EXT_WIDTH;
using Model = traj::TickGen<32, kExtWidth>;
// the external period as measured: at most 2^ExtWidth - 1
int measured(int clocks) { return kExtWidth >= 31 ? clocks : std::min(clocks, (1 << kExtWidth) - 1); }

class Bench {
 public:
  Bench() : ctx_(std::make_unique<VerilatedContext>()) {
    ctx_->randReset(2);
    rtl_ = std::make_unique<Vtraj_tick_gen>(ctx_.get());
    rtl_->clk_i = 0;
  }
  ~Bench() { rtl_->final(); }

  // one cycle; false (with why) on a mismatch once reset has been applied
  bool cycle(const Model::In& in, std::string* why) {
    rtl_->rst_ni = in.rst_n;
    rtl_->run_i = in.run;
    rtl_->period_i = in.period;
    rtl_->tick_ext_i = in.tick_ext;
    rtl_->clk_i = 0;
    rtl_->eval();
    const auto h = model_.outputs(in);
    tick_ = rtl_->tick_o;
    if (armed_ && (rtl_->tick_o != h.tick || rtl_->period_o != h.period)) {
      *why = "cycle " + std::to_string(cycles_) + ": tick rtl " + std::to_string(rtl_->tick_o) + " hls " +
             std::to_string(h.tick) + ", period rtl " + std::to_string(rtl_->period_o) + " hls " +
             std::to_string(h.period);
      return false;
    }
    if (!in.rst_n) armed_ = true;
    model_.clock(in);
    rtl_->clk_i = 1;
    rtl_->eval();
    ++cycles_;
    return true;
  }
  bool tick() const { return tick_; }  // tick_o of the last cycle
  uint32_t period() const { return rtl_->period_o; }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vtraj_tick_gen> rtl_;
  Model model_;
  bool armed_ = false, tick_ = false;
  uint64_t cycles_ = 0;
};

}  // namespace

TEST(TickGen, InternalPeriodOneStrobePerPeriod) {
  Bench b;
  std::string why;
  Model::In in;
  in.rst_n = false;
  ASSERT_TRUE(b.cycle(in, &why)) << why;
  in.rst_n = true;
  for (uint32_t P : {2u, 3u, 7u, 100u, 1000u}) {
    in.period = P;
    in.run = false;
    for (int i = 0; i < 5; ++i) {
      ASSERT_TRUE(b.cycle(in, &why)) << why;
    }
    in.run = true;
    int ticks = 0, last = -1, first = -1;
    const int n = 20 * static_cast<int>(P);
    for (int c = 0; c < n + 2; ++c) {
      ASSERT_TRUE(b.cycle(in, &why)) << why;
      if (b.tick()) {
        if (first < 0) first = c;
        if (last >= 0) {
          EXPECT_EQ(c - last, static_cast<int>(P)) << "period " << P;
        }
        last = c;
        ++ticks;
      }
    }
    EXPECT_EQ(first, static_cast<int>(P)) << "first tick P clocks after run (plus the output flop)";
    EXPECT_EQ(ticks, 20) << "period " << P;
  }
  // run low: no tick
  in.run = false;
  for (int c = 0; c < 3000; ++c) {
    ASSERT_TRUE(b.cycle(in, &why)) << why;
    if (c > 1) {
      EXPECT_FALSE(b.tick());
    }
  }
}

TEST(TickGen, ExternalOneStrobePerRisingEdgeAnyWidth) {
  const uint64_t seed = traj::test::env_seed(5);
  std::printf("  seed %llu (rerun: TRAJ_SEED=%llu)\n", (unsigned long long)seed, (unsigned long long)seed);
  std::mt19937_64 rng(seed);
  Bench b;
  std::string why;
  Model::In in;
  in.rst_n = false;
  ASSERT_TRUE(b.cycle(in, &why)) << why;
  in.rst_n = true;
  in.run = true;
  in.period = 0;
  int edges = 0, ticks = 0, widths = 0;
  int last_rise = -1, last_period = -1;
  std::uniform_int_distribution<int> width(1, 40), gap(2, 60);
  int c = 0;
  for (int e = 0; e < 400; ++e) {
    const int w = width(rng), g = gap(rng);
    widths += w;
    for (int i = 0; i < w; ++i, ++c) {
      in.tick_ext = true;
      ASSERT_TRUE(b.cycle(in, &why)) << why;
      ticks += b.tick();
      if (i == 0) {
        if (last_rise >= 0) last_period = c - last_rise;
        last_rise = c;
      }
    }
    ++edges;
    for (int i = 0; i < g; ++i, ++c) {
      in.tick_ext = false;
      ASSERT_TRUE(b.cycle(in, &why)) << why;
      ticks += b.tick();
    }
    if (last_period > 0) {
      EXPECT_EQ(static_cast<int>(b.period()), measured(last_period)) << "measured period";
    }
  }
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(b.cycle(in, &why)) << why;
    ticks += b.tick();
  }
  std::printf("  %d external pulses (%d cycles high in all): %d strobes\n", edges, widths, ticks);
  EXPECT_EQ(ticks, edges);
}

TEST(TickGen, RandomInputsRtlEqualsHls) {
  const uint64_t seed = traj::test::env_seed(9);
  std::printf("  seed %llu (rerun: TRAJ_SEED=%llu)\n", (unsigned long long)seed, (unsigned long long)seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  Bench b;
  std::string why;
  Model::In in;
  in.rst_n = false;
  ASSERT_TRUE(b.cycle(in, &why)) << why;
  for (int c = 0; c < 200000; ++c) {
    in.rst_n = U(rng) > 0.0005;
    if (U(rng) < 0.001) in.run = !in.run;
    if (U(rng) < 0.0005) in.period = U(rng) < 0.3 ? 0 : static_cast<uint32_t>(rng() % 50);
    if (U(rng) < 0.05) in.tick_ext = !in.tick_ext;
    ASSERT_TRUE(b.cycle(in, &why)) << "seed " << seed << ": " << why;
  }
}
