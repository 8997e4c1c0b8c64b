// SPDX-License-Identifier: Apache-2.0
// The path commands of the trajcore tool: plan, run, sim (main.cpp parses the
// command line into these and reports errors).
#pragma once
#include <cstddef>
#include <string>

#include "job/job.hpp"
#include "time_scale_cmd.hpp"

namespace traj::app {

// How G-code is read (input::GcodeOptions beside the machine's axes).
struct GcodeArgs {
  std::string tool_table;            // LinuxCNC tool table for G43 (empty: none; G43 is then refused)
  bool pause_as_stop = false;        // M0/M60 taken as exact stops (input::GcodeOptions::pauses_as_stops)
  bool pause_wait = false;           // M0/M60 as pauses the upload waits at (input::GcodeOptions::pauses_wait)
};

struct PlanArgs {
  job::JobConfig cfg;
  std::string input;                 // path file (empty with raster)
  std::string format;                // "json", "jsonl", "gcode", "svg", "dxf" or empty (by the file name)
  GcodeArgs gcode;
  bool blend_all = false;            // blend every corner, also where a stop is faster (job::ToolpathOptions::faster_stops off)
  std::string output = "out/plan.trj";
  size_t window = 0;                 // > 0: stream with this window
  bool window_given = false;         // --window was on the command line
  int threads = 2;                   // of a streamed plan (job::StreamOptions::prefetch)
  TimeScaleArgs scale;               // --time-scale: planned below the limits, ramp bounds reported
  size_t raster = 0;                 // > 0: a synthetic raster of this many pieces instead of a file
};
// Writes the segment stream; for a whole path also prints the plan report.
int plan_command(const PlanArgs& a);

struct RunArgs {
  job::JobConfig cfg;
  std::string input;
  std::string format;                // as PlanArgs::format
  GcodeArgs gcode;                   // as PlanArgs::gcode
  bool blend_all = false;            // as PlanArgs::blend_all
  std::string out_dir = "out";
  TimeScaleArgs scale;               // as PlanArgs::scale
};
// plan + simulate on the Verilated core + report and plots, all files or none.
int run_command(const RunArgs& a);

struct SimArgs {
  std::string input;
  std::string csv;      // empty: no samples written
  std::string samples;  // binary sample file (host/stream/README.md); empty: none
  int tick_gap = 0;
  bool check = false;   // the samples measured against `limits` (report/sample_check.hpp)
  plan::Limits limits;  // as given to plan (its defaults)
  int axes = 0;         // --axes given: its count, at most the stream's (0: not given)
  std::string plots;     // folder for path_feed.svg, profile.svg (and samples.bin unless --samples); empty: none
  bool check_feed = false;  // --feed given: the path speed checked too (a toolpath's feeds and rapids vary by move)
};
int sim_command(const SimArgs& a);

}  // namespace traj::app
