// SPDX-License-Identifier: Apache-2.0
// ArcLength::advance fast path (Taylor guess, Gauss-Kronrod 7/15 with error estimate, Newton with
// 2-point Gauss corrections) against independent references:
//   * a long-double composite 20-point Gauss-Legendre length of the returned step (arclength_ref.hpp,
//     speed from Curve::eval_span, not ArcLength's kernel), whose own convergence is checked (16 vs 32
//     panels);
//   * the adaptive Gauss-Legendre path forced (set_fast_path(false)).
// Requirement for every step: |L_ref(u0, u) - ds| <= 1e-12 ds (advance's documented stop), or, where
// that is below the parameter's resolution, <= 2 |r'(u)| ulp(u) (the adaptive path stops at a 4-ulp
// bracket; the fast path returns the nearer of its last two iterates, measured <= 0.5 ulp).
// Curves: random B-splines and NURBS of every degree 1..7 (2 and 3 axes), the butterfly near its cusps
// (u = 0.2563501, 0.7436435); steps log-uniform 1e-7 .. 1 unit, starts random, just before span ends
// (steps that cross spans) and near the curve end (steps that run off it).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "arclength_ref.hpp"
#include "geometry/geometry.hpp"
#include "test_util.hpp"

using namespace traj::geo;

namespace {

double ulp(double u) { return std::nextafter(std::abs(u), INFINITY) - std::abs(u); }

struct Worst {
  double rel = 0, ulps = 0;
  long n = 0;
};

// Checks one advance(u0, ds) = u against the long-double reference; returns false on failure.
bool check_step(const Curve& c, const ArcLength& al, double u0, double ds, double u, Worst& w, const char* what) {
  const double ue = c.u_end();
  const long double L = geotest::ref_length(c, u0, u, 16);
  const double err = static_cast<double>(std::fabs(L - static_cast<long double>(ds)));
  const double res = al.speed(u) * ulp(u);  // length resolution of the parameter at u
  ++w.n;
  if (u >= ue && L <= static_cast<long double>(ds) * (1 + 1e-12L) + res) return true;  // ran off the end
  w.rel = std::max(w.rel, err / ds);
  w.ulps = std::max(w.ulps, err / res);
  const bool ok = err <= 1e-12 * ds || err <= 2 * res;
  EXPECT_TRUE(ok) << what << ": u0=" << u0 << " ds=" << ds << " u=" << u << " rel err " << err / ds
                  << " (" << err / res << " ulp of u)";
  return ok;
}

const Curve& butterfly() {
  static const Curve c(load_curve(geotest::asset("butterfly_nurbs.json")), "butterfly_nurbs.json");
  return c;
}

}  // namespace

// The reference itself: 16 and 32 panels agree to ~1e-15 relative on butterfly steps near the cusps
// (the hardest integrand of the test set) and on random curves.
TEST(GeometryArcLengthFast, ReferenceConverged) {
  const Curve& c = butterfly();
  double worst = 0;
  for (double uc : {0.2563501, 0.7436435})
    for (double du : {1e-9, 1e-6, 1e-4, 1e-3, 3e-3}) {
      const long double a = geotest::ref_length(c, uc - du, uc + du, 16), b = geotest::ref_length(c, uc - du, uc + du, 32);
      worst = std::max(worst, static_cast<double>(std::fabs(a - b) / b));
    }
  std::printf("reference 16 vs 32 panels near the cusps: max rel diff %.2e\n", worst);
  EXPECT_LT(worst, 1e-14);
}

TEST(GeometryArcLengthFast, RandomCurvesEveryDegree) {
  std::mt19937_64 rng(geotest::seed() + 41);
  std::uniform_real_distribution<double> U01(0, 1);
  long fast = 0, fallback = 0;
  for (int p = 1; p <= 7; ++p)
    for (int rat = 0; rat < 2; ++rat) {
      Worst w;
      for (int rep = 0; rep < 3; ++rep) {
        const auto rs = geotest::random_spline(rng, p, 2 + rep % 2, p + 1 + static_cast<int>(rng() % 8), rat == 1);
        const Curve c(rs.lib);
        const ArcLength al(c);
        ArcLength ref(c);
        ref.set_fast_path(false);
        const double ub = c.u_begin(), ue = c.u_end();
        for (int t = 0; t < 150; ++t) {
          const double ds = std::pow(10.0, -7 + 7 * U01(rng));  // 1e-7 .. 1 unit
          double u0;
          switch (t % 3) {
            case 0: u0 = ub + (ue - ub) * U01(rng); break;
            case 1: {  // just before a span end: the step may cross it
              const auto& sp = c.spans()[rng() % c.spans().size()];
              u0 = sp.u1 - (sp.u1 - sp.u0) * std::pow(10.0, -9 * U01(rng));
              break;
            }
            default: u0 = ue - (ue - ub) * std::pow(10.0, -8 * U01(rng)); break;  // near the end
          }
          u0 = std::clamp(u0, ub, ue);
          const double u = al.advance(u0, ds);
          check_step(c, al, u0, ds, u, w, "fast");
          // the forced adaptive path agrees to its own (4-ulp bracket) accuracy
          const double ur = ref.advance(u0, ds);
          const double sig = al.speed(u);
          EXPECT_LE(std::abs(ur - u) * sig, 2e-12 * ds + 10 * sig * ulp(u)) << "p=" << p << " u0=" << u0 << " ds=" << ds;
        }
        fast += al.stats().fast_steps;
        fallback += al.stats().fast_fallbacks;
      }
      std::printf("degree %d %-12s %4ld steps: max rel err %.2e, max %.2f ulp of u\n", p,
                  rat ? "rational" : "non-rational", w.n, w.rel, w.ulps);
    }
  std::printf("fast path: %ld steps, %ld fallbacks to the adaptive path\n", fast, fallback);
  EXPECT_GT(fast, 20 * fallback);  // the fast path is the normal case
}

