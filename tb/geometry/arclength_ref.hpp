// SPDX-License-Identifier: Apache-2.0
// Independent arc-length reference for the arc-length benchmark and test: composite 20-point
// Gauss-Legendre in long double (nodes by Newton on P_20 in long double), speed |r'(u)| from
// Curve::eval_span (the power-basis evaluator, not ArcLength's speed kernel) with the norm taken in
// long double. `panels` equal panels on [a, b]; the caller checks convergence (panels vs 2 * panels).
#pragma once
#include <cmath>
#include <vector>

#include "geometry/curve.hpp"

namespace geotest {

struct GLRuleLD {
  std::vector<long double> x, w;
  explicit GLRuleLD(int n) : x(n), w(n) {
    for (int i = 0; i < n; ++i) {
      long double z = std::cos(3.14159265358979323846264338327950288L * (i + 0.75L) / (n + 0.5L)), dp = 0;
      for (int it = 0; it < 100; ++it) {
        long double p0 = 1, p1 = z;
        for (int k = 1; k < n; ++k) {
          const long double p2 = ((2 * k + 1) * z * p1 - k * p0) / (k + 1);
          p0 = p1;
          p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1);
        const long double dz = p1 / dp;
        z -= dz;
        if (std::fabs(dz) < 1e-19L) break;
      }
      x[i] = -z;
      w[i] = 2 / ((1 - z * z) * dp * dp);
    }
  }
};

inline const GLRuleLD& gl20ld() {
  static const GLRuleLD r(20);
  return r;
}

inline long double speed_ld(const traj::geo::Curve& c, int span, double u) {
  double buf[2 * 16];
  c.eval_span(span, u, 1, buf);
  const int dim = c.dim();
  long double s2 = 0;
  for (int d = 0; d < dim; ++d) s2 += static_cast<long double>(buf[dim + d]) * buf[dim + d];
  return std::sqrt(s2);
}

// Length of [a, b] (a <= b) on the curve, spans handled piecewise (each span's own polynomial).
inline long double ref_length(const traj::geo::Curve& c, double a, double b, int panels = 16) {
  if (!(b > a)) return 0;
  const auto& sp = c.spans();
  const GLRuleLD& r = gl20ld();
  long double total = 0;
  for (int si = c.find_span(a); si < static_cast<int>(sp.size()); ++si) {
    const long double lo = std::max<long double>(a, sp[si].u0), hi = std::min<long double>(b, sp[si].u1);
    if (hi > lo) {
      const long double h = (hi - lo) / panels;
      for (int k = 0; k < panels; ++k) {
        const long double pa = lo + k * h, m = pa + 0.5L * h;
        long double acc = 0;
        for (size_t i = 0; i < r.x.size(); ++i) acc += r.w[i] * speed_ld(c, si, static_cast<double>(m + 0.5L * h * r.x[i]));
        total += acc * 0.5L * h;
      }
    }
    if (sp[si].u1 >= b) break;
  }
  return total;
}

}  // namespace geotest
