// trajcore planner: the whole host job, curve -> compiled segment stream, and
// the report on what the core outputs.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "fd/fd_compiler.hpp"
#include "planner/planner.hpp"
#include "planner/segments.hpp"
#include "stream/segment_stream.hpp"

namespace traj::plan {

struct JobConfig {
  Limits limits;
  PlanOptions plan;
  int degree = 5;          // 5: quintic, C2 joins (default); 3: cubic
  fd::Format format;       // engine format; degree and axes are set from `degree` and 3 axes
  std::string units = "mm";
  JobConfig();
};

// Engine format for a segment degree (the builds the tool carries):
//   quintic: Axes 3, Degree 5, Width 96, Chunk 16, Guard 48, F 32 (1 LSB = 2^-32 units)
//   cubic:   Axes 3, Degree 3, Width 64, Chunk 16, Guard 32, F 16
fd::Format engine_format(int degree);

struct JobResult {
  Plan plan;
  std::vector<TickSample> ticks;
  std::vector<TimeSegment> segments;
  std::vector<fd::Compiled> compiled;
  stream::Header header;
  double fit_tol = 0;
  int repairs = 0;  // local speed caps added by the tick-level checks
  double t_plan = 0, t_ticks = 0, t_fit = 0, t_compile = 0;  // seconds
};

using Progress = std::function<void(const std::string& stage, double fraction)>;

Path load_path(const std::string& file);
// One plan (a whole path, or one streaming window) is sampled at every tick
// in memory: at most kMaxPlanTicks ticks (PlanError naming `what` beyond).
constexpr double kMaxPlanTicks = 1e7;
void check_tick_count(double duration, double period, const std::string& what);
JobResult run_job(const Path& p, const JobConfig& cfg, const Progress& progress = {});
std::vector<stream::Record> records_of(const JobResult& r);

// The core's output, as integers per tick and axis (OutWidth <= 63 bits).
struct Samples {
  std::vector<std::array<long long, 3>> v;
};

struct Report {
  double motion_time = 0;
  long long ticks = 0;
  size_t segments = 0;
  uint32_t k_min = 0, k_max = 0;
  double max_deviation = 0;  // distance of output samples to the exact curve, units
  double fit_tol = 0, quant = 0;
  double feed_fluct_max = 0, feed_fluct_min = 0, feed_fluct_rms = 0;
  Peaks plan_peaks, fit_peaks, out_peaks;
  double out_path_v = 0, out_path_a = 0, out_path_j = 0;  // from sample differences (vector norms)
  double allow_v = 0, allow_a = 0, allow_j = 0;           // quantisation allowance on sample differences, per axis
  double allow_path_v = 0;                                // the same for the path speed (vector norm): sqrt(dim) allow_v
  double worst_plan = 0, worst_fit = 0, worst_out = 0;
  std::string worst_plan_what, worst_fit_what, worst_out_what;
  int guard_needed = 0;
};

// The host's exact prediction of the core's samples (fd::Compiler::sample_at
// on every compiled segment): bit for bit what the engine outputs, without
// running it (tb/fd and the co-simulations check that identity).
Samples predicted_samples(const JobResult& r);

Report make_report(const Path& p, const JobConfig& cfg, const JobResult& r, const Samples& s);
std::string report_text(const JobConfig& cfg, const Report& rep, const JobResult& r);
// SVG plots: path coloured by feed; feed, acceleration and jerk against time.
void write_plots(const std::string& dir, const Path& p, const JobConfig& cfg, const JobResult& r, const Samples& s);

}  // namespace traj::plan
