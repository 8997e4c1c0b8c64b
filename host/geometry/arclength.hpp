// SPDX-License-Identifier: Apache-2.0
// Arc length of a Curve: adaptive Gauss-Legendre quadrature of the speed |r'(u)| per power-basis
// span, and its inverse (parameter at a given arc length) by a safeguarded Newton method.
//
// Quadrature (per interval [a,b] inside one span, where the speed is smooth): G6 = 6-point
// Gauss-Legendre on [a,b] ([NURBS]'s rule), G6' = G6 on both halves. If |G6 - G6'| <= tol, G6' is
// accepted; else both halves recurse with tol/2. The estimate |G6 - G6'| bounds the error of G6 (for
// smooth integrands); G6' is 2^12 times more accurate, so the accepted value is far inside tol.
// tol for a span = rel_tol * (span length estimate); minimum interval width 1e-14 * span width.
//
// Inverse: s(u) = target is solved on the span's bracket by Newton (derivative = speed, exact), the
// interval integral taken from the last accepted iterate (short intervals: 1 or 2 GL rules); a step
// that leaves the bracket or does not halve |f| is replaced by bisection. Converged when
// |f| <= s_tol or the bracket is below 4 ulp.
//
// Fast path of advance (and so u_at), tried first (set_fast_path(false) forces the path above):
//   * guess u1 = u_from + Taylor inverse of s(u) to third order (sigma, sigma', sigma'' at u_from;
//     u_guess is not used: the series is the better guess);
//   * short step (sigma varies by < ~1% over it): length of [u_from, u1] by Gauss-Kronrod 3/7 first,
//     accepted if |G3 - K7| is within the budget, else as follows;
//   * length of [u_from, u1] by the 15-point Gauss-Kronrod rule with the embedded 7-point Gauss rule,
//     error estimate E = |G7 - K15| (E bounds the error of G7; K15, exact to degree 22, is accepted and
//     is far more accurate than E says); if E exceeds the budget the interval is split in halves
//     (adaptive GK15, tolerance halved per level, at most 12 levels);
//   * Newton corrections from the last iterate u_k: third-order inverse series at u_k, the short
//     interval [u_k, u_k+1] by 2-point Gauss with the estimate |G2 - T3| (T3: the cubic Taylor
//     integral from sigma, sigma', sigma'' at u_k; G2 is exact to degree 3 and O(d^5) accurate);
//   * every estimate is summed into err; converged when |f| + err <= s_tol, or when the Newton step
//     is below 4 ulp of u with err <= the budget (the nearer of the last two iterates is returned:
//     the parameter's resolution, which bounds a step's accuracy for tiny steps);
//   * budget: err <= 0.25 max(s_tol, sigma ulp(u)); a step may cross span ends (the rest of the span
//     by adaptive GK15, then the next span); any non-finite value, zero speed, an iterate outside the
//     span, or more than 8 Newton iterations falls back to the adaptive path (stats().fast_fallbacks).
// Cost (butterfly, tb/geometry/bench_arclength): 7 speed + 2 derivative evaluations for short steps
// (<= 1e-4 mm), 10..20 + 2 up to 0.25 mm, 35 at 1 mm (100..350 at 0.1..1 mm next to the cusps); about
// 0.3..0.7 us per step on a loaded 2-core machine (adaptive path: 57..511 evaluations, 1..13 us).
// Deep speed minima: a quadrature rule whose nodes all lie on one side of a cusp (a zero of the
// speed, |r'| V-shaped there) integrates the smooth branch through it and misses the way back and
// forth: a cusp 8.6 nm inside a 4 mm cubic (simple-icons' furrynetwork.svg) lies before the first
// node of every interval down to 1/64 of the span, G6 and its halves agreed, and the length came out
// 1.7e-5 mm (twice the 8.6 nm) short. So each polynomial span's minima of |r'|^2 (the real roots
// of its derivative, a polynomial) where the speed falls below kDeepDip of the span's largest
// sampled speed are split points of every quadrature (the span's length, span_length, and the fast
// path's Gauss-Kronrod rules). Rational spans (conics) are
// not searched: a conic with positive weights has no cusp.
// Accuracy: |length(u_from, u) - ds| <= s_tol (default 1e-12 ds), or within 0.5 ulp of u where that
// is finer than u's resolution (the adaptive path stops at a 4-ulp bracket there).
#pragma once
#include <vector>

#include "geometry/curve.hpp"

