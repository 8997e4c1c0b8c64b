// SPDX-License-Identifier: Apache-2.0
#include "input/gcode_curves.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace traj::input::gcode {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct PlanePoint {
  double a, b;
};

// The point of the spiral (circle when dr == 0) at angle phi, radius r.
Eigen::Vector3d plane_point(const ArcSpec& s, double phi, double r, double normal) {
  Eigen::Vector3d p;
  p[s.first] = s.c1 + r * std::cos(phi);
  p[s.second] = s.c2 + r * std::sin(phi);
  p[s.normal] = normal;
  return p;
}

// Where the lines p0 + u t0 and p1 + v t1 meet (in the plane).
PlanePoint intersect(PlanePoint p0, PlanePoint t0, PlanePoint p1, PlanePoint t1) {
  const double det = t0.a * (-t1.b) - t0.b * (-t1.a);
  const double ra = p1.a - p0.a, rb = p1.b - p0.b;
  const double u = (ra * (-t1.b) - rb * (-t1.a)) / det;
  return {p0.a + u * t0.a, p0.b + u * t0.b};
}

double radius_of(const ArcSpec& s, const Eigen::Vector3d& p) {
  return std::hypot(p[s.first] - s.c1, p[s.second] - s.c2);
}

double angle_of(const ArcSpec& s, const Eigen::Vector3d& p) {
  return std::atan2(p[s.second] - s.c2, p[s.first] - s.c1);
}

geo::BSpline planar_arc(const ArcSpec& s) {
  const int m = std::max(1, static_cast<int>(std::ceil(std::abs(s.sweep) / (kPi / 2) - 1e-12)));
  const double r0 = radius_of(s, s.start), r1 = radius_of(s, s.end), a0 = angle_of(s, s.start);
  const double dr = (r1 - r0) / s.sweep;  // radius change per radian
  const double w = std::cos(std::abs(s.sweep) / m / 2);
  Eigen::MatrixXd ctrl(2 * m + 1, 3);
  Eigen::VectorXd weights = Eigen::VectorXd::Ones(2 * m + 1);
  Eigen::VectorXd knots(2 * m + 4);
  auto point = [&](int k) -> Eigen::Vector3d {
    if (k == 0) return s.start;
    if (k == m) return s.end;
    return plane_point(s, a0 + s.sweep * k / m, r0 + (r1 - r0) * k / m, s.start[s.normal]);
  };
  auto tangent = [&](int k) -> PlanePoint {
    const double phi = a0 + s.sweep * k / m, r = r0 + (r1 - r0) * k / m;
    return {dr * std::cos(phi) - r * std::sin(phi), dr * std::sin(phi) + r * std::cos(phi)};
  };
  for (int k = 0; k <= m; ++k) ctrl.row(2 * k) = point(k).transpose();
  for (int k = 0; k < m; ++k) {
    const Eigen::Vector3d p0 = ctrl.row(2 * k).transpose(), p1 = ctrl.row(2 * k + 2).transpose();
    const PlanePoint mid = intersect({p0[s.first], p0[s.second]}, tangent(k), {p1[s.first], p1[s.second]},
                                     tangent(k + 1));
    Eigen::Vector3d c;
    c[s.first] = mid.a;
    c[s.second] = mid.b;
    c[s.normal] = s.start[s.normal];
    ctrl.row(2 * k + 1) = c.transpose();
    weights[2 * k + 1] = w;
  }
  knots[0] = knots[1] = knots[2] = 0;
  for (int k = 1; k < m; ++k) knots[2 * k + 1] = knots[2 * k + 2] = static_cast<double>(k) / m;
  knots[2 * m + 1] = knots[2 * m + 2] = knots[2 * m + 3] = 1;
  geo::BSpline b;
  b.degree = 2;
  b.ctrl = ctrl;
  b.weights = weights;
  b.knots = knots;
  return b;
}

