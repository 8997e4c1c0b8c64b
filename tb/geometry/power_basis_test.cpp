// SPDX-License-Identifier: Apache-2.0
// Power-basis form ([NURBS]) against two independent evaluators: the textbook Cox-de Boor
// recursion (ref_deboor.hpp, in long double) and Eigen's Splines module; derivatives 0..3, every
// accepted degree (non-rational 1..kMaxDegree = 15, rational 1..kMaxDegreeRational = 7), 1..4 axes,
// random non-uniform knots with repeated knots.
//
// Tolerance: the accuracy target, 1e-12 relative to the bounding-box diagonal of the k-th
// hodograph's control points (test_util.hpp: derivative_scales; NURBS derivatives: max |C^(k)|).
// Error analysis: each power coefficient is rounded once (the conversion runs in long double) and
// Horner adds ~2 roundings per term; the terms |a_j| (h/2)^j of the expansion about the span midpoint
// can exceed the box by a factor that grows about 2x per degree (an ill-conditioned basis), so the
// error is ~eps * 2^q: measured ~1e-15 at degree 7, <= 1e-13 at 15, 2.3e-12 at 19 and 2.7e-12 at 20
// (bench_power_soak, --beyond, two seeds), hence the cap at 15.
#include <gtest/gtest.h>


#include "geometry/bspline.hpp"
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

class GeometryPowerBasisRational : public ::testing::TestWithParam<int> {};

TEST_P(GeometryPowerBasisRational, RationalMatchesCoxDeBoorQuotient) {
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
    const bool rational = rep % 2 == 1 && p <= traj::geo::kMaxDegreeRational;
    const auto rs = geotest::random_spline(rng, p, 1 + rep % 3, p + 2 + static_cast<int>(rng() % 8), rational, false);
    const Curve c(rs.lib);
    EXPECT_TRUE(c.spline().clamped());
    EXPECT_DOUBLE_EQ(c.u_begin(), rs.lib.u_begin());
    EXPECT_DOUBLE_EQ(c.u_end(), rs.lib.u_end());
    compare_one(rs, 200, rng, e, false);
  }
  for (int k = 0; k <= 3; ++k) EXPECT_LE(e.max_rel[k], 1e-12) << "degree " << p << " derivative " << k;
}

INSTANTIATE_TEST_SUITE_P(Degrees, GeometryPowerBasis, ::testing::Range(1, traj::geo::kMaxDegree + 1));
INSTANTIATE_TEST_SUITE_P(Degrees, GeometryPowerBasisRational, ::testing::Range(1, traj::geo::kMaxDegreeRational + 1));

// Beyond the caps: one clear error naming the field.
TEST(GeometryPowerBasis, DegreeCaps) {
  std::mt19937_64 rng(geotest::seed() + 21);
  auto msg = [](const BSpline& b) -> std::string {
    try {
      (void)Curve(b, "cap.json");
    } catch (const traj::geo::GeometryError& e) {
      return e.what();
    }
    return "";
  };
  const auto ok = geotest::random_spline(rng, traj::geo::kMaxDegree, 2, traj::geo::kMaxDegree + 3, false);
  EXPECT_EQ(msg(ok.lib), "");
  const auto hi = geotest::random_spline(rng, traj::geo::kMaxDegree + 1, 2, traj::geo::kMaxDegree + 3, false);
  EXPECT_EQ(msg(hi.lib).rfind("cap.json: degree: 16 out of range 1..15 (", 0), 0u) << msg(hi.lib);
  const auto rat = geotest::random_spline(rng, traj::geo::kMaxDegreeRational + 1, 2, 12, true);
  EXPECT_EQ(msg(rat.lib).rfind("cap.json: degree: 8 out of range 1..7 for a rational curve", 0), 0u) << msg(rat.lib);
  const auto rat7 = geotest::random_spline(rng, traj::geo::kMaxDegreeRational, 2, 12, true);
  EXPECT_EQ(msg(rat7.lib), "");
}

