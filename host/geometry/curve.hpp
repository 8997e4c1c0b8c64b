// SPDX-License-Identifier: Apache-2.0
// Curve: a B-spline/NURBS converted to piecewise power basis ([NURBS]): B-spline -> Bezier pieces
// (knot insertion) -> power basis per span, with explicit coefficient tables for the first, second
// and third derivatives. For a NURBS the tables hold the homogeneous coordinates (w x, w); the
// rational value and derivatives come from them by the quotient rule.
//
// Per span [u0, u1] and local variable tau = u - uc (uc = (u0+u1)/2, the span midpoint), column c (axis, or the weight column last):
//   d^k/du^k X_c(u) = sum_{j=0}^{p-k} a^{(k)}_{j,c} tau^j    (mathematically a^{(k)}_j = (j+k)!/j! a^{(0)}_{j+k}),
//   a^{(k)}_{j,c} = h^-j C(q,j) 2^-(q-j) sum_{i=0}^{q-j} C(q-j,i) (Delta^j B^{(k)})_{i,c},   q = p - k, h = u1 - u0,
// where B^{(k)} are the Bezier points of the span of the k-th hodograph (the derivative B-spline,
// degree p-k). Converting each derivative from its own hodograph keeps derivative errors at
// eps * |hodograph| like De Boor-Cox; differentiating the position table would amplify the rounding of
// the position Bezier points by 1/h^k on short spans (measured: 4e-10 relative, against 1e-15 from the hodographs).
// Expanding about the midpoint instead of u0 cuts the conversion's rounding growth from ~3^q to ~2^q.
// Evaluation is Horner: per column and derivative order k, (p-k) multiplies and (p-k) adds.
#pragma once
#include <Eigen/Dense>
#include <vector>

#include "geometry/bspline.hpp"

