// SPDX-License-Identifier: Apache-2.0
// A bench for the time-scale unit (hls model alone, or RTL and hls in
// lockstep): an engine that answers each tick with the next sample of a
// trajectory (repeating the last beyond the samples received, as the FD
// engine's underrun does), a link that delivers samples per servo tick with
// pauses, hold and override events; and, at every output, the exact
// reference (host/timescale TimeScaler::tick) given the same inputs.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "timescale/time_scale.hpp"
#include "traj_time_scale.hpp"

namespace traj::tsbench {

constexpr int kAxes = 3, kOutWidth = 48, kSW = 16, kWordWidth = 16;
using Unit = TimeScale<kAxes, kOutWidth, kSW, kWordWidth>;

// A smooth random trajectory sampled at the engine tick, in LSB, that starts
// and ends at rest (a sum of raised-cosine moves per axis).
inline std::vector<int64_t> smooth_samples(uint64_t seed, uint64_t n) {
  std::mt19937_64 rng(seed);
  std::vector<int64_t> s(n * kAxes);
  for (int a = 0; a < kAxes; ++a) {
    std::vector<double> amp(6), per(6);
    for (int i = 0; i < 6; ++i) {
      amp[i] = std::uniform_real_distribution<double>(-1, 1)(rng) * std::ldexp(1.0, 30);
      per[i] = std::floor(std::uniform_real_distribution<double>(1, 6)(rng));
    }
    for (uint64_t t = 0; t < n; ++t) {
      const double u = static_cast<double>(t) / static_cast<double>(n - 1);
      double x = 0;
      for (int i = 0; i < 6; ++i) x += amp[i] * (1 - std::cos(2 * M_PI * per[i] * u)) * 0.5 * u * u * (3 - 2 * u);
      s[t * kAxes + a] = static_cast<int64_t>(std::llround(x)) - (int64_t(1) << 40);
    }
  }
  return s;
}

struct Scenario {
  uint64_t seed = 1;
  uint64_t n_samples = 6000;
  int p = 4;                   // 2^p engine ticks per servo tick
  timescale::IntBounds b{10, 12, 1536};
  uint64_t link_per_tick = 0;  // 0: every sample at once
  uint64_t pause_every = 0, pause_len = 0;
  uint64_t hold_every = 0;     // a hold of hold_len servo ticks every hold_every
  uint64_t hold_len = 0;
  uint64_t override_every = 0;  // a random override every override_every servo ticks
  int engine_latency = 3;       // clocks from eng_tick to eng_valid
  uint64_t max_servo_ticks = 20000;
};

// Drives `step(in) -> Out` (the unit, or the lockstep of RTL and unit) with
// the scenario; returns "" or what first differed from the reference. The
// unit presents a servo tick's output at the next servo tick (sample_valid_o
// after its bits are read out): the reference's output of each servo tick the
// unit takes is queued and compared then, with S and the automatic-hold
// count. The engine answers a tick `engine_latency` clocks after it sees the
// strobe and keeps its sample in a RAM read through the unit's word port (the
// word at the address of the clock before). The servo period is the unit's
// bound (timescale::unit_tick_clocks: a servo tick that took longer would
// find the unit busy and set err_o). *busy_max: the longest run of busy
// clocks.
template <class Step>
std::string run_scenario(const Scenario& sc, Step&& step, uint64_t* outputs = nullptr, uint64_t* starved = nullptr,
                         uint64_t* busy_max = nullptr) {
  const std::vector<int64_t> samples = smooth_samples(sc.seed, sc.n_samples);
  const int n = 1 << sc.p;
  timescale::TimeScaler ref(sc.b, n, kAxes);
  std::mt19937_64 rng(sc.seed * 31 + 7);
  Unit::In in;
  in.m = static_cast<uint32_t>(sc.b.m);
  in.s_max = static_cast<uint32_t>(sc.b.s_max);
  in.override_s = 1u << sc.b.scale_bits;
  in.shift = static_cast<uint32_t>(32 - sc.b.scale_bits + sc.p);
  in.auto_resume = true;
  uint64_t received = sc.link_per_tick ? std::min<uint64_t>(sc.n_samples, 3) : sc.n_samples;
  uint64_t issued = 0;
  int pending = -1;      // clocks until the engine answers
  uint64_t ram_idx = 0;  // the sample in the engine's RAM
  // the engine's sample RAM word at an address {axis, word}
  const auto word = [&](uint32_t addr) {
    const uint32_t ax = addr >> Unit::kWB, w = addr & ((1u << Unit::kWB) - 1);
    if (ax >= static_cast<uint32_t>(kAxes)) return uint64_t{0};
    const u128 v = wrap(static_cast<u128>(samples[ram_idx * kAxes + ax]), kOutWidth);
    return static_cast<uint64_t>(bits(v, static_cast<int>(w) * kWordWidth, kWordWidth));
  };
  struct Expect {
    std::vector<int64_t> y;
    int64_t s;
    uint64_t starved;
    uint64_t tick;
  };
  std::deque<Expect> expect;
  bool primed = false;
  // reset
  in.rst_n = false;
  for (int i = 0; i < 3; ++i) step(in);
  in.rst_n = true;
  const uint64_t period =
      timescale::unit_tick_clocks(sc.b, sc.p, kAxes, sc.engine_latency, kOutWidth, kSW);
  uint64_t outs = 0, hold_until = 0, pause_until = 0, busy_run = 0;
  bool done = false;
  for (uint64_t t = 0; t < sc.max_servo_ticks && !done; ++t) {
    // the run ends one servo tick after the one that reached the last sample
    // (which presents its output)
    done = in.end && ref.engine_index() + 1 >= sc.n_samples && primed;
    // link and events, before the servo tick
    if (sc.pause_every && t % sc.pause_every == sc.pause_every / 2) pause_until = t + sc.pause_len;
    if (sc.link_per_tick && t >= pause_until) received = std::min<uint64_t>(sc.n_samples, received + sc.link_per_tick);
    if (sc.hold_every && t % sc.hold_every == sc.hold_every - 1) hold_until = t + sc.hold_len;
    in.hold = t < hold_until;
    if (sc.override_every && t % sc.override_every == 0 && t > 0)
      in.override_s = static_cast<uint32_t>(rng() % (sc.b.s_max + 1));
    in.end = received == sc.n_samples;
    for (uint64_t c = 0; c < period; ++c) {
      in.tick = c == 0;
      in.avail = static_cast<uint32_t>(received > issued ? received - issued : 0);
      in.eng_valid = pending == 0;
      if (in.tick && (primed || in.avail >= 2)) {  // a servo tick the unit takes: the reference's
        primed = true;
        ref.set_override(in.override_s);
        ref.hold(in.hold);
        const std::vector<int64_t> y = ref.tick(samples, received, in.end);
        expect.push_back({y, ref.s(), ref.starved_holds(), t});
      }
      const Unit::Out o = step(in);
      if (pending >= 0) --pending;
      if (in.eng_valid) ram_idx = std::min<uint64_t>(issued - 1, received - 1);  // underrun: the last again
      if (o.eng_tick) {
        ++issued;
        pending = sc.engine_latency;
      }
      in.eng_word = word(o.eng_addr);
      busy_run = o.busy ? busy_run + 1 : 0;
      if (busy_max) *busy_max = std::max(*busy_max, busy_run);
      if (o.err) return "servo tick " + std::to_string(t) + ": err_o";
      if (o.sample_valid) {
        if (expect.empty()) return "servo tick " + std::to_string(t) + ": an output before any servo tick was taken";
        const Expect e = expect.front();
        expect.pop_front();
        ++outs;
        const std::string at = "servo tick " + std::to_string(e.tick) + " (presented at " + std::to_string(t) + ")";
        for (int a = 0; a < kAxes; ++a)
          if (sext(o.sample[a], kOutWidth) != e.y[a])
            return at + " axis " + std::to_string(a) + ": unit " +
                   std::to_string(static_cast<long long>(sext(o.sample[a], kOutWidth))) + ", reference " +
                   std::to_string(e.y[a]);
        if (static_cast<int64_t>(o.s) != e.s)
          return at + ": S " + std::to_string(o.s) + ", reference " + std::to_string(e.s);
        if (o.starved_count != (e.starved & 0xffff))
          return at + ": starved count " + std::to_string(o.starved_count) + ", reference " + std::to_string(e.starved);
      }
    }
  }
  // the last servo tick taken presents its output at the next one
  if (expect.size() > 1) return std::to_string(expect.size()) + " servo ticks' outputs not presented (1 expected)";
  if (outputs) *outputs = outs;
  if (starved) *starved = ref.starved_holds();
  return "";
}

}  // namespace traj::tsbench
