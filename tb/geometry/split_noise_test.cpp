// SPDX-License-Identifier: Apache-2.0
// The noise-aware curvature-extremum scan (curvature.cpp; SplitOptions::noise_factor):
//  * circle arcs (exact rational quadratics, 2-D and tilted into 3-D: many radii, centres, start
//    angles and sweeps) and straight lines give no split point, and the scan costs exactly its samples
//    (no bisection): d(kappa^2)/du is zero there up to rounding, and the computed value lies within
//    its rounding-error bound (measured: at most 0.12 of it; the scan treats 4x the bound as zero);
//  * every real extremum is still found: on the butterfly, the [ARC] curves and random B-splines and
//    NURBS the split points are identical to those of the scan without the bound (noise_factor = 0),
//    and a conic that differs from a circle by 1e-3..1e-9 in one weight has its one extremum at the
//    symmetric point.
// The three-120-degree cubic Bezier circle ([ARC] curve 2) is not of constant curvature and is not
// used here.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/geometry.hpp"
#include "paper_curves.hpp"
#include "test_util.hpp"

using namespace traj::geo;

namespace {

// A planar curve placed in 3-D: x' = R (x, y, 0) + t for a fixed rotation R.
BSpline tilt_3d(const BSpline& b) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())).toRotationMatrix();
  BSpline o = b;
  o.ctrl.resize(b.n_ctrl(), 3);
  for (int i = 0; i < b.n_ctrl(); ++i) {
    const Eigen::Vector3d x = R * Eigen::Vector3d(b.ctrl(i, 0), b.ctrl(i, 1), 0.0) + Eigen::Vector3d(3, -4, 5);
    o.ctrl.row(i) = x.transpose();
  }
  return o;
}

struct NoSplitCheck {
  long long curves = 0, worst_evals_per_span = 0;
  double worst_ratio = 0;  // |d(kappa^2)/du| / its rounding-error bound, over all samples
};

// No extremum, no inflection, no split point; evaluations = samples only; value within its bound.
void expect_no_split(const Curve& c, const std::string& what, NoSplitCheck& chk) {
  SplitStats st;
  SplitOptions o;
  o.stats = &st;
  EXPECT_TRUE(split_params(c, o).empty()) << what;
  EXPECT_TRUE(curvature_extrema(c, o).empty()) << what;
  const long long samples = static_cast<long long>(c.spans().size()) * (o.samples_per_span + 1);
  // split_params (extrema + inflections) and curvature_extrema: each scan evaluates its samples once
  const long long expect_dk2 = c.degree() == 1 ? 0 : 2 * samples;
  const long long expect_cross = (c.dim() == 2 && c.degree() > 1) ? samples : 0;
  EXPECT_EQ(st.dk2_evals, expect_dk2) << what << ": bisection steps on rounding noise";
  EXPECT_EQ(st.cross_evals, expect_cross) << what;
  chk.worst_evals_per_span = std::max(chk.worst_evals_per_span, (st.dk2_evals / 2 + st.cross_evals) /
                                                                    static_cast<long long>(c.spans().size()));
  if (c.degree() > 1)
    for (int si = 0; si < static_cast<int>(c.spans().size()); ++si)
      for (int j = 0; j <= 64; ++j) {
        const PowerSpan& s = c.spans()[si];
        const double u = j == 64 ? s.u1 : s.u0 + (s.u1 - s.u0) * j / 64;
        const CurvatureSqDerivative d = curvature_sq_derivative(c, si, u);
        const double r = std::abs(d.value) / d.error_bound;
        chk.worst_ratio = std::max(chk.worst_ratio, r);
        EXPECT_LE(std::abs(d.value), d.error_bound) << what << " u = " << u;
      }
  ++chk.curves;
}

}  // namespace

TEST(GeometryCurvatureNoise, CircleArcsAndLinesHaveNoSplitPoints) {
  NoSplitCheck chk;
  const double sweeps[] = {0.1, -0.1, 1.0, M_PI / 2, 2.356, M_PI, -M_PI, 4.7, 2 * M_PI};
  for (double r : {1e-3, 0.5, 1.0, 37.0, 1e4})
    for (double off : {0.0, 1e3, -2.5e3, 1e5})
      for (double a0 : {0.0, -M_PI / 2, 0.3, 2.0})
        for (double sw : sweeps) {
          const BSpline b = make_arc(Eigen::Vector2d(off, -0.7 * off + 3), r, a0, a0 + sw);
          char what[128];
          std::snprintf(what, sizeof what, "arc r %g centre %g start %g sweep %g", r, off, a0, sw);
          expect_no_split(Curve(b), what, chk);
          expect_no_split(Curve(tilt_3d(b)), std::string(what) + " (3-D)", chk);
        }
  // Lines: degree 1 (2-D, 3-D), a straight cubic with non-uniform speed, a straight rational quadratic.
  Eigen::VectorXd a(2), e(2), a3(3), e3(3);
  a << -3, 7;
  e << 1e3, 2e3;
  a3 << 1, 2, 3;
  e3 << -40, 5, 77;
  expect_no_split(Curve(make_line(a, e)), "line 2-D", chk);
  expect_no_split(Curve(make_line(a3, e3)), "line 3-D", chk);
  Eigen::MatrixXd P(4, 2), Q(3, 3);
  P << 0, 0, 1, 2, 1.5, 3, 10, 20;
  Q << 1, 2, 3, 2, 4, 6, 50, 100, 150;
  expect_no_split(Curve(make_bezier(P)), "straight cubic", chk);
  expect_no_split(Curve(make_bezier(Q, Eigen::Vector3d(1, 3, 0.5))), "straight rational quadratic 3-D", chk);
  expect_no_split(Curve(tilt_3d(make_bezier(P))), "straight cubic 3-D", chk);
  std::printf("%lld curves: no split point, %lld evaluations per span at most (the samples), "
              "|d(kappa^2)/du| <= %.3g x its rounding-error bound\n",
              chk.curves, chk.worst_evals_per_span, chk.worst_ratio);

  // What the bound fixes: without it (noise_factor = 0) the raster benchmark's half circle (radius 0.5
  // at y = 500) has dozens of spurious split points, each bisected to 1e-9.
  const Curve half(make_arc(Eigen::Vector2d(20, 500.5), 0.5, -M_PI / 2, M_PI / 2));
  SplitOptions o0;
  o0.noise_factor = 0;
  SplitStats st0, st;
  o0.stats = &st0;
  const size_t spurious = split_params(half, o0).size();
  SplitOptions o;
  o.stats = &st;
  EXPECT_TRUE(split_params(half, o).empty());
  std::printf("raster half circle: %zu spurious split points and %lld d(kappa^2)/du evaluations without the bound, "
              "0 and %lld with it\n",
              spurious, st0.dk2_evals, st.dk2_evals);
  EXPECT_GT(spurious, 0u);
}

