// Arc length of a Curve: adaptive Gauss-Legendre quadrature of the speed |r'(u)| per power-basis
// span, and its inverse (parameter at a given arc length) by a safeguarded Newton method.
//
// Quadrature (per interval [a,b] inside one span, where the speed is smooth): G6 = 6-point
// Gauss-Legendre on [a,b] (seed 003's rule), G6' = G6 on both halves. If |G6 - G6'| <= tol, G6' is
// accepted; else both halves recurse with tol/2. The estimate |G6 - G6'| bounds the error of G6 (for
// smooth integrands); G6' is 2^12 times more accurate, so the accepted value is far inside tol.
// tol for a span = rel_tol * (span length estimate); minimum interval width 1e-14 * span width.
//
// Inverse: s(u) = target is solved on the span's bracket by Newton (derivative = speed, exact), the
// interval integral taken from the last accepted iterate (short intervals: 1 or 2 GL rules); a step
// that leaves the bracket or does not halve |f| is replaced by bisection. Converged when
// |f| <= s_tol or the bracket is below 4 ulp.
#pragma once
#include <vector>

#include "geometry/curve.hpp"

namespace traj::geo {

struct ArcLengthStats {
  long long integrand_evals = 0;  // speed evaluations |r'(u)| (each = one curve eval of order 1)
  long long intervals = 0;        // GL rules applied
  long long newton_iters = 0;
  long long bisections = 0;
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

  double speed(double u) const;
  double speed_span(int span, double u) const;
  const std::vector<double>& cumulative() const { return cum_; }  // s at each span start, + total
  const ArcLengthStats& stats() const { return stats_; }
  void reset_stats() const { stats_ = ArcLengthStats{}; }
  double rel_tol() const { return rel_tol_; }

 private:
  double gl6(int span, double a, double b) const;
  double adapt(int span, double a, double b, double whole, double tol, int depth) const;
  const Curve* c_;
  double rel_tol_;
  std::vector<double> cum_;
  std::vector<double> span_tol_;
  mutable ArcLengthStats stats_;
};

// Gauss-Legendre nodes (on [-1,1]) and weights of order n (Golub-Welsch free: Newton on P_n);
// used by the library (n = 6) and by tests to check seed 003's node spacing.
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w);

}  // namespace traj::geo
