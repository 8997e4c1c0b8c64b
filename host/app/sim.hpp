// trajcore: run a segment stream through the Verilated forward-difference
// engine (the tool carries the cubic and the quintic builds of
// rtl/traj_fd_engine.sv), with the hls model beside it on every cycle.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "planner/pipeline.hpp"
#include "stream/segment_stream.hpp"

namespace traj::app {

struct SimResult {
  plan::Samples samples;  // one per emitted sample (ticks in order)
  uint64_t cycles = 0, underruns = 0, mismatches = 0;
  bool tick_err = false;
  double seconds = 0;
};

// Throws std::runtime_error if no carried engine matches the stream's format.
SimResult simulate(const stream::Header& h, const std::vector<stream::Record>& recs, int tick_gap = 0,
                   const std::function<void(double)>& progress = {});

}  // namespace traj::app
