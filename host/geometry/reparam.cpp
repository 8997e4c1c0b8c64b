// SPDX-License-Identifier: Apache-2.0
#include "geometry/reparam.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/error.hpp"

namespace traj::geo {

std::vector<double> equal_arclength_params(const ArcLength& al, double step, bool include_end) {
  if (!(step > 0)) throw GeometryError("equal_arclength_params: step must be positive");
  const Curve& c = al.curve();
  const double L = al.total();
  const long long n = static_cast<long long>(std::floor(L / step * (1 + 1e-15)));
  std::vector<double> u;
  u.reserve(static_cast<size_t>(n) + 2);
  u.push_back(c.u_begin());
  for (long long k = 1; k <= n; ++k) {
    const double guess = u.size() >= 2 ? 2 * u.back() - u[u.size() - 2] : -1;
    const double next = al.advance(u.back(), step, guess);
    if (next >= c.u_end()) {
      // The last full step can reach the end only within rounding.
      u.push_back(c.u_end());
      return u;
    }
    u.push_back(next);
  }
  if (include_end && L - n * step > 1e-12 * step && u.back() < c.u_end()) u.push_back(c.u_end());
  return u;
}

std::vector<double> arc_paper_reparam(const Curve& c, double ua, double ub, int n, int passes) {
  if (n < 1) throw GeometryError("arc_paper_reparam: n must be >= 1");
  std::vector<double> tau(n, 1.0 / n), u(n + 1);
  const int dim = c.dim();
  std::vector<double> P((n + 1) * dim);
  auto points = [&]() {
    double t = 0;
    for (int i = 0; i <= n; ++i) {
      u[i] = (i == n) ? ub : ua + (ub - ua) * t;
      c.eval(u[i], 0, &P[i * dim]);
      if (i < n) t += tau[i];
    }
  };
  points();
  for (int pass = 0; pass < passes; ++pass) {
    std::vector<double> l(n);
    double lcurve = 0;
    for (int i = 0; i < n; ++i) {
      double d2 = 0;
      for (int d = 0; d < dim; ++d) d2 += (P[(i + 1) * dim + d] - P[i * dim + d]) * (P[(i + 1) * dim + d] - P[i * dim + d]);
      l[i] = std::sqrt(d2);  // [2_02] (as a length: |P_i - P_{i-1}|)
      lcurve += l[i];        // [2_03] (sum over the n steps)
    }
    double sum = 0;
    for (int i = 0; i < n; ++i) {
      tau[i] = tau[i] * lcurve / (n * l[i]);  // [2_04], with the previous tau in place of t_const
      sum += tau[i];
    }
    for (double& t : tau) t /= sum;  // "normalised by the factor resulting from their sum"
    points();
  }
  return u;
}

std::vector<double> arc_paper_reparam_spline(const Curve& c, const ArcLength& al, double step, int passes) {
  std::vector<double> out{c.u_begin()};
  const auto& spans = c.spans();
  for (size_t i = 0; i < spans.size(); ++i) {
    const double Li = al.cumulative()[i + 1] - al.cumulative()[i];
    const int n = std::max(1, static_cast<int>(std::lround(Li / step)));
    const std::vector<double> u = arc_paper_reparam(c, spans[i].u0, spans[i].u1, n, passes);
    out.insert(out.end(), u.begin() + 1, u.end());
  }
  return out;
}

std::vector<double> taylor_interpolate(const Curve& c, double feed, double period, int order) {
  if (order != 1 && order != 2) throw GeometryError("taylor_interpolate: order must be 1 or 2");
  const double ds = feed * period;
  const int dim = c.dim();
  std::vector<double> b(3 * dim);
  std::vector<double> u{c.u_begin()};
  const size_t cap = 100000000;
  while (u.size() < cap) {
    c.eval(u.back(), 2, b.data());
    double v2 = 0, d12 = 0;
    for (int d = 0; d < dim; ++d) {
      v2 += b[dim + d] * b[dim + d];
      d12 += b[dim + d] * b[2 * dim + d];
    }
    const double v = std::sqrt(v2);
    double du = ds / v;
    if (order == 2) du -= ds * ds * d12 / (2 * v2 * v2);
    const double next = u.back() + du;
    if (next >= c.u_end()) {
      u.push_back(c.u_end());
      break;
    }
    u.push_back(next);
  }
  return u;
}

namespace {
Fluctuation stats_of(const std::vector<double>& ds, double nominal) {
  Fluctuation f;
  if (ds.empty()) return f;
  f.max = -1e300;
  f.min = 1e300;
  double sq = 0, mx = 0, mn = 1e300;
  for (double d : ds) {
    const double e = d / nominal - 1;
    f.max = std::max(f.max, e);
    f.min = std::min(f.min, e);
    sq += e * e;
    mx = std::max(mx, d);
    mn = std::min(mn, d);
  }
  f.rms = std::sqrt(sq / ds.size());
  f.ratio = mx / mn;
  f.steps = static_cast<int>(ds.size());
  return f;
}
}  // namespace

Fluctuation feed_fluctuation(const ArcLength& al, const std::vector<double>& u, double nominal, bool skip_last) {
  std::vector<double> ds;
  const size_t n = u.size() < 2 ? 0 : u.size() - 1 - (skip_last ? 1 : 0);
  for (size_t k = 0; k < n; ++k) ds.push_back(al.length(u[k], u[k + 1]));
  return stats_of(ds, nominal);
}

Fluctuation chord_fluctuation(const Curve& c, const std::vector<double>& u) {
  std::vector<double> ds;
  double sum = 0;
  for (size_t k = 0; k + 1 < u.size(); ++k) {
    ds.push_back((c.point(u[k + 1]) - c.point(u[k])).norm());
    sum += ds.back();
  }
  return stats_of(ds, ds.empty() ? 1 : sum / ds.size());
}

}  // namespace traj::geo
