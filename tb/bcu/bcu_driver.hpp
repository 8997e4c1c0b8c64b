// SPDX-License-Identifier: Apache-2.0
// Test driver for the hls BCU generator: feeds stream words, ticks, records.
#pragma once
#include <cstdint>
#include <vector>

#include "sim/ports.hpp"
#include "traj_bcu_gen.hpp"

namespace traj::bcu::test {

struct Event {
  uint64_t cycle;
  bool valid, underrun, done;
  std::vector<int64_t> sample;
};

template <class Gen>
struct Driver {
  Gen gen;
  std::vector<uint64_t> words;
  size_t wi = 0;
  uint64_t cycle = 0;
  std::vector<Event> events;  // every cycle with valid or underrun

  // One clock. tick: tick_i this cycle; offer: s_axis_tvalid allowed.
  void step(bool tick, bool offer = true, bool rst_n = true) {
    typename Gen::In in;
    in.rst_n = rst_n;
    in.tick = tick;
    in.tvalid = offer && wi < words.size();
    in.tdata = in.tvalid ? words[wi] : 0;
    const auto o = sim::hls_ports(gen);
    const bool acc = o.tready && in.tvalid;
    if (o.sample_valid || o.underrun) {
      Event e{cycle, o.sample_valid, o.underrun, o.seg_done, {}};
      for (int a = 0; a < Gen::kAxes; ++a)
        e.sample.push_back(static_cast<int64_t>(sext(gen.sample_bits(a), Gen::kOutWidth)));
      events.push_back(e);
    }
    gen.clock(in);
    if (acc) ++wi;
    ++cycle;
  }
};

}  // namespace traj::bcu::test
