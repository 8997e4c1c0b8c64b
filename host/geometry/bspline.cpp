// SPDX-License-Identifier: Apache-2.0
#include "geometry/bspline.hpp"

#include <algorithm>
#include <cmath>
#include <charconv>
#include <string>

#include "geometry/error.hpp"
#include "util/format.hpp"

namespace traj::geo {

namespace {
[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw GeometryError(where + ": " + what);
}
using util::shortest;
}  // namespace

bool BSpline::clamped() const {
  const int n = n_ctrl(), p = degree;
  for (int i = 1; i <= p; ++i)
    if (knots[i] != knots[0] || knots[n + p - i] != knots[n + p]) return false;
  return true;
}

Eigen::MatrixXd BSpline::homogeneous() const {
  Eigen::MatrixXd h(n_ctrl(), dim() + 1);
  for (int i = 0; i < n_ctrl(); ++i) {
    const double w = rational() ? weights[i] : 1.0;
    h.row(i).head(dim()) = w * ctrl.row(i);
    h(i, dim()) = w;
  }
  return h;
}

BSpline BSpline::from_homogeneous(int degree, const Eigen::MatrixXd& hom, const Eigen::VectorXd& knots,
                                  bool rational, std::string name) {
  BSpline c;
  c.degree = degree;
  c.knots = knots;
  c.name = std::move(name);
  const int d = static_cast<int>(hom.cols()) - 1;
  c.ctrl.resize(hom.rows(), d);
  if (rational) c.weights.resize(hom.rows());
  for (int i = 0; i < hom.rows(); ++i) {
    const double w = hom(i, d);
    c.ctrl.row(i) = hom.row(i).head(d) / w;
    if (rational) c.weights[i] = w;
  }
  return c;
}

std::string degree_range_error(long long degree, bool rational, int max_degree, const std::string& shown) {
  const int cap = max_degree > 0 ? max_degree : (rational ? kMaxDegreeRational : kMaxDegree);
  if (degree >= 1 && degree <= cap) return {};
  std::string m = "degree: " + (shown.empty() ? std::to_string(degree) : shown) + " out of range 1.." + std::to_string(cap);
  if (degree > cap && max_degree <= 0)
    m += rational ? " for a rational curve (the quotient rule amplifies the power basis's rounding by the weights; "
                    "non-rational curves: up to " + std::to_string(kMaxDegree) + ")"
                  : " (the power basis loses about 1 bit per degree: beyond " + std::to_string(kMaxDegree) +
                        " it misses the 1e-12 accuracy target)";
  return m;
}

void validate(const BSpline& c, const std::string& where, int max_degree) {
  if (const std::string e = degree_range_error(c.degree, c.rational(), max_degree); !e.empty()) fail(where, e);
  if (c.dim() < 1) fail(where, "control_points: points have no coordinates");
  const int n = c.n_ctrl();
  if (n < c.degree + 1)
    fail(where, "control_points: " + std::to_string(n) + " points, degree " + std::to_string(c.degree) +
                    " needs at least " + std::to_string(c.degree + 1));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < c.dim(); ++j)
      if (!std::isfinite(c.ctrl(i, j)))
        fail(where, "control_points[" + std::to_string(i) + "][" + std::to_string(j) + "]: not a finite number");
      else if (std::abs(c.ctrl(i, j)) > kMaxCoordinate)
        fail(where, "control_points[" + std::to_string(i) + "][" + std::to_string(j) + "]: " + shortest(c.ctrl(i, j)) +
                        " beyond +-" + shortest(kMaxCoordinate) + " (the geometry's double-precision range)");
  if (c.rational()) {
    if (c.weights.size() != n)
      fail(where, "weights: " + std::to_string(c.weights.size()) + " weights for " + std::to_string(n) +
                      " control points");
    for (int i = 0; i < n; ++i) {
      if (!std::isfinite(c.weights[i]))
        fail(where, "weights[" + std::to_string(i) + "]: not a finite number");
      if (!(c.weights[i] > 0))
        fail(where, "weights[" + std::to_string(i) + "]: " + shortest(c.weights[i]) + " (weights must be positive)");
    }
    Eigen::Index lo = 0, hi = 0;
    c.weights.minCoeff(&lo);
    c.weights.maxCoeff(&hi);
    if (c.weights[hi] > kMaxWeightRatio * c.weights[lo])
      fail(where, "weights[" + std::to_string(hi) + "]: " + shortest(c.weights[hi]) + " is " +
                      shortest(c.weights[hi] / c.weights[lo]) + " times weights[" + std::to_string(lo) + "] = " +
                      shortest(c.weights[lo]) + ", beyond the ratio " + shortest(kMaxWeightRatio) +
                      " (the rational speed loses about ratio^2 ulp to cancellation)");
  }
  const int m = n + c.degree + 1;
  if (c.knots.size() != m)
    fail(where, "knots: " + std::to_string(c.knots.size()) + " knots, expected n_ctrl + degree + 1 = " +
                    std::to_string(m));
  for (int i = 0; i < m; ++i) {
    if (!std::isfinite(c.knots[i])) fail(where, "knots[" + std::to_string(i) + "]: not a finite number");
    if (std::abs(c.knots[i]) > kMaxKnot)
      fail(where, "knots[" + std::to_string(i) + "]: " + shortest(c.knots[i]) + " beyond +-" + shortest(kMaxKnot) +
                      " (the speed |r'| ~ |P| / knot span underflows: rescale the knot vector)");
    if (i > 0 && c.knots[i] < c.knots[i - 1])
      fail(where, "knots[" + std::to_string(i) + "]: " + shortest(c.knots[i]) + " < previous " + shortest(c.knots[i - 1]) +
                      " (knot vector must be non-decreasing)");
  }
  // No knot of multiplicity > degree+1, and inner multiplicity <= degree (else the curve is split).
  for (int i = 0; i + c.degree + 1 < m; ++i)
    if (c.knots[i] == c.knots[i + c.degree + 1])
      fail(where, "knots[" + std::to_string(i) + "]: multiplicity exceeds degree + 1");
  if (!(c.u_end() > c.u_begin()))
    fail(where, "knots: empty parameter domain [knots[degree], knots[n_ctrl]] = [" + shortest(c.u_begin()) + ", " +
                    shortest(c.u_end()) + "]");
  for (int i = c.degree + 1; i < n; ++i)
    if (c.knots[i] == c.knots[i + c.degree])
      fail(where, "knots[" + std::to_string(i) + "]: interior multiplicity exceeds degree (curve would be broken)");
}

