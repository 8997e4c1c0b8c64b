// SPDX-License-Identifier: Apache-2.0
// ArcTable (the planner's fast arc-length inverse) against an independent
// reference: composite 20-point Gauss-Legendre in long double over the
// curve's own power-basis speed (tb/geometry/arclength_ref.hpp), not the
// library's adaptive quadrature that the table is checked with when built.
//
// Stated accuracy (arc_table.hpp): |s(u_at(s)) - s| <= kCheckRel * piece +
// 1e-15 * total + the library's 1e-12 relative span tolerance: below
// 2e-12 * total at any s. The reference itself converges to ~1e-16 relative
// (checked here with twice the panels).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "arclength_ref.hpp"
#include "input/path_json.hpp"
#include "report/report.hpp"

using namespace traj;
using namespace traj::plan;
using namespace traj::input;
using namespace traj::job;
using namespace traj::report;

namespace {

#ifndef TRAJ_ASSETS
#error "TRAJ_ASSETS must name host/assets"
#endif

// Adaptive long-double reference on [a, b] inside one span: the 20-point rule
// on the interval against the sum on its halves, split until they agree to
// `tol` (a near-cusp needs many levels; the fixed-panel reference does not
// converge there).
long double ref_adaptive(const geo::Curve& c, int span, long double a, long double b, long double tol, int depth = 0) {
  const geotest::GLRuleLD& r = geotest::gl20ld();
  auto gl = [&](long double lo, long double hi) {
    long double acc = 0;
    const long double m = 0.5L * (lo + hi), h = 0.5L * (hi - lo);
    for (size_t i = 0; i < r.x.size(); ++i) acc += r.w[i] * geotest::speed_ld(c, span, static_cast<double>(m + h * r.x[i]));
    return acc * h;
  };
  const long double m = 0.5L * (a + b);
  const long double whole = gl(a, b), halves = gl(a, m) + gl(m, b);
  // the speed comes from double evaluations: 1e-15 of the interval's length
  // is the noise floor of the comparison
  if (std::fabs(whole - halves) <= std::max(tol, 1e-15L * std::fabs(halves)) || depth > 30) return halves;
  return ref_adaptive(c, span, a, m, 0.5L * tol, depth + 1) + ref_adaptive(c, span, m, b, 0.5L * tol, depth + 1);
}

// Reference arc length from u_begin to u.
long double ref_s(const geo::Curve& c, double u, long double tol) {
  long double s = 0;
  for (size_t si = 0; si < c.spans().size(); ++si) {
    const auto& sp = c.spans()[si];
    if (u <= sp.u0) break;
    s += ref_adaptive(c, static_cast<int>(si), sp.u0, std::min(u, sp.u1), tol);
  }
  return s;
}

// Worst |s_ref(u_at(s)) - s| over n random arc lengths, relative to the
// curve length; also checks that marching (hint carried, ascending s) gives
// bitwise the same u as a cold query and that u is monotone in s.
double worst_rel_error(const PathCurve& pc, int n, std::mt19937_64& rng) {
  const geo::Curve& c = *pc.curve;
  const double total = pc.al->total();
  std::uniform_real_distribution<double> U(0, total);
  std::vector<double> s(n);
  for (auto& x : s) x = U(rng);
  s.push_back(0);
  s.push_back(total);
  std::sort(s.begin(), s.end());
  double worst = 0, u_prev = -1e300;
  int hint = 0;
  for (double si : s) {
    const double u = pc.table->u_at(si, hint);
    EXPECT_EQ(u, pc.table->u_at(si)) << "s = " << si;
    EXPECT_GE(u, u_prev) << "s = " << si;
    u_prev = u;
    const long double ref = ref_s(c, u, 1e-16L * total);
    worst = std::max(worst, static_cast<double>(std::fabs(ref - static_cast<long double>(si)) / total));
  }
  return worst;
}

geo::BSpline random_nurbs(std::mt19937_64& rng, int p, int dim, int n, bool rational) {
  std::uniform_real_distribution<double> U(0, 1);
  geo::BSpline b;
  b.degree = p;
  b.ctrl.resize(n, dim);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < dim; ++d) b.ctrl(i, d) = 100 * (U(rng) - 0.5);
  if (rational) {
    b.weights.resize(n);
    for (int i = 0; i < n; ++i) b.weights[i] = 0.3 * std::pow(10.0, U(rng));
  }
  const int m = n + p + 1;
  b.knots.resize(m);
  std::vector<double> in(n - p - 1);
  for (auto& t : in) t = 0.02 + 0.96 * U(rng);
  std::sort(in.begin(), in.end());
  for (int i = 0; i <= p; ++i) {
    b.knots[i] = 0;
    b.knots[m - 1 - i] = 1;
  }
  for (int i = 0; i < n - p - 1; ++i) b.knots[p + 1 + i] = in[i];
  return b;
}

}  // namespace

