// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <string>

namespace traj::app {

// The columns of the demos' sample CSV (tb/app/check_demo_csv.cmake checks them).
inline constexpr const char* kDemoCsvHeader =
    "tick,t_s,segment,x_lsb,y_lsb,z_lsb,x_mm,y_mm,z_mm,x_ref_mm,y_ref_mm,z_ref_mm,err_lsb\n";

struct DemoOptions {
  double radius = 50.0;   // mm
  double feed = 50.0;     // mm/s
  double period = 1e-3;   // s
  int pieces = 1;         // time segments per arc
  int frac_bits = 16;     // output LSB = 2^-16 mm
  std::string csv = "out/demo_samples.csv";
  int tick_gap = 0;       // clock cycles between ticks (0: 64 for the FD engine, the core's
                          // minimum tick spacing for --engine bcu|mixed)
  std::string engine = "fd";  // fd: traj_fd_engine (the first demo); bcu | mixed: traj_core
  std::string stream;     // bcu | mixed: the segment stream written (default out/demo_<engine>.trj)
};

int run_demo(const DemoOptions& opt);
// --engine bcu | mixed (core_demo.cpp): the circle as BCU segments (K = 2^d
// ticks per arc), or arcs alternating FD / BCU / FD, chained exactly
// (traj::bcu::MixedChain), written as a segment stream with a BCU format, read back
// and run through the Verilated traj_core.
int run_core_demo(const DemoOptions& opt);

// trajcore spline (spline_cmd.cpp): [BCU]'s C1 interpolating cubic Bezier
// spline through the points of a JSON file, compiled for traj_core.
struct SplineOptions {
  std::string input;              // {"points": [[x, y(, z)], ...]}
  std::string output = "out/spline.trj";
  double lambda = 1.0 / 6.0;      // tension (eq. 9); mu = lambda gives C1
  double mu = -1;                 // < 0: = lambda
  double feed = 50;               // units/s: upper bound on the speed (chooses d per segment)
  double period = 1e-3;           // s
  int depth = -1;                 // >= 0: this d for every segment instead
  int frac_bits = 16;
  std::string engine = "bcu";     // bcu | mixed (odd segments as FD)
};
int run_spline(const SplineOptions& opt);

}  // namespace traj::app
