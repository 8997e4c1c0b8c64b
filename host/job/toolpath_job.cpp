// SPDX-License-Identifier: Apache-2.0
#include "job/toolpath_job.hpp"

#include <algorithm>
#include <cmath>

#include "corners/corners.hpp"
#include "util/format.hpp"

namespace traj::job {

using plan::PlanError;

input::Toolpath blend_toolpath(const input::Toolpath& tp, double tol, const ToolpathOptions& o, ToolpathPlan& r) {
  const double share = o.blend_share;
  if (!(share > 0 && share < 1)) throw PlanError("blend share must be in (0, 1)");
  input::Toolpath part = tp;
  for (auto& m : part.moves)
    if (m.tolerance >= 0) m.tolerance *= share;
  corners::BlendOptions bo;
  bo.wide = o.wide_blends;
  const corners::BlendResult b = corners::blend_corners(part, tol * share, bo);
  r.corners_blended = b.corners_blended;
  r.wide_blends = static_cast<int>(std::count_if(b.blends.begin(), b.blends.end(), [](const auto& x) { return x.wide; }));
  r.blend_deviation = b.max_deviation;
  r.corner_stops = b.stops.size();
  return corners::to_toolpath(b, tp);
}

double rapid_speed(const JobConfig& cfg, int axes, const ToolpathOptions& o) {
  // of X Y Z only: the further axes (A B C in degrees) keep their own limits
  // through the planner's per-axis bounds, without slowing rapids of X Y Z
  double v_axis_min = cfg.limits.v_axis[0];
  for (int a = 1; a < axes && a < 3; ++a) v_axis_min = std::min(v_axis_min, cfg.limits.v_axis[a]);
  return o.rapid > 0 ? o.rapid : v_axis_min;
}

ToolpathPlan toolpath_plan(const input::Toolpath& original, const JobConfig& cfg, const ToolpathOptions& o) {
  if (original.moves.empty()) throw PlanError("the toolpath has no moves");
  ToolpathPlan r;
  r.cfg = cfg;
  const input::Toolpath tp = o.blend ? blend_toolpath(original, cfg.limits.tol, o, r) : original;
  if (o.blend) r.cfg.limits.tol = cfg.limits.tol * (1 - o.blend_share);
  const double rapid = rapid_speed(cfg, tp.axes, o);
  double fastest = 0;
  std::vector<double> speed(tp.moves.size());
  for (size_t i = 0; i < tp.moves.size(); ++i) {
    const input::Move& m = tp.moves[i];
    r.path.add(m.curve, m.where);
    const bool is_rapid = m.kind == input::Move::Kind::kRapid;
    speed[i] = is_rapid ? rapid : (m.feed > 0 ? m.feed : cfg.limits.feed);
    if (!(speed[i] > 0) || !std::isfinite(speed[i]))
      throw PlanError(m.where + ": feed " + util::num(speed[i]) + " mm/s must be positive");
    fastest = std::max(fastest, speed[i]);
    (is_rapid ? r.rapids : r.feed_moves)++;
  }
  r.cfg.limits.feed = fastest;
  auto& caps = r.cfg.plan.caps;
  const double eps = 1e-9 * std::max(1.0, r.path.length());
  for (size_t i = 0; i < tp.moves.size(); ++i) {
    const double s0 = r.path.offset(i), s1 = r.path.offset(i + 1);
    if (speed[i] < fastest) caps.push_back({s0, s1, speed[i]});
    const bool last = i + 1 == tp.moves.size();
    if (tp.moves[i].exact_stop && !last) {  // the path's end is a stop anyway
      caps.push_back({s1 - eps, s1 + eps, 0.0});
      ++r.stops;
    }
    if (tp.moves[i].dwell > 0) r.cfg.plan.dwells.push_back({s1, tp.moves[i].dwell});
  }
  return r;
}

}  // namespace traj::job
