// SPDX-License-Identifier: Apache-2.0
#include "job/plan_fit.hpp"

#include <algorithm>
#include <chrono>
#include <array>
#include <cmath>

namespace traj::job {
namespace {

using Clock = std::chrono::steady_clock;
double secs(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

constexpr int kMaxAttempts = 200;

// A speed cap around tick sample t: over about five ticks' travel, at most
// `shrink` of the planned speed, and where a limit was exceeded by `ratio`
// (> 1) at most 0.95 ratio^(-1/3) of it (the jerk scales with v^3); never
// below `floor` (speed_floor).
plan::SpeedCap cap_around(const plan::TickSample& t, double ratio, double shrink, double period, double length,
                          double floor) {
  const double w = std::max(5 * period * t.v, 1e-9 * length) + 1e-9;
  double v = t.v * shrink;
  if (ratio > 1) v = std::min(v, t.v * 0.95 * std::pow(ratio, -1.0 / 3.0));
  return {t.s - w, t.s + w, std::max(v, floor)};
}

// The slowest a repair cap goes: 1e-6 of the fastest the path can move
// (Limits::top_speed; from the feed alone, a program's F far above the axes'
// speed would hold every cap above the speed a kink needs, and the repairs
// would not converge), and never above the speed at which a stop at a corner
// can turn within one tick: the one-tick polynomial turns the velocity by up
// to 2v, at a jerk of about 30 times that over h^2 (the planner's corner
// speed, host/planner/README.md), so v <= j h^2 / 60 for the smallest jerk
// limit j, taken here with a further half. With slow rotary axes (3000
// deg/s^3 at 1 ms against a top speed of 100) that is 2.5e-5, below 1e-6 of
// the top speed: a stop that falls badly within its tick was capped at the
// floor round after round, and the plan failed.
double speed_floor(const plan::Limits& l, int dim, double period) {
  double j = std::min(l.j_tan, l.j_cen);
  for (int a = 0; a < dim; ++a) j = std::min(j, l.j_axis[a]);
  return std::min(1e-6 * l.top_speed(dim), j * period * period / 120);
}

// The repair caps of earlier rounds, to tell how often a place has been
// capped already: a place capped again is slowed by a further 0.8 per time it
// was (0.8, 0.64, 0.51 ... of its speed), so that a place needing a large
// slow-down takes a number of rounds that grows as the square root of its
// logarithm, not as the logarithm.
class Earlier {
 public:
  Earlier(const std::vector<plan::SpeedCap>& caps, size_t from) {
    for (size_t i = from; i < caps.size(); ++i) {
      iv_.push_back({caps[i].s0, caps[i].s1});
      width_ = std::max(width_, caps[i].s1 - caps[i].s0);
    }
    std::sort(iv_.begin(), iv_.end());
  }
  // 0.8 to the power of the number of earlier caps holding s.
  double shrink(double s) const {
    auto it = std::upper_bound(iv_.begin(), iv_.end(), std::make_pair(s, 1e300));
    double f = 1;
    while (it != iv_.begin()) {
      --it;
      if (it->first < s - width_) break;
      if (it->second >= s) f *= 0.8;
    }
    return f;
  }

 private:
  std::vector<std::pair<double, double>> iv_;
  double width_ = 0;
};

// Caps where a tick of ts[first..] exceeds a limit (at most one cap per six
// ticks); returns how many.
size_t cap_tick_violations(const PlanFitRequest& req, const std::vector<plan::TickSample>& ts, size_t first,
                           std::vector<plan::SpeedCap>& caps, const Earlier& earlier) {
  const size_t before = caps.size();
  const int dim = req.path->dim();
  long long last = -1000000;
  for (size_t k = first; k < ts.size(); ++k) {
    const double q = plan::tick_ratio(ts[k], *req.limits, dim);
    if (q > 1 + 1e-9 && static_cast<long long>(k) > last + 5) {
      caps.push_back(cap_around(ts[k], q, earlier.shrink(ts[k].s), req.options.period, req.path->length(),
                                speed_floor(*req.limits, dim, req.options.period)));
      last = static_cast<long long>(k);
    }
  }
  return caps.size() - before;
}

// Ticks fitted at once: a longer tick sequence is fitted in parts that join
// at a shared tick, as streaming windows do (the part after it gets the
// fitted positions before it as history), so that a failure costs one part,
// not the whole fit.
constexpr size_t kFitPart = 1 << 16;
// After a failed fit, the search for further failures resumes this many
// ticks later (the caps already cover about five ticks' travel each side).
constexpr size_t kResumeAfterFailure = 8;
// ...in parts of this many ticks: a fit prepares its whole part before it
// fits the first tick (with fine ticks, the samples between fit ticks), so
// each resumption after a failure prepared the rest of a kFitPart part anew.
constexpr size_t kSearchPart = 1 << 12;

// The plan's positions of the (up to 3) ticks before ts[i], relative to
// ts[i]: the history of a part that follows a failed one (only to look for
// further failures; that round is not accepted). None where the fit tick is
// not the engine's (the history is of engine ticks).
std::vector<std::array<double, plan::kMaxAxes>> plan_history(const std::vector<plan::TickSample>& ts, size_t i,
                                                             const plan::SegmentOptions& so) {
  std::vector<std::array<double, plan::kMaxAxes>> h;
  if (so.fine_ticks > 1) return h;
  for (size_t k = i >= 3 ? i - 3 : 0; k < i; ++k) {
    std::array<double, plan::kMaxAxes> q{};
    for (int a = 0; a < plan::kMaxAxes; ++a) q[a] = ts[k].x[a] - ts[i].x[a];
    h.push_back(q);
  }
  return h;
}

// Fits every tick of `ts`, part by part, and caps the speed at every place
// where a fit fails (the search goes on after each failure, so one round
// finds them all: the number of rounds does not grow with the path's length).
// Returns the number of failures; `segs` is the fit when there were none.
// `prepared` counts the ticks given to the fit (with each part's preparation).
size_t fit_all(const PlanFitRequest& req, const plan::Plan& plan, const std::vector<plan::TickSample>& ts,
               std::vector<plan::TimeSegment>& segs, std::vector<plan::SpeedCap>& caps, const Earlier& earlier,
               size_t& prepared) {
  const double h = req.options.period;
  const size_t n = ts.size() - 1;  // ticks to fit: 1..n
  segs.clear();
  size_t failures = 0;
  plan::SegmentOptions so = req.segments;
  std::vector<plan::TickSample> part;
  for (size_t i0 = 0; i0 < n;) {
    const size_t i1 = std::min(n, i0 + (failures > 0 ? kSearchPart : kFitPart));
    const bool whole = i0 == 0 && i1 == n;
    if (!whole) part.assign(ts.begin() + static_cast<long>(i0), ts.begin() + static_cast<long>(i1) + 1);
    prepared += i1 - i0;
    try {
      auto s = plan::fit_segments(*req.path, plan, whole ? ts : part, *req.limits, so, h, req.t_offset,
                                  req.k_base + static_cast<long long>(i0));
      if (failures == 0) {
        so.history = plan::fitted_tail(s, req.path->dim(), so.engine_period(h), 3);
        segs.insert(segs.end(), s.begin(), s.end());
      } else {
        so.history = plan_history(ts, i1, so);
      }
      i0 = i1;
    } catch (const plan::FitError& e) {
      const long long idx = e.tick - req.k_base;
      if (idx <= 0 && req.carried)  // the carried tick is committed: nothing left to slow down there
        throw JunctionError(req.what +
                              ": the motion committed by the previous window cannot be continued within the limits "
                              "at their junction (" + e.what() + "); plan with a larger window (--window)");
      const size_t k = static_cast<size_t>(std::max<long long>(idx, 0));
      for (size_t j : {k, std::min(k + 1, n)})
        caps.push_back(cap_around(ts[j], 0, 0.8 * earlier.shrink(ts[j].s), h, req.path->length(),
                                  speed_floor(*req.limits, req.path->dim(), h)));
      ++failures;
      i0 = std::max(i0 + 1, std::min(n, k + kResumeAfterFailure));
      so.history = plan_history(ts, i0, so);
    }
  }
  return failures;
}

}  // namespace

PlanFitResult plan_and_fit(PlanFitRequest& req, std::vector<plan::TickSample>& ts) {
  PlanFitResult r;
  const double h = req.options.period;
  auto& caps = req.options.caps;
  const size_t given = caps.size();
  plan::RetimeMemo retimed;  // each round plans the same path with more caps
  std::vector<plan::TickSample> ahead;  // the look-ahead's ticks (sample_ahead)
  for (int attempt = 0;; ++attempt) {
    r.rounds = attempt + 1;
    r.repairs = caps.size() - given;
    if (attempt > kMaxAttempts)
      throw plan::PlanError(req.what + ": the limits cannot be met: " + std::to_string(caps.size() - given) +
                            " local speed caps in " + std::to_string(kMaxAttempts) + " rounds did not suffice");
    if (req.progress) req.progress("plan", 0);
    const auto a0 = Clock::now();
    r.plan = plan::plan_path(*req.path, *req.limits, req.options, &retimed);
    r.check_frames += r.plan.check_frames;
    r.moves_reused = retimed.reused;
    r.moves_searched = retimed.searched;
    check_tick_count(r.plan.duration(), h, req.what);
    if (req.progress) req.progress("plan", 1);
    const auto a1 = Clock::now();
    req.sample(r.plan, ts);
    if (req.progress) req.progress("ticks", 1);
    const auto a2 = Clock::now();
    r.t_plan += secs(a0, a1);
    r.t_ticks += secs(a1, a2);
    const Earlier earlier(caps, given);
    size_t capped = cap_tick_violations(req, ts, req.carried ? 1 : 0, caps, earlier);
    if (req.sample_ahead) {
      req.sample_ahead(r.plan, ahead);
      capped += cap_tick_violations(req, ahead, 0, caps, earlier);
    }
    if (capped > 0) continue;
    if (ts.size() < 2) {  // nothing to fit (a window's commit shorter than a tick)
      r.segments.clear();
      return r;
    }
    if (req.progress) req.progress("fit", 0);
    const auto a3 = Clock::now();
    const size_t failures = fit_all(req, r.plan, ts, r.segments, caps, earlier, r.fit_ticks);
    r.fit_failures += failures;
    r.t_fit += secs(a3, Clock::now());
    if (failures > 0) continue;
    if (req.progress) req.progress("fit", 1);
    return r;
  }
}

}  // namespace traj::job
