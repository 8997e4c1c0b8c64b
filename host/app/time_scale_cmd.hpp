// SPDX-License-Identifier: Apache-2.0
// `plan` and `run` with --time-scale: the plan is made below the machine's
// limits (the headroom that feed override and hold need), and the report
// gives the ramp bounds of s under which the re-timed trajectory keeps every
// per-axis limit (host/timescale/README.md), with the time-scale unit's
// integer configuration for the servo tick.
#pragma once
#include <string>
#include <vector>

#include "job/job.hpp"
#include "report/report.hpp"
#include "stream/segment_stream.hpp"

namespace traj::app {

struct TimeScaleArgs {
  double s_max = 0;                        // 0: no time scaling
  std::vector<double> headroom{0.7, 0.4};  // shares of the acceleration and jerk limits the plan uses
  double servo_period = 1e-3;              // s
  plan::Limits machine;                    // the machine's limits (set by apply_time_scale_headroom)
  bool on() const { return s_max > 0; }
};

// Checks the arguments and scales cfg's acceleration and jerk limits by the
// headroom shares (the plan is made with those), keeping the machine's
// limits in t.machine. PlanError naming the option on a bad value.
void apply_time_scale_headroom(job::JobConfig& cfg, TimeScaleArgs& t);

// The report's time-scaling section: the plan's per-axis peaks (the largest
// of plan, fit and output, with 2 % for the maxima between ticks), the ramp
// bounds under the machine's limits, and the unit's integer configuration.
// PlanError (naming the axis and the limit) when the plan leaves no headroom.
// The bounds also go into `header` (s_max, |ds/dt|, |d2s/dt2|: the stream's
// time-scaling fields, rounded toward the safe side).
std::string time_scale_text(const TimeScaleArgs& t, const report::Report& rep, const job::JobResult& res,
                            stream::Header& header);

}  // namespace traj::app
