// Benchmark: step-edge timing of the step/dir generator (hls model of
// rtl/traj_step_gen.sv, cycle-accurate) against the exact times a jerk-limited
// motion at the main job's limits crosses each step boundary.
//
// Motion (one axis, piecewise-constant jerk, exact cubic pieces): rest, a
// rest-to-rest move of +20 mm at the feed (50 mm/s), at once a move of -40 mm
// at the axis limit (200 mm/s), rest; acceleration 2000 mm/s^2, jerk
// 50000 mm/s^3 (README, "The main job"). Samples are floor(x(k h) / LSB) with
// LSB = 2^-32 mm (the main job's output format); one step = 2^26 LSB
// (1/64 mm). The clock is 48 MHz; pulse 1 us high / 1 us low, direction
// setup/hold 2 us.
//
// For every rising step edge (count c-1 -> c up, or c -> c-1 down) the exact
// time the motion crosses that boundary in that direction (nearest such
// crossing) is found by bisection on the cubic pieces; the error is the edge
// time minus the generator's constant latency (one tick plus the preparation
// clocks) minus the exact time. Printed per stream tick period (5 ms .. 10
// us): the engine tick the board runs it at (`trajcore upload` plays a stream
// with a tick above 1 ms at n = ceil(tick / 1 ms) engine ticks per tick, its
// segments re-compiled: stream/retick.hpp, whose samples are within 1 LSB =
// 2^-32 mm of the stream's polynomial, so the motion is sampled here at the
// engine tick), the sub-chords per engine tick, steps, max and RMS error, and
// the crossings with no edge (a boundary crossed and recrossed within one
// tick at a reversal). The last row plays 2 ms as it is (--max-engine-tick 0).
//
//   bench_step_timing            the full table
//   bench_step_timing --short    the test: 1.5 ms, 1 ms, 250 us, 50 us and 10 us
//                                ticks on a shorter move; fails unless the
//                                counts are exact and every edge is within 10 us
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "stream/retick.hpp"
#include "traj_step_gen.hpp"

#ifndef BENCH_FRAC
#define BENCH_FRAC 12  // FracBits of the board build (rtl/traj_board.sv)
#endif

