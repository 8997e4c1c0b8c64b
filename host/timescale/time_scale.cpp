// SPDX-License-Identifier: Apache-2.0
#include "timescale/time_scale.hpp"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace traj::timescale {

namespace {
std::string axis_name(size_t a) {
  static const char* kNames = "XYZABCUVW";
  return a < 9 ? std::string(1, kNames[a]) : "axis " + std::to_string(a);
}
}  // namespace

RampBounds derive_ramp_bounds(const std::vector<AxisKinematics>& plan, const std::vector<AxisKinematics>& limits,
                              double s_max, const OutputError& err, double rate_share) {
  if (plan.size() != limits.size()) throw std::invalid_argument("time scaling: plan and limits differ in axes");
  if (!(s_max > 0 && s_max <= 2)) throw std::invalid_argument("time scaling: s_max must be in (0, 2]");
  if (!(rate_share > 0 && rate_share < 1)) throw std::invalid_argument("time scaling: rate_share must be in (0, 1)");
  RampBounds b;
  b.s_max = s_max;
  double rate = std::numeric_limits<double>::infinity();
  for (size_t a = 0; a < plan.size(); ++a) {
    const AxisKinematics& p = plan[a];
    const AxisKinematics& L = limits[a];
    if (p.v <= 0) continue;  // the axis does not move
    char sm[32];
    std::snprintf(sm, sizeof sm, "%g", s_max);
    const std::string who = std::string("time scaling up to s = ") + sm + ": axis " + axis_name(a) + ": ";
    const double e = err.of_axis(p), H = err.servo_tick;
    if (p.v * s_max + 2 * e / H > L.v) throw std::invalid_argument(who + "velocity peak x s_max is above its limit");
    const double head_a = L.a - p.a * s_max * s_max - 4 * e / (H * H);
    const double head_j = L.j - p.j * s_max * s_max * s_max - 8 * e / (H * H * H);
    // the interpolation's own share (an engine tick too coarse for the servo
    // tick), named apart from the plan's
    const double interp_a = 4 * e / (H * H), interp_j = 8 * e / (H * H * H);
    if (head_a <= 0 || head_j <= 0) {
      const bool interp = (head_a <= 0 && L.a - p.a * s_max * s_max > 0) || (head_j <= 0 && L.j - p.j * s_max * s_max * s_max > 0);
      if (interp) {
        char buf[256];
        std::snprintf(buf, sizeof buf,
                      "the interpolation between engine samples %g s apart at the servo tick %g s takes %.3g of the "
                      "acceleration limit and %.3g of the jerk limit: tick the engine finer (plan with a shorter --period)",
                      err.engine_tick, H, interp_a / L.a, interp_j / L.j);
        throw std::invalid_argument(who + buf);
      }
      throw std::invalid_argument(who + (head_a <= 0 ? "the plan's acceleration" : "the plan's jerk") +
                                  " leaves no headroom (plan it below the limit)");
    }
    rate = std::min(rate, head_a / p.v);
    if (p.a > 0) rate = std::min(rate, rate_share * head_j / (3 * p.a * s_max));
  }
  if (!std::isfinite(rate)) throw std::invalid_argument("time scaling: no axis moves");
  double accel = std::numeric_limits<double>::infinity();
  for (size_t a = 0; a < plan.size(); ++a) {
    const AxisKinematics& p = plan[a];
    const AxisKinematics& L = limits[a];
    if (p.v <= 0) continue;
    const double e = err.of_axis(p), H = err.servo_tick;
    accel = std::min(accel, (L.j - p.j * s_max * s_max * s_max - 8 * e / (H * H * H) - 3 * p.a * s_max * rate) / p.v);
  }
  b.rate = rate;
  b.accel = accel;
  return b;
}

IntBounds integer_bounds(const RampBounds& b, double servo_period) {
  if (!(servo_period > 0) || !(b.accel > 0) || !(b.rate > 0))
    throw std::invalid_argument("time scaling: the ramp bounds and the servo period must be positive");
  IntBounds ib;
  const double step = b.accel * servo_period * servo_period;  // largest jerk step of s per servo tick^2
  ib.scale_bits = static_cast<int>(std::ceil(-std::log2(step)));
  while (std::ldexp(1.0, -ib.scale_bits) > step) ++ib.scale_bits;  // 2^-sb <= step
  if (ib.scale_bits < 1 || ib.scale_bits > 40)
    throw std::invalid_argument("time scaling: the ramp's jerk step per servo tick (" + std::to_string(step) +
                                ") needs 1..40 scale bits");
  ib.m = static_cast<int64_t>(std::floor(b.rate * servo_period * std::ldexp(1.0, ib.scale_bits)));
  if (ib.m < 1)
    throw std::invalid_argument("time scaling: the rate bound is below one step of s per servo tick");
  ib.s_max = static_cast<int64_t>(std::floor(b.s_max * std::ldexp(1.0, ib.scale_bits)));
  return ib;
}

SCurve::SCurve(const IntBounds& b, int64_t s0) : m_(b.m), s_max_(b.s_max), s_(s0), target_(s0) {}

void SCurve::set_target(int64_t target) { target_ = std::clamp<int64_t>(target, 0, s_max_); }

namespace {
// Whether S, moving at rate k (after this tick's change), can still land on
// the target exactly: the shortest stop from k covers |k| (|k| - 1) / 2 in
// its direction, and any longer distance is reachable (hold a level longer).
bool can_land(int64_t e, int64_t k) {
  if (k == 0) return true;
  const int64_t need = (k > 0 ? k : -k) * ((k > 0 ? k : -k) - 1) / 2;
  return k > 0 ? e >= need : -e >= need;
}
}  // namespace