namespace traj::geo {

constexpr int kMaxDeriv = 3;

struct PowerSpan {
  double u0 = 0, u1 = 0;
  double uc = 0;  // expansion point (span midpoint): tau = u - uc, tau in [-h/2, h/2]
  // coef: for k = 0..3, (p+1-k) x cols block, row j = coefficient of tau^j of the k-th derivative
  // (tau = u - uc, u-units). Stored flat: element (k, j, c) at offset(k) + j*cols + c.
  std::vector<double> coef;
  int degree = 0, cols = 0;
  int offset(int k) const { return cols * (k * (degree + 1) - k * (k - 1) / 2); }
};

namespace detail {
// The evaluation kernel of Curve::eval_span, templated on the scalar T so that a benchmark can count
// its arithmetic with an instrumented scalar (tb/geometry/eval_kernels.hpp); the library instantiates
// it with T = double. Coefficients are doubles; T(c) converts one.

// Horner evaluation of one column of one derivative table.
template <class T>
inline T horner(const double* c, int nterms, int stride, const T& tau) {
  T acc = T(c[(nterms - 1) * stride]);
  for (int j = nterms - 2; j >= 0; --j) acc = acc * tau + T(c[j * stride]);
  return acc;
}

// All COLS columns of one derivative's coefficient block at once (rows j = tau^j, COLS values each):
// the same Horner operations, in the same order, as `horner` per column, so the result is bitwise the
// same; a fixed column count lets the compiler keep the accumulators in registers.
template <int COLS, class T>
inline void horner_rows(const double* c, int nterms, const T& tau, T* out) {
  T acc[COLS];
  for (int i = 0; i < COLS; ++i) acc[i] = T(c[(nterms - 1) * COLS + i]);
  for (int j = nterms - 2; j >= 0; --j)
    for (int i = 0; i < COLS; ++i) acc[i] = acc[i] * tau + T(c[j * COLS + i]);
  for (int i = 0; i < COLS; ++i) out[i] = acc[i];
}

template <class T>
inline void horner_rows_any(const double* c, int nterms, int cols, const T& tau, T* out) {
  switch (cols) {
    case 1: return horner_rows<1>(c, nterms, tau, out);
    case 2: return horner_rows<2>(c, nterms, tau, out);
    case 3: return horner_rows<3>(c, nterms, tau, out);
    case 4: return horner_rows<4>(c, nterms, tau, out);
    default:
      for (int d = 0; d < cols; ++d) out[d] = horner<T>(c + d, nterms, cols, tau);
  }
}

// Non-rational span (cols == dim): position and derivatives 0..nd at u, out[k*dim + axis]. Per
// derivative k <= p: tau = u - uc once, then (p-k) multiplies and (p-k) adds per axis. The general
// (runtime-sized) kernel; eval_power_span below uses the specialised one where there is one.
template <class T>
inline void eval_power_span_general(const PowerSpan& s, int dim, const T& u, int nd, T* out) {
  const T tau = u - T(s.uc);
  for (int k = 0; k <= nd; ++k) {
    if (k > s.degree) {
      for (int d = 0; d < dim; ++d) out[k * dim + d] = T(0.0);
      continue;
    }
    horner_rows_any<T>(s.coef.data() + s.offset(k), s.degree + 1 - k, s.cols, tau, out + k * dim);
  }
}

// Offset of derivative table k in a span of degree P with C columns (PowerSpan::offset at compile time).
template <int P, int C>
constexpr int table_offset(int k) {
  return C * (k * (P + 1) - k * (k - 1) / 2);
}

// Specialised kernel for DIM axes, rational (RAT) or not, degree P, all fixed at compile time:
// position and derivatives 0..nd (nd <= 3) into out[k*DIM + axis]. The Horner recurrences of the
// derivative tables 0..min(nd, P) run in one pass (one loop over the powers of tau, all accumulators in
// registers, table offsets constant); each accumulator sees the same operations in the same order as
// in the general kernel (horner_rows), and the quotient rule is rational_derivatives' expression
// unrolled (the factor C(k,1) = C(k,k) = 1 is dropped: 1 * w is exact), so the results are bitwise
// those of the general path (test GeometryFastEval.*). Requires the compiler not to contract a*b + c
// into an FMA in one path and not the other: curve.cpp is built with -ffp-contract=off.
template <class T, int DIM, bool RAT, int P>
inline void eval_span_fixed(const PowerSpan& s, const T& u, int nd, T* out) {
  constexpr int C = DIM + (RAT ? 1 : 0);
  constexpr int K = P < kMaxDeriv ? P : kMaxDeriv;  // highest derivative with a stored table
  const double* c = s.coef.data();
  const T tau = u - T(s.uc);
  const int kn = nd < 0 ? 0 : nd < K ? nd : K;  // nd >= 0 expected
  T acc[K + 1][C];
  for (int k = 0; k <= K; ++k) {
    if (k > kn) break;
    for (int i = 0; i < C; ++i) acc[k][i] = T(c[table_offset<P, C>(k) + (P - k) * C + i]);
  }
  // Table k has P + 1 - k terms: Horner step j (j = P-k-1 .. 0) applies to the tables with k < P - j.
  for (int j = P - 1; j >= 0; --j)
    for (int k = 0; k <= K; ++k) {
      if (k > kn || k >= P - j) break;
      for (int i = 0; i < C; ++i) acc[k][i] = acc[k][i] * tau + T(c[table_offset<P, C>(k) + j * C + i]);
    }
  if constexpr (!RAT) {
    for (int k = 0; k <= nd; ++k)
      for (int i = 0; i < DIM; ++i) out[k * DIM + i] = k <= kn ? acc[k][i] : T(0.0);
  } else {
    // Homogeneous A^(k) = acc[k][0..DIM-1], w^(k) = acc[k][DIM] (0 beyond the degree); quotient rule
    // C^(k) = (A^(k) - sum_{i=1..k} C(k,i) w^(i) C^(k-i)) / w, in rational_derivatives' order.
    T w[kMaxDeriv + 1];
    for (int k = 0; k <= kMaxDeriv; ++k) w[k] = k <= kn ? acc[k][DIM] : T(0.0);
    auto A = [&](int k, int i) { return k <= kn ? acc[k][i] : T(0.0); };
    const T iw = T(1.0) / w[0];
    T* C0 = out;
    for (int i = 0; i < DIM; ++i) C0[i] = A(0, i) * iw;
    if (nd < 1) return;
    T* C1 = out + DIM;
    for (int i = 0; i < DIM; ++i) C1[i] = (A(1, i) - w[1] * C0[i]) * iw;
    if (nd < 2) return;
    T* C2 = out + 2 * DIM;
    const T b21 = T(2.0) * w[1];
    for (int i = 0; i < DIM; ++i) C2[i] = ((A(2, i) - b21 * C1[i]) - w[2] * C0[i]) * iw;
    if (nd < 3) return;
    T* C3 = out + 3 * DIM;
    const T b31 = T(3.0) * w[1], b32 = T(3.0) * w[2];
    for (int i = 0; i < DIM; ++i) C3[i] = (((A(3, i) - b31 * C2[i]) - b32 * C1[i]) - w[3] * C0[i]) * iw;
  }
}

template <class T>
using SpanKernel = void (*)(const PowerSpan&, const T&, int, T*);

constexpr int kFixedMaxDim = 3;     // specialised kernels: 1..3 axes,
constexpr int kFixedMaxDegree = 5;  // degree 1..5 (rational or not)

template <class T, int DIM, bool RAT>
inline SpanKernel<T> fixed_kernel_deg(int p) {
  switch (p) {
    case 1: return &eval_span_fixed<T, DIM, RAT, 1>;
    case 2: return &eval_span_fixed<T, DIM, RAT, 2>;
    case 3: return &eval_span_fixed<T, DIM, RAT, 3>;
    case 4: return &eval_span_fixed<T, DIM, RAT, 4>;
    case 5: return &eval_span_fixed<T, DIM, RAT, 5>;
    default: return nullptr;
  }
}

// The specialised kernel for (dim, rational, degree), or nullptr where there is none.
template <class T>
inline SpanKernel<T> fixed_kernel(int dim, bool rational, int p) {
  switch (dim) {
    case 1: return rational ? fixed_kernel_deg<T, 1, true>(p) : fixed_kernel_deg<T, 1, false>(p);
    case 2: return rational ? fixed_kernel_deg<T, 2, true>(p) : fixed_kernel_deg<T, 2, false>(p);
    case 3: return rational ? fixed_kernel_deg<T, 3, true>(p) : fixed_kernel_deg<T, 3, false>(p);
    default: return nullptr;
  }
}

// Non-rational span: the kernel Curve::eval_span uses (specialised where there is one, else general).
template <class T>
inline void eval_power_span(const PowerSpan& s, int dim, const T& u, int nd, T* out) {
  if (const SpanKernel<T> f = fixed_kernel<T>(dim, false, s.degree)) return f(s, u, nd, out);
  eval_power_span_general<T>(s, dim, u, nd, out);
}
}  // namespace detail

class Curve {
 public:
  Curve() = default;
  // Validates (GeometryError on bad input), clamps if needed, converts to power basis. max_degree: see
  // validate() (0 = the accepted range; larger only to measure the accuracy beyond it).
  explicit Curve(const BSpline& spline, const std::string& where = "curve", int max_degree = 0);