// Bernstein coefficients (on t in [0,1]) of the polynomial sum_j c_j s^j, s = 2t - 1: Horner's
// scheme in Bernstein form, where multiplying by s = (-1, 1) and adding a constant are
// convex-combination steps (no cancellation beyond that of the values themselves).
std::vector<long double> bernstein_of(const std::vector<long double>& c) {
  const int n = static_cast<int>(c.size()) - 1;
  std::vector<long double> q{c[n]};
  for (int j = n - 1; j >= 0; --j) {
    const int d = static_cast<int>(q.size()) - 1;
    std::vector<long double> r(d + 2);
    for (int k = 0; k <= d + 1; ++k) {
      const long double lo = k > 0 ? q[k - 1] * k / (d + 1) : 0.0L;
      const long double hi = k <= d ? q[k] * (d + 1 - k) / (d + 1) : 0.0L;
      r[k] = lo - hi + c[j];
    }
    q.swap(r);
  }
  return q;
}

// One helix piece about angle phi_m, tau in [-h, h] (h signed: the direction of the sweep):
// Bernstein control points of degree kHelixTaylorDegree + 1, rows (first, second, normal) in xyz.
Eigen::MatrixXd helix_piece(const ArcSpec& s, double phi_m, double h, double r_m, double dr, double z_m,
                            double dz) {
  const int n = kHelixTaylorDegree;
  std::vector<long double> cosp(n + 1, 0.0L), sinp(n + 1, 0.0L);  // Taylor of cos(tau), sin(tau)
  long double fact = 1;
  for (int j = 0; j <= n; ++j) {
    if (j > 0) fact *= j;
    const long double t = ((j / 2) % 2 == 0 ? 1.0L : -1.0L) / fact;
    (j % 2 == 0 ? cosp : sinp)[j] = t;
  }
  const long double cm = std::cos(static_cast<long double>(phi_m)), sm = std::sin(static_cast<long double>(phi_m));
  std::vector<long double> xa(n + 2, 0.0L), xb(n + 2, 0.0L), xz(n + 2, 0.0L);
  for (int j = 0; j <= n; ++j) {
    const long double ca = cm * cosp[j] - sm * sinp[j];  // cos(phi_m + tau)
    const long double cb = sm * cosp[j] + cm * sinp[j];  // sin(phi_m + tau)
    xa[j] += r_m * ca;
    xa[j + 1] += dr * ca;
    xb[j] += r_m * cb;
    xb[j + 1] += dr * cb;
  }
  xa[0] += s.c1;
  xb[0] += s.c2;
  xz[0] = z_m;
  xz[1] = dz;
  long double hp = 1;
  for (int j = 0; j <= n + 1; ++j) {
    xa[j] *= hp;
    xb[j] *= hp;
    xz[j] *= hp;
    hp *= h;
  }
  const auto ba = bernstein_of(xa), bb = bernstein_of(xb), bz = bernstein_of(xz);
  Eigen::MatrixXd p(n + 2, 3);
  for (int k = 0; k <= n + 1; ++k) {
    p(k, s.first) = static_cast<double>(ba[k]);
    p(k, s.second) = static_cast<double>(bb[k]);
    p(k, s.normal) = static_cast<double>(bz[k]);
  }
  return p;
}

geo::BSpline helical_arc(const ArcSpec& s) {
  const double r0 = radius_of(s, s.start), r1 = radius_of(s, s.end), a0 = angle_of(s, s.start);
  const double z0 = s.start[s.normal], z1 = s.end[s.normal];
  const int m = helix_pieces(s);
  if (m > kMaxHelixPieces) throw std::invalid_argument("helical arc: radius too large to cut into pieces");
  const int p = kHelixTaylorDegree + 1;
  const double dr = (r1 - r0) / s.sweep, dz = (z1 - z0) / s.sweep, h = s.sweep / (2 * m);
  Eigen::MatrixXd ctrl(p * m + 1, 3);
  for (int k = 0; k < m; ++k) {
    const double f = (k + 0.5) / m;
    const Eigen::MatrixXd piece = helix_piece(s, a0 + s.sweep * f, h, r0 + (r1 - r0) * f, dr, z0 + (z1 - z0) * f, dz);
    ctrl.block(p * k, 0, p + 1, 3) = piece;
  }
  for (int k = 0; k <= m; ++k) {
    const Eigen::Vector3d q = k == 0 ? s.start
                              : k == m
                                  ? s.end
                                  : plane_point(s, a0 + s.sweep * k / m, r0 + (r1 - r0) * k / m, z0 + (z1 - z0) * k / m);
    ctrl.row(p * k) = q.transpose();
  }
  Eigen::VectorXd knots(p * m + p + 2);
  int i = 0;
  for (int j = 0; j <= p; ++j) knots[i++] = 0;
  for (int k = 1; k < m; ++k)
    for (int j = 0; j < p; ++j) knots[i++] = static_cast<double>(k) / m;
  for (int j = 0; j <= p; ++j) knots[i++] = 1;
  geo::BSpline b;
  b.degree = p;
  b.ctrl = ctrl;
  b.knots = knots;
  return b;
}

}  // namespace

