// SPDX-License-Identifier: Apache-2.0
// Arc length, inverse arc length, curvature extrema / inflections and the ACC/DEC split, checked
// against published data (the butterfly, host/assets/README.md) and independent references:
// closed forms (circle, line), a chord-polygon length with Richardson extrapolation evaluated with the
// Cox-de Boor reference, and the exact roots of a cubic Bezier's inflection quadratic.
#include <gtest/gtest.h>

#include "arclength_ref.hpp"
#include "cusp_cubic.hpp"
#include "geometry/geometry.hpp"
#include "test_util.hpp"

using namespace traj::geo;

namespace {

const BSpline& butterfly_spline() {
  static const BSpline b = load_curve(geotest::asset("butterfly_nurbs.json"));
  return b;
}
const Curve& butterfly() {
  static const Curve c(butterfly_spline(), "butterfly_nurbs.json");
  return c;
}
ref::Spline butterfly_ref() {
  const BSpline& b = butterfly_spline();
  ref::Spline r;
  r.p = b.degree;
  r.U.assign(b.knots.data(), b.knots.data() + b.knots.size());
  for (int i = 0; i < b.n_ctrl(); ++i) r.P.push_back({b.ctrl(i, 0), b.ctrl(i, 1)});
  r.W.assign(b.weights.data(), b.weights.data() + b.n_ctrl());
  return r;
}

// Independent arc length: chord polygon with N and 2N chords per knot span (uniform in u, points by
// the Cox-de Boor reference in long double, each span's own polynomial); the chord error is
// c2/N^2 + c4/N^4 + ..., so Richardson (4 L_2N - L_N)/3 removes the leading term and leaves O(N^-4).
long double chord_length_richardson(const ref::Spline& r, int N) {
  auto poly = [&](int n) {
    long double L = 0;
    for (int j = r.p; j + 1 < static_cast<int>(r.U.size()) - r.p; ++j) {
      const double a = r.U[j], b = r.U[j + 1];
      if (!(b > a)) continue;
      std::vector<long double> prev;
      for (int i = 0; i <= n; ++i) {
        const double u = a + (b - a) * i / n;
        const auto P = ref::cox_de_boor_derivs_r<long double>(r, u, 0, j)[0];
        if (!prev.empty()) L += std::sqrt((P[0] - prev[0]) * (P[0] - prev[0]) + (P[1] - prev[1]) * (P[1] - prev[1]));
        prev = P;
      }
    }
    return L;
  };
  const long double L1 = poly(N), L2 = poly(2 * N);
  return (4 * L2 - L1) / 3;
}

// Independent arc length of [U_j, u] inside knot span j (u <= U_{j+1}): composite 20-point
// Gauss-Legendre in long double (rule from arclength_ref.hpp: nodes by Newton on P_20), `panels` equal
// panels, speed |r'| from the Cox-de Boor reference in long double.
long double ref_span_length(const ref::Spline& r, int j, double u, int panels) {
  const geotest::GLRuleLD& g = geotest::gl20ld();
  const long double a = r.U[j], h = (static_cast<long double>(u) - a) / panels;
  long double L = 0;
  for (int k = 0; k < panels; ++k) {
    const long double m = a + (k + 0.5L) * h;
    long double acc = 0;
    for (size_t i = 0; i < g.x.size(); ++i) {
      const auto d = ref::cox_de_boor_derivs_r<long double>(r, static_cast<double>(m + 0.5L * h * g.x[i]), 1, j);
      acc += g.w[i] * std::sqrt(d[1][0] * d[1][0] + d[1][1] * d[1][1]);
    }
    L += acc * 0.5L * h;
  }
  return L;
}

}  // namespace

TEST(GeometryArcLength, ButterflyPublishedLength) {
  const ArcLength al(butterfly());
  std::printf("butterfly: L = %.9f mm, %lld integrand evaluations, %lld GL rules, %zu spans\n", al.total(),
              al.stats().integrand_evals, al.stats().intervals, butterfly().spans().size());
  RecordProperty("integrand_evals", std::to_string(al.stats().integrand_evals));
  // Published 382.86031 (8 significant digits: +-5e-6) .
  EXPECT_NEAR(al.total(), 382.86031, 5e-6);
}

