// SPDX-License-Identifier: Apache-2.0
// Shared helpers for the geometry tests: random splines (built once, handed both to the library and
// to the independent reference), the asset path, and the test seed.
#pragma once
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdlib>
#include <random>
#include <string>

#include "geometry/bspline.hpp"
#include "ref_deboor.hpp"
#include "test_seed.hpp"

namespace geotest {

inline std::string asset(const std::string& name) { return std::string(GEO_ASSETS_DIR) + "/" + name; }

// The random seed (tb/common/test_seed.hpp): TRAJ_SEED or a fixed default.
inline unsigned seed() { return static_cast<unsigned>(traj::test::test_seed(20240604u)); }

struct RandomSpline {
  traj::geo::BSpline lib;
  ref::Spline ref;
};

// Random clamped (or unclamped) spline: degree p, dim axes, n control points in [-50, 50]^dim (plus a
// random offset), random non-uniform interior knots on a random domain, some knots repeated (up to
// multiplicity p), optional random weights in [0.2, 5].
inline RandomSpline random_spline(std::mt19937_64& rng, int p, int dim, int n, bool rational, bool clamped = true) {
  std::uniform_real_distribution<double> U01(0.0, 1.0);
  RandomSpline r;
  auto& c = r.lib;
  c.degree = p;
  c.ctrl.resize(n, dim);
  const double off = 200 * (U01(rng) - 0.5);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < dim; ++d) c.ctrl(i, d) = off + 100 * (U01(rng) - 0.5);
  if (rational) {
    c.weights.resize(n);
    for (int i = 0; i < n; ++i) c.weights[i] = 0.2 * std::pow(25.0, U01(rng));
  }
  const int m = n + p + 1;
  c.knots.resize(m);
  const double a = 4 * (U01(rng) - 0.5), b = a + 0.5 + 3 * U01(rng);
  if (clamped) {
    std::vector<double> in;
    while (static_cast<int>(in.size()) < n - p - 1) {
      const double t = a + (b - a) * (0.02 + 0.96 * U01(rng));
      const int mult = std::min<int>(n - p - 1 - static_cast<int>(in.size()), U01(rng) < 0.15 ? 1 + static_cast<int>(U01(rng) * p) : 1);
      for (int k = 0; k < mult; ++k) in.push_back(t);
    }
    std::sort(in.begin(), in.end());
    for (int i = 0; i <= p; ++i) {
      c.knots[i] = a;
      c.knots[m - 1 - i] = b;
    }
    for (int i = 0; i < n - p - 1; ++i) c.knots[p + 1 + i] = in[i];
  } else {
    std::vector<double> all(m);
    for (auto& t : all) t = a + (b - a) * U01(rng);
    std::sort(all.begin(), all.end());
    all.front() = a;
    all.back() = b;
    for (int i = 0; i < m; ++i) c.knots[i] = all[i];
  }
  r.ref.p = p;
  r.ref.U.assign(c.knots.data(), c.knots.data() + m);
  r.ref.P.assign(n, std::vector<double>(dim));
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < dim; ++d) r.ref.P[i][d] = c.ctrl(i, d);
  if (rational) r.ref.W.assign(c.weights.data(), c.weights.data() + n);
  return r;
}

// Scale of the k-th derivative for relative errors: the bounding-box diagonal of the control points of
// the k-th hodograph (they bound C^(k) by the convex hull),
// Q^(k)_i = (p-k+1) (Q^(k-1)_{i+1} - Q^(k-1)_i) / (t_{i+p+1} - t_{i+k}) (non-rational).
// One exception, where a scale of the diagonal alone fails:
// when the k-th hodograph's control points all coincide (diagonal 0: derivative k = p of a single-span
// spline, a constant vector Q), the bounding box is a point and an error relative to it is undefined;
// both evaluators round that constant by ~eps |Q| (1e-14 absolute was seen, relative to 1e-300 that is
// 1e286). There the scale is |Q|, the constant's own magnitude.
inline std::vector<double> derivative_scales(const ref::Spline& s, int kmax) {
  std::vector<double> out;
  std::vector<std::vector<double>> Q = s.P;
  const int dim = s.dim();
  for (int k = 0; k <= kmax; ++k) {
    if (k > 0) {
      std::vector<std::vector<double>> R;
      for (size_t i = 0; i + 1 < Q.size(); ++i) {
        const double den = s.U[i + s.p + 1] - s.U[i + k];
        std::vector<double> q(dim, 0.0);
        if (den > 0)
          for (int d = 0; d < dim; ++d) q[d] = (s.p - k + 1) * (Q[i + 1][d] - Q[i][d]) / den;
        R.push_back(q);
      }
      Q.swap(R);
    }
    double diag2 = 0, maxnorm = 0;
    for (auto& q : Q) {
      double n2 = 0;
      for (int d = 0; d < dim; ++d) n2 += q[d] * q[d];
      maxnorm = std::max(maxnorm, std::sqrt(n2));
    }
    for (int d = 0; d < dim; ++d) {
      double lo = 1e300, hi = -1e300;
      for (auto& q : Q) {
        lo = std::min(lo, q[d]);
        hi = std::max(hi, q[d]);
      }
      if (!Q.empty()) diag2 += (hi - lo) * (hi - lo);
    }
    const double diag = std::sqrt(diag2);
    out.push_back(Q.empty() ? 1.0 : diag > 0 ? diag : std::max(maxnorm, 1e-300));
  }
  return out;
}

}  // namespace geotest
