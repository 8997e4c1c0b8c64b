// SPDX-License-Identifier: Apache-2.0
// Independent checks of the core's output samples for the planner tests: the
// limits as the samples show them, and the distance of every sample to the
// path. Written apart from the planner's own report (report/report.cpp) and fit
// checks (segments.cpp, sampled.hpp), from the definitions in host/planner/README.md:
//   per axis: v, a, j = first, second, third difference over h, h^2, h^3;
//   path speed = chord / h; tangential a, j = first, second difference of the
//   chord speed; centripetal a = the part of the second difference normal to
//   the central chord x_{k+2} - x_k; centripetal jerk = the part of the third
//   difference normal to the middle chord x_{k+2} - x_{k+1}.
// Each sample may differ from the fitted polynomial by q (units, per axis);
// the differences then by 2q/h, 4q/h^2, 8q/h^3 per axis, sqrt(dim) times that
// for path quantities: the stated quantisation allowance.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "planner/planner.hpp"

namespace traj::test {

struct OutputVerdict {
  double worst = 0;  // largest (value - allowance) / limit
  std::string what;
  long long tick = -1;
};

inline OutputVerdict check_output_limits(const std::vector<std::array<double, 3>>& x, int dim,
                                         const plan::Limits& L, double h, double q, bool jerk) {
  OutputVerdict v;
  auto note = [&](double value, double allow, double lim, const char* what, size_t k) {
    const double r = (value - allow) / lim;
    if (r > v.worst) {
      v.worst = r;
      v.what = what;
      v.tick = static_cast<long long>(k);
    }
  };
  const double sd = std::sqrt(static_cast<double>(dim));
  const double av = 2 * q / h, aa = 4 * q / (h * h), aj = 8 * q / (h * h * h);
  auto sub = [&](size_t i, size_t j, int a) { return x[i][a] - x[j][a]; };
  auto len = [&](size_t i, size_t j) {
    double s = 0;
    for (int a = 0; a < dim; ++a) s += sub(i, j, a) * sub(i, j, a);
    return std::sqrt(s);
  };
  const size_t n = x.size();
  const char* names_v[3] = {"v_axis.x", "v_axis.y", "v_axis.z"};
  const char* names_a[3] = {"a_axis.x", "a_axis.y", "a_axis.z"};
  const char* names_j[3] = {"j_axis.x", "j_axis.y", "j_axis.z"};
  for (size_t k = 0; k + 1 < n; ++k) {
    for (int a = 0; a < dim; ++a) {
      note(std::fabs(sub(k + 1, k, a)) / h, av, L.v_axis[a], names_v[a], k);
      if (k + 2 < n)
        note(std::fabs(x[k + 2][a] - 2 * x[k + 1][a] + x[k][a]) / (h * h), aa, L.a_axis[a], names_a[a], k);
      if (jerk && k + 3 < n)
        note(std::fabs(x[k + 3][a] - 3 * x[k + 2][a] + 3 * x[k + 1][a] - x[k][a]) / (h * h * h), aj, L.j_axis[a],
             names_j[a], k);
    }
    note(len(k + 1, k) / h, sd * av, L.feed, "feed", k);
    if (k + 2 < n) {
      const double s0 = len(k + 1, k) / h, s1 = len(k + 2, k + 1) / h;
      note(std::fabs(s1 - s0) / h, sd * aa, L.a_tan, "a_tan", k);
      const double c = len(k + 2, k);
      if (c > 1e-9) {
        double A2 = 0, AT = 0;
        for (int a = 0; a < dim; ++a) {
          const double Aa = (x[k + 2][a] - 2 * x[k + 1][a] + x[k][a]) / (h * h);
          A2 += Aa * Aa;
          AT += Aa * sub(k + 2, k, a) / c;
        }
        note(std::sqrt(std::max(0.0, A2 - AT * AT)), sd * aa, L.a_cen, "a_cen", k);
      }
      if (jerk && k + 3 < n) {
        const double s2 = len(k + 3, k + 2) / h;
        note(std::fabs(s2 - 2 * s1 + s0) / (h * h), sd * aj, L.j_tan, "j_tan", k);
        const double m = len(k + 2, k + 1);
        if (m > 1e-9) {
          double J2 = 0, JT = 0;
          for (int a = 0; a < dim; ++a) {
            const double Ja = (x[k + 3][a] - 3 * x[k + 2][a] + 3 * x[k + 1][a] - x[k][a]) / (h * h * h);
            J2 += Ja * Ja;
            JT += Ja * sub(k + 2, k + 1, a) / m;
          }
          note(std::sqrt(std::max(0.0, J2 - JT * JT)), sd * aj, L.j_cen, "j_cen", k);
        }
      }
    }
  }
  return v;
}

// Squared distance from x to c(u).
inline double dist2_at(const geo::Curve& c, const double* x, double u) {
  double q[3];
  c.eval(u, 0, q);
  double e2 = 0;
  for (int a = 0; a < c.dim(); ++a) e2 += (q[a] - x[a]) * (q[a] - x[a]);
  return e2;
}

// Distance from x to curve c, from above, searching near u_guess: a scan of
// the span holding u_guess and its neighbours (256 parameters each), then a
// golden-section search between the nearest scan point's neighbours.
inline double distance_to_curve_near(const geo::Curve& c, const double* x, double u_guess) {
  const int sp = c.find_span(u_guess), ns = static_cast<int>(c.spans().size());
  const double ua = c.spans()[std::max(0, sp - 1)].u0, ub = c.spans()[std::min(ns - 1, sp + 1)].u1;
  const int n = 768;
  double bd = dist2_at(c, x, u_guess);
  int bi = -1;
  for (int i = 0; i <= n; ++i) {
    const double e2 = dist2_at(c, x, ua + (ub - ua) * i / n);
    if (e2 < bd) {
      bd = e2;
      bi = i;
    }
  }
  double lo, hi;
  if (bi < 0) {
    lo = std::max(ua, u_guess - (ub - ua) / n);
    hi = std::min(ub, u_guess + (ub - ua) / n);
  } else {
    lo = ua + (ub - ua) * std::max(0, bi - 1) / n;
    hi = ua + (ub - ua) * std::min(n, bi + 1) / n;
  }
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo), f1 = dist2_at(c, x, m1), f2 = dist2_at(c, x, m2);
  for (int it = 0; it < 120 && hi - lo > 1e-15 * (1 + std::fabs(lo)); ++it) {
    if (f1 < f2) {
      hi = m2;
      m2 = m1;
      f2 = f1;
      m1 = hi - g * (hi - lo);
      f1 = dist2_at(c, x, m1);
    } else {
      lo = m1;
      m1 = m2;
      f1 = f2;
      m2 = lo + g * (hi - lo);
      f2 = dist2_at(c, x, m2);
    }
  }
  return std::sqrt(std::min({bd, f1, f2}));
}

// Distance from x to the path, from above: for curves hint-1 .. hint+2, a
// scan at 64 parameters per span, then distance_to_curve_near from the
// nearest. It is the distance to a point of the path (an upper bound of the
// distance to the path: enough to show a tolerance holds); `hint` follows the
// nearest curve (samples come in path order).
inline double distance_to_path(const plan::Path& p, const double* x, size_t& hint) {
  double best = 1e300;
  const size_t c0 = hint > 0 ? hint - 1 : 0, c1 = std::min(p.size(), hint + 3);
  for (size_t ci = c0; ci < c1; ++ci) {
    const geo::Curve& c = p.curve(ci);
    double bu = c.u_begin(), bd = 1e300;
    const int n = 64 * static_cast<int>(c.spans().size());
    for (int i = 0; i <= n; ++i) {
      const double u = c.u_begin() + (c.u_end() - c.u_begin()) * i / n;
      const double e2 = dist2_at(c, x, u);
      if (e2 < bd) {
        bd = e2;
        bu = u;
      }
    }
    const double dist = distance_to_curve_near(c, x, bu);
    if (dist < best) {
      best = dist;
      hint = ci;
    }
  }
  return best;
}

}  // namespace traj::test
