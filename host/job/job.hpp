// SPDX-License-Identifier: Apache-2.0
// A job: a whole path planned, fitted and compiled into the engine's segment
// stream (run_job). Streaming over paths of any length is job/streaming.hpp;
// the report on what the core outputs is report/report.hpp.
#pragma once
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "fd/fd_compiler.hpp"
#include "job/machine.hpp"
#include "planner/planner.hpp"
#include "planner/segments.hpp"
#include "stream/segment_stream.hpp"

namespace traj::job {

// The longest segment the fit makes, in fit ticks, where the fit tick is
// more than one engine tick (Machine::fit_ticks): a second at the 1 ms fit
// tick; the engine's pieces are cut from it (engine_pieces).
constexpr uint32_t kMaxFitTicks = 1000;
// The plan's share of the feed where the fit tick is coarser than the
// engine's (plan::PlanOptions::feed_share): room for the fit's speed error,
// which the chord check at every engine tick holds to the feed.
constexpr double kFineFeedShare = 1 - 1e-4;
// SegmentOptions::feed_rel where the fit tick is coarser than the engine's
// and no --feed-accuracy is given: every chord within 2e-3 of the plan's.
constexpr double kFineFeedRel = 1e-3;

struct JobConfig {
  plan::Limits limits;
  plan::PlanOptions plan;  // planner tuning; its period is set from `machine` (the fit tick)
  Machine machine;
  // run_job: the plan sampled at every engine tick in JobResult::ticks (what
  // the report compares the core's samples with). Off, the result holds the
  // fit ticks' samples only, and the job's memory does not grow with the
  // tick rate (`trajcore plan` without a report, the benchmarks).
  bool engine_ticks = true;
  // Program pauses (run_job): at each, the path has a stop and a rest (a
  // dwell of at least kPauseRest fit ticks), and the segment that ends there
  // carries the pause (TimeSegment::pause; the stream's pause record).
  struct PauseAt {
    double s = 0;  // arc length of the stop
    plan::ProgramPause pause{};
  };
  std::vector<PauseAt> pauses;
  // Validates the limits and the machine; PlanError naming the field.
  void validate() const;
  // The planner options with the machine's tick period.
  plan::PlanOptions plan_options() const;
  // The fit options: the machine's degree, longest segment and fit budget.
  plan::SegmentOptions segment_options() const;
};

struct JobResult {
  plan::Plan plan;
  // The plan at every engine tick (JobConfig::engine_ticks), else at every
  // fit tick (Machine::fit_ticks apart); `engine_tick_count` either way.
  std::vector<plan::TickSample> ticks;
  // The plan's peaks at the samples its tick checks ran on (the fit ticks,
  // with the engine ticks beside each curvature step): what the plan is held
  // to. Between fit ticks the plan's bounds are not checked (the fit's
  // segments are, at every engine tick, and the core's samples are);
  // unset where the result was not made by run_job.
  std::optional<plan::Peaks> plan_peaks;
  uint64_t engine_tick_count = 0;
  std::vector<plan::TimeSegment> segments;
  std::vector<fd::Compiled> compiled;
  stream::Header header;
  double fit_tol = 0;
  int repairs = 0;  // local speed caps added by the tick-level checks and the fit
  int rounds = 0;   // plans made (each round adds every cap its checks found)
  // over every round: the exact checks' frames of moves re-timed on the
  // tick grid, and the curved moves searched or taken from an earlier round
  long long check_frames = 0, moves_searched = 0, moves_reused = 0;
  size_t fit_ticks = 0, fit_failures = 0;  // over every round: ticks given to the fit, its failures
  double t_plan = 0, t_ticks = 0, t_fit = 0, t_compile = 0;  // seconds
};

using Progress = std::function<void(const std::string& stage, double fraction)>;

// One plan (a whole path, or one streaming window) is sampled at every tick
// in memory: at most kMaxPlanTicks ticks (PlanError naming `what` beyond).
constexpr double kMaxPlanTicks = 1e7;
void check_tick_count(double duration, double period, const std::string& what);
// Machine::check_range on every curve of `p` (run_job and every streaming window, before planning).
void check_path_range(const plan::Path& p, const Machine& m);

JobResult run_job(const plan::Path& p, const JobConfig& cfg, const Progress& progress = {});
std::vector<stream::Record> records_of(const JobResult& r);

// Compiles time segments one after another, each from the exact integer end
// state of the one before (no drift), into one reused fd::Compiled.
class SegmentCompiler {
 public:
  explicit SegmentCompiler(const Machine& m);
  // The compiled segment is valid until the next call. PlanError on a compile error.
  const fd::Compiled& compile(const plan::TimeSegment& seg, size_t index);

 private:
  // The segment starts at the previous one's exact register end, which may
  // be up to Machine::joint_lsb (plus the register error) from its
  // polynomial's start; the compiler blends the
  // difference out linearly (the target is the polynomial plus
  // delta (1 - t/T)), and the joint |delta| is stated apart
  // (fd::Compiled::offset_lsb).
  void compile_joined(const plan::TimeSegment& seg, const std::string& where);
  // A bound of |delta| in output LSB, from the two polynomials in long double.
  double joint_lsb(const plan::TimeSegment& seg) const;
  void load(const plan::TimeSegment& seg);  // the segment's polynomial into ps_
  double quant_bound(uint32_t K);          // fd::Compiler::quant_bound_lsb, remembered per K
  std::vector<double> qbound_;
  fd::Compiler comp_;
  fd::PolySegment ps_;
  fd::Compiled c_;
  bool have_end_ = false;
  double joint_bound_ = 0;  // Machine::joint_lsb of the format
  plan::TimeSegment prev_;  // the last segment compiled (its polynomial's end)
};

// A fitted segment (on the engine's tick) in pieces the compiler takes: at
// most `kmax` ticks, each the polynomial re-expanded at its start (Taylor
// shift: the pieces join where the polynomial does, up to rounding, which
// the segment compiler's joints take). Appended to `out`.
// The least rest at a program pause, in fit ticks: a segment of the fit
// ends within it (mark_pauses).
constexpr int kPauseRest = 2;

// Marks, for each pause, the first segment of `segs` (k0 on the engine's
// tick, `n` engine ticks a fit tick) that ends where the plan rests at the
// pause's arc length; `ts[i]` is the plan at fit tick k_base + i. PlanError
// naming the pause if no segment ends there.
void mark_pauses(std::vector<plan::TimeSegment>& segs, const std::vector<plan::TickSample>& ts, long long k_base,
                 int n, const std::vector<JobConfig::PauseAt>& pauses, double length);
// The pause records of a run_job result: one before the record after each
// marked segment.
std::vector<stream::Pause> pauses_of(const JobResult& r);

void engine_pieces(const plan::TimeSegment& seg, uint32_t kmax, double h, std::vector<plan::TimeSegment>& out);

// One tick at `x`: the last segment of a motion, so that the core's last
// sample is the end point (a segment emits its start, not its end).
plan::TimeSegment hold_segment(long long k0, const double* x, int dim, int degree);

}  // namespace traj::job