// Tolerance from the error budget, not a bare epsilon:
//  * library: adaptive GL at rel_tol 1e-14 per span, so |error| <= 1e-14 L summed over the spans;
//  * reference: Richardson leaves O(N^-4), so the error of R(800) is about |R(800) - R(400)| / 15
//    (checked: the ratio of successive differences is ~16, as N^-4 predicts); allowed twice that;
//  * rounding: long double sums of ~80,000 chords, ~1e-16 L.
// Measured: R(400) - R(800) = 3.1e-13 L, library - R(800) = -2.1e-14 L (R(800)'s own error); tolerance
// 5.3e-14 L. (Against the composite-GL20 long-double reference below the library differs by 4e-16 L.)
TEST(GeometryArcLength, ButterflyAgainstChordRichardson) {
  const ArcLength al(butterfly());
  const ref::Spline r = butterfly_ref();
  const long double r200 = chord_length_richardson(r, 200), r400 = chord_length_richardson(r, 400),
                    r800 = chord_length_richardson(r, 800);
  const double L = al.total();
  const double ratio = static_cast<double>((r200 - r400) / (r400 - r800));
  const double ref_err = static_cast<double>(std::fabs(r400 - r800) / 15);
  const double tol = 1e-14 * L + 2 * ref_err + 1e-15 * L;
  std::printf("butterfly: adaptive GL %.12f, chord+Richardson N=800 %.12Lf, diff %.2e L (N=400: %.2e L); "
              "difference ratio %.1f; tolerance %.2e L\n",
              L, r800, static_cast<double>((L - r800) / L), static_cast<double>((L - r400) / L), ratio, tol / L);
  EXPECT_GT(ratio, 12);  // the O(N^-4) error model behind ref_err holds
  EXPECT_LT(ratio, 20);
  EXPECT_NEAR(L, static_cast<double>(r800), tol);
}

TEST(GeometryArcLength, ToleranceControlsError) {
  // Looser tolerance: error still below the tolerance times the length (checked against the tight one).
  const ArcLength tight(butterfly(), 1e-14);
  for (double tol : {1e-4, 1e-6, 1e-8, 1e-10}) {
    const ArcLength al(butterfly(), tol);
    EXPECT_LE(std::abs(al.total() - tight.total()), tol * tight.total()) << "tol " << tol;
    std::printf("rel_tol %.0e: L = %.12f, err %.1e, %lld integrand evaluations\n", tol, al.total(),
                al.total() - tight.total(), al.stats().integrand_evals);
  }
}

TEST(GeometryArcLength, CircleArcExactAndInverse) {
  // Exact NURBS arc: length r * sweep; the point at arc length s is at angle a0 + s/r. Both closed form.
  const double r = 12.5, a0 = 0.3, sweep = 5.0;
  const Eigen::Vector2d ctr(1, 2);
  const Curve arc(make_arc(ctr, r, a0, a0 + sweep));
  const ArcLength al(arc);
  EXPECT_NEAR(al.total(), r * sweep, 1e-13 * r * sweep);
  for (int i = 0; i <= 37; ++i) {
    const double s = al.total() * i / 37.0;
    const double u = al.u_at(s);
    const Eigen::Vector2d p = arc.point(u);
    const Eigen::Vector2d q = ctr + r * Eigen::Vector2d(std::cos(a0 + s / r), std::sin(a0 + s / r));
    EXPECT_LT((p - q).norm(), 1e-11 * r) << "s=" << s;
    EXPECT_NEAR(al.s(u), s, 1e-12 * al.total());
  }
  // Arbitrary sub-intervals: length(u0, u1) = r * (angle difference).
  std::mt19937_64 rng(geotest::seed() + 3);
  std::uniform_real_distribution<double> U(0, 1);
  for (int t = 0; t < 50; ++t) {
    const double u0 = U(rng), u1 = U(rng);
    const Eigen::Vector2d p0 = arc.point(u0) - ctr, p1 = arc.point(u1) - ctr;
    double d = std::atan2(p1.y(), p1.x()) - std::atan2(p0.y(), p0.x());
    // unwrap to the arc's direction of travel
    const double sgn = u1 >= u0 ? 1 : -1;
    while (sgn * d < 0) d += sgn * 2 * M_PI;
    EXPECT_NEAR(al.length(u0, u1), r * d, 1e-11 * r);
  }
}

