// SPDX-License-Identifier: Apache-2.0
// A path planned below the limits (the headroom time scaling needs) at a
// fine engine tick, its engine samples (the host's exact prediction) and its
// per-axis peaks: the input of the time-scaling tests, the plot and the
// simulated board's time-scaling test. The butterfly at 20 us.
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

// A path planned below the limits at a fine engine tick h (the headroom
// time scaling needs: 70 % of the acceleration and 40 % of the jerk limits),
// its engine samples (the host's exact prediction) and per-axis peaks.
struct ScaledPlan {
  job::JobConfig real;              // the machine's limits
  job::JobResult res;               // the plan (its header and records)
  std::vector<int64_t> samples;     // engine samples, 3 per tick
  uint64_t n = 0;                   // engine samples
  double lsb = 0, h = 0;
  std::vector<timescale::AxisKinematics> peaks, limits;
};
using Butterfly = ScaledPlan;

// `cfg`: the job's configuration at the machine's limits (its period is set to h).
inline ScaledPlan scaled_plan(const plan::Path& p, job::JobConfig cfg, double h, int engine_width = 0) {
  ScaledPlan r;
  r.real = cfg;
  r.h = h;
  cfg.machine.period = h;
  r.real.machine.period = h;
  if (engine_width) cfg.machine.engine_width = engine_width;
  for (int a = 0; a < 3; ++a) {
    cfg.limits.a_axis[a] *= 0.7;
    cfg.limits.j_axis[a] *= 0.4;
  }
  cfg.limits.a_tan *= 0.7;
  cfg.limits.a_cen *= 0.7;
  cfg.limits.j_tan *= 0.4;
  cfg.limits.j_cen *= 0.4;
  r.res = job::run_job(p, cfg);
  const report::Samples s = report::predicted_samples(r.res);
  r.lsb = std::ldexp(1.0, -r.res.header.frac_bits);
  r.n = s.v.size();
  for (const auto& v : s.v)
    for (int a = 0; a < 3; ++a) r.samples.push_back(v[a]);
  // the plan's peaks per axis: the engine samples' differences st ticks
  // (at least 100 us) apart, with a 2 % margin for the maxima between them
  // (at 20 us the samples' rounding and exact-joint offsets, ~1e3 LSB, would
  // swamp the third differences)
  r.peaks.assign(3, {});
  const uint64_t st = std::max<uint64_t>(1, static_cast<uint64_t>(std::lround(100e-6 / h)));
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
}

inline plan::Path butterfly_path() { return input::load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json"); }

// The butterfly at a 20 us engine tick (the time-scaling tests and plot).
inline const Butterfly& butterfly() {
  static const Butterfly b = scaled_plan(butterfly_path(), job::JobConfig{}, 20e-6);
  return b;
}

}  // namespace traj
