// The step/dir generator: Verilated RTL (rtl/traj_step_gen.sv) against the hls
// model (hls/traj_step_gen.hpp) on every cycle (step, dir, enable, err), and
// independent checks on the pins, decoded here without the model:
//   * step count: whenever the motion has held still for a while, the decoded
//     count (rising step edges, +1 with dir high, -1 with dir low) equals
//     floor(sample / 2^shift) - floor(first sample / 2^shift), per axis;
//   * pulse timing: step high exactly `pulse` clocks, low at least `pulse`
//     clocks; dir stable at least `setup` clocks before a rising step edge and
//     after a falling one;
//   * no error flag on a feasible stream.
// Random smooth motion (velocity random walk with pauses), random shifts,
// tick periods (odd seeds: multiples of 2..8 long enough for 2..8 sub-chords),
// a period change halfway, pulse widths and setup times. TRAJ_SEED=<n> reruns
// one seed.
#include <gtest/gtest.h>
#include <verilated.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "Vtraj_step_gen.h"
#include "test_seed.hpp"
#include "traj_step_gen.hpp"

namespace {

constexpr int kAxes = 3, kOut = 48;
using Model = traj::StepGen<kAxes, kOut>;

class Bench {
 public:
  Bench() : ctx_(std::make_unique<VerilatedContext>()) {
    ctx_->randReset(2);
    rtl_ = std::make_unique<Vtraj_step_gen>(ctx_.get());
    rtl_->clk_i = 0;
  }
  ~Bench() { rtl_->final(); }

  bool cycle(const Model::In& in, std::string* why) {
    apply(in);
    rtl_->clk_i = 0;
    rtl_->eval();
    const auto h = model_.outputs();
    for (int a = 0; a < kAxes; ++a) {
      step_[a] = (rtl_->step_o >> a) & 1;
      dir_[a] = (rtl_->dir_o >> a) & 1;
    }
    err_ = rtl_->err_o;
    if (armed_) {
      std::string w;
      for (int a = 0; a < kAxes; ++a) {
        if (step_[a] != h.step[a]) w += " step_o[" + std::to_string(a) + "]";
        if (dir_[a] != h.dir[a]) w += " dir_o[" + std::to_string(a) + "]";
      }
      if (rtl_->enable_o != h.enable) w += " enable_o";
      if (rtl_->err_o != h.err) w += " err_o";
      if (!w.empty()) {
        *why = "cycle " + std::to_string(cycles_) + ": RTL != hls on" + w;
        return false;
      }
    }
    if (!in.rst_n) armed_ = true;
    model_.clock(in);
    rtl_->clk_i = 1;
    rtl_->eval();
    ++cycles_;
    return true;
  }
  // Two cycles in reset with the inputs of `in` (its rst_n is ignored).
  bool reset(Model::In in, std::string* why) {
    in.rst_n = false;
    return cycle(in, why) && cycle(in, why);
  }
  bool step(int a) const { return step_[a]; }
  bool dir(int a) const { return dir_[a]; }
  bool err() const { return err_; }