void SCurve::step() {
  const int64_t e = target_ - s_;
  // moving, but not toward the target (it moved behind, or S is on it): brake
  const bool away = k_ != 0 && (e == 0 || (e > 0) != (k_ > 0));
  int64_t k = 0;
  if (away) {
    k = k_ > 0 ? k_ - 1 : k_ + 1;
  } else if (e != 0) {
    // toward the target (or from rest): the largest change toward it after
    // which it can still land; else hold the rate; else brake
    const int64_t dir = e > 0 ? 1 : -1;
    const int64_t up = k_ + dir;
    if ((up > 0 ? up : -up) <= m_ && can_land(e - up, up)) k = up;
    else if (can_land(e - k_, k_)) k = k_;
    else k = k_ - dir;
  }
  k_ = k;
  s_ += k_;
}

int64_t stop_ticks_bound(const IntBounds& b) {
  const int64_t m = std::max<int64_t>(b.m, 1);
  return 3 * m + (b.s_max + m * m + m - 1) / m + 4;
}

uint64_t unit_tick_clocks(const IntBounds& b, int p, int axes, int engine_clocks, int out_width, int scale_width) {
  const uint64_t stop = static_cast<uint64_t>(stop_ticks_bound(b));
  const uint64_t n = uint64_t(axes) * uint64_t(out_width);       // sample bits
  const uint64_t ncmp = std::max<uint64_t>(2 * uint64_t(scale_width) + 45, 65);  // a serial pass
  const uint64_t ec = static_cast<uint64_t>(engine_clocks);
  const uint64_t prime = 2 * (ec + 3) + n + 1;                    // or the readout, n + 1
  const uint64_t check = 4 * (stop + 1) + 1 + ncmp + 1;
  const uint64_t phi = 2 * (ncmp + 1);
  const uint64_t advance = (uint64_t(1) << (p + 1)) * (ec + 37) + n + 2;
  const uint64_t interp = uint64_t(axes) * (34 + uint64_t(out_width));
  // the latch and the plan (2), the tick's own step and its commit (5), and
  // the clock of the servo tick itself
  return prime + 2 + check + 5 + phi + advance + interp + 1;
}

int64_t SCurve::stop_travel() const {
  SCurve c = *this;
  c.set_target(0);
  int64_t sum = 0;
  while (!c.at_rest()) {
    c.step();
    sum += c.s();
  }
  return sum;
}

TimeScaler::TimeScaler(const IntBounds& b, int n, int axes)
    : b_(b), n_(n), axes_(axes), curve_(b, 0), override_(int64_t(1) << b.scale_bits) {
  if (n < 1) throw std::invalid_argument("time scaling: at least one engine tick per servo tick");
  curve_.set_target(override_);
}

void TimeScaler::set_override(int64_t s_target) { override_ = std::clamp<int64_t>(s_target, 0, b_.s_max); }

void TimeScaler::hold(bool on) { hold_ = on; }

int64_t TimeScaler::travel_needed() const {
  // this tick at the present target, then a stop from there
  SCurve c = curve_;
  c.step();
  return (c.s() + c.stop_travel()) * n_;
}

std::vector<int64_t> TimeScaler::tick(const std::vector<int64_t>& samples, uint64_t n_samples, bool end) {
  const int sh = 32 - b_.scale_bits;
  const auto to_phi = [&](int64_t s_units) { return static_cast<unsigned __int128>(s_units) << sh; };
  // trajectory time available ahead (phi units): up to the last sample at the
  // end, else up to the one before it (the unit's window at phi holds the
  // sample after phi's, so it has to be there)
  const uint64_t last_index = end ? (n_samples > 0 ? n_samples - 1 : 0) : (n_samples > 1 ? n_samples - 2 : 0);
  const unsigned __int128 last = static_cast<unsigned __int128>(last_index) << 32;
  const unsigned __int128 ahead = last > phi_ ? last - phi_ : 0;
  if (!end) {
    curve_.set_target(hold_ || starved_ ? 0 : override_);
    if (!starved_ && to_phi(travel_needed()) > ahead) {
      starved_ = true;  // a stop from the next tick would run past the data: stop now
      ++starved_holds_;
      curve_.set_target(0);
    } else if (starved_ && auto_resume_ && !hold_) {
      // hysteresis: the data covers twice a tick at the target and a stop
      // from it (else a trickle of data would start and stop the machine by
      // a few samples at a time)
      if (to_phi((override_ + SCurve(b_, override_).stop_travel()) * n_) * 2 <= ahead) {
        starved_ = false;
        curve_.set_target(override_);
      }
    }
  } else {
    curve_.set_target(hold_ ? 0 : override_);
  }
  curve_.step();
  phi_ += to_phi(curve_.s() * n_);
  if (phi_ > last) {
    // only at the trajectory's end (at rest there); before it the automatic
    // hold keeps every stop within the samples received
    if (!end) throw std::logic_error("time scaling: trajectory time ran past the samples received");
    phi_ = last;
  }
  const uint64_t e = static_cast<uint64_t>(phi_ >> 32);
  const uint64_t f = static_cast<uint64_t>(phi_ & 0xffffffffu);
  std::vector<int64_t> y(axes_, 0);
  if (n_samples == 0) return y;
  for (int a = 0; a < axes_; ++a) {
    const int64_t y0 = samples[e * axes_ + a];
    if (f == 0 || e + 1 >= n_samples) {
      y[a] = y0;
      continue;
    }
    const __int128 d = static_cast<__int128>(samples[(e + 1) * axes_ + a]) - y0;
    __int128 p = d * static_cast<__int128>(f);
    // floor division by 2^32 (arithmetic shift floors)
    y[a] = y0 + static_cast<int64_t>(p >> 32);
  }
  return y;
}

}  // namespace traj::timescale
