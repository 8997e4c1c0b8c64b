// Curve: a B-spline/NURBS converted to piecewise power basis (seed 003): B-spline -> Bezier pieces
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
// the position Bezier points by 1/h^k on short spans (measured: 4e-10 relative, vs 1e-15 now).
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
  // Coefficient table of derivative k as a matrix (rows: powers of tau, columns: x.., [w]).
  Eigen::MatrixXd coefficients(int k) const;
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
// derivative k <= p: tau = u - uc once, then (p-k) multiplies and (p-k) adds per axis.
template <class T>
inline void eval_power_span(const PowerSpan& s, int dim, const T& u, int nd, T* out) {
  const T tau = u - T(s.uc);
  for (int k = 0; k <= nd; ++k) {
    if (k > s.degree) {
      for (int d = 0; d < dim; ++d) out[k * dim + d] = T(0.0);
      continue;
    }
    horner_rows_any<T>(s.coef.data() + s.offset(k), s.degree + 1 - k, s.cols, tau, out + k * dim);
  }
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
  // polynomial is extended). No allocation for dim <= 15.
  void eval_span(int span, double u, int nd, double* out) const;
  void eval(double u, int nd, double* out) const { eval_span(find_span(u), u, nd, out); }
  Eigen::VectorXd point(double u) const { return eval(u, 0).col(0); }

 private:
  BSpline spline_;
  std::vector<BezierPiece> bezier_;
  std::vector<PowerSpan> spans_;
  std::vector<double> breaks_;  // span start parameters (size = spans), for binary search
};

// Quotient rule for rational curves: from homogeneous derivatives A^(k) (dim values each) and
// w^(k), k = 0..nd, the Cartesian derivatives C^(k) = (A^(k) - sum_{i=1..k} C(k,i) w^(i) C^(k-i)) / w.
void rational_derivatives(const double* A, const double* w, int dim, int nd, double* C);

}  // namespace traj::geo
