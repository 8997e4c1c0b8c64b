// SPDX-License-Identifier: Apache-2.0
// Comparison of Curve::eval against the Cox-de Boor reference and Eigen's Splines module, shared by
// power_basis_test.cpp and bench_power_soak.cpp.
#pragma once
#include <functional>
#include <memory>
#include <unsupported/Eigen/Splines>

#include "geometry/curve.hpp"
#include "test_util.hpp"

namespace powercmp {

template <int D>
std::function<Eigen::MatrixXd(double, int)> eigen_spline_fixed(const geotest::RandomSpline& rs) {
  using S = Eigen::Spline<double, D>;
  typename S::KnotVectorType kn(static_cast<Eigen::Index>(rs.ref.U.size()));
  for (size_t i = 0; i < rs.ref.U.size(); ++i) kn(static_cast<Eigen::Index>(i)) = rs.ref.U[i];
  typename S::ControlPointVectorType cp(D, rs.lib.n_ctrl());
  for (int i = 0; i < rs.lib.n_ctrl(); ++i)
    for (int d = 0; d < D; ++d) cp(d, i) = rs.ref.P[i][d];
  auto sp = std::make_shared<S>(kn, cp);
  return [sp](double u, int k) { return Eigen::MatrixXd(sp->derivatives(u, k).matrix()); };
}

inline std::function<Eigen::MatrixXd(double, int)> eigen_spline(const geotest::RandomSpline& rs, int dim) {
  switch (dim) {
    case 1: return eigen_spline_fixed<1>(rs);
    case 2: return eigen_spline_fixed<2>(rs);
    case 3: return eigen_spline_fixed<3>(rs);
    default: return eigen_spline_fixed<4>(rs);
  }
}

struct ErrStats {
  double max_rel[4] = {0, 0, 0, 0};
};

// Compare Curve::eval with the Cox-de Boor reference (and Eigen's spline when non-rational) at
// `points` random parameters of one spline. Returns the max relative errors per derivative order.
// max_degree: passed to Curve (0 = the library's caps; larger only to measure beyond them).
inline void compare_one(const geotest::RandomSpline& rs, int points, std::mt19937_64& rng, ErrStats& e, bool use_eigen,
                        int max_degree = 0) {
  const traj::geo::Curve c(rs.lib, "curve", max_degree);
  const int dim = rs.lib.dim(), p = rs.lib.degree;
  const int nd = std::min(3, 3);
  std::vector<double> scale;
  if (rs.lib.rational()) {
    scale.assign(4, 0.0);
  } else {
    scale = geotest::derivative_scales(rs.ref, 3);
  }
  // Eigen's Spline needs a fixed dimension (Dim = Dynamic does not work in Eigen 3.4).
  std::function<Eigen::MatrixXd(double, int)> es;
  if (use_eigen) es = eigen_spline(rs, dim);
  std::uniform_real_distribution<double> U(c.u_begin(), c.u_end());
  std::vector<std::vector<std::vector<double>>> refs;
  std::vector<Eigen::MatrixXd> mine;
  std::vector<double> us;
  for (int t = 0; t < points; ++t) {
    const double u = U(rng);
    us.push_back(u);
    refs.push_back(ref::cox_de_boor_derivs<long double>(rs.ref, u, nd));  // 64-bit mantissa reference
    mine.push_back(c.eval(u, nd));
  }
  if (rs.lib.rational()) {
    // Position: the bounding-box diagonal of the control points (positive weights: the curve lies in
    // their convex hull). Derivatives: a NURBS has no hodograph hull, so max |C^(k)| over the samples.
    scale[0] = geotest::derivative_scales(rs.ref, 0)[0];
    for (auto& r : refs)
      for (int k = 1; k <= nd; ++k) {
        double n2 = 0;
        for (int d = 0; d < dim; ++d) n2 += r[k][d] * r[k][d];
        scale[k] = std::max(scale[k], std::sqrt(n2));
      }
    for (auto& s : scale) s = std::max(s, 1e-300);
  }
  for (size_t t = 0; t < us.size(); ++t) {
    for (int k = 0; k <= nd; ++k) {
      double err = 0, erre = 0, erx = 0;
      Eigen::MatrixXd ed;
      if (use_eigen && k <= p) ed = es(us[t], k);
      for (int d = 0; d < dim; ++d) {
        err = std::max(err, std::abs(mine[t](d, k) - refs[t][k][d]));
        if (use_eigen) erre = std::max(erre, std::abs(mine[t](d, k) - (k <= p ? ed(d, k) : 0.0)));
        if (use_eigen) erx = std::max(erx, std::abs(refs[t][k][d] - (k <= p ? ed(d, k) : 0.0)));
      }
      e.max_rel[k] = std::max({e.max_rel[k], err / scale[k], erre / scale[k]});
      if (getenv("GEO_DEBUG") && std::max(err, erre) / scale[k] > 1e-12)
        std::printf("k=%d p=%d err_ref=%.3g err_eigen=%.3g ref_vs_eigen=%.3g scale=%.3g\n", k, p, err / scale[k],
                    erre / scale[k], erx / scale[k], scale[k]);
    }
  }
}

}  // namespace powercmp
