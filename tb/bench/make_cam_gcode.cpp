// Writes the benchmark's CAM-like G-code program (cam_program.hpp).
//   usage: make_cam_gcode LINES out.ngc
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "cam_program.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_cam_gcode LINES out.ngc\n");
    return 2;
  }
  const long lines = std::strtol(argv[1], nullptr, 10);
  if (lines < 8) {
    std::fprintf(stderr, "make_cam_gcode: at least 8 lines\n");
    return 2;
  }
  std::ofstream o(argv[2]);
  traj::bench::write_cam_program(o, lines);
  return o ? 0 : 1;
}
