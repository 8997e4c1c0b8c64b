// SPDX-License-Identifier: Apache-2.0
// Reparameterisation by arc length. The project's method is checked step by step against
// independent arc lengths (closed form on the exact circle; composite 20-point Gauss-Legendre with the
// Cox-de Boor reference evaluator elsewhere). [ARC]'s algorithm is checked against its own claims.
#include <gtest/gtest.h>

#include "geometry/geometry.hpp"
#include "paper_curves.hpp"
#include "test_util.hpp"

using namespace traj::geo;

namespace {

ref::Spline to_ref(const BSpline& b) {
  ref::Spline r;
  r.p = b.degree;
  r.U.assign(b.knots.data(), b.knots.data() + b.knots.size());
  for (int i = 0; i < b.n_ctrl(); ++i) {
    std::vector<double> p(b.dim());
    for (int d = 0; d < b.dim(); ++d) p[d] = b.ctrl(i, d);
    r.P.push_back(p);
  }
  if (b.rational()) r.W.assign(b.weights.data(), b.weights.data() + b.n_ctrl());
  return r;
}

// Independent length of [a,b]: split at knots, 20-point Gauss-Legendre (nodes by Newton on P_20,
// computed here) on each piece, speed from the Cox-de Boor reference.
double ref_length(const ref::Spline& r, double a, double b) {
  static std::vector<double> x, w;
  if (x.empty()) {
    const int n = 20;
    for (int i = 0; i < n; ++i) {
      double z = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1;
      for (int it = 0; it < 50; ++it) {
        double p0 = 1, p1 = z;
        for (int k = 1; k < n; ++k) {
          const double p2 = ((2 * k + 1) * z * p1 - k * p0) / (k + 1);
          p0 = p1;
          p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1);
        z -= p1 / dp;
      }
      x.push_back(z);
      w.push_back(2 / ((1 - z * z) * dp * dp));
    }
  }
  std::vector<double> cuts{a};
  for (double t : r.U)
    if (t > a && t < b && t != cuts.back()) cuts.push_back(t);
  cuts.push_back(b);
  double L = 0;
  for (size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double m = 0.5 * (cuts[i] + cuts[i + 1]), h = 0.5 * (cuts[i + 1] - cuts[i]);
    for (size_t j = 0; j < x.size(); ++j) {
      const auto d = ref::cox_de_boor_derivs(r, m + h * x[j], 1);
      double s2 = 0;
      for (double v : d[1]) s2 += v * v;
      L += w[j] * h * std::sqrt(s2);
    }
  }
  return L;
}

void check_equal_steps(const BSpline& b, double step, double tol_rel) {
  const Curve c(b);
  const ArcLength al(c);
  const auto u = equal_arclength_params(al, step);
  const ref::Spline r = to_ref(b);
  ASSERT_GE(u.size(), 3u);
  double worst = 0;
  const size_t full = static_cast<size_t>(std::floor(al.total() / step));
  for (size_t k = 0; k + 1 < u.size() && k < full; ++k) worst = std::max(worst, std::abs(ref_length(r, u[k], u[k + 1]) / step - 1));
  std::printf("%s: step %.4g, %zu steps, max |ds/step - 1| = %.2e\n", b.name.c_str(), step, full, worst);
  EXPECT_LE(worst, tol_rel) << b.name;
  EXPECT_EQ(u.back(), c.u_end());
}

}  // namespace

TEST(GeometryReparam, ExactCircleClosedForm) {
  const double r = 20, a0 = 0.1, sweep = 2 * M_PI;
  const Curve arc(make_arc(Eigen::Vector2d(0, 0), r, a0, a0 + sweep));
  const ArcLength al(arc);
  const double step = 0.05;
  const auto u = equal_arclength_params(al, step);
  double worst = 0;
  for (size_t k = 0; k + 2 < u.size(); ++k) {
    const Eigen::Vector2d p = arc.point(u[k]), q = arc.point(u[k + 1]);
    double d = std::atan2(q.y(), q.x()) - std::atan2(p.y(), p.x());
    if (d < 0) d += 2 * M_PI;
    worst = std::max(worst, std::abs(r * d / step - 1));
  }
  std::printf("exact circle r=20: %zu steps of 0.05, max |ds/step - 1| = %.2e\n", u.size() - 2, worst);
  EXPECT_LE(worst, 1e-9);
}

TEST(GeometryReparam, ButterflyStepsWithin1e9) {
  check_equal_steps(load_curve(geotest::asset("butterfly_nurbs.json")), 0.05, 1e-9);
}

