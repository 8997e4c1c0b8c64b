// SPDX-License-Identifier: Apache-2.0
// Soak run of the power-basis validation: 10^6 random parameters (default) over random splines of every
// accepted degree (non-rational 1..kMaxDegree, rational 1..kMaxDegreeRational; 1..4 axes, non-uniform
// knots with repeats, some unclamped; non-rational ones also against Eigen's Splines module, rational
// ones against the Cox-de Boor quotient, both references in long double), derivatives 0..3. Prints the
// maximum error relative to the bounding-box diagonal of the k-th hodograph's control points
// (non-rational; rational positions: of the control points) or to max |C^(k)| (rational derivatives).
// Exit status 1 if any exceeds 1e-12.
// --beyond: the same measurement for degrees above the caps (non-rational kMaxDegree+1..24, rational
// kMaxDegreeRational+1..16; curves built with Curve's max_degree override, which production code never
// uses): the figures that justify the caps. Informational, no exit status.
// Usage: bench_power_soak [total_points] [seed] [--beyond]
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <utility>
#include <vector>

#include "geometry/bspline.hpp"
#include "power_compare.hpp"

namespace {

bool run(const std::vector<std::pair<int, int>>& configs, long long total, unsigned seed, int max_degree) {
  const long long per_curve = 500;
  std::printf("%6s %9s %9s | %10s %10s %10s %10s\n", "degree", "rational", "points", "d0", "d1", "d2", "d3");
  bool ok = true;
  for (const auto& [p, rat] : configs) {
    std::mt19937_64 rng(seed + 100u * p + rat);
    powercmp::ErrStats e;
    long long pts = 0;
    const long long want = total / static_cast<long long>(configs.size());
    for (int rep = 0; pts < want; ++rep) {
      const auto rs = geotest::random_spline(rng, p, 1 + rep % 4, p + 1 + static_cast<int>(rng() % 12), rat == 1,
                                             rep % 5 != 4);
      powercmp::compare_one(rs, static_cast<int>(per_curve), rng, e, rat == 0 && rep % 5 != 4, max_degree);
      pts += per_curve;
    }
    std::printf("%6d %9s %9lld | %10.2e %10.2e %10.2e %10.2e\n", p, rat ? "yes" : "no", pts, e.max_rel[0], e.max_rel[1],
                e.max_rel[2], e.max_rel[3]);
    std::fflush(stdout);
    for (double v : e.max_rel) ok = ok && v <= 1e-12;
  }
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  long long total = 1000000;
  unsigned seed = 20240604u;
  bool beyond = false;
  int pos = 0;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--beyond")) beyond = true;
    else if (pos++ == 0) total = std::atoll(argv[i]);
    else seed = static_cast<unsigned>(std::atoll(argv[i]));
  }
  using traj::geo::kMaxDegree;
  using traj::geo::kMaxDegreeRational;
  std::vector<std::pair<int, int>> configs;
  if (!beyond) {
    for (int p = 1; p <= kMaxDegree; ++p) {
      configs.push_back({p, 0});
      if (p <= kMaxDegreeRational) configs.push_back({p, 1});
    }
    std::printf("power basis vs Cox-de Boor (+ Eigen Splines for non-rational): %lld points, seed %u\n", total, seed);
    const bool ok = run(configs, total, seed, 0);
    std::printf("%s\n", ok ? "all within 1e-12" : "FAILED: some error above 1e-12");
    return ok ? 0 : 1;
  }
  for (int p = kMaxDegree + 1; p <= 24; ++p) configs.push_back({p, 0});
  for (int p = kMaxDegreeRational + 1; p <= 16; ++p) configs.push_back({p, 1});
  std::printf("BEYOND THE CAPS (degree > %d, rational > %d; not accepted by validate): %lld points, seed %u\n", kMaxDegree,
              kMaxDegreeRational, total, seed);
  const bool ok = run(configs, total, seed, 24);
  std::printf("%s\n", ok ? "all within 1e-12" : "some error above 1e-12 (why the caps are where they are)");
  return 0;
}
