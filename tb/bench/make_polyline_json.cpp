// SPDX-License-Identifier: Apache-2.0
// An unblended polyline as a JSON path (one degree-1 B-spline: every
// interior knot a corner): random segments of 0.3 to 2 mm, each turning by
// up to +-1.2 rad (69 degrees) from the one before, seeded. For the repair
// rounds and planning time of corner-dense paths (host/job/README.md).
//   usage: make_polyline_json CORNERS OUT.json [seed=3]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s CORNERS OUT.json [seed=3]\n", argv[0]);
    return 2;
  }
  const long corners = std::strtol(argv[1], nullptr, 10);
  const unsigned seed = argc > 3 ? static_cast<unsigned>(std::strtoul(argv[3], nullptr, 10)) : 3u;
  if (corners < 1) {
    std::fprintf(stderr, "make_polyline_json: CORNERS must be at least 1\n");
    return 2;
  }
  std::FILE* f = std::fopen(argv[2], "w");
  if (!f) {
    std::perror(argv[2]);
    return 1;
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> turn(-1.2, 1.2), len(0.3, 2.0);
  const long n = corners + 2;  // points
  std::fprintf(f, "{\"degree\": 1,\n \"knots\": [0, 0");
  for (long i = 1; i + 1 < n; ++i) std::fprintf(f, ", %.17g", static_cast<double>(i) / static_cast<double>(n - 1));
  std::fprintf(f, ", 1, 1],\n \"control_points\": [[0, 0]");
  double x = 0, y = 0, a = 0;
  for (long i = 1; i < n; ++i) {
    a += turn(rng);
    const double l = len(rng);
    x += l * std::cos(a);
    y += l * std::sin(a);
    std::fprintf(f, ", [%.17g, %.17g]", x, y);
  }
  std::fprintf(f, "]}\n");
  if (std::fclose(f) != 0) {
    std::perror(argv[2]);
    return 1;
  }
  std::printf("%s: %ld corners\n", argv[2], corners);
  return 0;
}
