// SPDX-License-Identifier: Apache-2.0
// Stacked panels of series against time, as SVG (the profile page of the
// report's plots, plots.cpp; also the time-scaling plot, tb/timescale).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace traj::report {

// A series against time: y(k) at t0 + k dt for k < count, computed on demand
// (no copy of the samples, whatever the length of the run).
enum class Band { kFill, kEdges };  // a min/max band: filled, or its outline only
struct Series {
  std::string label, colour;
  double t0 = 0, dt = 1;
  size_t count = 0;
  std::function<double(size_t)> y;
  double width = 1.1, opacity = 1;
  Band band = Band::kEdges;
  double fill = 0.25;  // fill opacity of a kFill band
  // indices with t in [ta, tb], widened by one on each side
  std::pair<size_t, size_t> range(double ta, double tb) const {
    if (!count) return {1, 0};
    const double a = std::floor((ta - t0) / dt) - 1, b = std::ceil((tb - t0) / dt) + 1;
    const double last = static_cast<double>(count - 1);
    return {static_cast<size_t>(std::clamp(a, 0.0, last)), static_cast<size_t>(std::clamp(b, 0.0, last))};
  }
};

struct LimitLine {
  double v;
  std::string colour;
};

struct Panel {
  std::string id, title, ylabel;
  std::vector<Series> series;
  std::string note;               // after the title ("not limited (cubic, C1 joins)")
  std::vector<LimitLine> limits;  // horizontal dashed lines
  std::string limit_label;        // legend entry for the limits ("" = none)
  bool from_zero = false;         // y range starts at 0 (speed, centripetal)
  double limit = 0;               // the limit the peaks are compared with (0: none)
  double allowance = 0;           // quantisation allowance on the output (report.txt)
};

// Stacked panels against time over [ta, tb]; every y range covers the data
// and the limits (nothing is clamped).
std::string profile_svg(const std::string& title, const std::string& subtitle, const std::vector<Panel>& panels,
                        double ta, double tb);

}  // namespace traj::report
