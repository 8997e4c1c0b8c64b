// SPDX-License-Identifier: Apache-2.0
// Cost and accuracy of ArcLength::advance (the planner's per-tick arc-length inverse) on the butterfly.
// For each step ds: `advance(u, ds)` from N random start parameters (uniform on the curve, fixed seed)
// and from N start parameters within +-2e-3 of the two cusps (u = 0.2563501, 0.7436435), timed (best
// of R repetitions, us per call) and counted (speed evaluations per call); then every step is checked
// against an independent long-double composite 20-point Gauss-Legendre reference (arclength_ref.hpp):
//   rel = |L_ref(u0, u) - ds| / ds,   ulps = |L_ref(u0, u) - ds| / (|r'(u)| ulp(u))
// (ulps: the error in units of the parameter's own resolution; a step can never be more exact than
// about 0.5 ulp of u, which matters for tiny steps). A step passes if rel <= 1e-12 or ulps <= 2.
// Also a planner-like march (consecutive advances from u_begin, as sample_ticks_range does).
// Usage: bench_arclength [--short] [--rel-tol X] [--reference]   (--reference: force the adaptive path)
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "arclength_ref.hpp"
#include "geometry/geometry.hpp"

using namespace traj::geo;

namespace {

double ulp(double u) { return std::nextafter(std::abs(u), INFINITY) - std::abs(u); }

struct Acc {
  double max_rel = 0, max_ulps = 0;
  long fails = 0, checked = 0;
};

void check(const Curve& c, const ArcLength& al, double u0, double u, double ds, Acc& a, bool verbose) {
  const long double L = geotest::ref_length(c, u0, u, 8);
  const double err = static_cast<double>(std::fabs(L - static_cast<long double>(ds)));
  const double sig = al.speed(u);
  const double rel = err / ds, ulps = err / (sig * ulp(u));
  a.max_rel = std::max(a.max_rel, rel);
  a.max_ulps = std::max(a.max_ulps, ulps);
  ++a.checked;
  if (!(rel <= 1e-12 || ulps <= 2)) {
    ++a.fails;
    if (verbose && a.fails <= 5)
      std::printf("    FAIL u0=%.17g ds=%.3g u=%.17g rel=%.3e ulps=%.2f\n", u0, ds, u, rel, ulps);
  }
}

}  // namespace

int main(int argc, char** argv) {
  bool shrt = false, reference = false;
  double rel_tol = 1e-12;  // the planner's setting (planner.cpp)
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--short")) shrt = true;
    else if (!std::strcmp(argv[i], "--reference")) reference = true;
    else if (!std::strcmp(argv[i], "--rel-tol") && i + 1 < argc) rel_tol = std::atof(argv[++i]);
  }
  const BSpline b = load_curve(std::string(GEO_ASSETS_DIR) + "/butterfly_nurbs.json");
  const Curve c(b);
  ArcLength al(c, rel_tol);
#ifdef AL_HAS_FAST_PATH
  al.set_fast_path(!reference);
#else
  if (reference) std::printf("(no fast path in this build: --reference ignored)\n");
#endif
  const int N = shrt ? 400 : 4000, R = shrt ? 1 : 3, NCHK = shrt ? 200 : 2000;
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> U(c.u_begin(), c.u_end()), C(-2e-3, 2e-3);
  std::vector<double> starts_rand(N), starts_cusp(N);
  for (int i = 0; i < N; ++i) {
    starts_rand[i] = U(rng);
    starts_cusp[i] = (i % 2 ? 0.7436435 : 0.2563501) + C(rng);
  }
  std::printf("butterfly: L = %.9f mm, %zu spans, ArcLength rel_tol %.0e, %s path\n", al.total(), c.spans().size(),
              rel_tol, reference ? "reference (adaptive)" : "default");
  std::printf("%-6s %9s | %9s %8s %8s | %9s %9s %6s/%-6s\n", "starts", "ds [mm]", "us/adv", "evals", "bisect",
              "max rel", "max ulps", "fails", "chk");
  const double steps[] = {1e-7, 1e-6, 1e-4, 1e-2, 0.1, 0.25, 1.0};
  bool ok = true;
  for (int set = 0; set < 2; ++set) {
    const std::vector<double>& st = set ? starts_cusp : starts_rand;
    for (double ds : steps) {
      std::vector<double> out(N);
      double best = 1e300;
      for (int r = 0; r < R; ++r) {
        al.reset_stats();
        const auto t0 = std::chrono::steady_clock::now();
        for (int i = 0; i < N; ++i) out[i] = al.advance(st[i], ds);
        const auto t1 = std::chrono::steady_clock::now();
        best = std::min(best, std::chrono::duration<double, std::micro>(t1 - t0).count() / N);
      }
      const double evals = static_cast<double>(al.stats().integrand_evals) / N;
      const double bis = static_cast<double>(al.stats().bisections) / N;
      Acc a;
      for (int i = 0; i < NCHK && i < N; ++i) {
        if (out[i] >= c.u_end()) continue;  // ran off the curve end
        check(c, al, st[i], out[i], ds, a, true);
      }
      ok = ok && a.fails == 0;
      std::printf("%-6s %9.2g | %9.3f %8.1f %8.2f | %9.2e %9.2f %6ld/%-6ld\n", set ? "cusps" : "random", ds, best, evals,
                  bis, a.max_rel, a.max_ulps, a.fails, a.checked);
    }
  }
  // Planner-like march: consecutive advances from u_begin with a constant step.
  std::printf("\nmarch from u_begin (consecutive advances, like sample_ticks_range):\n");
  for (double ds : {1e-4, 0.05, 0.25}) {
    const long n = std::min<long>(shrt ? 2000 : 40000, static_cast<long>(al.total() / ds));
    std::vector<double> us(n + 1);
    al.reset_stats();
    const auto t0 = std::chrono::steady_clock::now();
    us[0] = c.u_begin();
    for (long k = 0; k < n; ++k) us[k + 1] = al.advance(us[k], ds);
    const auto t1 = std::chrono::steady_clock::now();
    Acc a;
    const long stride = std::max<long>(1, n / NCHK);
    for (long k = 0; k < n; k += stride) check(c, al, us[k], us[k + 1], ds, a, true);
    ok = ok && a.fails == 0;
    std::printf("  ds %7.0e: %ld steps, %.3f us/adv, %.1f evals/adv, max rel %.2e, max ulps %.2f, fails %ld/%ld\n", ds, n,
                std::chrono::duration<double, std::micro>(t1 - t0).count() / n,
                static_cast<double>(al.stats().integrand_evals) / n, a.max_rel, a.max_ulps, a.fails, a.checked);
  }
  std::printf("%s\n", ok ? "all steps within 1e-12 relative or 2 ulp of u" : "SOME STEPS FAILED");
  return ok ? 0 : 1;
}
