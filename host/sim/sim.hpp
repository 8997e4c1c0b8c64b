// SPDX-License-Identifier: Apache-2.0
// trajcore: run a segment stream through a Verilated engine, with its hls
// model beside it on every cycle (the lockstep driver, lockstep.hpp).
// Streams without a BCU format (forward-difference segments only) run on a
// traj_fd_engine build, streams whose header carries a BCU format (FD and BCU
// records in any order) on a traj_core build (both engines behind one word
// stream, tuser = kind). The builds the tool carries are listed once,
// in host/sim/CMakeLists.txt (TRAJ_SIM_BUILDS); carried() describes them.
#pragma once
#include <array>
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
  report::Samples samples;  // one per emitted sample (ticks in order); empty when a sink took them
  uint64_t sample_count = 0;
  uint64_t cycles = 0, underruns = 0, mismatches = 0;
  bool tick_err = false;
  double seconds = 0;
  std::string engine = "traj_fd_engine";  // the unit of the build run
  int tick_gap = 0;                       // clock cycles between ticks used
  // traj_core runs (streams with a BCU format) only:
  uint64_t prediction_mismatches = 0;  // samples (and seg_done) != the exact prediction from the records
  uint64_t switches = 0;               // kind switches between consecutive segments
  uint64_t fd_segments = 0, bcu_segments = 0;
};

// Receives every sample in tick order instead of SimResult::samples: the
// simulation then holds nothing per tick (memory bounded whatever K is).
using SampleSink = std::function<void(uint64_t tick, const report::Sample& sample)>;

// Pulls the next record of a stream: false at its end.
using RecordPull = std::function<bool(stream::Record&)>;

// Throws std::runtime_error if no carried build matches the stream's format.
SimResult simulate(const stream::Header& h, const std::vector<stream::Record>& recs, int tick_gap = 0,
                   const std::function<void(double)>& progress = {}, const SampleSink& sink = {});
// The same for a stream without a BCU format, its records pulled one at a
// time: with a sink, memory is bounded by one segment whatever the stream's
// length. `records` (0: unknown) scales the progress.
SimResult simulate_pulled(const stream::Header& h, const RecordPull& pull, uint64_t records, int tick_gap = 0,
                          const std::function<void(double)>& progress = {}, const SampleSink& sink = {});

// One engine build the tool carries.
struct Build {
  std::string name, unit;  // e.g. fd_cubic, traj_fd_engine
  fd::Format fd;           // its FD engine (frac_bits: the caller's)
  bool has_bcu = false;    // traj_core: and its BCU generator
  bcu::Format bcu;
  int min_tick_gap = 0;      // clock cycles between ticks, at least (a segment load; the core's minimum spacing)
  int default_tick_gap = 0;  // used when simulate() is given none
  fd::Format fd_format(int frac_bits) const;
  bcu::Format bcu_format(int frac_bits) const;
  stream::Header header(int frac_bits, double period, const std::string& units) const;
};
const std::vector<Build>& carried();
// The carried build of that name; throws std::runtime_error naming the carried ones.
const Build& carried(const std::string& name);
bool has_core();  // a traj_core build is carried (false if the tool was built without host/bcu)

}  // namespace traj::sim