BSpline insert_knot(const BSpline& c, double u, int times) {
  Eigen::MatrixXd P = c.homogeneous();
  Eigen::VectorXd U = c.knots;
  const int p = c.degree;
  for (int r = 0; r < times; ++r) {
    const int n = static_cast<int>(P.rows());
    // k: last index with U[k] <= u, restricted to [p, n-1] so that u in [U_k, U_{k+1}) or u = domain end.
    int k = p;
    while (k + 1 < n && U[k + 1] <= u) ++k;
    int total = 0, s = 0;  // total multiplicity of u; s = multiplicity at indices <= k (Boehm's s)
    for (int i = 0; i < U.size(); ++i)
      if (U[i] == u) {
        ++total;
        if (i <= k) ++s;
      }
    if (total >= p) throw GeometryError("insert_knot: multiplicity of " + shortest(u) + " would exceed degree");
    Eigen::MatrixXd Q(n + 1, P.cols());
    for (int i = 0; i <= k - p; ++i) Q.row(i) = P.row(i);
    for (int i = k - p + 1; i <= k - s; ++i) {
      const double a = (u - U[i]) / (U[i + p] - U[i]);
      // coincident points stay exactly so (a retracted Bezier handle, P2 =
      // P3, split by a corner blend: a P[i] + (1 - a) P[i-1] moved the new
      // point by an ulp, leaving an end speed of 1e-16 whose speed bound made
      // the planner cruise the last 1e-15 mm at 1e-28 mm/s for 1e13 s)
      if (P.row(i) == P.row(i - 1))
        Q.row(i) = P.row(i);
      else
        Q.row(i) = a * P.row(i) + (1.0 - a) * P.row(i - 1);
    }
    for (int i = k - s + 1; i <= n; ++i) Q.row(i) = P.row(i - 1);
    Eigen::VectorXd V(U.size() + 1);
    V.head(k + 1) = U.head(k + 1);
    V[k + 1] = u;
    V.tail(U.size() - k - 1) = U.tail(U.size() - k - 1);
    P.swap(Q);
    U.swap(V);
  }
  return BSpline::from_homogeneous(p, P, U, c.rational(), c.name);
}

