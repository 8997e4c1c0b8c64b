// SPDX-License-Identifier: Apache-2.0
#include "job/toolpath_job.hpp"

#include <algorithm>
#include <cmath>

#include "corners/corners.hpp"
#include "util/format.hpp"

namespace traj::job {

using plan::PlanError;

namespace {

void add_line(plan::Path& p, const corners::Point& a, const corners::Point& b, const char* where) {
  if ((b - a).norm() > 1e-9) p.add(geo::make_line(a, b), where);
}

// Whether the corner is passed sooner as an exact stop than through its blend: both planned at the
// job's limits, from rest to rest on straight legs along the corner's, each half the straight-on path
// on its side (the blend takes at most half of its leg) but no longer than a speed-up from rest to the
// feed needs, and on a long leg no longer than the blend's part of it and two speed-ups: there both
// plans reach the feed and cruise alike, and a longer leg only costs time (legs of a metre at F400,
// 6.7 mm/s, make each plan 150 000 ticks). A plan that fails keeps the blend.
bool stop_is_faster(const corners::CornerCandidate& c, const JobConfig& cfg) {
  plan::Limits L = cfg.limits;
  if (c.feed > 0) L.feed = c.feed;  // the moves' own feed (toolpath_plan lets it exceed the job's)
  plan::PlanOptions po = cfg.plan_options();
  po.caps.clear();
  po.dwells.clear();
  // here the blend lies between two rests, where the planner would re-time
  // it with its legs as one move on the tick grid; on the whole path the
  // legs go on at speed, so the blend is planned as the path's profile plans it
  po.align_curved_moves = false;
  // a jerk-limited speed-up from rest to the top speed v (the feed, or the axes' velocity limits
  // together where a program's F is above them) covers at most v (v / a + a / j) at the tangential
  // jerk the planner gives a path's profile (0.6 j); two of them (speeding up on the leg, slowing to
  // the blend) at most 2 reach
  const double v = L.top_speed(static_cast<int>(c.v.size()));
  const double reach = v * (v / L.a_tan + L.a_tan / L.j_tan);
  const corners::Point b0 = c.blend.ctrl.row(0).transpose(), b1 = c.blend.ctrl.row(c.blend.n_ctrl() - 1).transpose();
  const double blend_in = (c.v - b0).dot(c.t_in), blend_out = (b1 - c.v).dot(c.t_out);
  const double h_in = std::min(std::max(0.5 * c.leg_in, std::min(0.5 * c.run_in, reach)), blend_in + 2 * reach);
  const double h_out = std::min(std::max(0.5 * c.leg_out, std::min(0.5 * c.run_out, reach)), blend_out + 2 * reach);
  const corners::Point a = c.v - h_in * c.t_in, b = c.v + h_out * c.t_out;
  plan::Path blended, stopped;
  add_line(blended, a, b0, "leg in");
  blended.add(c.blend, "blend");
  add_line(blended, b1, b, "leg out");
  add_line(stopped, a, c.v, "leg in");
  add_line(stopped, c.v, b, "leg out");
  try {
    return plan::plan_path(stopped, L, po).duration() < plan::plan_path(blended, L, po).duration();
  } catch (const PlanError&) {
    return false;
  }
}

}  // namespace

input::Toolpath blend_toolpath(const input::Toolpath& tp, const JobConfig& cfg, const ToolpathOptions& o,
                               ToolpathPlan& r, bool starts_at_rest, bool ends_at_rest) {
  const double tol = cfg.limits.tol;
  const double share = o.blend_share;
  if (!(share > 0 && share < 1)) throw PlanError("blend share must be in (0, 1)");
  input::Toolpath part = tp;
  for (auto& m : part.moves)
    if (m.tolerance >= 0) m.tolerance *= share;
  corners::BlendOptions bo;
  bo.wide = o.wide_blends;
  bo.from_stops = o.stop_blends;
  if (!o.offset_corners) bo.offset_share = 0;
  bo.starts_at_rest = starts_at_rest;
  bo.ends_at_rest = ends_at_rest;
  if (o.faster_stops) bo.stop_if_faster = [&cfg](const corners::CornerCandidate& c) { return stop_is_faster(c, cfg); };
  const corners::BlendResult b = corners::blend_corners(part, tol * share, bo);
  r.corners_blended = b.corners_blended;
  r.wide_blends = static_cast<int>(std::count_if(b.blends.begin(), b.blends.end(), [](const auto& x) { return x.wide; }));
  r.blend_deviation = b.max_deviation;
  r.corner_stops = b.stops.size();
  r.faster_stops = static_cast<size_t>(std::count_if(b.stops.begin(), b.stops.end(), [](const auto& x) {
    return x.reason == corners::StopReason::kFaster;
  }));
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
  const input::Toolpath tp = o.blend ? blend_toolpath(original, cfg, o, r) : original;
  if (o.blend) r.cfg.limits.tol = cfg.limits.tol * (1 - o.blend_share);
  const double rapid = rapid_speed(cfg, tp.axes, o);
  double fastest = 0;
  std::vector<double> speed(tp.moves.size());
  r.rapid_curve.assign(tp.moves.size(), 0);
  for (size_t i = 0; i < tp.moves.size(); ++i) {
    const input::Move& m = tp.moves[i];
    r.path.add(m.curve, m.where);
    const bool is_rapid = m.kind == input::Move::Kind::kRapid;
    r.rapid_curve[i] = is_rapid;
    speed[i] = is_rapid ? rapid : (m.feed > 0 ? m.feed : cfg.limits.feed);
    if (!(speed[i] > 0) || !std::isfinite(speed[i]))
      throw PlanError(m.where + ": feed " + util::num(speed[i]) + " mm/s must be positive");
    fastest = std::max(fastest, speed[i]);
    (is_rapid ? r.rapids : r.feed_moves)++;
  }
  r.cfg.limits.feed = fastest;
  auto& caps = r.cfg.plan.caps;
  for (size_t i = 0; i < tp.moves.size(); ++i) {
    const double s0 = r.path.offset(i), s1 = r.path.offset(i + 1);
    if (speed[i] < fastest) caps.push_back({s0, s1, speed[i]});
    const bool last = i + 1 == tp.moves.size();
    if (tp.moves[i].exact_stop && !last) {  // the path's end is a stop anyway
      caps.push_back(plan::stop_cap(s1, r.path.length()));
      ++r.stops;
    }
    // a pause rests at least kPauseRest fit ticks, so that a segment ends within the rest (mark_pauses)
    const double dwell = tp.moves[i].pause && !last
                             ? std::max(tp.moves[i].dwell, kPauseRest * cfg.machine.fit_period())
                             : tp.moves[i].dwell;
    if (dwell > 0) r.cfg.plan.dwells.push_back({s1, dwell});
    if (tp.moves[i].pause && !last) r.cfg.pauses.push_back({s1, tp.moves[i].pause});
  }
  return r;
}

}  // namespace traj::job
