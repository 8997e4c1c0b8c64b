// SPDX-License-Identifier: Apache-2.0
// The butterfly planned below the limits (the headroom time scaling needs)
// at a 20 us engine tick, its engine samples (the host's exact prediction)
// and its per-axis peaks: the input of the time-scaling tests and plot.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "input/path_json.hpp"
#include "job/job.hpp"
#include "report/report.hpp"
#include "timescale/time_scale.hpp"

namespace traj {

// The butterfly planned below the limits at a fine engine tick, then played
// through the time-scale reference at a 1 ms servo tick.
struct Butterfly {
  job::JobConfig real;              // the machine's limits
  std::vector<int64_t> samples;     // engine samples, 3 per tick
  uint64_t n = 0;                   // engine samples
  double lsb = 0, h = 0;
  std::vector<timescale::AxisKinematics> peaks, limits;
};

inline const Butterfly& butterfly() {
  static const Butterfly b = [] {
    Butterfly r;
    const plan::Path p = input::load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json");
    job::JobConfig cfg;
    r.h = 20e-6;
    cfg.machine.period = r.h;
    // headroom for time scaling: the plan keeps 70 % of the acceleration and
    // 40 % of the jerk limits (the ramp bounds are derived from what is left)
    for (int a = 0; a < 3; ++a) {
      cfg.limits.a_axis[a] *= 0.7;
      cfg.limits.j_axis[a] *= 0.4;
    }
    cfg.limits.a_tan *= 0.7;
    cfg.limits.a_cen *= 0.7;
    cfg.limits.j_tan *= 0.4;
    cfg.limits.j_cen *= 0.4;
    const job::JobResult res = job::run_job(p, cfg);
    const report::Samples s = report::predicted_samples(res);
    r.lsb = std::ldexp(1.0, -res.header.frac_bits);
    r.n = s.v.size();
    for (const auto& v : s.v)
      for (int a = 0; a < 3; ++a) r.samples.push_back(v[a]);
    // the plan's peaks per axis: the engine samples' differences 5 ticks
    // (100 us) apart, with a 2 % margin for the maxima between them (at h
    // itself the samples' rounding and exact-joint offsets, ~1e3 LSB, would
    // swamp the third differences)
    r.peaks.assign(3, {});
    const uint64_t st = 5;
    const double hs = st * r.h;
    for (uint64_t i = 3 * st; i < r.n; ++i)
      for (int a = 0; a < 3; ++a) {
        auto x = [&](uint64_t k) { return static_cast<double>(r.samples[k * 3 + a]) * r.lsb; };
        const double d1 = x(i) - x(i - st), d2 = d1 - (x(i - st) - x(i - 2 * st)),
                     d3 = d2 - (x(i - st) - 2 * x(i - 2 * st) + x(i - 3 * st));
        r.peaks[a].v = std::max(r.peaks[a].v, 1.02 * std::fabs(d1) / hs);
        r.peaks[a].a = std::max(r.peaks[a].a, 1.02 * std::fabs(d2) / (hs * hs));
        r.peaks[a].j = std::max(r.peaks[a].j, 1.02 * std::fabs(d3) / (hs * hs * hs));
      }
    for (int a = 0; a < 3; ++a) r.limits.push_back({r.real.limits.v_axis[a], r.real.limits.a_axis[a], r.real.limits.j_axis[a]});
    for (int a = 0; a < 3; ++a)
      std::printf("  plan axis %d: v %.1f a %.0f j %.0f (limits %.0f %.0f %.0f)\n", a, r.peaks[a].v, r.peaks[a].a,
                  r.peaks[a].j, r.limits[a].v, r.limits[a].a, r.limits[a].j);
    return r;
  }();
  return b;
}

}  // namespace traj
