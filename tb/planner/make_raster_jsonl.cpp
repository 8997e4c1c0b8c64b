// SPDX-License-Identifier: Apache-2.0
// Writes the synthetic raster toolpath (planner/raster.hpp: straight passes
// joined by half-circle NURBS arcs) as a JSON Lines path file, one curve per
// line, for testing and measuring `trajcore plan <file>.jsonl` on large paths.
//   make_raster_jsonl <pieces> <out.jsonl> [pass step rows]
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "input/jsonl_source.hpp"
#include "input/raster.hpp"

int main(int argc, char** argv) {
  if (argc != 3 && argc != 6) {
    std::fprintf(stderr, "usage: %s <pieces> <out.jsonl> [pass step rows]\n", argv[0]);
    return 2;
  }
  const size_t pieces = std::strtoull(argv[1], nullptr, 10);
  const double pass = argc == 6 ? std::atof(argv[3]) : 20.0;
  const double step = argc == 6 ? std::atof(argv[4]) : 1.0;
  const size_t rows = argc == 6 ? std::strtoull(argv[5], nullptr, 10) : 1000;
  if (pieces == 0 || !(pass > 0) || !(step > 0) || rows == 0) {
    std::fprintf(stderr, "%s: pieces, pass, step and rows must be positive\n", argv[0]);
    return 2;
  }
  const std::string out = argv[2], tmp = out + ".tmp";
  std::ofstream o(tmp, std::ios::binary);
  if (!o) {
    std::fprintf(stderr, "%s: cannot write %s\n", argv[0], tmp.c_str());
    return 1;
  }
  o << "# trajcore raster toolpath: " << pieces << " pieces, pass " << pass << ", step " << step << ", rows " << rows
    << "\n";
  traj::input::RasterSource src(pieces, pass, step, rows);
  const size_t n = traj::input::write_jsonl(src, o);
  o.close();
  if (!o || std::rename(tmp.c_str(), out.c_str()) != 0) {
    std::fprintf(stderr, "%s: write failed: %s\n", argv[0], out.c_str());
    std::remove(tmp.c_str());
    return 1;
  }
  std::printf("%s: %zu curves\n", out.c_str(), n);
  return 0;
}
