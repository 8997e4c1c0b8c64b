// SPDX-License-Identifier: Apache-2.0
#include "time_scale_cmd.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "timescale/time_scale.hpp"

namespace traj::app {

using plan::PlanError;

void apply_time_scale_headroom(job::JobConfig& cfg, TimeScaleArgs& t) {
  t.machine = cfg.limits;
  if (!(t.s_max > 0 && t.s_max <= 2)) throw PlanError("--time-scale: the largest s must be in (0, 2]");
  if (t.headroom.size() != 2 || !(t.headroom[0] > 0 && t.headroom[0] <= 1) || !(t.headroom[1] > 0 && t.headroom[1] <= 1))
    throw PlanError("--scale-headroom: two shares in (0, 1]: of the acceleration and of the jerk limits");
  if (!(std::isfinite(t.servo_period) && t.servo_period >= cfg.machine.period))
    throw PlanError("--servo-period: at least the tick period (the engine ticks at the tick period)");
  auto& L = cfg.limits;
  for (int a = 0; a < plan::kMaxAxes; ++a) {
    L.a_axis[a] *= t.headroom[0];
    L.j_axis[a] *= t.headroom[1];
  }
  L.a_tan *= t.headroom[0];
  L.a_cen *= t.headroom[0];
  L.j_tan *= t.headroom[1];
  L.j_cen *= t.headroom[1];
}

std::string time_scale_text(const TimeScaleArgs& t, const report::Report& rep, const job::JobResult& res,
                            stream::Header& header) {
  const plan::Limits& machine = t.machine;
  const int axes = std::min(res.header.axes, plan::kMaxAxes);
  std::vector<timescale::AxisKinematics> peaks(axes), limits(axes);
  const plan::Peaks* all[3] = {&rep.plan_peaks, &rep.fit_peaks, &rep.out_peaks};
  for (int a = 0; a < axes; ++a) {
    for (const plan::Peaks* p : all) {
      peaks[a].v = std::max(peaks[a].v, 1.02 * p->v_axis[a]);
      peaks[a].a = std::max(peaks[a].a, 1.02 * p->a_axis[a]);
      peaks[a].j = std::max(peaks[a].j, 1.02 * p->j_axis[a]);
    }
    limits[a] = {machine.v_axis[a], machine.a_axis[a], machine.j_axis[a]};
  }
  const double h = res.header.period, H = t.servo_period;
  const timescale::OutputError err{h, H, std::ldexp(1.0, -res.header.frac_bits)};
  timescale::RampBounds rb;
  timescale::IntBounds ib;
  try {
    rb = timescale::derive_ramp_bounds(peaks, limits, t.s_max, err);
    ib = timescale::integer_bounds(rb, H);
  } catch (const std::invalid_argument& e) {
    throw PlanError(std::string(e.what()) + " (--scale-headroom: the shares of the limits the plan uses; --period: the engine tick)");
  }
  // the stream's fields: s_max rounded down to 1/4096, the bounds to the
  // float below them (each only makes the ramps slower)
  header.scale_max = std::floor(t.s_max * stream::kScaleMaxUnit + 1e-9) / stream::kScaleMaxUnit;
  header.scale_rate = std::nextafter(static_cast<float>(rb.rate), 0.0f);
  header.scale_accel = std::nextafter(static_cast<float>(rb.accel), 0.0f);
  const double n = H / h;
  const double p = std::log2(n);
  char buf[1024];
  std::string s;
  std::snprintf(buf, sizeof buf,
                "Time scaling (--time-scale %g: feed override up to %g %%, hold, a stop when data runs out)\n"
                "  planned at            %g %% of the acceleration and %g %% of the jerk limits\n",
                t.s_max, 100 * t.s_max, 100 * t.headroom[0], 100 * t.headroom[1]);
  s += buf;
  for (int a = 0; a < axes; ++a) {
    if (peaks[a].v <= 0) continue;  // the axis does not move
    std::snprintf(buf, sizeof buf, "  plan peaks, axis %c    v %.4g, a %.4g, j %.4g (limits %g, %g, %g; +2 %% for the maxima between ticks)\n",
                  machine.axis(a)[0], peaks[a].v, peaks[a].a, peaks[a].j, limits[a].v, limits[a].a, limits[a].j);
    s += buf;
  }
  std::snprintf(buf, sizeof buf,
                "  ramp bounds           s <= %g, |ds/dt| <= %.4g /s, |d2s/dt2| <= %.4g /s^2 (servo tick %g s, %g engine "
                "ticks each)\n"
                "  time-scale unit       scale bits %d, m %lld, S_max %lld%s\n",
                t.s_max, rb.rate, rb.accel, H, n, ib.scale_bits, static_cast<long long>(ib.m),
                static_cast<long long>(ib.s_max),
                std::fabs(p - std::round(p)) < 1e-9
                    ? (", shift " + std::to_string(32 - ib.scale_bits + static_cast<int>(std::lround(p)))).c_str()
                    : " (the unit needs a power of two engine ticks per servo tick)");
  s += buf;
  return s;
}

}  // namespace traj::app
