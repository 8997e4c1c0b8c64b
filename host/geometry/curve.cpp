// SPDX-License-Identifier: Apache-2.0
#include "geometry/curve.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/error.hpp"
#include "util/format.hpp"

namespace traj::geo {

namespace {
double binom(int n, int k) {
  double r = 1;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}
}  // namespace

namespace {
// Hodograph of a non-rational B-spline (any number of columns): degree p-1, control points
// Q'_i = p (Q_{i+1} - Q_i) / (t_{i+p+1} - t_{i+1}) (0 where the denominator is 0), knots without the
// first and the last.
void hodograph(int p, const Eigen::MatrixXd& Q, const Eigen::VectorXd& U, Eigen::MatrixXd& Qd, Eigen::VectorXd& Ud) {
  const Eigen::Index n = Q.rows();
  Qd.resize(n - 1, Q.cols());
  for (Eigen::Index i = 0; i + 1 < n; ++i) {
    const double den = U[i + p + 1] - U[i + 1];
    if (den > 0) Qd.row(i) = p * (Q.row(i + 1) - Q.row(i)) / den;
    else Qd.row(i).setZero();
  }
  Ud = U.segment(1, U.size() - 2);
}
}  // namespace

Curve::Curve(const BSpline& spline, const std::string& where, int max_degree) {
  validate(spline, where, max_degree);
  spline_ = clamp(spline);
  bezier_ = bezier_pieces(spline_);
  const int p = spline_.degree;
  // Columns: the axes, plus the weight when rational (homogeneous (w x, w)); for a non-rational
  // curve the weight column is all ones and is not stored.
  const int cols = spline_.dim() + (spline_.rational() ? 1 : 0);
  for (const BezierPiece& b : bezier_) {
    PowerSpan s;
    s.u0 = b.u0;
    s.u1 = b.u1;
    s.uc = 0.5 * (b.u0 + b.u1);
    s.degree = p;
    s.cols = cols;
    s.coef.assign(static_cast<size_t>(s.offset(std::min(kMaxDeriv, p) + 1)), 0.0);
    spans_.push_back(std::move(s));
    breaks_.push_back(b.u0);
  }
  kernel_ = detail::fixed_kernel<double>(spline_.dim(), spline_.rational(), p);
  // Derivative k's table is converted from the k-th hodograph (a B-spline of degree p-k), not by
  // differentiating the position polynomial: the power coefficients of a short span are j-th
  // differences of its Bezier points divided by h^j, and differencing positions would amplify their
  // rounding (eps * |P|) by 1/h^k. The hodograph's control points are differences of the original
  // control points over knot distances, exact to eps * |Q^(k)| (the accuracy of De Boor-Cox).
  // Hodographs are taken from the input spline as given (clamped or not: the derivative formula holds
  // for any knot vector); each hodograph is then clamped and split into Bezier pieces on its own.
  Eigen::MatrixXd Q = spline.homogeneous().leftCols(cols);
  Eigen::VectorXd U = spline.knots;
  for (int k = 0; k <= std::min(kMaxDeriv, p); ++k) {
    if (k > 0) {
      Eigen::MatrixXd Qd;
      Eigen::VectorXd Ud;
      hodograph(p - k + 1, Q, U, Qd, Ud);
      Q.swap(Qd);
      U.swap(Ud);
    }
    const int q = p - k;
    if (q == 0) {  // piecewise constant: span [t_j, t_{j+1}) of the original has value Q_{j-p}
      size_t si = 0;
      for (int j = p; j < spline.n_ctrl(); ++j) {
        if (!(spline.knots[j] < spline.knots[j + 1])) continue;
        PowerSpan& s = spans_.at(si++);
        for (int c = 0; c < cols; ++c) s.coef[s.offset(k) + c] = Q(j - p, c);
      }
      continue;
    }
    BSpline d;
    d.degree = q;
    d.ctrl = Q;
    d.knots = U;
    const std::vector<BezierPiece> pieces = bezier_pieces(d);
    if (pieces.size() != spans_.size()) throw GeometryError(where + ": internal: span count mismatch in hodograph");
    for (size_t si = 0; si < pieces.size(); ++si) {
      PowerSpan& s = spans_[si];
      // Bezier -> power basis about the span midpoint uc (a double): with t = (u - u0)/h and
      // t_c = (uc - u0)/h, the Taylor coefficients at t_c (de Casteljau form)
      //   a_j = C(q,j) sum_{i=0}^{q-j} (Delta^j B)_i b^{q-j}_i(t_c),   b^m_i: Bernstein polynomials,
      // then tau = u - uc: a_j /= h^j. About the midpoint the rounding growth is ~2^q instead of ~3^q
      // for an end-point expansion. t_c, h and the Bernstein weights are computed in long double so
      // that the expansion point is exactly the stored double uc (an offset error in uc would cost
      // |a_1| * eps * |u|, large on short spans far from u = 0).
      const long double hl = static_cast<long double>(s.u1) - s.u0;
      const long double tc = (static_cast<long double>(s.uc) - s.u0) / hl;
      Eigen::MatrixXd D = pieces[si].hom.leftCols(cols);
      for (int j = 0; j <= q; ++j) {
        if (j > 0) D = (D.bottomRows(D.rows() - 1) - D.topRows(D.rows() - 1)).eval();
        const int m = q - j;
        long double scale = binom(q, j);
        for (int r = 0; r < j; ++r) scale /= hl;
        for (int cc = 0; cc < cols; ++cc) {
          long double acc = 0;
          for (int i = 0; i <= m; ++i) {
            long double b = binom(m, i);
            for (int r = 0; r < i; ++r) b *= tc;
            for (int r = 0; r < m - i; ++r) b *= (1 - tc);
            acc += b * D(i, cc);
          }
          s.coef[s.offset(k) + j * cols + cc] = static_cast<double>(scale * acc);
        }
      }
    }
  }
  for (const PowerSpan& s : spans_)
    for (double v : s.coef)
      if (!std::isfinite(v))
        throw GeometryError(where + ": knots: the span [" + util::shortest(s.u0) + ", " + util::shortest(s.u1) +
                            "] is too short for its control points: the curve's derivatives there overflow the "
                            "double range (merge or respace the knots)");
}

int Curve::find_span(double u) const {
  auto it = std::upper_bound(breaks_.begin(), breaks_.end(), u);
  int i = static_cast<int>(it - breaks_.begin()) - 1;
  return std::clamp(i, 0, static_cast<int>(spans_.size()) - 1);
}

void rational_derivatives(const double* A, const double* w, int dim, int nd, double* C) {
  static const double B[4][4] = {{1, 0, 0, 0}, {1, 1, 0, 0}, {1, 2, 1, 0}, {1, 3, 3, 1}};
  const double iw = 1.0 / w[0];
  for (int k = 0; k <= nd; ++k) {
    for (int d = 0; d < dim; ++d) {
      double v = A[k * dim + d];
      for (int i = 1; i <= k; ++i) v -= B[k][i] * w[i] * C[(k - i) * dim + d];
      C[k * dim + d] = v * iw;
    }
  }
}

void Curve::eval_span_general(int si, double u, int nd, double* out) const {
  const PowerSpan& s = spans_[si];
  const int p = s.degree, cols = s.cols, dim = spline_.dim();
  const double tau = u - s.uc;
  if (!spline_.rational()) {
    detail::eval_power_span_general<double>(s, dim, u, nd, out);
    return;
  }
  constexpr int kStack = 16;
  double abuf[4 * (kStack + 1)], wbuf[4], row[kStack + 1];
  std::vector<double> heap;
  double* A = abuf;
  double* R = row;
  if (dim > kStack) {
    heap.resize(5 * (dim + 1));
    A = heap.data();
    R = heap.data() + 4 * (dim + 1);
  }
  for (int k = 0; k <= nd; ++k) {
    if (k > p) {
      for (int d = 0; d < dim; ++d) A[k * dim + d] = 0;
      wbuf[k] = 0;
      continue;
    }
    detail::horner_rows_any<double>(s.coef.data() + s.offset(k), p + 1 - k, cols, tau, R);
    for (int d = 0; d < dim; ++d) A[k * dim + d] = R[d];
    wbuf[k] = R[dim];
  }
  rational_derivatives(A, wbuf, dim, nd, out);
}

Eigen::MatrixXd Curve::eval(double u, int nd) const {
  if (nd < 0 || nd > kMaxDeriv) throw GeometryError("Curve::eval: derivative order must be 0..3");
  Eigen::MatrixXd m(dim(), nd + 1);
  eval(u, nd, m.data());
  return m;
}

}  // namespace traj::geo
