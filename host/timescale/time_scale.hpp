// SPDX-License-Identifier: Apache-2.0
// Time scaling of a planned trajectory (feed override, feed hold, a stop on
// the path when data runs out): the exact per-servo-tick reference of the
// time-scale unit, in integers, and the bounds on its ramps that keep every
// axis within its limits. README.md beside this file derives them.
//
// The engine samples the trajectory x at a fine tick h (n engine ticks per
// servo tick H = n h at full speed). Trajectory time advances by s servo
// ticks per servo tick, 0 <= s <= s_max; the output at a servo tick is the
// linear interpolation between the two engine samples around trajectory
// time, so the machine follows the same points re-timed.
//   * s = S * 2^-sb (S an integer; sb = ScaleBits, s = 1 is S = 2^sb); its
//     rate dS per servo tick is k (an integer, |k| <= m) and k changes by at
//     most 1 per servo tick: |ds/dt| <= m 2^-sb / H, |d2s/dt2| <= 2^-sb / H^2.
//   * trajectory time phi in 2^-32 engine ticks: phi += S n 2^(32-sb).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace traj::timescale {

// Per-axis bounds of the planned trajectory's velocity, acceleration and
// jerk (plan peaks) and the machine's limits, units/s^i.
struct AxisKinematics {
  double v = 0, a = 0, j = 0;
};

// The continuous bounds on s(t) under which every axis keeps its limits:
// s <= s_max, |ds/dt| <= rate, |d2s/dt2| <= accel.
struct RampBounds {
  double s_max = 1, rate = 0, accel = 0;
};

// The output's error about the re-timed trajectory x(tau(t)), units: linear
// interpolation between engine samples h apart (a h^2 / 8, a the plan's
// acceleration peak of the axis) plus 2 LSB (the samples' rounding and the
// interpolation's). Its share of the i-th sample difference at the servo tick
// H is at most 2^i e / H^i.
struct OutputError {
  double engine_tick = 0, servo_tick = 1e-3, lsb = 0;
  double of_axis(const AxisKinematics& plan) const { return plan.a * engine_tick * engine_tick / 8 + 2 * lsb; }
};

// The largest rate and accel for s_max such that for every axis
//   v s_max + 2e/H <= V,
//   a s_max^2 + v rate + 4e/H^2 <= A,
//   j s_max^3 + 3 a s_max rate + v accel + 8e/H^3 <= J
// (plan peaks v, a, j; limits V, A, J; e = err.of_axis). `rate_share` of the
// jerk headroom (J - j s_max^3 - 8e/H^3) goes to the rate term, the rest to
// accel. Throws std::invalid_argument naming the axis and the limit when the
// plan leaves no headroom at s_max.
RampBounds derive_ramp_bounds(const std::vector<AxisKinematics>& plan, const std::vector<AxisKinematics>& limits,
                              double s_max, const OutputError& err, double rate_share = 0.5);

// The integer form of RampBounds for a servo tick H: ScaleBits sb (the
// jerk step of s is 2^-sb per servo tick^2, the largest power of two within
// accel H^2) and the rate bound m (|k| <= m, m 2^-sb <= rate H).
struct IntBounds {
  int scale_bits = 0;
  int64_t m = 0;
  int64_t s_max = 0;  // S <= s_max (= floor(s_max 2^sb))
};
IntBounds integer_bounds(const RampBounds& b, double servo_period);

// Servo ticks a stop (target 0) takes from any state of the curve
// (0 <= S <= s_max, |k| <= m), at most: k turns toward the target by one per
// tick (<= m ticks while S still rises, by at most m^2 in all), reaches -m
// (<= m), moves at most (s_max + m^2) / m ticks at it, and turns back to 0
// (<= m), with ticks of landing on S = 0 exactly (+4).
// tb/timescale checks it against SCurve from extreme and random states.
int64_t stop_ticks_bound(const IntBounds& b);