// Bezier curves of every accepted degree (1..15): Bernstein form evaluated directly (de Casteljau in
// long double), derivative k from the k-th hodograph p!/(p-k)! Delta^k P, both written here. Error
// relative to the bounding-box diagonal of the k-th hodograph's control points (a one-point hodograph:
// its magnitude), limit 1e-12 (the accuracy target).
TEST(GeometryBezier, MatchesDeCasteljauAndHodograph) {
  std::mt19937_64 rng(geotest::seed() + 5);
  std::uniform_real_distribution<double> U(-10, 10), T(0, 1);
  using LD = long double;
  for (int p = 1; p <= traj::geo::kMaxDegree; ++p) {
    double worst = 0;
    for (int rep = 0; rep < 20; ++rep) {
      Eigen::MatrixXd P(p + 1, 3);
      for (int i = 0; i <= p; ++i)
        for (int d = 0; d < 3; ++d) P(i, d) = U(rng) + (rep % 2 ? 40.0 : 0.0);  // some far from the origin
      const Curve c(traj::geo::make_bezier(P));
      // Hodographs in long double: Q_k = p!/(p-k)! Delta^k P (rows), and their scales.
      std::vector<std::vector<std::vector<LD>>> Q(4);
      std::vector<double> scale(4, 0.0);
      for (int i = 0; i <= p; ++i) Q[0].push_back({P(i, 0), P(i, 1), P(i, 2)});
      for (int k = 1; k <= 3; ++k)
        for (size_t i = 0; i + 1 < Q[k - 1].size(); ++i) {
          std::vector<LD> q(3);
          for (int d = 0; d < 3; ++d) q[d] = (p - k + 1) * (Q[k - 1][i + 1][d] - Q[k - 1][i][d]);
          Q[k].push_back(q);
        }
      for (int k = 0; k <= 3; ++k) {
        LD diag2 = 0, maxn = 0;
        for (int d = 0; d < 3; ++d) {
          LD lo = 1e300L, hi = -1e300L;
          for (auto& q : Q[k]) lo = std::min(lo, q[d]), hi = std::max(hi, q[d]);
          if (!Q[k].empty()) diag2 += (hi - lo) * (hi - lo);
        }
        for (auto& q : Q[k]) maxn = std::max(maxn, std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]));
        scale[k] = static_cast<double>(diag2 > 0 ? std::sqrt(diag2) : std::max(maxn, 1e-300L));
      }
      for (int s = 0; s < 50; ++s) {
        const double t = T(rng);
        const Eigen::MatrixXd m = c.eval(t, 3);
        for (int k = 0; k <= 3; ++k) {
          std::vector<std::vector<LD>> B = Q[k];
          for (size_t r = 1; r < B.size(); ++r)
            for (size_t i = 0; i + r < B.size(); ++i)
              for (int d = 0; d < 3; ++d) B[i][d] = (1 - LD(t)) * B[i][d] + LD(t) * B[i + 1][d];
          double err = 0;
          for (int d = 0; d < 3; ++d) err = std::max(err, static_cast<double>(std::fabs(m(d, k) - (B.empty() ? 0 : B[0][d]))));
          if (B.empty()) {
            EXPECT_EQ(err, 0) << "p=" << p << " k=" << k;
            continue;
          }
          worst = std::max(worst, err / scale[k]);
          EXPECT_LE(err, 1e-12 * scale[k]) << "p=" << p << " k=" << k << " t=" << t;
        }
      }
    }
    std::printf("Bezier degree %2d: worst error / hodograph box = %.2e\n", p, worst);
  }
}