TEST(GeometryArcLengthFast, ButterflyNearCusps) {
  const Curve& c = butterfly();
  const ArcLength al(c, 1e-12);  // the planner's setting
  const ArcLength al14(c);       // the default
  std::mt19937_64 rng(geotest::seed() + 42);
  std::uniform_real_distribution<double> U01(0, 1);
  Worst w;
  for (double uc : {0.2563501, 0.7436435})
    for (int t = 0; t < 400; ++t) {
      const double ds = std::pow(10.0, -7 + 7 * U01(rng));
      const double u0 = t == 0 ? uc : uc + (U01(rng) - 0.5) * (t % 2 ? 4e-3 : 4e-5);
      check_step(c, al, u0, ds, al.advance(u0, ds), w, "butterfly rel_tol 1e-12");
      check_step(c, al14, u0, ds, al14.advance(u0, ds), w, "butterfly rel_tol 1e-14");
      // advance_from: the speed and its u-derivatives at u0 given by the caller (the planner's
      // march passes those of its frame), here from r', r'', r''' directly
      double b[8];
      c.eval(u0, 3, b);
      const double s11 = b[2] * b[2] + b[3] * b[3], s12 = b[2] * b[4] + b[3] * b[5];
      const double s22 = b[4] * b[4] + b[5] * b[5], s13 = b[2] * b[6] + b[3] * b[7];
      const double sig[3] = {std::sqrt(s11), s12 / std::sqrt(s11), (s22 + s13 - s12 * s12 / s11) / std::sqrt(s11)};
      check_step(c, al, u0, ds, al.advance_from(u0, sig, ds), w, "butterfly advance_from");
    }
  std::printf("butterfly near the cusps: %ld steps, max rel err %.2e, max %.2f ulp of u; fast %lld, fallbacks %lld\n",
              w.n, w.rel, w.ulps, al.stats().fast_steps, al.stats().fast_fallbacks);
}

TEST(GeometryArcLengthFast, ButterflyMarchSumsToLength) {
  // Planner-like march with 0.05 mm steps: every step checked, and the sum equals s(u_n).
  const Curve& c = butterfly();
  const ArcLength al(c, 1e-12);
  Worst w;
  double u = c.u_begin();
  const double ds = 0.05;
  long n = 0;
  while (true) {
    const double un = al.advance(u, ds);
    if (un >= c.u_end()) break;
    if (n % 7 == 0) check_step(c, al, u, ds, un, w, "march");
    u = un;
    ++n;
  }
  EXPECT_NEAR(al.s(u), n * ds, 1e-12 * al.total());
  std::printf("march: %ld steps of %.2f mm, max rel err %.2e, fallbacks %lld\n", n, ds, w.rel, al.stats().fast_fallbacks);
  EXPECT_EQ(al.stats().fast_fallbacks, 0);
}

TEST(GeometryArcLengthFast, UAtAgreesWithAdaptivePath) {
  const Curve& c = butterfly();
  const ArcLength al(c);
  ArcLength ref(c);
  ref.set_fast_path(false);
  std::mt19937_64 rng(geotest::seed() + 43);
  std::uniform_real_distribution<double> S(0, al.total());
  for (int t = 0; t < 300; ++t) {
    const double s = S(rng);
    const double u = al.u_at(s), ur = ref.u_at(s);
    EXPECT_LE(std::abs(u - ur) * al.speed(u), 3e-14 * al.total()) << "s=" << s;
    EXPECT_NEAR(al.s(u), s, 2e-14 * al.total());
  }
}