namespace {

constexpr double kClock = 48e6;
constexpr int kShift = 26;
constexpr double kLsb = 1.0 / 4294967296.0;  // 2^-32 mm
const double kStep = std::ldexp(1.0, kShift) * kLsb;

// piecewise-constant jerk motion
struct Piece {
  double t0, dt, x, v, a, j;
  double pos(double t) const {
    const double u = t - t0;
    return x + u * (v + u * (a / 2 + u * j / 6));
  }
  double vel(double t) const {
    const double u = t - t0;
    return v + u * (a + u * j / 2);
  }
};

struct Motion {
  std::vector<Piece> p;
  double t = 0, x = 0, v = 0, a = 0;
  void add(double dt, double j) {
    if (dt <= 0) return;
    p.push_back({t, dt, x, v, a, j});
    x = p.back().pos(t + dt);
    v = v + dt * (a + dt * j / 2);
    a = a + dt * j;
    t += dt;
  }
  // rest-to-rest move of distance d (sign = direction) at speed vmax
  void move(double d, double vmax, double amax, double jmax) {
    const double s = d < 0 ? -1 : 1;
    double tj = amax / jmax, ta = vmax / amax - tj;
    if (ta < 0) {
      tj = std::sqrt(vmax / jmax);
      ta = 0;
    }
    const double tacc = 2 * tj + ta;
    const double cruise = (std::fabs(d) - vmax * tacc) / vmax;  // callers keep it >= 0
    add(tj, s * jmax);
    add(ta, 0);
    add(tj, -s * jmax);
    add(cruise, 0);
    add(tj, -s * jmax);
    add(ta, 0);
    add(tj, s * jmax);
    a = 0;  // exact zero after the profile (rounding)
    v = 0;
  }
  double pos(double t) const {
    for (const auto& q : p)
      if (t <= q.t0 + q.dt) return q.pos(t);
    return x;
  }
};

struct Crossing {
  double t;
  int64_t c;  // count after the crossing
  bool up;
};

// every crossing of a step boundary, in time order
std::vector<Crossing> crossings(const Motion& m) {
  std::vector<Crossing> out;
  for (const auto& q : m.p) {
    // split the piece where the velocity is zero (monotone parts)
    std::vector<double> cuts{q.t0, q.t0 + q.dt};
    const double A = q.j / 2, B = q.a, C = q.v;
    if (A != 0) {
      const double disc = B * B - 4 * A * C;
      if (disc >= 0)
        for (double r : {(-B - std::sqrt(disc)) / (2 * A), (-B + std::sqrt(disc)) / (2 * A)})
          if (r > 0 && r < q.dt) cuts.push_back(q.t0 + r);
    } else if (B != 0) {
      const double r = -C / B;
      if (r > 0 && r < q.dt) cuts.push_back(q.t0 + r);
    }
    std::sort(cuts.begin(), cuts.end());
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
      const double ta = cuts[i], tb = cuts[i + 1];
      const double xa = q.pos(ta), xb = q.pos(tb);
      if (xa == xb) continue;
      const bool up = xb > xa;
      // boundaries b = c * kStep strictly crossed
      int64_t lo = static_cast<int64_t>(std::floor(std::min(xa, xb) / kStep)) + 1;
      int64_t hi = static_cast<int64_t>(std::floor(std::max(xa, xb) / kStep));
      std::vector<Crossing> part;
      for (int64_t c = lo; c <= hi; ++c) {
        const double b = c * kStep;
        double l = ta, r = tb;
        for (int it = 0; it < 80; ++it) {
          const double mid = 0.5 * (l + r);
          if ((q.pos(mid) >= b) == up) r = mid;
          else l = mid;
        }
        part.push_back({r, up ? c : c - 1, up});
      }
      if (!up) std::reverse(part.begin(), part.end());
      out.insert(out.end(), part.begin(), part.end());
    }
  }
  return out;
}

struct Result {
  int64_t edges = 0, final_count = 0, expect_count = 0, unmatched = 0;
  double max_err = 0, rms = 0, worst_t = 0;
  bool err_flag = false;
};

using Gen = traj::StepGen<1, 48, BENCH_FRAC>;

