// SPDX-License-Identifier: Apache-2.0
// The butterfly re-timed by a feed hold and overrides through the
// time-scale reference (host/timescale), plotted against time: the scale s,
// the path feed of the output beside the unscaled run's, and each axis's
// acceleration and jerk from the output's sample differences with the
// limits. Usage: plot_time_scale OUT.svg (the figure in
// host/timescale/README.md).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "report/profile_svg.hpp"
#include "scaled_butterfly.hpp"
#include "timescale/time_scale.hpp"

namespace {

using namespace traj;

struct Run {
  std::vector<std::array<double, 3>> y;  // output, units
  std::vector<double> s;                 // the scale at each servo tick
};

struct Event {
  double t;        // s
  int kind;        // 0 hold, 1 resume, 2 override
  double value;
};

Run play(const Butterfly& bf, const timescale::IntBounds& ib, int n, const std::vector<Event>& ev) {
  timescale::TimeScaler ts(ib, n, 3);
  Run r;
  size_t next = 0;
  for (uint64_t t = 0; t < 100000; ++t) {
    const double now = static_cast<double>(t) * 1e-3;
    while (next < ev.size() && ev[next].t <= now) {
      const Event& e = ev[next++];
      if (e.kind == 0) ts.hold(true);
      if (e.kind == 1) ts.hold(false);
      if (e.kind == 2) ts.set_override(static_cast<int64_t>(std::ldexp(e.value, ib.scale_bits)));
    }
    const auto y = ts.tick(bf.samples, bf.n, true);
    r.y.push_back({y[0] * bf.lsb, y[1] * bf.lsb, y[2] * bf.lsb});
    r.s.push_back(std::ldexp(static_cast<double>(ts.s()), -ib.scale_bits));
    if (ts.engine_index() + 1 >= bf.n) break;
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: plot_time_scale OUT.svg\n");
    return 2;
  }
  const Butterfly& bf = butterfly();
  const double H = 1e-3;
  const int n = static_cast<int>(std::lround(H / bf.h));
  const timescale::OutputError err{bf.h, H, bf.lsb};
  const auto rb = timescale::derive_ramp_bounds(bf.peaks, bf.limits, 1.2, err);
  const auto ib = timescale::integer_bounds(rb, H);
  const std::vector<Event> ev = {{2.5, 0, 0}, {3.5, 1, 0}, {6.0, 2, 0.5}, {8.5, 2, 1.2}};
  const Run scaled = play(bf, ib, n, ev), plain = play(bf, ib, n, {});
  auto feed = [&](const Run& r) {
    return [&r, H](size_t k) {
      if (k == 0) return 0.0;
      double d = 0;
      for (int a = 0; a < 3; ++a) d += std::pow(r.y[k][a] - r.y[k - 1][a], 2);
      return std::sqrt(d) / H;
    };
  };
  auto diff = [&](int order, int axis) {
    return [&scaled, order, axis, H](size_t k) {
      const auto& y = scaled.y;
      if (k < 3) return 0.0;
      const double d1 = y[k][axis] - y[k - 1][axis], d2 = d1 - (y[k - 1][axis] - y[k - 2][axis]);
      const double d3 = d2 - (y[k - 1][axis] - 2 * y[k - 2][axis] + y[k - 3][axis]);
      return order == 2 ? d2 / (H * H) : d3 / (H * H * H);
    };
  };
  const double T = static_cast<double>(scaled.y.size()) * H;
  std::vector<report::Panel> panels;
  {
    report::Panel p;
    p.id = "scale";
    p.title = "time scale s (hold 2.5-3.5 s, override 50 % at 6 s, 120 % at 8.5 s)";
    p.ylabel = "s";
    p.from_zero = true;
    report::Series s{"s", "#1f77b4", 0, H, scaled.s.size(), [&](size_t k) { return scaled.s[k]; }};
    p.series.push_back(s);
    panels.push_back(p);
  }
  {
    report::Panel p;
    p.id = "feed";
    p.title = "path feed of the output";
    p.ylabel = "mm/s";
    p.from_zero = true;
    p.series.push_back({"unscaled", "#aaaaaa", 0, H, plain.y.size(), feed(plain)});
    p.series.push_back({"re-timed", "#d62728", 0, H, scaled.y.size(), feed(scaled)});
    panels.push_back(p);
  }
  const char* names[2] = {"x", "y"};
  const char* colours[2] = {"#1f77b4", "#2ca02c"};
  for (int order : {2, 3}) {
    report::Panel p;
    p.id = order == 2 ? "acc" : "jerk";
    p.title = order == 2 ? "acceleration per axis" : "jerk per axis";
    p.ylabel = order == 2 ? "mm/s²" : "mm/s³";
    const double lim = order == 2 ? bf.limits[0].a : bf.limits[0].j;
    p.limits = {{lim, "#444444"}, {-lim, "#444444"}};
    p.limit_label = "limit";
    p.limit = lim;
    for (int a = 0; a < 2; ++a) p.series.push_back({names[a], colours[a], 0, H, scaled.y.size(), diff(order, a)});
    panels.push_back(p);
  }
  char sub[256];
  std::snprintf(sub, sizeof sub,
                "butterfly planned at 70 %% of the acceleration and 40 %% of the jerk limits, engine tick 20 us, "
                "servo tick 1 ms\nramp bounds |ds/dt| <= %.2f /s, |d2s/dt2| <= %.0f /s^2 (s_max 1.2)",
                rb.rate, rb.accel);
  std::ofstream(argv[1]) << report::profile_svg("Feed hold and override by time scaling", sub, panels, 0, T);
  std::printf("wrote %s (%zu servo ticks, %.2f s; unscaled %.2f s)\n", argv[1], scaled.y.size(), T,
              static_cast<double>(plain.y.size()) * H);
  return 0;
}