// A cusp just inside a cubic (cusp_cubic.hpp, lengths in closed form). With uc = 0.002 the cusp lies
// before the first Gauss node of every interval down to 1/64 of the span: the quadrature saw only the
// smooth branch and came out twice the way back (4e-5 mm) short (simple-icons' furrynetwork.svg,
// host/geometry/arclength.hpp "Deep speed minima").
TEST(GeometryArcLength, CuspJustInsideTheSpan) {
  const geotest::CuspCubic cc{10, 20, 0.002};
  const Curve c(make_bezier(cc.bezier()));
  const ArcLength al(c);
  const double L = cc.s(1);
  std::printf("  length %.15f mm (closed form %.15f), the way back %.3e mm\n", al.total(), L, cc.back());
  EXPECT_NEAR(al.total(), L, 1e-13 * L);
  for (const double u : {1e-4, 1e-3, 0.0019, 0.0021, 0.003, 0.01, 0.3, 0.9}) {
    EXPECT_NEAR(al.s(u), cc.s(u), 1e-13 * L) << "u = " << u;
    EXPECT_NEAR(al.u_at(cc.s(u)), u, 1e-9) << "u = " << u;
  }
  // the fast path (advance from a point before the cusp across it) agrees
  EXPECT_NEAR(al.advance(1e-4, cc.s(0.5) - cc.s(1e-4)), 0.5, 1e-9);
}

TEST(GeometryArcLength, LineLength) {
  const Curve line(make_line(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3, 4, 12)));
  const ArcLength al(line);
  EXPECT_NEAR(al.total(), 13, 1e-14);
  EXPECT_NEAR(al.u_at(6.5), 0.5, 1e-15);
}

// u_at(s) against an independent reference: s_ref(u) = sum of the reference lengths of the knot spans
// before u + the reference length of [U_j, u] (composite GL20 in long double, Cox-de Boor speed; 8
// panels, checked against 16). Budget: u_at stops at |s(u) - s| <= 1e-14 L; the library's span table
// is within 1e-14 L; the reference's own error is measured (8 vs 16 panels) and added; u's resolution
// costs |r'| ulp(u) < 1e-15 L. Also the library's own consistency (complementary pieces).
TEST(GeometryArcLength, InverseOnButterflyRoundTrip) {
  const ArcLength al(butterfly());
  const ref::Spline r = butterfly_ref();
  const double L = al.total();
  std::vector<long double> cum{0};  // reference length at the start of each knot span j >= p
  std::vector<int> span_of;
  double ref_err = 0;
  for (int j = r.p; j < r.n(); ++j) {
    const long double a = r.U[j + 1] > r.U[j] ? ref_span_length(r, j, r.U[j + 1], 8) : 0;
    const long double b = r.U[j + 1] > r.U[j] ? ref_span_length(r, j, r.U[j + 1], 16) : 0;
    ref_err += static_cast<double>(std::fabs(a - b));
    cum.push_back(cum.back() + b);
  }
  std::printf("reference total %.13Lf (library %.13f, diff %.2e L); 8 vs 16 panels differ by %.2e L in total\n",
              cum.back(), L, static_cast<double>((L - cum.back()) / L), ref_err / L);
  const double tol = 2e-14 * L + 2 * ref_err + 1e-15 * L;
  EXPECT_NEAR(static_cast<double>(cum.back()), L, tol);
  std::mt19937_64 rng(geotest::seed() + 4);
  std::uniform_real_distribution<double> S(0, L);
  double worst = 0;
  for (int t = 0; t < 300; ++t) {
    const double s = S(rng);
    const double u = al.u_at(s);
    const int j = ref::find_span(r, u);
    const long double s_ref = cum[j - r.p] + ref_span_length(r, j, u, 16);
    const double err = static_cast<double>(std::fabs(s_ref - static_cast<long double>(s)));
    worst = std::max(worst, err);
    EXPECT_LE(err, tol) << "s = " << s << ", u = " << u;
    // The library's own consistency: s(u) + length(u, end) must equal the total (different intervals).
    EXPECT_NEAR(al.length(butterfly().u_begin(), u), s, 2e-14 * L);
    EXPECT_NEAR(al.length(u, butterfly().u_end()) + s, L, 3e-14 * L);
  }
  std::printf("u_at on 300 random s: worst |s_ref(u) - s| = %.2e L (tolerance %.2e L)\n", worst / L, tol / L);
}

