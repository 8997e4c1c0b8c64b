// Soak run of the power-basis validation: 10^6 random parameters (default) over random splines of every
// degree 1..7 (1..4 axes, non-uniform knots with repeats; non-rational ones also against Eigen's
// Splines module, rational ones against the Cox-de Boor quotient), derivatives 0..3. Prints the
// maximum error relative to the bounding box of the k-th derivative's control points (non-rational) or
// to max |C^(k)| (rational). Exit status 1 if any exceeds 1e-12.
// Usage: bench_power_soak [total_points] [seed]
#include <cstdio>
#include <cstdlib>

#include "power_compare.hpp"

int main(int argc, char** argv) {
  const long long total = argc > 1 ? std::atoll(argv[1]) : 1000000;
  const unsigned seed = argc > 2 ? static_cast<unsigned>(std::atoll(argv[2])) : 20240604u;
  const long long per_curve = 500;
  std::printf("power basis vs Cox-de Boor (+ Eigen Splines for non-rational): %lld points, seed %u\n", total, seed);
  std::printf("%6s %9s %9s | %10s %10s %10s %10s\n", "degree", "rational", "points", "d0", "d1", "d2", "d3");
  bool ok = true;
  for (int p = 1; p <= 7; ++p)
    for (int rat = 0; rat <= 1; ++rat) {
      std::mt19937_64 rng(seed + 100u * p + rat);
      powercmp::ErrStats e;
      long long pts = 0;
      const long long want = total / 14;
      for (int rep = 0; pts < want; ++rep) {
        const auto rs = geotest::random_spline(rng, p, 1 + rep % 4, p + 1 + static_cast<int>(rng() % 12), rat == 1,
                                               rep % 5 != 4);
        powercmp::compare_one(rs, static_cast<int>(per_curve), rng, e, rat == 0 && rep % 5 != 4);
        pts += per_curve;
      }
      std::printf("%6d %9s %9lld | %10.2e %10.2e %10.2e %10.2e\n", p, rat ? "yes" : "no", pts, e.max_rel[0], e.max_rel[1],
                  e.max_rel[2], e.max_rel[3]);
      for (double v : e.max_rel) ok = ok && v <= 1e-12;
    }
  std::printf("%s\n", ok ? "all within 1e-12" : "FAILED: some error above 1e-12");
  return ok ? 0 : 1;
}
