// SPDX-License-Identifier: Apache-2.0
// Curvature, its extrema and (2-D) inflection points, and the split of a curve into ACC/DEC units
// ([NURBS]): between two consecutive split parameters the curvature is monotone, so the
// curvature-limited feed is monotone too and each unit needs only an accelerating or a decelerating
// profile.
//
// kappa = sqrt(|r'|^2 |r''|^2 - (r'.r'')^2) / |r'|^3 (any dimension; = |r' x r''| / |r'|^3 in 3-D).
// d(kappa^2)/du = G'/|r'|^6 - 6 G (r'.r'')/|r'|^8, G = |r'|^2|r''|^2 - (r'.r'')^2,
//   G' = 2 |r'|^2 (r''.r''') - 2 (r'.r'')(r'.r''')   (exact, from the third derivative).
// Extrema: sign changes of d(kappa^2)/du found on a scan of `samples_per_span` points per span
// (span ends included, evaluated from inside the span, so a sign change across a knot, where r'''
// jumps, is found too and located at the knot), then bisection to |du| <= u_tol.
// Values within a rounding-error bound of zero count as zero (SplitOptions::noise_factor): on a
// circle or a straight line, where d(kappa^2)/du is zero up to rounding, the scan sees no sign change.
// Degree-1 curves (every span straight, kappa = 0) return no extrema and no inflections at once.
// Inflections (2-D only): sign changes of the cross product x'y'' - y'x'', bisection to u_tol.
#pragma once
#include <vector>

#include "geometry/arclength.hpp"
#include "geometry/curve.hpp"

namespace traj::geo {

double curvature(const Curve& c, double u);
// Signed curvature of a planar curve ((x'y'' - y'x'') / |r'|^3); throws if dim != 2.
double signed_curvature(const Curve& c, double u);

// d(kappa^2)/du at u evaluated in span `span` (as the extremum scan does), with a bound on its
// rounding error (first order in the evaluation errors; +inf where |r'| is rounding noise). On a circle
// or a line the value is zero up to rounding, and within the bound.
struct CurvatureSqDerivative {
  double value = 0;
  double error_bound = 0;
};
CurvatureSqDerivative curvature_sq_derivative(const Curve& c, int span, double u);

struct CurvatureExtremum {
  double u = 0;
  double kappa = 0;
  bool maximum = false;  // else a minimum
  bool at_knot = false;  // located at a knot (derivative jumps in sign there)
};

// Work counters of the scans (optional, SplitOptions::stats).
struct SplitStats {
  long long dk2_evals = 0;    // d(kappa^2)/du evaluations (scan samples + bisection steps)
  long long cross_evals = 0;  // x'y'' - y'x'' evaluations (inflection scan + bisection), 2-D only
};

struct SplitOptions {
  int samples_per_span = 64;
  double u_tol = 1e-9;        // bisection width (|du|), must be <= 1e-7 (the required accuracy)
  bool inflections = true;    // 2-D curves: also split at signed-curvature zero crossings
  bool minima = true;         // split at curvature minima too (else maxima only)
  // Noise-aware extremum scan: a sample whose |d(kappa^2)/du| is at most noise_factor times its
  // first-order rounding-error bound (from the magnitudes of the terms; see curvature.cpp) counts as
  // zero, and an extremum needs a sign change between two samples above their bounds. 0 = every
  // nonzero sign counts (the plain scan; on a circle it bisects rounding noise).
  double noise_factor = 4;
  SplitStats* stats = nullptr;  // if set, the scans add their evaluation counts here
};

std::vector<CurvatureExtremum> curvature_extrema(const Curve& c, const SplitOptions& o = {});
std::vector<double> inflection_points(const Curve& c, const SplitOptions& o = {});

// Sorted interior split parameters (curvature extrema, and inflections for 2-D curves), without
// duplicates closer than 10 u_tol, excluding the domain ends.
std::vector<double> split_params(const Curve& c, const SplitOptions& o = {});

enum class UnitKind { Accelerate, Decelerate, Constant };

struct Unit {
  double u0 = 0, u1 = 0;      // parameter interval
  double s0 = 0, s1 = 0;      // arc length at the ends (from the curve start)
  double length = 0;          // s1 - s0
  double kappa0 = 0, kappa1 = 0;
  double kappa_max = 0, u_kappa_max = 0;  // at one end, since kappa is monotone in a unit
  UnitKind kind = UnitKind::Constant;     // kappa falling: feed may rise (Accelerate); rising: Decelerate
};

// ACC/DEC units between consecutive split parameters (and the domain ends).
std::vector<Unit> split_units(const Curve& c, const ArcLength& al, const SplitOptions& o = {});

}  // namespace traj::geo