// kappa formula: sqrt(|r'|^2|r''|^2 - (r'.r'')^2)/|r'|^3 equals |r' x r''|/|r'|^3 in 3-D.
TEST(GeometryCurvature, GeneralFormulaEqualsCrossProduct) {
  std::mt19937_64 rng(geotest::seed() + 6);
  const auto rs = geotest::random_spline(rng, 4, 3, 9, true);
  const Curve c(rs.lib);
  std::uniform_real_distribution<double> U(c.u_begin(), c.u_end());
  for (int t = 0; t < 200; ++t) {
    const double u = U(rng);
    const auto d = ref::cox_de_boor_derivs(rs.ref, u, 2);
    const Eigen::Vector3d r1(d[1][0], d[1][1], d[1][2]), r2(d[2][0], d[2][1], d[2][2]);
    const double k = r1.cross(r2).norm() / std::pow(r1.norm(), 3);
    EXPECT_NEAR(curvature(c, u), k, 1e-9 * k);
  }
  const Curve arc(make_arc(Eigen::Vector2d(0, 0), 4.0, 0, 3.0));
  EXPECT_NEAR(curvature(arc, 0.37), 0.25, 1e-12);
  EXPECT_NEAR(signed_curvature(arc, 0.37), 0.25, 1e-12);
  const Curve cw(make_arc(Eigen::Vector2d(0, 0), 4.0, 3.0, 0));
  EXPECT_NEAR(signed_curvature(cw, 0.37), -0.25, 1e-12);
}

TEST(GeometryCurvature, ButterflyPeaks) {
  SplitOptions o;
  o.minima = true;
  const auto ext = curvature_extrema(butterfly(), o);
  std::vector<CurvatureExtremum> big;
  for (const auto& e : ext)
    if (e.maximum && e.kappa > 1.0) big.push_back(e);
  for (const auto& e : big) std::printf("  max kappa %.6f 1/mm at u = %.9f%s\n", e.kappa, e.u, e.at_knot ? " (knot)" : "");
  EXPECT_EQ(big.size(), 10u);
  auto top = std::max_element(big.begin(), big.end(), [](auto& a, auto& b) { return a.kappa < b.kappa; });
  ASSERT_NE(top, big.end());
  // Published: 43.2513 at u = 0.2563501; mirror 42.4950 at u = 0.7436435 (rounded as printed).
  EXPECT_NEAR(top->kappa, 43.2513, 5e-5);
  EXPECT_NEAR(top->u, 0.2563501, 5e-8);
  bool mirror = false;
  for (const auto& e : big)
    if (std::abs(e.u - 0.7436435) < 5e-8) {
      mirror = true;
      EXPECT_NEAR(e.kappa, 42.4950, 5e-5);
    }
  EXPECT_TRUE(mirror);
}

// Each extremum is located to |du| <= 1e-7: kappa (reference evaluator) at u -/+ 1e-7 is below the
// value at u for a maximum (above for a minimum), unless the extremum sits at a knot.
TEST(GeometryCurvature, ExtremaLocatedTo1e7) {
  const ref::Spline r = butterfly_ref();
  auto kref = [&](double u) {
    const auto d = ref::cox_de_boor_derivs(r, u, 2);
    const double cr = d[1][0] * d[2][1] - d[1][1] * d[2][0];
    return std::abs(cr) / std::pow(std::hypot(d[1][0], d[1][1]), 3);
  };
  int checked = 0;
  for (const auto& e : curvature_extrema(butterfly())) {
    const double k0 = kref(e.u), km = kref(e.u - 1e-7), kp = kref(e.u + 1e-7);
    if (e.maximum) {
      EXPECT_GE(k0, std::max(km, kp) - 1e-12 * k0) << "u=" << e.u;
    } else {
      EXPECT_LE(k0, std::min(km, kp) + 1e-12 * k0 + 1e-15) << "u=" << e.u;
    }
    ++checked;
  }
  EXPECT_GT(checked, 20);
}

// Inflections of a planar cubic Bezier: x'y'' - y'x'' is a quadratic in t, solved in closed form here.
std::vector<double> cubic_inflections_closed_form(const Eigen::MatrixXd& P) {
  // B'(t) = 3[(1-t)^2 d0 + 2t(1-t) d1 + t^2 d2], B'' = 6[(1-t)(d1-d0) + t(d2-d1)]; cross(B',B'') =
  // 18 (a t^2 + b t + c) with a, b, c from the differences (standard result, derived by expanding).
  const Eigen::Vector2d d0 = P.row(1) - P.row(0), d1 = P.row(2) - P.row(1), d2 = P.row(3) - P.row(2);
  auto cr = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); };
  // f(t) = cross((1-t)^2 d0 + 2t(1-t) d1 + t^2 d2, (1-t)(d1-d0) + t(d2-d1)); evaluate at 3 points and
  // fit the quadratic exactly (Lagrange), then solve.
  auto f = [&](double t) {
    const Eigen::Vector2d v = (1 - t) * (1 - t) * d0 + 2 * t * (1 - t) * d1 + t * t * d2;
    const Eigen::Vector2d w = (1 - t) * (d1 - d0) + t * (d2 - d1);
    return cr(v, w);
  };
  const double f0 = f(0), f1 = f(0.5), f2 = f(1);
  const double A = 2 * f0 - 4 * f1 + 2 * f2, B = -3 * f0 + 4 * f1 - f2, C = f0;
  const double disc = B * B - 4 * A * C;
  std::vector<double> roots;
  if (disc >= 0)
    for (double sg : {-1.0, 1.0}) {
      const double t = (-B + sg * std::sqrt(disc)) / (2 * A);
      if (t > 0 && t < 1) roots.push_back(t);
    }
  return roots;
}

