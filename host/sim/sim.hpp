// trajcore: run a segment stream through a Verilated core, with the hls model
// beside it on every cycle. Version-1 streams (forward-difference segments
// only) run on the forward-difference engine (the tool carries the cubic and
// the quintic builds of rtl/traj_fd_engine.sv); version-2 streams (the header
// carries a BCU format; FD and BCU records in any order) run on rtl/traj_core.sv
// (both engines behind one word stream, tuser = kind; the build in
// host/app/CMakeLists.txt, constants below).
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bcu/bcu_format.hpp"
#include "fd/fd_compiler.hpp"
#include "report/report.hpp"
#include "stream/segment_stream.hpp"

namespace traj::sim {

struct SimResult {
  report::Samples samples;  // one per emitted sample (ticks in order)
  uint64_t cycles = 0, underruns = 0, mismatches = 0;
  bool tick_err = false;
  double seconds = 0;
  // traj_core runs (version-2 streams) only:
  std::string engine = "traj_fd_engine";
  uint64_t prediction_mismatches = 0;  // samples (and seg_done) != the exact prediction from the records
  uint64_t switches = 0;               // kind switches between consecutive segments
  uint64_t fd_segments = 0, bcu_segments = 0;
  int tick_gap = 0;                    // clock cycles between ticks used
};

// Throws std::runtime_error if no carried engine matches the stream's format.
SimResult simulate(const stream::Header& h, const std::vector<stream::Record>& recs, int tick_gap = 0,
                   const std::function<void(double)>& progress = {});

// The traj_core build the tool carries (host/app/CMakeLists.txt verilates
// rtl/traj_core.sv with exactly these; they are traj_core's defaults).
struct CoreBuild {
  static constexpr int kAxes = 3, kDegree = 3, kWidth = 64, kChunk = 16, kGuard = 32;
  static constexpr int kCtrl = 40, kBcuGuard = 9, kMaxDepth = 12;
};
bool has_core();  // false if the tool was built without host/bcu (TRAJ_SKIP)
// Formats of the carried core for output fraction bits F.
fd::Format core_fd_format(int frac_bits);
bcu::Format core_bcu_format(int frac_bits);
// The core's minimum tick spacing (hls: Core::kMinTickSpacing): the default tick gap.
int core_min_tick_spacing();
// Stream header for the carried core.
stream::Header core_header(int frac_bits, double period, const std::string& units);

}  // namespace traj::sim
