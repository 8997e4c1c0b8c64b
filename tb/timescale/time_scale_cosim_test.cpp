// SPDX-License-Identifier: Apache-2.0
// Co-simulation of the time-scale unit: rtl/traj_time_scale.sv (Verilated)
// == hls/traj_time_scale.hpp on every cycle and every output port, while the
// bench (time_scale_bench.hpp) checks the unit's output at every servo tick
// against the exact reference (host/timescale).
#include <gtest/gtest.h>
#include <verilated.h>

#include <memory>
#include <string>

#include "sim/vl_bits.hpp"
#include "test_seed.hpp"
#include "time_scale_bench.hpp"
#include "Vtraj_time_scale.h"

namespace {

using namespace traj::tsbench;
using traj::u128;

class Lockstep {
 public:
  Lockstep() : ctx_(std::make_unique<VerilatedContext>()) {
    ctx_->randReset(2);  // unreset state random: a dependence on it shows
    rtl_ = std::make_unique<Vtraj_time_scale>(ctx_.get());
    rtl_->clk_i = 0;
  }
  ~Lockstep() { rtl_->final(); }

  Unit::Out step(const Unit::In& in) {
    rtl_->rst_ni = in.rst_n;
    rtl_->tick_i = in.tick;
    rtl_->m_i = in.m;
    rtl_->s_max_i = in.s_max;
    rtl_->override_i = in.override_s;
    rtl_->shift_i = in.shift;
    rtl_->hold_i = in.hold;
    rtl_->auto_resume_i = in.auto_resume;
    rtl_->end_i = in.end;
    rtl_->avail_i = in.avail;
    rtl_->eng_valid_i = in.eng_valid;
    rtl_->eng_word_i = static_cast<uint32_t>(in.eng_word);
    rtl_->clk_i = 0;
    rtl_->eval();
    const Unit::Out h = unit_.outputs();
    Unit::Out r{};
    r.eng_tick = rtl_->eng_tick_o;
    r.eng_addr = rtl_->eng_addr_o;
    r.sample_valid = rtl_->sample_valid_o;
    for (int a = 0; a < kAxes; ++a) r.sample[a] = traj::vl_bits(rtl_->sample_o, a * kOutWidth, kOutWidth);
    r.s = rtl_->s_o;
    r.starved = rtl_->starved_o;
    r.starved_count = rtl_->starved_count_o;
    r.busy = rtl_->busy_o;
    r.err = rtl_->err_o;
    if (armed_ && why_.empty()) compare(r, h);
    if (!in.rst_n) armed_ = true;
    unit_.clock(in);
    rtl_->clk_i = 1;
    rtl_->eval();
    ++cycles_;
    return h;
  }
  const std::string& why() const { return why_; }
  uint64_t cycles() const { return cycles_; }

 private:
  void compare(const Unit::Out& r, const Unit::Out& h) {
    auto differ = [&](const std::string& port, u128 rv, u128 hv) {
      if (rv != hv && why_.empty())
        why_ = "cycle " + std::to_string(cycles_) + ": " + port + " rtl " + std::to_string(static_cast<unsigned long long>(rv)) +
               " hls " + std::to_string(static_cast<unsigned long long>(hv));
    };
    differ("eng_tick_o", r.eng_tick, h.eng_tick);
    // the word address (combinational from datapath counters, not reset) where
    // the unit reads the engine's sample RAM
    if (h.eng_addr_used) differ("eng_addr_o", r.eng_addr, h.eng_addr);
    differ("sample_valid_o", r.sample_valid, h.sample_valid);
    differ("s_o", r.s, h.s);
    differ("starved_o", r.starved, h.starved);
    differ("starved_count_o", r.starved_count, h.starved_count);
    differ("busy_o", r.busy, h.busy);
    differ("err_o", r.err, h.err);
    if (h.sample_valid)
      for (int a = 0; a < kAxes; ++a) differ("sample_o axis " + std::to_string(a), r.sample[a], h.sample[a]);
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vtraj_time_scale> rtl_;
  Unit unit_;
  bool armed_ = false;
  std::string why_;
  uint64_t cycles_ = 0;
};

void expect_rtl_is_hls(const Scenario& sc, const char* what) {
  Lockstep ls;
  uint64_t outs = 0, starved = 0;
  const std::string ref_why = run_scenario(sc, [&](const Unit::In& in) { return ls.step(in); }, &outs, &starved);
  std::printf("  %s (seed %llu): %llu cycles, %llu servo ticks, %llu automatic holds\n", what,
              static_cast<unsigned long long>(sc.seed), static_cast<unsigned long long>(ls.cycles()),
              static_cast<unsigned long long>(outs), static_cast<unsigned long long>(starved));
  EXPECT_EQ(ls.why(), "") << what << ": RTL != hls";
  EXPECT_EQ(ref_why, "") << what << ": != the reference";
  EXPECT_GT(outs, 100u);
}

TEST(TimeScaleCosim, HoldsOverridesAndStarvation) {
  Scenario sc;
  sc.seed = traj::test::env_seed(1);
  sc.n_samples = 4000;
  sc.hold_every = 89;
  sc.hold_len = 30;
  sc.override_every = 61;
  expect_rtl_is_hls(sc, "holds and overrides");
  Scenario st;
  st.seed = traj::test::env_seed(2);
  st.n_samples = 4000;
  st.link_per_tick = 11;
  st.pause_every = 120;
  st.pause_len = 50;
  st.override_every = 77;
  expect_rtl_is_hls(st, "starved link");
}

TEST(TimeScaleCosim, ServoTickWhileBusySetsErr) {
  Lockstep ls;
  Unit::In in;
  in.m = 4;
  in.s_max = 1024;
  in.override_s = 1024;
  in.shift = 26;
  in.avail = 1000;
  in.rst_n = false;
  ls.step(in);
  in.rst_n = true;
  in.tick = true;
  ls.step(in);
  const Unit::Out o = ls.step(in);  // a second strobe while priming
  in.tick = false;
  const Unit::Out o2 = ls.step(in);
  EXPECT_TRUE(o.busy);
  EXPECT_TRUE(o2.err);
  EXPECT_EQ(ls.why(), "");
}

}  // namespace