// [ARC]'s curve 1 (with an inflection) and curve 3 (without), tb/geometry/paper_curves.hpp.
TEST(GeometryCurvature, CubicInflectionsClosedForm) {
  Eigen::MatrixXd P(4, 2);
  P << 0, 0, 25, 71.5, 60, -42.9, 100, 0;
  const std::vector<double> roots = cubic_inflections_closed_form(P);
  const auto mine = inflection_points(Curve(make_bezier(P)));
  ASSERT_EQ(roots.size(), 1u);
  ASSERT_EQ(mine.size(), roots.size());
  EXPECT_NEAR(mine[0], roots[0], 1e-9);
  P << 0, 0, 10, 90, 90, 100, 94.15, 100;
  EXPECT_TRUE(cubic_inflections_closed_form(P).empty());
  EXPECT_TRUE(inflection_points(Curve(make_bezier(P))).empty());
}

// ACC/DEC units: curvature monotone inside every unit (sampled with the reference evaluator), units
// contiguous, lengths add up to the total, kinds consistent with the end curvatures.
TEST(GeometryCurvature, ButterflyUnitsMonotone) {
  const ArcLength al(butterfly());
  const auto units = split_units(butterfly(), al);
  const ref::Spline r = butterfly_ref();
  auto kref = [&](double u) {
    const auto d = ref::cox_de_boor_derivs(r, u, 2);
    return std::abs(d[1][0] * d[2][1] - d[1][1] * d[2][0]) / std::pow(std::hypot(d[1][0], d[1][1]), 3);
  };
  ASSERT_GT(units.size(), 20u);
  double total = 0;
  for (size_t i = 0; i < units.size(); ++i) {
    const Unit& un = units[i];
    if (i > 0) {
      EXPECT_EQ(un.u0, units[i - 1].u1);
      EXPECT_NEAR(un.s0, units[i - 1].s1, 1e-12);
    }
    total += un.length;
    const double sgn = un.kind == UnitKind::Accelerate ? -1 : 1;
    double prev = kref(un.u0 + 1e-9);
    for (int j = 1; j <= 40; ++j) {
      const double u = un.u0 + (un.u1 - un.u0) * j / 40.0 - (j == 40 ? 1e-9 : 0);
      const double k = kref(u);
      EXPECT_GE(sgn * (k - prev), -1e-9 * std::max(1.0, k)) << "unit " << i << " [" << un.u0 << ", " << un.u1 << "]";
      prev = k;
    }
    EXPECT_DOUBLE_EQ(un.kappa_max, std::max(un.kappa0, un.kappa1));
  }
  EXPECT_NEAR(total, al.total(), 1e-10);
  EXPECT_EQ(units.front().u0, butterfly().u_begin());
  EXPECT_EQ(units.back().u1, butterfly().u_end());
}

// [NURBS]: the 6-point Gauss-Legendre nodes, 4 of 6 per sub-interval plus both ends (4n+2 points),
// have spacing 0.1694, 0.2113, 0.2386, 0.2113, 0.1694 (+0.1694 of the next) of the interval.
TEST(GeometryArcLength, NurbsPaperNodeSpacing) {
  std::vector<double> x, w;
  gauss_legendre(6, x, w);
  double sw = 0;
  for (double v : w) sw += v;
  EXPECT_NEAR(sw, 2.0, 1e-15);
  std::vector<double> t;
  for (double v : x) t.push_back(0.5 * (v + 1));
  EXPECT_NEAR(t[1] - 0.0, 0.1694, 5e-5);
  EXPECT_NEAR(t[2] - t[1], 0.2113, 5e-5);
  EXPECT_NEAR(t[3] - t[2], 0.2386, 5e-5);
  EXPECT_NEAR(t[4] - t[3], 0.2113, 5e-5);
  EXPECT_NEAR(1.0 - t[4], 0.1694, 5e-5);
  // GL6 is exact for degree 11: integrate t^11 on [0,1].
  double I = 0;
  for (int i = 0; i < 6; ++i) I += 0.5 * w[i] * std::pow(t[i], 11);
  EXPECT_NEAR(I, 1.0 / 12, 1e-15);
}