  const BSpline& spline() const { return spline_; }  // clamped form
  int degree() const { return spline_.degree; }
  int dim() const { return spline_.dim(); }
  bool rational() const { return spline_.rational(); }
  double u_begin() const { return spline_.u_begin(); }
  double u_end() const { return spline_.u_end(); }
  const std::vector<PowerSpan>& spans() const { return spans_; }
  const std::vector<BezierPiece>& bezier() const { return bezier_; }

  // Span containing u (clamped to the domain; u = span boundary goes to the span on the right,
  // except at u_end).
  int find_span(double u) const;

  // Position and derivatives 0..nd (nd <= 3) at u: out is dim x (nd+1), column k = k-th derivative.
  Eigen::MatrixXd eval(double u, int nd = 0) const;
  // Same into a caller buffer out[k*dim + axis], using span `span` (u may lie anywhere; the span
  // polynomial is extended). No allocation for dim <= 16. Uses the specialised kernel
  // (detail::eval_span_fixed: 1..3 axes, degree 1..5, rational or not) where there is one.
  void eval_span(int span, double u, int nd, double* out) const {
    if (kernel_) kernel_(spans_[span], u, nd, out);
    else eval_span_general(span, u, nd, out);
  }
  // The general (runtime-sized) path, any dim and degree: the reference the specialised kernels are
  // tested against (bitwise equal).
  void eval_span_general(int span, double u, int nd, double* out) const;
  void eval(double u, int nd, double* out) const { eval_span(find_span(u), u, nd, out); }
  Eigen::VectorXd point(double u) const {
    Eigen::VectorXd p(dim());
    eval(u, 0, p.data());
    return p;
  }

 private:
  BSpline spline_;
  std::vector<BezierPiece> bezier_;
  std::vector<PowerSpan> spans_;
  std::vector<double> breaks_;  // span start parameters (size = spans), for binary search
  detail::SpanKernel<double> kernel_ = nullptr;  // specialised kernel for this curve, if any
};

// Quotient rule for rational curves: from homogeneous derivatives A^(k) (dim values each) and
// w^(k), k = 0..nd, the Cartesian derivatives C^(k) = (A^(k) - sum_{i=1..k} C(k,i) w^(i) C^(k-i)) / w.
void rational_derivatives(const double* A, const double* w, int dim, int nd, double* C);

}  // namespace traj::geo
