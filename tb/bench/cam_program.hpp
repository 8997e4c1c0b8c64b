// A CAM-like G-code program of a given number of lines, for the planning
// benchmarks and the streaming tests: a zig-zag surface finish of short G1
// segments over a smooth surface (small direction changes at every vertex),
// the passes joined by semicircular G2/G3 u-turns in the XY plane.
//
//   surface   z = 1.5 sin(pi x / 100) (0.6 + 0.4 cos(2 pi y / 60)) mm, zero at
//             both pass ends so that the u-turns stay in the plane z = 0;
//   passes    x from 0 to 100 mm and back, 200 segments of 0.5 mm, step-over
//             1 mm (u-turn radius 0.5 mm), feed F1500 (25 mm/s);
//   program   G21 G90 G17 G64 P0.05, a rapid to the start, the passes, a
//             rapid retract, M2. `lines` counts the program's lines (the
//             passes are cut short to make the count exact).
#pragma once
#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>

namespace traj::bench {

struct CamProgram {
  int segments_per_pass = 200;
  double pass_length = 100;  // mm
  double stepover = 1;       // mm
  double feed = 1500;        // mm/min
  double tolerance = 0.05;   // G64 P, mm
};

inline double cam_surface(double x, double y) {
  const double pi = 3.14159265358979323846;
  return 1.5 * std::sin(pi * x / 100) * (0.6 + 0.4 * std::cos(2 * pi * y / 60));
}

// Writes a program of exactly `lines` lines (at least 8).
inline void write_cam_program(std::ostream& o, long lines, const CamProgram& c = {}) {
  char b[160];
  auto put = [&](const char* s) {
    o << s << '\n';
    --lines;
  };
  std::snprintf(b, sizeof b, "G21 G90 G17 G64 P%g", c.tolerance);
  put("%");
  put("(zig-zag surface finish, short G1 segments, G2/G3 u-turns)");
  put(b);
  put("G0 Z5");
  std::snprintf(b, sizeof b, "G1 Z0 F%g", c.feed);
  put(b);
  // the rest: G0 Z5, M2, % (3 lines)
  const double dx = c.pass_length / c.segments_per_pass;
  double y = 0;
  int dir = 1;
  int i = 0;  // vertex index along the pass
  while (lines > 3) {
    if (i < c.segments_per_pass) {
      ++i;
      const double x = dir > 0 ? i * dx : c.pass_length - i * dx;
      std::snprintf(b, sizeof b, "G1 X%.4f Y%.4f Z%.4f", x, y, cam_surface(x, y));
      put(b);
    } else {  // u-turn: counter-clockwise at x = L going +x, clockwise at x = 0 going -x
      const double r = c.stepover / 2;
      std::snprintf(b, sizeof b, "%s X%.4f Y%.4f I0 J%.4f", dir > 0 ? "G3" : "G2",
                    dir > 0 ? c.pass_length : 0.0, y + c.stepover, r);
      put(b);
      y += c.stepover;
      dir = -dir;
      i = 0;
    }
  }
  put("G0 Z5");
  put("M2");
  put("%");
}

}  // namespace traj::bench
