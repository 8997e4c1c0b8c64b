// SPDX-License-Identifier: Apache-2.0
#include "job/plan_fit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace traj::job {
namespace {

using Clock = std::chrono::steady_clock;
double secs(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

constexpr int kMaxAttempts = 200;

// A speed cap around tick sample t: over about five ticks' travel, at most
// `shrink` of the planned speed, and where a limit was exceeded by `ratio`
// (> 1) at most 0.95 ratio^(-1/3) of it (the jerk scales with v^3).
plan::SpeedCap cap_around(const plan::TickSample& t, double ratio, double shrink, double period, double length,
                          double feed) {
  const double w = std::max(5 * period * t.v, 1e-9 * length) + 1e-9;
  double v = t.v * shrink;
  if (ratio > 1) v = std::min(v, t.v * 0.95 * std::pow(ratio, -1.0 / 3.0));
  return {t.s - w, t.s + w, std::max(v, 1e-6 * feed)};
}

// Caps where a tick exceeds a limit (at most one cap per six ticks); returns how many.
size_t cap_tick_violations(const PlanFitRequest& req, const std::vector<plan::TickSample>& ts,
                           std::vector<plan::SpeedCap>& caps) {
  const size_t before = caps.size();
  const int dim = req.path->dim();
  long long last = -1000000;
  for (size_t k = req.carried ? 1 : 0; k < ts.size(); ++k) {
    const double q = plan::tick_ratio(ts[k], *req.limits, dim);
    if (q > 1 + 1e-9 && static_cast<long long>(k) > last + 5) {
      caps.push_back(cap_around(ts[k], q, 1.0, req.options.period, req.path->length(), req.limits->feed));
      last = static_cast<long long>(k);
    }
  }
  return caps.size() - before;
}

}  // namespace

PlanFitResult plan_and_fit(PlanFitRequest& req, std::vector<plan::TickSample>& ts) {
  PlanFitResult r;
  const double h = req.options.period;
  auto& caps = req.options.caps;
  for (int attempt = 0;; ++attempt) {
    if (attempt > kMaxAttempts)
      throw plan::PlanError(req.what + ": the limits cannot be met: " + std::to_string(caps.size()) +
                            " local speed caps did not suffice");
    if (req.progress) req.progress("plan", 0);
    const auto a0 = Clock::now();
    r.plan = plan::plan_path(*req.path, *req.limits, req.options);
    check_tick_count(r.plan.duration(), h, req.what);
    if (req.progress) req.progress("plan", 1);
    const auto a1 = Clock::now();
    req.sample(r.plan, ts);
    if (req.progress) req.progress("ticks", 1);
    const auto a2 = Clock::now();
    r.t_plan += secs(a0, a1);
    r.t_ticks += secs(a1, a2);
    if (cap_tick_violations(req, ts, caps) > 0) continue;
    if (ts.size() < 2) {  // nothing to fit (a window's commit shorter than a tick)
      r.segments.clear();
      return r;
    }
    if (req.progress) req.progress("fit", 0);
    const auto a3 = Clock::now();
    try {
      r.segments = plan::fit_segments(*req.path, r.plan, ts, *req.limits, req.segments, h, req.t_offset, req.k_base);
    } catch (const plan::FitError& e) {
      r.t_fit += secs(a3, Clock::now());
      const long long idx = e.tick - req.k_base;
      if (idx <= 0 && req.carried)  // the carried tick is committed: nothing left to slow down there
        throw plan::PlanError(req.what +
                              ": the motion committed by the previous window cannot be continued within the limits "
                              "at their junction (" + e.what() + "); plan with a larger window (--window)");
      const size_t k = static_cast<size_t>(idx);
      for (size_t j : {k, std::min(k + 1, ts.size() - 1)})
        caps.push_back(cap_around(ts[j], 0, 0.8, h, req.path->length(), req.limits->feed));
      continue;
    }
    r.t_fit += secs(a3, Clock::now());
    if (req.progress) req.progress("fit", 1);
    return r;
  }
}

}  // namespace traj::job
