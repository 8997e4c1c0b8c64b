// SPDX-License-Identifier: Apache-2.0
// Feed fluctuation of four interpolators on [ARC]'s three curves and on the butterfly.
//   fluctuation_k = (true arc length between consecutive samples) / (commanded feed * period) - 1,
// the true arc length by adaptive Gauss-Legendre (rel_tol 1e-14) between the consecutive parameters.
// The last, partial step of the Taylor interpolators and of the project's method is left out.
// [ARC]'s curves: n = 20 steps per Bezier segment as in the paper (the nominal step is L / n_total,
// so feed * period = L / n_total); butterfly: 50 and 100 mm/s, period 1 ms.
// Usage: bench_reparam [--short]   (--short: [ARC] curves and butterfly at 100 mm/s only)
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

#include "geometry/geometry.hpp"
#include "paper_curves.hpp"

using namespace traj::geo;

namespace {

void row(const char* method, const Fluctuation& f, const char* note = "") {
  std::printf("  %-34s %7d %+11.3e %+11.3e %10.3e %9.5f %s\n", method, f.steps, f.max, f.min, f.rms, f.ratio, note);
}

void run(const BSpline& b, double feed, double period, int arc_n_per_segment) {
  const Curve c(b);
  const ArcLength al(c);
  const double L = al.total();
  double step = feed * period;
  if (arc_n_per_segment > 0) {  // [ARC]'s own resolution
    step = L / (arc_n_per_segment * static_cast<double>(c.spans().size()));
    feed = step / period;
  }
  std::printf("\n%s: L = %.6f mm, feed %.3f mm/s, period %.0f ms, step %.6f mm, %zu span(s)\n", b.name.c_str(), L, feed,
              period * 1e3, step, c.spans().size());
  std::printf("  %-34s %7s %11s %11s %10s %9s\n", "method", "steps", "max", "min", "rms", "max/min");
  row("uniform parameter (no levelling)", feed_fluctuation(al, arc_paper_reparam_spline(c, al, step, 0), step, false),
      "([ARC] unlevelled)");
  row("Taylor 1st order", feed_fluctuation(al, taylor_interpolate(c, feed, period, 1), step, true));
  row("Taylor 2nd order", feed_fluctuation(al, taylor_interpolate(c, feed, period, 2), step, true));
  row("[ARC] 1 pass", feed_fluctuation(al, arc_paper_reparam_spline(c, al, step, 1), step, false));
  row("[ARC] 3 passes (cascaded)", feed_fluctuation(al, arc_paper_reparam_spline(c, al, step, 3), step, false));
  row("[ARC] 10 passes (cascaded)", feed_fluctuation(al, arc_paper_reparam_spline(c, al, step, 10), step, false));
  al.reset_stats();
  const auto t0 = std::chrono::steady_clock::now();
  const auto u = equal_arclength_params(al, step);
  const auto t1 = std::chrono::steady_clock::now();
  const long long ev = al.stats().integrand_evals;
  char note[160];
  std::snprintf(note, sizeof note, "(%lld speed evals, %.2f per step, %.1f ms)", ev, double(ev) / (u.size() - 1),
                std::chrono::duration<double, std::milli>(t1 - t0).count());
  row("project: GL arc length + Newton", feed_fluctuation(al, u, step, true), note);
}

// Chord-error-limited feed (the published butterfly set-up: feed F, chord error delta): per tick the
// commanded feed is V_k = min(F, (2/T) sqrt(rho^2 - (rho - delta)^2)), rho = 1/kappa(u_k). Fluctuation
// is then the true step over V_k T. [ARC] (fixed equal steps) does not apply here.
void run_chord_limited(const BSpline& b, double F, double T, double delta) {
  const Curve c(b);
  const ArcLength al(c);
  std::printf("\n%s, chord-error-limited feed: F = %.0f mm/s, T = %.0f ms, chord error %.0e mm\n", b.name.c_str(), F, T * 1e3,
              delta);
  std::printf("  %-34s %7s %11s %11s %10s %9s\n", "method", "steps", "max", "min", "rms", "max/min");
  auto vcmd = [&](double u) {
    const double k = curvature(c, u);
    if (k <= 0) return F;
    const double rho = 1 / k;
    return rho > delta ? std::min(F, 2 / T * std::sqrt(rho * rho - (rho - delta) * (rho - delta))) : F;
  };
  for (int method = 0; method < 3; ++method) {
    std::vector<double> u{c.u_begin()}, nominal;
    const int dim = c.dim();
    std::vector<double> buf(3 * dim);
    while (true) {
      const double V = vcmd(u.back()), ds = V * T;
      double next;
      if (method < 2) {
        c.eval(u.back(), 2, buf.data());
        double v2 = 0, d12 = 0;
        for (int d = 0; d < dim; ++d) {
          v2 += buf[dim + d] * buf[dim + d];
          d12 += buf[dim + d] * buf[2 * dim + d];
        }
        next = u.back() + ds / std::sqrt(v2) - (method == 1 ? ds * ds * d12 / (2 * v2 * v2) : 0.0);
      } else {
        next = al.advance(u.back(), ds, -1);
      }
      if (next >= c.u_end()) break;
      u.push_back(next);
      nominal.push_back(ds);
    }
    std::vector<double> e;
    Fluctuation f;
    f.max = -1e300;
    f.min = 1e300;
    double sq = 0, mx = 0, mn = 1e300;
    for (size_t k = 0; k + 1 < u.size(); ++k) {
      const double r = al.length(u[k], u[k + 1]) / nominal[k] - 1;
      f.max = std::max(f.max, r);
      f.min = std::min(f.min, r);
      sq += r * r;
      mx = std::max(mx, r + 1);
      mn = std::min(mn, r + 1);
    }
    f.steps = static_cast<int>(u.size() - 1);
    f.rms = std::sqrt(sq / f.steps);
    f.ratio = mx / mn;
    row(method == 0 ? "Taylor 1st order" : method == 1 ? "Taylor 2nd order" : "project: GL arc length + Newton", f,
        method == 2 ? "" : "");
  }
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--short") == 0;
  std::printf("Feed fluctuation = true arc length per sample / (feed * period) - 1 (fractions, not percent); max/min = ratio of the\n"
              "largest to the smallest true step ([ARC]'s '1 : x' figure is of this kind, with chords).\n");
  try {
    run(seedcurves::curve1(), 0, 1e-3, 20);
    run(seedcurves::curve2(), 0, 1e-3, 20);
    run(seedcurves::curve3(), 0, 1e-3, 20);
    const BSpline bf = load_curve(std::string(GEO_ASSETS_DIR) + "/butterfly_nurbs.json");
    if (!quick) run(bf, 50, 1e-3, 0);
    run(bf, 100, 1e-3, 0);
    if (!quick) run_chord_limited(bf, 50, 1e-3, 1e-3);
    run_chord_limited(bf, 100, 1e-3, 1e-3);
  } catch (const GeometryError& e) {
    std::fprintf(stderr, "bench_reparam: %s\n", e.what());
    return 1;
  }
  return 0;
}