// Knot insertion (Boehm) leaves the curve unchanged: compare before/after with the reference.
TEST(GeometryKnotInsertion, CurveUnchanged) {
  std::mt19937_64 rng(geotest::seed() + 9);
  for (int p = 1; p <= traj::geo::kMaxDegree; ++p) {
    auto rs = geotest::random_spline(rng, p, 2, p + 5, p % 2 == 0 && p <= traj::geo::kMaxDegreeRational);
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

// [ARC]: "for a circle cascaded from 3 segments of 120 degrees each, the peripheral standard deviation
// of the graph compared to a circle based on sin/cos is in the order of 1e-3", and the speed in the
// middle of a segment is "about 88%" of the end speed. Checked here against the exact circle: the
// radial error of the k = 4/3 tan(30 deg) construction is 1.5e-3 r, and the speed ratio is exactly 7/8.
TEST(GeometryBezier, ArcPaperBezierCircleClaims) {
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

// split_at: the two halves trace the original curve. Reference: the textbook Cox-de Boor recursion
// (ref_deboor.hpp, long double) on the original control points, at parameters on both sides of the
// cut; also at a cut on an existing knot; the halves meet at the cut and keep the ends.
TEST(GeometrySplit, HalvesTraceTheOriginal) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U01(0.0, 1.0);
  for (int rep = 0; rep < 300; ++rep) {
    const int p = 1 + rep % 5, dim = 1 + rep % 3, n = p + 1 + static_cast<int>(U01(rng) * 6);
    const bool rational = rep % 2 == 1;
    const auto rs = geotest::random_spline(rng, p, dim, n, rational);
    const BSpline& c = rs.lib;
    const double a = c.u_begin(), b = c.u_end();
    // a random cut, or an interior knot when there is one
    double u = a + (b - a) * (0.05 + 0.9 * U01(rng));
    if (rep % 3 == 0)
      for (int i = p + 1; i < c.n_ctrl(); ++i)
        if (c.knots[i] > a && c.knots[i] < b) u = c.knots[i];
    const auto halves = traj::geo::split_at(c, u);
    ASSERT_EQ(halves.first.u_begin(), a);
    ASSERT_EQ(halves.first.u_end(), u);
    ASSERT_EQ(halves.second.u_begin(), u);
    ASSERT_EQ(halves.second.u_end(), b);
    const Curve left(halves.first), right(halves.second);
    double scale = 0;
    for (int i = 0; i < c.n_ctrl(); ++i) scale = std::max(scale, c.ctrl.row(i).cwiseAbs().maxCoeff());
    for (int k = 0; k <= 40; ++k) {
      const double t = a + (b - a) * k / 40.0;
      const auto ref = ref::cox_de_boor_derivs<long double>(rs.ref, t, 0);
      const Eigen::VectorXd x = t <= u ? left.point(t) : right.point(t);
      for (int d = 0; d < dim; ++d)
        ASSERT_NEAR(x[d], ref[0][d], 1e-11 * scale) << "rep " << rep << " p " << p << " t " << t << " cut " << u;
    }
    const Eigen::VectorXd l1 = left.point(u), r0 = right.point(u);
    for (int d = 0; d < dim; ++d) EXPECT_NEAR(l1[d], r0[d], 1e-12 * scale);
  }
  // out of the domain: refused
  const auto rs = geotest::random_spline(rng, 3, 2, 6, false);
  EXPECT_THROW(traj::geo::split_at(rs.lib, rs.lib.u_begin()), traj::geo::GeometryError);
  EXPECT_THROW(traj::geo::split_at(rs.lib, rs.lib.u_end() + 1), traj::geo::GeometryError);
}

// Coincident control points (a retracted Bezier handle, P0 = P1 or P2 = P3)
// stay exactly coincident in both halves: a split that moved one by an ulp
// gave the curve an end speed of 1e-16 instead of 0 (a cusp the planner
// treats as one), which planned as 1e13 s (tb/job, RetractedHandle...).
TEST(GeometrySplit, CoincidentControlPointsStayExact) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(-30.0, 30.0), U01(0.01, 0.99);
  for (int rep = 0; rep < 2000; ++rep) {
    Eigen::MatrixXd P(4, 2);
    for (int i = 0; i < 4; ++i) P.row(i) << U(rng), U(rng);
    P.row(2) = P.row(3);
    P.row(1) = P.row(0);
    BSpline c;
    c.degree = 3;
    c.ctrl = P;
    c.knots.resize(8);
    c.knots << 0, 0, 0, 0, 1, 1, 1, 1;
    const auto halves = traj::geo::split_at(c, U01(rng));
    ASSERT_EQ(halves.second.ctrl.row(3), halves.second.ctrl.row(2)) << "rep " << rep;
    ASSERT_EQ(halves.first.ctrl.row(0), halves.first.ctrl.row(1)) << "rep " << rep;
  }
}
