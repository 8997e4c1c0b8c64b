// SPDX-License-Identifier: Apache-2.0
// trajcore planner: per-axis time polynomials on the tick grid.
//
// Each segment [k0, k0+K] (integer ticks) holds, per axis, the quintic Hermite
// interpolant of the planned x(t) = C(u(s(t))): position, velocity and
// acceleration match at both ends, so consecutive segments join C2. A segment
// is accepted when
//   * at every tick inside it the fitted point is within fit_tol of the planned
//     point (which lies on the curve), and within feed_rel of that tick's
//     travel v h (feed accuracy), and
//   * the chord between consecutive ticks is at most feed * h, and
//   * per axis, the exact maxima over the segment of |x'|, |x''|, |x'''| of the
//     fitted polynomial (end points and real roots of the next derivative) are
//     within the limits;
// otherwise it is split in half. Breaks are placed first at the ticks nearest
// the profile's jerk switches and the curve's knot crossings (where the plan's
// jerk steps), so a fit rarely spans a jerk step.
// Degree 3 ("cubic where asked"): cubic Hermite (position and velocity at both
// ends), C1 joins; acceleration may step at a join, so no jerk bound is
// claimed for cubic segments.
//
// Sampled output: for a C2 signal, the k-th finite difference over k ticks is
// h^k times a B-spline-weighted mean of the k-th derivative, so
// |Delta^k x| / h^k <= max |x^(k)|: the per-axis bounds carry over to the
// samples, up to the output quantisation (see report).
#pragma once
#include <array>
#include <vector>

#include "planner/planner.hpp"
#include "planner/program_pause.hpp"

namespace traj::plan {

struct TimeSegment {
  long long k0 = 0;
  uint32_t K = 0;
  int degree = 5;
  std::array<std::array<double, 6>, kMaxAxes> coef{};  // per axis, coefficient of tau^j, tau = t - k0 h (seconds)
  double max_dev = 0;                       // max |fit - plan| at the ticks inside
  ProgramPause pause{};  // a program pause follows: the plan rests at this segment's end
  double eval(int axis, double tau, int deriv = 0) const;
  // eval(axis, tau) - eval(axis, 0), rounded at the scale of the travel, not of the coordinate.
  double travel(int axis, double tau) const;
  // The same in long double: the differences of travels over a few ticks of
  // a long segment at fine ticks keep their precision.
  long double travel_ld(int axis, long double tau) const;
};

// Exact maxima over a segment of |x'|, |x''|, |x'''| per axis (end points and
// real roots of the next derivative): what the report quotes. The fit decides
// with the same exact test, skipped where a Bernstein bound already suffices.
struct SegmentPeaks {
  double v[kMaxAxes] = {}, a[kMaxAxes] = {}, j[kMaxAxes] = {};
};
SegmentPeaks segment_peaks(const TimeSegment& seg, int dim, double period);

// No one-tick segment meets the limits at `tick`: the plan must slow down there.
class FitError : public PlanError {
 public:
  FitError(const std::string& what, long long tick) : PlanError(what), tick(tick) {}
  long long tick;
};

struct SegmentOptions {
  int degree = 5;              // 5 (C2 joins) or 3 (C1)
  uint32_t max_ticks = 1000;   // from the engine format (longest segment the compiler accepts)
  double fit_tol = 1e-3;       // deviation budget of the fit, units
  // Feed accuracy: at each tick the deviation is also kept below
  // max(feed_rel * v h, feed_abs), so that the chord between consecutive
  // output samples is within about 2 feed_rel of the planned arc.
  double feed_rel = 0.0025, feed_abs = 1e-8;
  // Where the fit tick is coarser than the engine's: the chords within
  // 2 feed_rel at every engine tick, bounded between the samples (true: a
  // bound asked for, --feed-accuracy), or checked at the samples only (false:
  // the default, whose feed accuracy the report measures but no one asked to
  // bound; it needs no samples between fit ticks where the plan is slow).
  bool feed_bound = false;
  // With feed_bound: the output's own error on the chord between two
  // samples, units (their rounding and register error, Machine). The fit
  // leaves it out of the budget, so that the samples' chords, not only the
  // fitted polynomials', are within 2 feed_rel of the plan's.
  double feed_quant = 0;
  // Fitted positions of the (up to 3) ticks before ts[0], oldest first,
  // relative to the fit's end there (a streaming window continuing a
  // committed one, or the part of a long fit after another): the sampled
  // tangential and normal checks (sampled.hpp) then also cover the windows
  // that straddle ts[0]. Relative, because those checks take differences of
  // up to three ticks, which absolute coordinates would round to noise at
  // fine ticks. Empty at the start of a motion (at rest).
  std::vector<std::array<double, kMaxAxes>> history;
  // The engine's tick where it is finer than the fit's: the fit tick
  // (`period` of fit_segments) is `fine_ticks` engine ticks of `fine_period`;
  // each segment accepted on the fit ticks is then checked for every engine
  // tick by per-segment bounds (fine_check.hpp). 1: the fit tick is the
  // engine's, and the checks above are made at every engine tick.
  int fine_ticks = 1;
  double fine_period = 0;
  // The engine's tick, given the fit's.
  double engine_period(double fit_period) const { return fine_ticks > 1 ? fine_period : fit_period; }
};

// ts[0] is global tick k_base; the plan starts at global time t_offset. A
// first sample whose curve index is outside the path was carried from a
// previous window (it lies just before the path's start). Returned k0 are
// global ticks.
//
// Checks, per segment, in addition to those above: at every tick window of the
// fitted positions (sampled.hpp), the sampled tangential acceleration and
// jerk and the normal (centripetal) acceleration and jerk within a_tan, j_tan,
// a_cen, j_cen. Unlike the per-axis maxima these are not polynomial in the
// fit, so they are checked where the core samples them: at the ticks.
std::vector<TimeSegment> fit_segments(const Path& p, const Plan& plan, const std::vector<TickSample>& ts,
                                      const Limits& L, const SegmentOptions& o, double period,
                                      double t_offset = 0, long long k_base = 0);

// Positions of the last `count` ticks before the end of a fitted sequence
// (oldest first), relative to the sequence's end, for SegmentOptions::history
// of the next window.
std::vector<std::array<double, kMaxAxes>> fitted_tail(const std::vector<TimeSegment>& segs, int dim, double period,
                                                      int count = 3);

// Exact max |q(t)| over [0, T] of a polynomial q (coefficients c[0..n]).
double max_abs_poly(const double* c, int n, double T);
// An upper bound of max |q(t)| over [0, T] (n <= 5): the largest Bernstein
// coefficient of q on [0, T] (the convex-hull property), within a few ulps.
double bernstein_bound(const double* c, int n, double T);

}  // namespace traj::plan
