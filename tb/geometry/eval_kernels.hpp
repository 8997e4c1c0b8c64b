// SPDX-License-Identifier: Apache-2.0
// The two evaluation kernels compared by the benchmarks, templated on the scalar so that an
// instrumented scalar can count their arithmetic. Both evaluate a non-rational B-spline's position and
// derivatives 1..nd at u in a known span (span search is not counted in either).
//  * De Boor-Cox: The NURBS Book A2.3 basis-function derivatives + linear combination (ref_deboor.hpp).
//  * Power basis: the library's own kernel, traj::geo::detail::eval_power_span (curve.hpp): it runs the
//    kernel Curve::eval_span uses for a non-rational span (detail::eval_span_fixed where specialised,
//    else the general one; T = double there), here instantiated with the counting scalar. Same code,
//    same operations in the same order; the only difference from a call of Curve::eval is the span
//    search (find_span), which is not counted.
#pragma once
#include "geometry/curve.hpp"
#include "ref_deboor.hpp"

namespace kernels {

template <class T>
void power_eval(const traj::geo::PowerSpan& s, int dim, const T& u, int nd, T* out) {
  traj::geo::detail::eval_power_span<T>(s, dim, u, nd, out);
}

template <class T>
void deboor_eval(const traj::geo::BSpline& b, const double* P, int span, const T& u, int nd, T* out) {
  ref::deboor_cox_derivs<T>(b.degree, b.knots.data(), P, b.dim(), span, u, nd, out);
}

// Operation-counting scalar. Convention: every +, - (binary or unary) on a counted value is one add,
// every * one multiply, every / one divide; constants folded at compile time, comparisons, index and
// span arithmetic are not counted.
struct Cnt {
  double v = 0;
  static inline long long adds = 0, muls = 0, divs = 0;
  Cnt() = default;
  explicit Cnt(double x) : v(x) {}
  static void reset() { adds = muls = divs = 0; }
  friend Cnt operator+(const Cnt& a, const Cnt& b) { ++adds; return Cnt(a.v + b.v); }
  friend Cnt operator-(const Cnt& a, const Cnt& b) { ++adds; return Cnt(a.v - b.v); }
  friend Cnt operator-(const Cnt& a) { ++adds; return Cnt(-a.v); }
  friend Cnt operator*(const Cnt& a, const Cnt& b) { ++muls; return Cnt(a.v * b.v); }
  friend Cnt operator/(const Cnt& a, const Cnt& b) { ++divs; return Cnt(a.v / b.v); }
};

}  // namespace kernels