TEST(GeometryReparam, SeedCurvesAndRandomSplinesWithin1e9) {
  check_equal_steps(seedcurves::curve1(), 0.1, 1e-9);
  check_equal_steps(seedcurves::curve2(), 0.1, 1e-9);
  check_equal_steps(seedcurves::curve3(), 0.1, 1e-9);
  std::mt19937_64 rng(geotest::seed() + 11);
  for (int p = 2; p <= 7; ++p) {
    auto rs = geotest::random_spline(rng, p, 3, p + 6, p % 2 == 1);
    rs.lib.name = "random degree " + std::to_string(p);
    check_equal_steps(rs.lib, 0.7, 1e-9);
  }
}

TEST(GeometryReparam, TaylorInterpolatorsBehaveAsTheoryPredicts) {
  // On one piece of the exact circle |r'| varies (rational parameterisation, smooth inside the piece):
  // the second-order Taylor step error is O((VT)^3) and must be far below the first-order O((VT)^2).
  // (Across a C0 knot of a multi-piece arc |r'| jumps and both orders err alike.)
  const Curve arc(make_arc(Eigen::Vector2d(0, 0), 10, 0, 1.5));
  const ArcLength al(arc);
  const double V = 50, T = 1e-3;
  const auto f1 = feed_fluctuation(al, taylor_interpolate(arc, V, T, 1), V * T, true);
  const auto f2 = feed_fluctuation(al, taylor_interpolate(arc, V, T, 2), V * T, true);
  EXPECT_LT(std::max(std::abs(f2.max), std::abs(f2.min)), 0.1 * std::max(std::abs(f1.max), std::abs(f1.min)));
}

// [ARC]'s formula [2_04] tau = t_const * l_curve / (n * l_secant). The text before it says the
// deviation factor is l_secant / l_curve ([2_02]/[2_03]); that is off by the factor n (the deviation
// factor is n l_secant / l_curve). Dividing t_const by the text's factor gives steps that sum to about
// n instead of 1; after the paper's normalisation both give the same steps, so the algorithm survives
// the slip. Checked here: the [2_04] steps sum to ~1 before normalisation, the text's to ~n.
TEST(GeometryReparam, ArcPaperFormulaCheck) {
  const Curve c(seedcurves::curve1());
  const int n = 20;
  double lcurve = 0;
  std::vector<double> l(n);
  for (int i = 0; i < n; ++i) {
    l[i] = (c.point((i + 1.0) / n) - c.point(static_cast<double>(i) / n)).norm();
    lcurve += l[i];
  }
  double sum204 = 0, sumtext = 0;
  std::vector<double> a(n), b(n);
  for (int i = 0; i < n; ++i) {
    a[i] = (1.0 / n) * lcurve / (n * l[i]);  // [2_04]
    b[i] = (1.0 / n) / (l[i] / lcurve);      // text: divide t_const by [2_02]/[2_03]
    sum204 += a[i];
    sumtext += b[i];
  }
  EXPECT_NEAR(sum204, 1.0, 0.2);
  EXPECT_NEAR(sumtext, n, 0.2 * n);
  for (int i = 0; i < n; ++i) EXPECT_NEAR(a[i] / sum204, b[i] / sumtext, 1e-15);
  // One pass of the library's implementation equals these normalised steps.
  const auto u = arc_paper_reparam(c, 0, 1, n, 1);
  double t = 0;
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(u[i], t, 1e-14);
    t += a[i] / sum204;
  }
}

// [ARC]'s claims on its curves, and the figures host/geometry/README.md quotes (bench_reparam's
// method: n = 20 steps per Bezier segment, nominal step L / n_total; "true" = max/min of the arc
// length between consecutive parameters, [ARC]'s "1 : x" is the same ratio with chords). Each
// quoted figure must lie within half a unit of its last printed digit (the band is that rounding).
namespace {
double true_ratio(const Curve& c, int passes, int n_per_segment = 20) {
  const ArcLength al(c);
  const double step = al.total() / (n_per_segment * static_cast<double>(c.spans().size()));
  return feed_fluctuation(al, arc_paper_reparam_spline(c, al, step, passes), step, false).ratio;
}
double chord_ratio(const Curve& c, int passes, int n_per_segment = 20) {
  const ArcLength al(c);
  const double step = al.total() / (n_per_segment * static_cast<double>(c.spans().size()));
  return chord_fluctuation(c, arc_paper_reparam_spline(c, al, step, passes)).ratio;
}
// |x - quoted| <= half a unit of the quoted figure's last digit (`decimals` digits after the point).
void expect_quoted(double x, double quoted, int decimals, const std::string& what) {
  EXPECT_LE(std::abs(x - quoted), 0.5 * std::pow(10.0, -decimals) * (1 + 1e-9)) << what << ": " << x << " vs quoted " << quoted;
}
}  // namespace

