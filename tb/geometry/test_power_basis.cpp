// Power-basis form (seed 003) against two independent evaluators: the textbook Cox-de Boor
// recursion (ref_deboor.hpp) and Eigen's Splines module; derivatives 0..3, every degree 1..7,
// 1..4 axes, random non-uniform knots with repeated knots, rational and non-rational.
//
// Tolerance (error analysis): the conversion Bezier -> power basis multiplies control points by
// binomial sums of size <= sum_j C(p,j) 2^j = 3^p (2187 for p = 7); Horner adds ~2p roundings of terms
// bounded by that. The error is therefore <= ~3^p * 4p * eps * bbox ~ 1e-11 * bbox for p = 7 in the
// worst case, typically 1e-14. The requirement is 1e-12 relative to the bounding box (of the
// k-th derivative's control points for derivative k); the tests check exactly that.
#include <gtest/gtest.h>


#include "geometry/curve.hpp"
#include "geometry/error.hpp"
#include "power_compare.hpp"
#include "test_util.hpp"

using traj::geo::BSpline;
using traj::geo::Curve;

using powercmp::ErrStats;
using powercmp::compare_one;

class GeometryPowerBasis : public ::testing::TestWithParam<int> {};

TEST_P(GeometryPowerBasis, MatchesCoxDeBoorAndEigenSplines) {
  const int p = GetParam();
  std::mt19937_64 rng(geotest::seed() + 1000u * p);
  ErrStats e;
  int points = 0;
  for (int rep = 0; rep < 24; ++rep) {
    const int dim = 1 + rep % 4;
    const int n = p + 1 + static_cast<int>(rng() % 12);
    const auto rs = geotest::random_spline(rng, p, dim, n, false);
    compare_one(rs, 400, rng, e, true);
    points += 400;
  }
  for (int k = 0; k <= 3; ++k) {
    RecordProperty("max_rel_err_d" + std::to_string(k), std::to_string(e.max_rel[k]));
    EXPECT_LE(e.max_rel[k], 1e-12) << "degree " << p << " derivative " << k << " over " << points << " points";
  }
  std::printf("degree %d: %d points, max rel err d0..d3 = %.2e %.2e %.2e %.2e\n", p, points, e.max_rel[0],
              e.max_rel[1], e.max_rel[2], e.max_rel[3]);
}

TEST_P(GeometryPowerBasis, RationalMatchesCoxDeBoorQuotient) {
  const int p = GetParam();
  std::mt19937_64 rng(geotest::seed() + 7000u * p);
  ErrStats e;
  for (int rep = 0; rep < 16; ++rep) {
    const auto rs = geotest::random_spline(rng, p, 1 + rep % 4, p + 1 + static_cast<int>(rng() % 10), true);
    compare_one(rs, 300, rng, e, false);
  }
  for (int k = 0; k <= 3; ++k) EXPECT_LE(e.max_rel[k], 1e-12) << "degree " << p << " derivative " << k;
}

TEST_P(GeometryPowerBasis, UnclampedConvertedByKnotInsertion) {
  const int p = GetParam();
  std::mt19937_64 rng(geotest::seed() + 13000u * p);
  ErrStats e;
  for (int rep = 0; rep < 12; ++rep) {
    const auto rs = geotest::random_spline(rng, p, 1 + rep % 3, p + 2 + static_cast<int>(rng() % 8), rep % 2 == 1, false);
    const Curve c(rs.lib);
    EXPECT_TRUE(c.spline().clamped());
    EXPECT_DOUBLE_EQ(c.u_begin(), rs.lib.u_begin());
    EXPECT_DOUBLE_EQ(c.u_end(), rs.lib.u_end());
    compare_one(rs, 200, rng, e, false);
  }
  for (int k = 0; k <= 3; ++k) EXPECT_LE(e.max_rel[k], 1e-12) << "degree " << p << " derivative " << k;
}

INSTANTIATE_TEST_SUITE_P(Degrees, GeometryPowerBasis, ::testing::Range(1, 8));

// Bezier curve of any degree: Bernstein form evaluated directly (de Casteljau), derivatives by
// differencing the control points (hodograph), both written here.
TEST(GeometryBezier, MatchesDeCasteljauAndHodograph) {
  std::mt19937_64 rng(geotest::seed() + 5);
  std::uniform_real_distribution<double> U(-10, 10), T(0, 1);
  for (int p = 1; p <= 7; ++p) {
    Eigen::MatrixXd P(p + 1, 3);
    for (int i = 0; i <= p; ++i)
      for (int d = 0; d < 3; ++d) P(i, d) = U(rng);
    const Curve c(traj::geo::make_bezier(P));
    auto casteljau = [](Eigen::MatrixXd Q, double t) {
      for (int r = 1; r < Q.rows(); ++r)
        for (int i = 0; i + r < Q.rows(); ++i) Q.row(i) = (1 - t) * Q.row(i) + t * Q.row(i + 1);
      return Eigen::VectorXd(Q.row(0).transpose());
    };
    for (int s = 0; s < 200; ++s) {
      const double t = T(rng);
      const Eigen::MatrixXd m = c.eval(t, 3);
      Eigen::MatrixXd Q = P;
      double fac = 1;
      for (int k = 0; k <= 3; ++k) {
        if (Q.rows() == 0) {
          EXPECT_LT(m.col(k).norm(), 1e-12);
          continue;
        }
        const Eigen::VectorXd r = fac * casteljau(Q, t);
        EXPECT_LT((m.col(k) - r).norm(), 1e-12 * std::max(1.0, r.norm()) * 20) << "p=" << p << " k=" << k;
        // next hodograph
        if (Q.rows() > 1) {
          fac *= (Q.rows() - 1);
          Q = (Q.bottomRows(Q.rows() - 1) - Q.topRows(Q.rows() - 1)).eval();
        } else {
          Q.resize(0, 3);
        }
      }
    }
  }
}