namespace traj::geo {

struct ArcLengthStats {
  long long integrand_evals = 0;  // speed evaluations |r'(u)| (each = one curve eval of order 1)
  long long intervals = 0;        // GL rules applied
  long long newton_iters = 0;
  long long bisections = 0;
  long long fast_steps = 0;      // advance calls answered by the fast path
  long long fast_fallbacks = 0;  // advance calls where the fast path gave up (adaptive path used)
};

class ArcLength {
 public:
  // rel_tol: relative error tolerance per span (default 1e-14: near double precision).
  explicit ArcLength(const Curve& c, double rel_tol = 1e-14);

  const Curve& curve() const { return *c_; }
  double total() const { return cum_.back(); }
  // Arc length from u_begin to u.
  double s(double u) const;
  // Arc length from u0 to u1 (signed: negative if u1 < u0).
  double length(double u0, double u1) const;
  // Length of [a,b] that lies in one span (no span search; a, b clamped to the span).
  double span_length(int span, double a, double b) const;
  // Parameter u with s(u) = s_target (clamped to [0, total]); |s(u) - s_target| <= s_tol.
  double u_at(double s_target, double s_tol = -1) const;
  // Parameter u in [u_from, u_end] with length(u_from, u) = ds (ds >= 0), Newton started from
  // u_guess (if inside); the marching primitive of the equal-arc-length reparameterisation.
  double advance(double u_from, double ds, double u_guess = -1, double s_tol = -1) const;
  // The same, given sigma, sigma', sigma'' (d/du of the speed) at u_from, as a caller that has just
  // evaluated the curve there knows them: saves one evaluation per step when marching.
  double advance_from(double u_from, const double* speed_derivs_at_from, double ds, double s_tol = -1) const;

  double speed(double u) const;
  double speed_span(int span, double u) const;
  const std::vector<double>& cumulative() const { return cum_; }  // s at each span start, + total
  const ArcLengthStats& stats() const { return stats_; }
  void reset_stats() const { stats_ = ArcLengthStats{}; }
  double rel_tol() const { return rel_tol_; }
  // Fast path of advance/u_at on (default) or off (the adaptive Gauss-Legendre path only).
  void set_fast_path(bool on) { fast_ = on; }
  bool fast_path() const { return fast_; }
  // Speeds |r'(u_i)| at n points of one span (batched power-basis kernel; counted as n evaluations).
  void speeds_span(int span, const double* u, int n, double* out) const;

 private:
  double gl6(int span, double a, double b) const;
  // Adaptive GL6 on [a, b] of one span. At most kAdaptBudget interval splits (12 evaluations each):
  // a tolerance that is never met (a speed that overflows or underflows, extreme knot spacing or
  // weights) is refused with a GeometryError naming the span instead of halving 2^60 times.
  static constexpr long kAdaptBudget = 20000;
  double adapt(int span, double a, double b, double whole, double tol) const;
  double adapt(int span, double a, double b, double whole, double tol, int depth, long& budget) const;
  [[noreturn]] void refuse(int span, const std::string& why) const;
  // Fast path pieces (see the header comment); false = give up, result undefined.
  bool fast_advance(int span, double u_from, double ds, double s_tol, double& u_out,
                    const double* d_from = nullptr) const;
  double advance_impl(double u_from, double ds, double u_guess, double s_tol, const double* d_from) const;
  bool gk_adapt(int span, double a, double b, double tol, int depth, double& val, double& err) const;
  bool gk_split(int span, double a, double b, double tol, double& val, double& err) const;
  bool dip_inside(int span, double a, double b) const;
  void gk15(int span, double a, double b, double& val, double& err) const;
  void gk7(int span, double a, double b, double& val, double& err) const;
  // sigma, sigma', sigma'' (d/du) at u from r', r'', r'''.
  void speed_derivs(int span, double u, double* d) const;
  bool fast_ = true;
  const Curve* c_;
  double rel_tol_;
  std::vector<double> cum_;
  std::vector<double> span_tol_;
  std::vector<double> noise_;  // per span: relative rounding noise of the speed (see speed_noise)
  // per span: the parameters inside it where the speed has a deep minimum (see speed_dips);
  // quadrature splits there
  std::vector<std::vector<double>> dips_;
  double split_length(int span, double a, double b, double whole_tol) const;
  template <class F>
  bool each_piece(int span, double a, double b, F piece) const;
  mutable ArcLengthStats stats_;
};

// Gauss-Legendre nodes (on [-1,1]) and weights of order n (Golub-Welsch free: Newton on P_n);
// used by the library (n = 6) and by tests to check [NURBS]'s node spacing.
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w);

}  // namespace traj::geo