std::pair<BSpline, BSpline> split_at(const BSpline& c0, double u) {
  const BSpline c = clamp(c0);
  const int p = c.degree;
  if (!(u > c.u_begin() && u < c.u_end()))
    throw GeometryError("split_at: u = " + shortest(u) + " is not inside the domain (" + shortest(c.u_begin()) + ", " +
                        shortest(c.u_end()) + ")");
  int mult = 0;
  for (int i = 0; i < c.knots.size(); ++i) mult += (c.knots[i] == u);
  const BSpline d = mult < p ? insert_knot(c, u, p - mult) : c;
  int r = 0;  // first index of u in the knots (it now occupies r .. r+p-1)
  while (d.knots[r] != u) ++r;
  const int n = d.n_ctrl(), dim = d.dim();
  const Eigen::MatrixXd H = d.homogeneous();
  Eigen::VectorXd kl(r + p + 1), kr(n + p + 1 - r + 1);
  kl.head(r + p) = d.knots.head(r + p);
  kl[r + p] = u;
  kr[0] = u;
  kr.tail(n + p + 1 - r) = d.knots.tail(n + p + 1 - r);
  BSpline left = BSpline::from_homogeneous(p, H.topRows(r), kl, c.rational(), c.name);
  BSpline right = BSpline::from_homogeneous(p, H.bottomRows(n - r + 1), kr, c.rational(), c.name);
  (void)dim;
  return {left, right};
}

BSpline clamp(const BSpline& c0) {
  if (c0.clamped()) return c0;
  const int p = c0.degree;
  auto mult = [](const BSpline& c, double u) {
    int s = 0;
    for (int i = 0; i < c.knots.size(); ++i) s += (c.knots[i] == u);
    return s;
  };
  BSpline c = c0;
  // Front: raise the multiplicity of a = t_p to at least p; then only control points i >= l0 - p
  // (l0 = last index of a) act on [a, ...]; keep those, with knots from l0 - p (first one set to a;
  // N_{i,p} on [t_{i+p}, ...) does not depend on t_i).
  {
    const double a = c.u_begin();
    const int s = mult(c, a);
    if (s < p) c = insert_knot(c, a, p - s);
    int l0 = 0;
    while (l0 + 1 < c.knots.size() && c.knots[l0 + 1] <= a) ++l0;
    const int i0 = l0 - p;
    const int keep = c.n_ctrl() - i0;
    Eigen::MatrixXd P = c.homogeneous().bottomRows(keep);
    Eigen::VectorXd U = c.knots.tail(c.knots.size() - i0);
    U[0] = a;
    c = BSpline::from_homogeneous(p, P, U, c.rational(), c.name);
  }
  // Back: symmetric. f = first index of b; control points 0..f-1 act on [..., b]; knots 0..f+p,
  // the last one set to b.
  {
    const double b = c.u_end();
    const int s = mult(c, b);
    if (s < p) c = insert_knot(c, b, p - s);
    int f = 0;
    while (c.knots[f] < b) ++f;
    const int keep = f;
    Eigen::MatrixXd P = c.homogeneous().topRows(keep);
    Eigen::VectorXd U = c.knots.head(keep + p + 1);
    U[keep + p] = b;
    c = BSpline::from_homogeneous(p, P, U, c.rational(), c.name);
  }
  return c;
}

std::vector<BezierPiece> bezier_pieces(const BSpline& c0) {
  // The NURBS Book's A5.6 (DecomposeCurve): one left-to-right sweep that raises each interior knot
  // to multiplicity p in the piece being built and starts the next piece from the points it leaves,
  // O(n p^2) in all (inserting the knots one at a time into the whole curve copies it per knot).
  const BSpline c = clamp(c0);
  const int p = c.degree;
  const Eigen::VectorXd& U = c.knots;
  const Eigen::MatrixXd P = c.homogeneous();
  const int m = static_cast<int>(U.size()) - 1;
  std::vector<BezierPiece> out;
  Eigen::MatrixXd Q = P.topRows(p + 1), next(p + 1, P.cols());
  std::vector<double> alpha(static_cast<size_t>(p) + 1);
  int a = p, b = p + 1;
  while (b < m) {
    const int i0 = b;
    while (b < m && U[b + 1] == U[b]) ++b;
    const int mult = b - i0 + 1;
    if (mult < p) {
      const double numer = U[b] - U[a];
      for (int j = p; j > mult; --j) alpha[j - mult - 1] = numer / (U[a + j] - U[a]);
      const int r = p - mult;
      for (int j = 1; j <= r; ++j) {
        const int save = r - j, s = mult + j;
        for (int k = p; k >= s; --k) {
          const double al = alpha[k - s];
          Q.row(k) = al * Q.row(k) + (1.0 - al) * Q.row(k - 1);
        }
        if (b < m) next.row(save) = Q.row(p);
      }
    }
    BezierPiece piece;
    piece.u0 = U[a];
    piece.u1 = U[b];
    piece.hom = Q;
    out.push_back(std::move(piece));
    if (b < m) {
      // (a hodograph of a curve with a C0 knot has interior multiplicity p + 1: no point inserted)
      for (int i = std::max(0, p - mult); i <= p; ++i) next.row(i) = P.row(b - p + i);
      Q.swap(next);
      a = b;
      ++b;
    }
  }
  return out;
}