int helix_pieces(const ArcSpec& s) {
  const double r = std::max(radius_of(s, s.start), radius_of(s, s.end)), sweep = std::abs(s.sweep);
  const auto fits = [&](int m) { return helix_piece_bound(r, sweep / (2 * m)) <= kHelixBound; };
  int lo = std::max(1, static_cast<int>(std::ceil(sweep / (kPi / 4) - 1e-12)));
  if (fits(lo)) return lo;
  int hi = lo;  // the bound falls as m grows: double until it fits, then bisect
  while (!fits(hi)) {
    if (hi > kMaxHelixPieces) return kMaxHelixPieces + 1;
    lo = hi;
    hi *= 2;
  }
  while (hi - lo > 1) {
    const int mid = lo + (hi - lo) / 2;
    (fits(mid) ? hi : lo) = mid;
  }
  return hi;
}

double helix_piece_bound(double r, double h) {
  const int n = kHelixTaylorDegree;
  double t1 = 1, t2;
  for (int j = 1; j <= n + 1; ++j) t1 *= h / j;  // h^(n+1)/(n+1)!
  t2 = t1 * h / (n + 2);                          // h^(n+2)/(n+2)!
  return r * (t1 + t2);
}

geo::BSpline line3(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return geo::make_line(a, b);
}

geo::BSpline arc3(const ArcSpec& a) {
  return a.start[a.normal] == a.end[a.normal] && !a.helix_form ? planar_arc(a) : helical_arc(a);
}

geo::BSpline with_further_axes(geo::BSpline xyz, const Eigen::VectorXd& e0, const Eigen::VectorXd& e1) {
  const Eigen::Index n = xyz.ctrl.rows(), d = xyz.ctrl.cols(), m = e0.size();
  if (m == 0) return xyz;
  if (xyz.rational() && e0 != e1) throw std::invalid_argument("further axes moving along a rational curve");
  Eigen::MatrixXd c(n, d + m);
  c.leftCols(d) = xyz.ctrl;
  const double u0 = xyz.u_begin(), span = xyz.u_end() - u0;
  for (Eigen::Index i = 0; i < n; ++i) {
    double greville = 0;  // mean of knots i+1 .. i+degree, as a share of the parameter range
    for (int j = 1; j <= xyz.degree; ++j) greville += xyz.knots[i + j];
    const double f = xyz.degree > 0 ? (greville / xyz.degree - u0) / span : 0.0;
    c.block(i, d, 1, m) = (e0 + (e1 - e0) * f).transpose();
  }
  c.block(0, d, 1, m) = e0.transpose();  // the programmed points exactly (clamped ends)
  c.block(n - 1, d, 1, m) = e1.transpose();
  xyz.ctrl = c;
  return xyz;
}

geo::BSpline bezier3(const Eigen::MatrixXd& ctrl) { return geo::make_bezier(ctrl); }

geo::BSpline nurbs3(const Eigen::MatrixXd& ctrl, const Eigen::VectorXd& weights, int order) {
  const int n = static_cast<int>(ctrl.rows()) - 1, k = order;
  geo::BSpline b;
  b.degree = k - 1;
  b.ctrl = ctrl;
  if ((weights.array() != weights[0]).any()) b.weights = weights;  // equal weights: the same curve, non-rational
  b.knots.resize(n + k + 1);
  for (int i = 0; i <= n + k; ++i) b.knots[i] = i < k ? 0.0 : i <= n ? i - k + 1.0 : n - k + 2.0;
  return b;
}

}  // namespace traj::input::gcode