// Knot insertion (Boehm) leaves the curve unchanged: compare before/after with the reference.
TEST(GeometryKnotInsertion, CurveUnchanged) {
  std::mt19937_64 rng(geotest::seed() + 9);
  for (int p = 1; p <= 7; ++p) {
    auto rs = geotest::random_spline(rng, p, 2, p + 5, p % 2 == 0);
    const double u = 0.5 * (rs.lib.u_begin() + rs.lib.u_end()) + 1e-3;
    const BSpline ins = traj::geo::insert_knot(rs.lib, u, 1);
    ref::Spline r2;
    r2.p = p;
    r2.U.assign(ins.knots.data(), ins.knots.data() + ins.knots.size());
    for (int i = 0; i < ins.n_ctrl(); ++i) r2.P.push_back({ins.ctrl(i, 0), ins.ctrl(i, 1)});
    if (ins.rational()) r2.W.assign(ins.weights.data(), ins.weights.data() + ins.n_ctrl());
    for (int s = 0; s <= 50; ++s) {
      const double t = rs.lib.u_begin() + (rs.lib.u_end() - rs.lib.u_begin()) * s / 50.0;
      const auto a = ref::cox_de_boor_derivs(rs.ref, t, 0), b = ref::cox_de_boor_derivs(r2, t, 0);
      for (int d = 0; d < 2; ++d) EXPECT_NEAR(a[0][d], b[0][d], 1e-11 * 300);
    }
  }
}

// Lines and circular arcs as curves: the arc is an exact rational quadratic NURBS, so every point is
// at distance r from the centre, the tangent is perpendicular to the radius and kappa = 1/r.
TEST(GeometryPrimitives, LineAndExactArc) {
  const Curve line(traj::geo::make_line(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(4, 6, 3)));
  for (double u : {0.0, 0.3, 1.0}) {
    const Eigen::MatrixXd m = line.eval(u, 3);
    EXPECT_NEAR((m.col(0) - Eigen::Vector3d(1 + 3 * u, 2 + 4 * u, 3)).norm(), 0, 1e-14);
    EXPECT_NEAR((m.col(1) - Eigen::Vector3d(3, 4, 0)).norm(), 0, 1e-14);
    EXPECT_EQ(m.col(2).norm(), 0);
  }
  for (double sweep : {0.3, M_PI / 2, 2.0, M_PI, 1.5 * M_PI, 2 * M_PI, -2.5}) {
    const Eigen::Vector2d ctr(3, -1);
    const double r = 7.5;
    const Curve arc(traj::geo::make_arc(ctr, r, 0.4, 0.4 + sweep));
    EXPECT_NEAR((arc.point(0) - (ctr + r * Eigen::Vector2d(std::cos(0.4), std::sin(0.4)))).norm(), 0, 1e-13);
    EXPECT_NEAR((arc.point(1) - (ctr + r * Eigen::Vector2d(std::cos(0.4 + sweep), std::sin(0.4 + sweep)))).norm(), 0, 1e-13);
    for (int s = 0; s <= 100; ++s) {
      const double u = s / 100.0;
      const Eigen::MatrixXd m = arc.eval(u, 2);
      const Eigen::Vector2d rad = m.col(0) - ctr, d1 = m.col(1), d2 = m.col(2);
      EXPECT_NEAR(rad.norm(), r, 1e-12 * r);
      EXPECT_NEAR(rad.dot(d1) / (r * d1.norm()), 0, 1e-12);
      const double kappa = std::abs(d1.x() * d2.y() - d1.y() * d2.x()) / std::pow(d1.norm(), 3);
      EXPECT_NEAR(kappa, 1 / r, 1e-11 / r);
    }
  }
}

// Seed 004: "for a circle cascaded from 3 segments of 120 degrees each, the peripheral standard deviation
// of the graph compared to a circle based on sin/cos is in the order of 1e-3", and the speed in the
// middle of a segment is "about 88%" of the end speed. Checked here against the exact circle: the
// radial error of the k = 4/3 tan(30 deg) construction is 1.5e-3 r, and the speed ratio is exactly 7/8.
TEST(GeometryBezier, Seed004BezierCircleClaims) {
  const Curve c(traj::geo::make_bezier_circle(Eigen::Vector2d(0, 0), 1.0, 3));
  double rmax = 0, vmin = 1e300, vmax = 0;
  for (int s = 0; s <= 30000; ++s) {
    const Eigen::MatrixXd m = c.eval(s / 30000.0, 1);
    rmax = std::max(rmax, std::abs(m.col(0).norm() - 1));
    vmin = std::min(vmin, m.col(1).norm());
    vmax = std::max(vmax, m.col(1).norm());
  }
  EXPECT_GT(rmax, 1e-3);
  EXPECT_LT(rmax, 2e-3);
  EXPECT_NEAR(vmin / vmax, 0.875, 1e-6);  // "about 88%"
}