TEST(GeometryCurvatureNoise, RealExtremaUnchanged) {
  auto same = [](const Curve& c, const std::string& what) -> size_t {
    SplitOptions o0;
    o0.noise_factor = 0;
    const auto a = curvature_extrema(c), b = curvature_extrema(c, o0);
    EXPECT_EQ(a.size(), b.size()) << what;
    for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
      EXPECT_EQ(a[i].u, b[i].u) << what;
      EXPECT_EQ(a[i].maximum, b[i].maximum) << what;
      EXPECT_EQ(a[i].at_knot, b[i].at_knot) << what;
    }
    EXPECT_EQ(split_params(c), split_params(c, o0)) << what;
    return a.size();
  };
  const BSpline bf = load_curve(geotest::asset("butterfly_nurbs.json"));
  const Curve bc(bf);
  EXPECT_EQ(same(bc, "butterfly"), 73u);  // 37 maxima + 36 minima
  double least = 1e300;  // smallest |d(kappa^2)/du| / bound over the butterfly's scan samples
  for (int si = 0; si < static_cast<int>(bc.spans().size()); ++si)
    for (int j = 0; j <= 64; ++j) {
      const PowerSpan& s = bc.spans()[si];
      const double u = j == 64 ? s.u1 : s.u0 + (s.u1 - s.u0) * j / 64;
      const CurvatureSqDerivative d = curvature_sq_derivative(bc, si, u);
      least = std::min(least, std::abs(d.value) / d.error_bound);
    }
  std::printf("butterfly: every scan sample's |d(kappa^2)/du| >= %.3g x its rounding-error bound\n", least);
  EXPECT_GT(least, 4.0);
  same(Curve(seedcurves::curve1()), "[ARC] curve 1");
  same(Curve(seedcurves::curve2()), "[ARC] curve 2");
  same(Curve(seedcurves::curve3()), "[ARC] curve 3");
  std::mt19937_64 rng(geotest::seed() + 77);
  size_t total = 0;
  for (int it = 0; it < 600; ++it) {
    const int p = 2 + it % 6, dim = 2 + (it / 6) % 2;
    const bool rat = (it / 12) % 2 == 1;
    const auto rs = geotest::random_spline(rng, p, dim, p + 1 + it % 9, rat);
    total += same(Curve(rs.lib), "random " + std::to_string(it));
  }
  std::printf("random curves: %zu extrema, all identical with and without the noise bound\n", total);
}

// A conic close to a circle (the middle weight of a 90-degree arc scaled by 1 + delta) has one
// curvature extremum, at the symmetric point u = 0.5; the bound must not hide it.
TEST(GeometryCurvatureNoise, NearCircleConicExtremumFound) {
  for (double off : {0.0, 1e3})
    for (double delta : {1e-3, -1e-3, 1e-6, -1e-6, 1e-9}) {
      if (off > 0 && std::abs(delta) < 1e-6) continue;  // far from the origin 1e-9 is below double resolution
      BSpline b = make_arc(Eigen::Vector2d(off, 0), 1.0, 0.2, 0.2 + M_PI / 2);
      b.weights[1] *= 1 + delta;
      const auto e = curvature_extrema(Curve(b));
      ASSERT_EQ(e.size(), 1u) << "offset " << off << " delta " << delta;
      EXPECT_NEAR(e[0].u, 0.5, 1e-7) << "offset " << off << " delta " << delta;
      EXPECT_EQ(e[0].maximum, delta > 0) << "offset " << off << " delta " << delta;
    }
  // Below the resolution (printed, not asserted): 1000 radii from the origin, the curvature of a conic
  // within 1e-11 of a circle varies by less than the rounding of its own control points allows.
  for (double delta : {1e-9, 1e-11, 1e-13}) {
    BSpline b = make_arc(Eigen::Vector2d(1e3, 0), 1.0, 0.2, 0.2 + M_PI / 2);
    b.weights[1] *= 1 + delta;
    SplitOptions o0;
    o0.noise_factor = 0;
    const auto with = curvature_extrema(Curve(b)), without = curvature_extrema(Curve(b), o0);
    std::printf("conic at 1000 radii, weight x (1 + %.0e): u - 0.5 of the extrema with the bound (", delta);
    for (const auto& x : with) std::printf(" %.2e", x.u - 0.5);
    std::printf(" ), without (");
    for (const auto& x : without) std::printf(" %.2e", x.u - 0.5);
    std::printf(" )\n");
  }
}