Result run(const Motion& m, double h) {
  const uint32_t P = static_cast<uint32_t>(std::llround(h * kClock));
  Gen gen;
  Gen::In in;
  in.rst_n = false;
  gen.clock(in);
  in.rst_n = true;
  in.period = P;
  in.pulse = 48;   // 1 us
  in.setup = 96;   // 2 us
  in.enable = true;
  in.shift[0] = kShift;
  const auto cross = crossings(m);
  // latency: the chord of ticks k-1 -> k runs one tick late, after the
  // preparation (kPrepClocks), the load and the pulse flop
  const double latency = h + (Gen::kPrepClocks + 3) / kClock;
  const int ticks = static_cast<int>(std::ceil(m.t / h)) + 4;
  Result r;
  const int64_t n0 = static_cast<int64_t>(std::floor(m.pos(0) / kLsb)) >> kShift;
  bool step = false;
  int64_t count = 0;
  std::vector<char> used(cross.size(), 0);
  double sum2 = 0;
  size_t hint = 0;
  int64_t s = 0;
  for (int k = 0; k < ticks + 2; ++k) {
    s = static_cast<int64_t>(std::floor(m.pos(std::min(k * h, m.t)) / kLsb));
    in.sample[0] = static_cast<traj::u128>(s) & traj::mask(48);
    for (uint32_t c = 0; c < P; ++c) {
      in.sample_valid = (c == 0);
      const auto o = gen.outputs();
      if (o.step[0] && !step) {
        count += o.dir[0] ? 1 : -1;
        ++r.edges;
        const double t = (static_cast<double>(k) * P + c) / kClock - latency;
        const int64_t c_after = n0 + count;
        // nearest unused exact crossing to this count, same direction
        double best = 1e9;
        size_t bi = cross.size();
        const size_t from = hint > 64 ? hint - 64 : 0;
        for (size_t i = from; i < cross.size() && i < hint + 4096; ++i) {
          if (used[i] || cross[i].c != c_after || cross[i].up != o.dir[0]) continue;
          const double e = std::fabs(t - cross[i].t);
          if (e < best) best = e, bi = i;
        }
        if (bi < cross.size()) {
          used[bi] = 1;
          hint = bi;
          sum2 += best * best;
          if (best > r.max_err) r.max_err = best, r.worst_t = cross[bi].t;
        } else {
          ++r.unmatched;
        }
      }
      step = o.step[0];
      gen.clock(in);
    }
  }
  r.err_flag = gen.outputs().err;
  r.final_count = count;
  r.expect_count = (s >> kShift) - n0;
  r.rms = r.edges ? std::sqrt(sum2 / r.edges) : 0;
  int64_t lost = 0;
  for (char u : used) lost += !u;
  r.unmatched += lost;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const bool short_run = argc > 1 && std::strcmp(argv[1], "--short") == 0;
  Motion m;
  m.add(0.01, 0);
  if (short_run) {
    m.move(4.003, 50, 2000, 50000);  // ends off a step boundary
    m.move(-4.005, 50, 2000, 50000);
  } else {
    m.move(20.003, 50, 2000, 50000);  // ends off a step boundary
    m.move(-40.005, 200, 2000, 50000);
  }
  m.add(0.01, 0);
  std::printf("step timing: %.3f s of motion, %.0f steps/mm, clock %.0f MHz, pulse 1 us, dir setup/hold 2 us\n",
              m.t, 1 / kStep, kClock / 1e6);
  std::printf("%12s %12s %5s %8s %8s %12s %12s %10s %9s\n", "stream tick", "engine tick", "subs", "edges", "count",
              "max err us", "rms err us", "at t (s)", "no edge");
  struct Row {
    double stream_tick, max_engine_tick;
  };
  const double kMax = traj::stream::kMaxStepEngineTick;
  const std::vector<Row> rows =
      short_run ? std::vector<Row>{{1.5e-3, kMax}, {1e-3, kMax}, {250e-6, kMax}, {50e-6, kMax}, {10e-6, kMax}}
                : std::vector<Row>{{5e-3, kMax}, {2e-3, kMax}, {1.5e-3, kMax}, {1e-3, kMax},
                                   {500e-6, kMax}, {250e-6, kMax}, {50e-6, kMax}, {10e-6, kMax}, {2e-3, 0}};
  bool ok = true;
  for (const Row& row : rows) {
    const double h = row.stream_tick / traj::stream::engine_ticks_per_tick(row.stream_tick, row.max_engine_tick);
    const Result r = run(m, h);
    const int subs = 1 << Gen::sub_bits(static_cast<uint32_t>(std::llround(h * kClock)));
    std::printf("%9.0f us %9.0f us %5d %8lld %8s %12.2f %12.3f %10.4f %9lld%s%s\n", row.stream_tick * 1e6, h * 1e6,
                subs, (long long)r.edges, r.final_count == r.expect_count ? "exact" : "WRONG", r.max_err * 1e6,
                r.rms * 1e6, r.worst_t, (long long)r.unmatched, r.err_flag ? "  err_o!" : "",
                row.max_engine_tick > 0 ? "" : "  (as is: --max-engine-tick 0)");
    ok = ok && r.final_count == r.expect_count && !r.err_flag;
    if (h <= kMax) ok = ok && r.max_err <= 10e-6 && r.unmatched == 0;
  }
  if (short_run && !ok) {
    std::printf("FAIL\n");
    return 1;
  }
  return 0;
}
