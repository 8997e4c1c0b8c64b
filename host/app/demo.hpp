#pragma once
#include <string>

namespace traj::app {

struct DemoOptions {
  double radius = 50.0;   // mm
  double feed = 50.0;     // mm/s
  double period = 1e-3;   // s
  int pieces = 1;         // time segments per arc
  int frac_bits = 16;     // output LSB = 2^-16 mm
  std::string csv = "out/demo_samples.csv";
  int tick_gap = 64;      // clock cycles between ticks
};

int run_demo(const DemoOptions& opt);

}  // namespace traj::app