 private:
  void apply(const Model::In& in) {
    rtl_->rst_ni = in.rst_n;
    uint32_t sh = 0;
    for (int a = 0; a < kAxes; ++a) sh |= static_cast<uint32_t>(in.shift[a] & 63) << (6 * a);
    rtl_->shift_i = sh;
    rtl_->period_i = in.period;
    rtl_->pulse_i = in.pulse;
    rtl_->setup_i = in.setup;
    rtl_->enable_i = in.enable;
    rtl_->sample_valid_i = in.sample_valid;
    for (int w = 0; w < (kAxes * kOut + 31) / 32; ++w) rtl_->sample_i[w] = 0;
    for (int a = 0; a < kAxes; ++a)
      for (int b = 0; b < kOut; ++b)
        if ((in.sample[a] >> b) & 1) rtl_->sample_i[(a * kOut + b) / 32] |= 1u << ((a * kOut + b) % 32);
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vtraj_step_gen> rtl_;
  Model model_;
  bool armed_ = false, err_ = false;
  bool step_[kAxes] = {}, dir_[kAxes] = {};
  uint64_t cycles_ = 0;
};

// Pin decoder and timing checker of one axis, independent of the RTL/model.
struct Decoder {
  int64_t count = 0;
  bool step = false, dir = true;
  int64_t since_dir = 1 << 30, since_rise = 1 << 30, since_fall = 1 << 30;
  std::string fault;
  void clock(bool s, bool d, int pulse, int setup) {
    ++since_dir, ++since_rise, ++since_fall;
    if (d != dir) {
      if (step && fault.empty()) fault = "dir changed while step high";
      if (since_fall < setup && fault.empty()) fault = "dir hold " + std::to_string(since_fall) + " < " + std::to_string(setup);
      since_dir = 0;
    }
    if (s && !step) {
      if (since_dir < setup && fault.empty()) fault = "dir setup " + std::to_string(since_dir) + " < " + std::to_string(setup);
      if (since_fall < pulse && fault.empty()) fault = "step low " + std::to_string(since_fall) + " < " + std::to_string(pulse);
      count += d ? 1 : -1;
      since_rise = 0;
    }
    if (!s && step) {
      if (since_rise != pulse && fault.empty()) fault = "step high " + std::to_string(since_rise) + " != " + std::to_string(pulse);
      since_fall = 0;
    }
    step = s;
    dir = d;
  }
};

int64_t floor_shift(int64_t s, int shift) { return s >> shift; }  // arithmetic: floor

void run_seed(uint64_t seed, int ticks) {
  std::printf("  seed %llu (rerun: TRAJ_SEED=%llu)\n", (unsigned long long)seed, (unsigned long long)seed);
  std::mt19937_64 rng(seed);
  auto uni = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  Model::In in;
  auto random_period = [&] {
    if (seed % 2 == 0) return static_cast<uint32_t>(uni(Model::kPrepClocks + 2, 600));
    return static_cast<uint32_t>(uni(2 * Model::kPrepClocks, 2 * Model::kPrepClocks + 40) << uni(1, 3));
  };
  in.period = random_period();
  const uint32_t period2 = std::max(random_period(), in.period / 2);
  in.pulse = static_cast<uint32_t>(uni(1, 4));
  in.setup = static_cast<uint32_t>(uni(0, 6));
  in.enable = true;
  int shift[kAxes];
  for (int a = 0; a < kAxes; ++a) in.shift[a] = static_cast<uint8_t>(shift[a] = uni(0, 24));
  // at most this many steps per tick keeps the pulses ahead of the samples
  const int pulse_clocks = 2 * static_cast<int>(in.pulse) + 2 * static_cast<int>(in.setup) + 6;
  const double max_steps = std::max(1.0, 0.4 * std::min(in.period, period2) / pulse_clocks);
  std::printf("    period %u (%d sub-chords) then %u (%d), pulse %u, setup %u, shifts %d %d %d, <= %.1f steps/tick\n",
              in.period, 1 << Model::sub_bits(in.period), period2, 1 << Model::sub_bits(period2), in.pulse, in.setup,
              shift[0], shift[1], shift[2], max_steps);

  Bench b;
  Decoder dec[kAxes];
  std::string why;
  ASSERT_TRUE(b.reset(in, &why)) << why;
  in.rst_n = true;

  double x[kAxes], v[kAxes] = {};
  int64_t s0[kAxes], s[kAxes];
  for (int a = 0; a < kAxes; ++a) x[a] = std::uniform_real_distribution<double>(-1e9, 1e9)(rng);
  std::normal_distribution<double> N(0, 1);
  int checks = 0, pause = 0;
  for (int k = 0; k < ticks; ++k) {
    const uint32_t tick_clocks = in.period;
    // motion: pauses of 4 ticks every now and then, else a smooth velocity walk
    if (pause == 0 && uni(0, 60) == 0) pause = 6;
    for (int a = 0; a < kAxes; ++a) {
      const double vmax = max_steps * std::ldexp(1.0, shift[a]);
      if (pause > 0) v[a] = 0;
      else v[a] = std::clamp(v[a] + 0.15 * vmax * N(rng), -vmax, vmax);
      x[a] += v[a];
      s[a] = static_cast<int64_t>(std::floor(x[a]));
      if (k == 0) s0[a] = s[a];
      in.sample[a] = static_cast<traj::u128>(s[a]) & traj::mask(kOut);
    }
    for (uint32_t c = 0; c < tick_clocks; ++c) {
      in.sample_valid = (c == 0);
      // the new period from the last clock of the tick before (the contract:
      // it holds in the clock before a sample too)
      if (k + 1 == ticks / 2 && c + 1 == tick_clocks) in.period = period2;
      ASSERT_TRUE(b.cycle(in, &why)) << "seed " << seed << " tick " << k << ": " << why;
      for (int a = 0; a < kAxes; ++a) {
        dec[a].clock(b.step(a), b.dir(a), static_cast<int>(in.pulse), static_cast<int>(in.setup));
        ASSERT_TRUE(dec[a].fault.empty()) << "seed " << seed << " axis " << a << " tick " << k << ": " << dec[a].fault;
      }
    }
    if (pause > 0 && --pause == 0) {
      // held still for several ticks: everything commanded has been stepped
      for (int a = 0; a < kAxes; ++a)
        ASSERT_EQ(dec[a].count, floor_shift(s[a], shift[a]) - floor_shift(s0[a], shift[a]))
            << "seed " << seed << " axis " << a << " tick " << k;
      ++checks;
    }
  }
  EXPECT_FALSE(b.err()) << "seed " << seed;
  std::printf("    %d ticks, %d still points checked, steps %lld %lld %lld: RTL == hls\n", ticks, checks,
              (long long)dec[0].count, (long long)dec[1].count, (long long)dec[2].count);
  EXPECT_GT(checks, 0);
}

}  // namespace

TEST(StepGen, RandomMotionExactCountsAndPulseTiming) {
  if (traj::test::env_seed_given()) {
    run_seed(traj::test::env_seed(0), 3000);
    return;
  }
  for (uint64_t seed : {1, 2, 3, 4, 5, 6, 7, 8}) run_seed(seed, 1500);
}

TEST(StepGen, SampleBeforePrepDoneIsAnError) {
  // A tick period shorter than the preparation: the second sample arrives
  // while the first is still being prepared; err_o must rise (both models).
  Bench b;
  std::string why;
  Model::In in;
  in.rst_n = false;
  ASSERT_TRUE(b.cycle(in, &why)) << why;
  in.rst_n = true;
  in.period = 1000;
  for (int k = 0; k < 3; ++k) {
    in.sample[0] = static_cast<traj::u128>(k * 1000);
    for (int c = 0; c < 20; ++c) {
      in.sample_valid = (c == 0);
      ASSERT_TRUE(b.cycle(in, &why)) << why;
    }
  }
  in.sample_valid = false;
  ASSERT_TRUE(b.cycle(in, &why)) << why;
  EXPECT_TRUE(b.err());
}

// The step rate the board promises: 1 MHz per axis on 3 axes at once, at the
// iCEBreaker's 30 MHz core clock with a 0.47 us pulse (14 clocks high, 14
// low: one step per 28 clocks, 1.07 MHz at most), 1 ms ticks. Each axis
// ramps up to 1000 steps per tick (1 MHz; axis 1 backwards, axis 2 half a
// tick later), holds, ramps down; the pins decoded here give the exact
// count, the pulse timing holds, no error, and the busiest 1 ms window of
// every axis has at least 1000 rising edges.
TEST(StepGen, OneMegahertzOnThreeAxes) {
  constexpr uint32_t kClocksPerTick = 30000;  // 1 ms at 30 MHz
  constexpr int kRamp = 8, kHold = 12, kTicks = 2 * kRamp + kHold + 4;
  Model::In in;
  in.period = kClocksPerTick;
  in.pulse = 14;
  in.setup = 2;
  in.enable = true;
  for (int a = 0; a < kAxes; ++a) in.shift[a] = 0;
  Bench b;
  Decoder dec[kAxes];
  std::string why;
  ASSERT_TRUE(b.reset(in, &why)) << why;
  in.rst_n = true;
  const int sign[kAxes] = {1, -1, 1};
  int64_t s[kAxes] = {0, 0, 0};  // from 0: the decoded count is the position in steps
  std::vector<uint64_t> rises[kAxes];
  uint64_t clock = 0;
  for (int k = 0; k < kTicks; ++k) {
    for (int a = 0; a < kAxes; ++a) {
      // steps this tick: ramp 0 -> 1000 over kRamp ticks, hold, ramp down (axis 2 half a ramp step later)
      const double t = k - (a == 2 ? 0.5 : 0.0);
      const double rate = t < 0 ? 0 : t < kRamp ? 1000 * t / kRamp
                                : t < kRamp + kHold ? 1000 : std::max(0.0, 1000 * (2 * kRamp + kHold - t) / kRamp);
      s[a] += sign[a] * static_cast<int64_t>(std::lround(rate));
      in.sample[a] = static_cast<traj::u128>(s[a]) & traj::mask(kOut);
    }
    for (uint32_t c = 0; c < in.period; ++c, ++clock) {
      in.sample_valid = (c == 0);
      ASSERT_TRUE(b.cycle(in, &why)) << "tick " << k << ": " << why;
      for (int a = 0; a < kAxes; ++a) {
        const bool was = dec[a].step;
        dec[a].clock(b.step(a), b.dir(a), static_cast<int>(in.pulse), static_cast<int>(in.setup));
        ASSERT_TRUE(dec[a].fault.empty()) << "axis " << a << " tick " << k << ": " << dec[a].fault;
        if (!was && dec[a].step) rises[a].push_back(clock);
      }
    }
  }
  EXPECT_FALSE(b.err());
  for (int a = 0; a < kAxes; ++a) {
    EXPECT_EQ(dec[a].count, s[a]) << "axis " << a;
    size_t busiest = 0;
    for (size_t i = 0, j = 0; j < rises[a].size(); ++j) {
      while (rises[a][j] - rises[a][i] >= kClocksPerTick) ++i;
      busiest = std::max(busiest, j - i + 1);
    }
    EXPECT_GE(busiest, 1000u) << "axis " << a;
    std::printf("  axis %d: %lld steps, busiest 1 ms window %zu rising edges (%.3f MHz)\n", a,
                static_cast<long long>(dec[a].count), busiest, busiest / 1e3);
  }
}

TEST(StepGen, MoreThanOneStepPerClockIsAnError) {
  // Axis 0 at a constant speed of `per_tick` steps per tick of 400 clocks
  // (shift 0). Above 400 the DDA would need more than one step a clock:
  // err_o rises the clock after such an interval starts, in both models
  // (compared every cycle: a late or missing flag in either is a mismatch,
  // before the pulses could fall behind and raise it for their own reason).
  // At 150 steps per tick there is no error.
  auto run = [](int64_t per_tick, bool* err, std::string* why) {
    Bench b;
    Model::In in;
    in.period = 400;
    in.pulse = 1;
    in.setup = 0;
    in.enable = true;
    if (!b.reset(in, why)) return false;
    in.rst_n = true;
    for (int k = 0; k < 6; ++k) {
      in.sample[0] = static_cast<traj::u128>(k * per_tick);
      for (uint32_t c = 0; c < in.period; ++c) {
        in.sample_valid = (c == 0);
        if (!b.cycle(in, why)) return false;
      }
    }
    *err = b.err();
    return true;
  };
  std::string why;
  bool err = false;
  ASSERT_TRUE(run(150, &err, &why)) << why;
  EXPECT_FALSE(err) << "150 steps per tick of 400 clocks";
  ASSERT_TRUE(run(1200, &err, &why)) << why;
  EXPECT_TRUE(err) << "1200 steps per tick of 400 clocks";
}