BSpline make_bezier(const Eigen::MatrixXd& ctrl, const Eigen::VectorXd& weights) {
  BSpline c;
  c.degree = static_cast<int>(ctrl.rows()) - 1;
  c.ctrl = ctrl;
  c.weights = weights;
  c.knots.resize(2 * ctrl.rows());
  c.knots.head(ctrl.rows()).setZero();
  c.knots.tail(ctrl.rows()).setOnes();
  c.name = "bezier";
  validate(c, "make_bezier");
  return c;
}

BSpline make_line(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() != b.size()) throw GeometryError("make_line: end points of different dimension");
  Eigen::MatrixXd P(2, a.size());
  P.row(0) = a.transpose();
  P.row(1) = b.transpose();
  BSpline c = make_bezier(P);
  c.name = "line";
  return c;
}

BSpline make_arc(const Eigen::Vector2d& ctr, double r, double a0, double a1) {
  const double sweep = a1 - a0;
  if (!(r > 0) || !std::isfinite(r)) throw GeometryError("make_arc: radius must be positive and finite");
  if (!(std::abs(sweep) > 0) || std::abs(sweep) > 2 * M_PI * (1 + 1e-15))
    throw GeometryError("make_arc: sweep must be non-zero and at most 2 pi");
  const int pieces = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / (M_PI / 2) - 1e-12)));
  const double dth = sweep / pieces;
  const double wm = std::cos(dth / 2);
  const int n = 2 * pieces + 1;
  BSpline c;
  c.degree = 2;
  c.name = "arc";
  c.ctrl.resize(n, 2);
  c.weights.resize(n);
  c.knots.resize(n + 3);
  auto on = [&](double a) { return Eigen::Vector2d(ctr + r * Eigen::Vector2d(std::cos(a), std::sin(a))); };
  for (int k = 0; k < pieces; ++k) {
    const double t0 = a0 + k * dth, tm = t0 + dth / 2;
    c.ctrl.row(2 * k) = on(t0).transpose();
    c.weights[2 * k] = 1.0;
    // Middle control point: intersection of the end tangents, at distance r / cos(dth/2) along tm.
    c.ctrl.row(2 * k + 1) = (ctr + (r / wm) * Eigen::Vector2d(std::cos(tm), std::sin(tm))).transpose();
    c.weights[2 * k + 1] = wm;
  }
  c.ctrl.row(n - 1) = on(a1).transpose();
  c.weights[n - 1] = 1.0;
  c.knots.head(3).setZero();
  c.knots.tail(3).setOnes();
  for (int k = 1; k < pieces; ++k) c.knots[1 + 2 * k] = c.knots[2 + 2 * k] = static_cast<double>(k) / pieces;
  validate(c, "make_arc");
  return c;
}

BSpline make_bezier_circle(const Eigen::Vector2d& ctr, double r, int segments) {
  if (segments < 2) throw GeometryError("make_bezier_circle: need at least 2 segments");
  const double th = 2 * M_PI / segments;
  const double k = 4.0 / 3.0 * std::tan(th / 4);
  const int n = 3 * segments + 1;
  BSpline c;
  c.degree = 3;
  c.name = "bezier_circle";
  c.ctrl.resize(n, 2);
  for (int s = 0; s < segments; ++s) {
    const double a = s * th, b = a + th;
    const Eigen::Vector2d p0(std::cos(a), std::sin(a)), p3(std::cos(b), std::sin(b));
    const Eigen::Vector2d t0(-std::sin(a), std::cos(a)), t3(-std::sin(b), std::cos(b));
    c.ctrl.row(3 * s) = (ctr + r * p0).transpose();
    c.ctrl.row(3 * s + 1) = (ctr + r * (p0 + k * t0)).transpose();
    c.ctrl.row(3 * s + 2) = (ctr + r * (p3 - k * t3)).transpose();
  }
  c.ctrl.row(n - 1) = c.ctrl.row(0);
  c.knots.resize(n + 4);
  c.knots.head(4).setZero();
  c.knots.tail(4).setOnes();
  for (int s = 1; s < segments; ++s)
    for (int j = 0; j < 3; ++j) c.knots[1 + 3 * s + j] = static_cast<double>(s) / segments;
  validate(c, "make_bezier_circle");
  return c;
}

}  // namespace traj::geo
