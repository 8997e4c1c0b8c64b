// SPDX-License-Identifier: Apache-2.0
// The one loop that turns a path (the whole path, or one streaming window)
// into time segments: plan -> sample every tick -> check every tick against
// the limits -> cap the speed locally where a check or the fit fails -> plan
// again, until the fit succeeds. Used by run_job and run_streaming.
//
// Why caps: the planner guarantees the limits on its arc-length grid; between
// grid points, and where no segment of one tick meets the limits, the tick
// checks and the fit find what the grid missed. A cap slows the plan over a
// few ticks' arc length around the place, so the repair stays local.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "job/job.hpp"
#include "planner/planner.hpp"
#include "planner/segments.hpp"

namespace traj::job {

// The motion committed by a previous window (the carried tick) cannot be
// continued within the limits.
class JunctionError : public plan::PlanError {
 public:
  using plan::PlanError::PlanError;
};

struct PlanFitRequest {
  const plan::Path* path = nullptr;
  const plan::Limits* limits = nullptr;
  plan::PlanOptions options;      // planner options; the caps found are added here
  plan::SegmentOptions segments;  // fit options
  std::string what;               // names the path or window in messages
  // Fills `ts` with the tick samples of `plan` (reusing its storage). A
  // streaming window puts the last tick of the previous window first.
  std::function<void(const plan::Plan&, std::vector<plan::TickSample>&)> sample;
  // Optional (a streaming window): fills `ahead` with the ticks of `plan`
  // after those of `sample` (called after it in each round, so it may use
  // what `sample` found), its look-ahead, which the next window plans
  // again. They are checked as the others, not fitted: a cap the next window
  // would find there could slow its start below the speed committed here.
  std::function<void(const plan::Plan&, std::vector<plan::TickSample>&)> sample_ahead;
  bool carried = false;   // ts[0] was carried from a previous window: not checked, cannot be slowed
  double t_offset = 0;    // passed to fit_segments: global time of the plan's start...
  long long k_base = 0;   // ...and the global tick of ts[0]
  Progress progress;      // optional: "plan", "ticks", "fit" stages
};

struct PlanFitResult {
  plan::Plan plan;
  std::vector<plan::TimeSegment> segments;
  double t_plan = 0, t_ticks = 0, t_fit = 0;  // host seconds
  int rounds = 0;      // plans made (1: no repair needed)
  size_t repairs = 0;  // speed caps added by the tick checks and the fit (beyond the request's own)
  // the exact checks of moves re-timed on the tick grid, over every round:
  // frames evaluated, and curved moves searched or taken from an earlier round
  long long check_frames = 0, moves_searched = 0, moves_reused = 0;
  // the fits of every round: ticks given to them (each prepared before it is
  // fitted), and failures (each one a cap or two)
  size_t fit_ticks = 0, fit_failures = 0;
};

// The tick samples of the accepted plan are left in `ts`. Throws
// plan::PlanError naming `what` if the limits cannot be met.
PlanFitResult plan_and_fit(PlanFitRequest& req, std::vector<plan::TickSample>& ts);

}  // namespace traj::job
