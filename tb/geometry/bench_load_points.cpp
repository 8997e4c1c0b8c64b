// Loading time of a cubic B-spline against its number of control points: Curve (Bezier pieces, power
// basis) and ArcLength, the work of loading a path. Usage: bench_load_points [max_points] (default 1e6).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "geometry/geometry.hpp"

using namespace traj::geo;

int main(int argc, char** argv) {
  const long max_n = argc > 1 ? std::atol(argv[1]) : 1000000;
  std::printf("%10s %10s %10s %12s\n", "points", "curve_s", "arclen_s", "us_per_point");
  for (long n = 1000; n <= max_n; n *= 10) {
    const int p = 3;
    BSpline b;
    b.degree = p;
    b.ctrl.resize(n, 2);
    for (long i = 0; i < n; ++i) b.ctrl.row(i) << i * 0.1, std::sin(i * 0.01);
    b.knots.resize(n + p + 1);
    for (long i = 0; i < b.knots.size(); ++i) b.knots[i] = static_cast<double>(std::clamp<long>(i - p, 0, n - p));
    const auto t0 = std::chrono::steady_clock::now();
    const Curve c(b);
    const auto t1 = std::chrono::steady_clock::now();
    const ArcLength al(c);
    const auto t2 = std::chrono::steady_clock::now();
    const double cs = std::chrono::duration<double>(t1 - t0).count(), as = std::chrono::duration<double>(t2 - t1).count();
    std::printf("%10ld %10.3f %10.3f %12.2f\n", n, cs, as, 1e6 * (cs + as) / n);
  }
}
