// SPDX-License-Identifier: Apache-2.0
// Reparameterisation by arc length, and the interpolators it is compared with.
//
// Project method (equal_arclength_params): u_0 = u_begin; u_{k+1} solves length(u_k, u) = step by the
// safeguarded Newton of ArcLength::advance, started from the linear extrapolation 2u_k - u_{k-1}.
// Each step is exact to |length(u_k,u_{k+1}) - step| <= 1e-12 step + quadrature error (adaptive GL at
// rel_tol 1e-14 on the short step interval), i.e. far below the 1e-9 target.
//
// [ARC] (Brodtmann & Schilberg), as its authors describe it, for one curve piece [ua, ub] with n
// steps: start from equal parameter steps tau_i = 1/n; compute the points, their chord ("secant")
// lengths l_i and l_curve = sum l_i; rescale tau_i <- tau_i * l_curve / (n l_i) ([2_04]); normalise so
// that sum tau_i = 1; repeat ("cascading by feedback") `passes` times. For a spline the resolution of
// each Bezier segment is chosen proportional to its arc length (n_i = max(1, round(L_i / step))).
//
// Taylor interpolators (the classic CNC parametric interpolators), feed V, period T:
//   first order : u_{k+1} = u_k + V T / |r'|
//   second order: u_{k+1} = u_k + V T / |r'| - (V T)^2 (r'.r'') / (2 |r'|^4)
#pragma once
#include <vector>

#include "geometry/arclength.hpp"
#include "geometry/curve.hpp"

namespace traj::geo {

// Parameters at equal arc-length steps from u_begin. If include_end, u_end is appended when the
// remainder is > 1e-12 step (the last step is then a partial one).
std::vector<double> equal_arclength_params(const ArcLength& al, double step, bool include_end = true);

// [ARC]'s levelling on [ua, ub] with n steps and `passes` passes (passes = 0: uniform parameter).
std::vector<double> arc_paper_reparam(const Curve& c, double ua, double ub, int n, int passes);
// [ARC] applied per Bezier segment of a spline, n_i proportional to the segment arc length.
std::vector<double> arc_paper_reparam_spline(const Curve& c, const ArcLength& al, double step, int passes);

// Taylor interpolator of order 1 or 2 at feed*period per tick; ends with u_end (partial last step).
std::vector<double> taylor_interpolate(const Curve& c, double feed, double period, int order);

struct Fluctuation {
  double max = 0, min = 0, rms = 0;  // of ds_k / nominal - 1
  double ratio = 0;                  // max ds / min ds ([ARC]'s "1 : x" figure)
  int steps = 0;
};
// True arc length between consecutive parameters (accurate quadrature) vs the nominal step.
// skip_last: leave out the last (partial) step.
Fluctuation feed_fluctuation(const ArcLength& al, const std::vector<double>& u, double nominal, bool skip_last);
// [ARC]'s measure: chord lengths between consecutive points, max/min ratio (and deviations from the
// mean chord).
Fluctuation chord_fluctuation(const Curve& c, const std::vector<double>& u);

}  // namespace traj::geo