// The shortest servo tick (clocks) at which the hardware unit
// (rtl/traj_time_scale.sv) never finds a servo tick busy: one clock more than
// its work for a servo tick takes at most, from its schedule (rtl/README.md):
// the window primed (the first tick: two engine ticks and a copy of a sample,
// Axes*OutWidth + 1 clocks; later ticks read the previous output out instead,
// as long), the check's stop one S-curve step per 4 clocks after a first step
// toward the target (4 (stop + 1) + 1), three bit-serial passes over
// X 2^shift + frac (kNCmp = max(2 SW + 45, 65) clocks each and one), the
// tick's own step (5), the engine ticks trajectory time needs, at most
// 2^(p+1) at s <= 2 (each a 33-clock decrement, the strobe and the answer:
// engine_clocks + 37) and a copy of the sample before the last, and the
// interpolation (Axes (33 + OutWidth)). engine_clocks: the most clocks the
// engine takes from a tick to its sample. out_width and scale_width: the
// unit's OutWidth and SW (the defaults are the largest the unit builds, so the
// bound holds for every build). A servo tick shorter than this may find the
// unit busy (STATUS tick error).
uint64_t unit_tick_clocks(const IntBounds& b, int p, int axes, int engine_clocks, int out_width = 64,
                          int scale_width = 24);

// The S-curve of s: each servo tick k changes by -1, 0 or +1 and S by the
// new k, toward the target (landing on it exactly, k = 0 there). The choice
// is greedy: the largest change of k after which the target can still be
// reached exactly, which holds whenever |e| >= |k| (|k| - 1) / 2 in the
// direction of motion (e = target - S); it never passes a target it moves
// toward, so S stays between the targets it was given.
class SCurve {
 public:
  explicit SCurve(const IntBounds& b, int64_t s0);
  void set_target(int64_t target);  // clamped to 0..s_max
  void step();                      // one servo tick
  int64_t s() const { return s_; }
  int64_t k() const { return k_; }
  int64_t target() const { return target_; }
  bool at_rest() const { return k_ == 0 && s_ == target_; }
  // The trajectory time (in S servo-tick units, the sum of S over the ticks)
  // a stop from now takes with this curve: the sum of S until S = 0.
  int64_t stop_travel() const;

 private:
  int64_t m_, s_max_;
  int64_t s_ = 0, k_ = 0, target_ = 0;
};

// The time-scale unit's exact reference: an S-curve, trajectory time, the
// engine ticks it asks for, the interpolated output, and the automatic
// hold when the samples ahead would not cover a stop.
class TimeScaler {
 public:
  // n: engine ticks per servo tick at s = 1.
  TimeScaler(const IntBounds& b, int n, int axes);

  void set_override(int64_t s_target);  // feed override (S units), taken at the next servo tick
  void hold(bool on);                   // feed hold: target 0 while on
  void set_auto_resume(bool on) { auto_resume_ = on; }

  // One servo tick. `samples` holds the engine's samples 0..n_samples-1
  // received so far, axis a of sample i at [i * axes + a] (all of them if
  // `end`: the trajectory ends, at rest, at the last one). Returns the output
  // sample per axis (the interpolation rounded down).
  std::vector<int64_t> tick(const std::vector<int64_t>& samples, uint64_t n_samples, bool end);

  int64_t s() const { return curve_.s(); }
  uint64_t engine_index() const { return static_cast<uint64_t>(phi_ >> 32); }
  bool starved_hold() const { return starved_; }
  uint64_t starved_holds() const { return starved_holds_; }

 private:
  int64_t travel_needed() const;  // 2^-32 engine ticks a stop from now takes

  IntBounds b_;
  int n_, axes_;
  SCurve curve_;
  unsigned __int128 phi_ = 0;
  int64_t override_;
  bool hold_ = false, starved_ = false, auto_resume_ = true;
  uint64_t starved_holds_ = 0;
};

}  // namespace traj::timescale