TEST(GeometryReparam, ArcPaperClaims) {
  const Curve c1(seedcurves::curve1()), c2(seedcurves::curve2()), c3(seedcurves::curve3());
  // Unlevelled (uniform parameter, n = 20): the chord ratios curves 1 and 3 are tuned to.
  expect_quoted(chord_ratio(c1, 0), 2.271, 3, "curve 1 before (paper 1 : 2.271)");
  expect_quoted(chord_ratio(c1, 0), 2.2709, 4, "curve 1 unlevelled (host/geometry/README.md)");
  expect_quoted(chord_ratio(c3, 0), 11.107, 3, "curve 3 unlevelled (host/geometry/README.md; paper 1 : 11.108)");
  // The circle (unambiguous: three 120-degree cubic Beziers): paper 1 : 1.135 at n = 20 is not
  // reproduced; the chord ratio is 1.1226 at n = 20 and rounds to 1.135 only for n = 51..56.
  expect_quoted(chord_ratio(c2, 0), 1.1226, 4, "circle before, n = 20");
  expect_quoted(true_ratio(c2, 0), 1.1227, 4, "circle before, n = 20, true steps");
  for (int n = 20; n <= 60; ++n) {
    const bool rounds_to_1135 = std::abs(chord_ratio(c2, 0, n) - 1.135) <= 0.0005;
    EXPECT_EQ(rounds_to_1135, n >= 51 && n <= 56) << "n = " << n << ": " << chord_ratio(c2, 0, n);
  }
  // Cascaded levelling (true steps), as quoted in "How to read it".
  expect_quoted(true_ratio(c2, 3), 1.00006, 5, "circle, 3 passes");
  expect_quoted(true_ratio(c2, 10), 1.00006, 5, "circle, 10 passes");
  expect_quoted(true_ratio(c1, 3), 1.029, 3, "curve 1, 3 passes");
  expect_quoted(true_ratio(c1, 10), 1.0098, 4, "curve 1, 10 passes");
  expect_quoted(true_ratio(c3, 3), 1.078, 3, "curve 3, 3 passes");
  expect_quoted(true_ratio(c3, 10), 1.0008, 4, "curve 3, 10 passes");
  // The same in chords ([ARC]'s own measure): levelled to 1.000000 after 10 passes.
  expect_quoted(chord_ratio(c1, 3), 1.0231, 4, "curve 1, 3 passes, chords");
  expect_quoted(chord_ratio(c3, 3), 1.0778, 4, "curve 3, 3 passes, chords");
  for (const Curve* c : {&c1, &c2, &c3}) EXPECT_LT(chord_ratio(*c, 10) - 1, 1e-6) << c->spline().name;
  // Levelling reduces the fluctuation (the paper's claim), by more than 5x after 3 passes.
  for (const Curve* c : {&c1, &c2, &c3}) EXPECT_LT(true_ratio(*c, 3) - 1, 0.2 * (true_ratio(*c, 0) - 1)) << c->spline().name;
  // Curve 1 has an inflection (exactly one), curves 2 and 3 none.
  EXPECT_EQ(inflection_points(c1).size(), 1u);
  EXPECT_TRUE(inflection_points(c2).empty());
  EXPECT_TRUE(inflection_points(c3).empty());
}

// The butterfly: [ARC] applied per Bezier segment still leaves about 10% after 10 passes.
TEST(GeometryReparam, ArcPaperOnButterfly) {
  const Curve c(load_curve(geotest::asset("butterfly_nurbs.json")));
  const ArcLength al(c);
  const Fluctuation f = feed_fluctuation(al, arc_paper_reparam_spline(c, al, 0.1, 10), 0.1, false);
  expect_quoted(f.ratio, 1.121, 3, "butterfly, 0.1 mm, 10 passes");
  expect_quoted(f.max, 0.106, 3, "butterfly, 0.1 mm, 10 passes, max");
  expect_quoted(f.min, -0.014, 3, "butterfly, 0.1 mm, 10 passes, min");
}