TEST(ArcTable, ReferenceAgreesWithFixedPanels) {
  // the adaptive reference and the fixed-panel one (16 and 32 panels per span)
  // agree on the butterfly, where the latter converges
  const Path p = load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json");
  const geo::Curve& c = p.curve(0);
  for (double f : {0.1, 0.37, 0.5, 0.93}) {
    const double u = c.u_begin() + f * (c.u_end() - c.u_begin());
    const long double a = geotest::ref_length(c, c.u_begin(), u, 16), b = geotest::ref_length(c, c.u_begin(), u, 32);
    EXPECT_LE(std::fabs(a - b), 1e-15L * p.length());
    EXPECT_LE(std::fabs(ref_s(c, u, 1e-16L * p.length()) - b), 1e-15L * p.length());
  }
  EXPECT_NEAR(static_cast<double>(ref_s(c, c.u_end(), 1e-16L * p.length())), 382.86031, 5e-6);  // published
}

TEST(ArcTable, ButterflyWithinStatedBound) {
  const Path p = load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json");
  std::mt19937_64 rng(11);
  const double w = worst_rel_error(p.entry(0), 3000, rng);
  std::printf("butterfly: %zu pieces, %zu fallback spans, %lld speed evaluations, worst |s(u_at(s)) - s| / total = %.3e\n",
              p.table(0).pieces(), p.table(0).fallback_spans(), p.table(0).speed_evals(), w);
  EXPECT_LE(w, 2e-12);
  EXPECT_EQ(p.table(0).fallback_spans(), 0u);
}

TEST(ArcTable, RandomSplinesLinesAndArcsWithinStatedBound) {
  std::mt19937_64 rng(12);
  double worst = 0;
  for (int rep = 0; rep < 24; ++rep) {
    const int p = 1 + rep % 7, dim = 2 + rep % 2;
    const PathCurve pc(random_nurbs(rng, p, dim, p + 1 + rep % 9, rep % 3 == 0), "random");
    worst = std::max(worst, worst_rel_error(pc, 150, rng));
  }
  Eigen::VectorXd a(3), b(3);
  a << 1, -2, 3;
  b << 40, 7, -5;
  worst = std::max(worst, worst_rel_error(PathCurve(geo::make_line(a, b), "line"), 100, rng));
  worst = std::max(worst, worst_rel_error(PathCurve(geo::make_arc({3, 4}, 0.5, -M_PI / 2, M_PI / 2), "arc"), 100, rng));
  worst = std::max(worst, worst_rel_error(PathCurve(geo::make_arc({0, 0}, 80, 0.3, 2.9), "arc"), 100, rng));
  std::printf("random NURBS (degree 1..7), line, arcs: worst |s(u_at(s)) - s| / total = %.3e\n", worst);
  EXPECT_LE(worst, 2e-12);
}

TEST(ArcTable, NearCuspFallsBackAndStaysAccurate) {
  // A cubic Bezier whose speed nearly vanishes at t = 1/2 (a near-cusp): the
  // series cannot converge there at any reasonable depth, so those pieces are
  // answered by the library's adaptive path, and the bound still holds.
  Eigen::MatrixXd ctrl(4, 2);
  ctrl << 0, 0, 1, 1, 1e-7, 1, 1, 0;
  const PathCurve pc(geo::make_bezier(ctrl), "near-cusp");
  std::mt19937_64 rng(13);
  const double w = worst_rel_error(pc, 400, rng);
  std::printf("near-cusp: %zu pieces, %zu fallback spans, worst %.3e\n", pc.table->pieces(), pc.table->fallback_spans(), w);
  EXPECT_LE(w, 2e-12);
}
