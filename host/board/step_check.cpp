// SPDX-License-Identifier: Apache-2.0
#include "board/step_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "fd/fd_ticker.hpp"
#include "traj_step_gen.hpp"

namespace traj::board {
namespace {

int64_t floor_shift(int64_t v, int sh) { return v >= 0 ? v >> sh : -((-v - 1) >> sh) - 1; }
int64_t floor_div(__int128 v, __int128 d) { return static_cast<int64_t>(v >= 0 ? v / d : -((-v - 1) / d) - 1); }

// rtl/traj_board.sv's step generator (its sub-chord count for a period)
using BoardStepGen = traj::StepGen<3, 48, 12, 16, 8, 16, 3>;
constexpr int kFrac = 12;

// Every tick's sample of one axis, in order, from the records.
std::vector<int64_t> predicted_samples(const stream::ReadResult& r, int axis) {
  fd::FdTicker t(r.header.width, r.header.guard_bits);
  std::vector<int64_t> s;
  for (const auto& rec : r.records) {
    t.load(rec.regs);
    for (uint32_t k = 0; k < rec.ticks; ++k) s.push_back(t.sample_and_step(axis));
  }
  return s;
}

class AxisChecker {
 public:
  // period: the step generator's tick period in clocks (0: the spacing of `ticks`)
  AxisChecker(const std::vector<uint64_t>& ticks, const StepDecoder& d, int shift, StepCheck& c, AxisSteps& a,
              uint64_t period = 0)
      : ticks_(ticks), edges_(d.edges()), sh_(shift), c_(c), a_(a),
        pair_clocks_(2.0 * d.timing().setup + 3.0 * d.timing().pulse + 8), period_(period) {}

  void run(const std::vector<int64_t>& s) {
    const size_t n_max = std::min(s.size(), ticks_.size());
    std::vector<int64_t> q(n_max);
    for (size_t n = 0; n < n_max; ++n)
      q[n] = sh_ >= kFrac ? floor_shift(s[n], sh_ - kFrac) : s[n] * (int64_t{1} << (kFrac - sh_));
    for (size_t n = 1; n < n_max; ++n) tick(n, q);
    match();
    if (!s.empty()) a_.final_expected = floor_shift(s[n_max - 1], sh_) - floor_shift(s[0], sh_);
    a_.decoded = edges_.size();
    for (const auto& e : edges_) a_.final_decoded += e.up ? 1 : -1;
    if (a_.decoded + 2 * a_.cancelled != a_.expected)
      problem("axis step count: " + std::to_string(a_.decoded) + " edges decoded, " + std::to_string(a_.expected) +
              " steps predicted, " + std::to_string(a_.cancelled) + " pairs cancelled");
  }

 private:
  // The steps between ticks n-1 and n: the generator's path is 2^m
  // sub-chords through Y_i / (2 M^2) (M = 2^m, i = 0..M), Y_i = 2 M^2 q0 +
  // 2 M i D1 + i (i - M) D2 (q: the samples with kFrac fraction bits of a
  // step; D1 = q_n - q_n-1, D2 = D1 - D1 of the tick before; the first tick
  // starts from q_0's step boundary with D2 = 0). Each sub-chord takes
  // P / M clocks; every boundary it crosses is one step.
  void tick(size_t n, const std::vector<int64_t>& q) {
    const uint64_t p = period_ ? period_ : n + 1 < ticks_.size() ? ticks_[n + 1] - ticks_[n] : ticks_[n] - ticks_[n - 1];
    const int m = BoardStepGen::sub_bits(static_cast<uint32_t>(std::min<uint64_t>(p, (1u << 16) - 1)));
    const int64_t M = int64_t{1} << m;
    const int64_t q0 = n == 1 ? floor_shift(q[0], kFrac) << kFrac : q[n - 1];
    const int64_t d1 = q[n] - q0, d2 = n >= 2 ? d1 - (q[n - 1] - (n == 2 ? floor_shift(q[0], kFrac) << kFrac : q[n - 2])) : 0;
    const __int128 scale = static_cast<__int128>(2 * M * M) << kFrac;  // one step in Y
    auto y = [&](int64_t i) {
      return static_cast<__int128>(2 * M * M) * q0 + static_cast<__int128>(2 * M * i) * d1 + static_cast<__int128>(i * (i - M)) * d2;
    };
    for (int64_t i = 0; i < M; ++i) {
      const __int128 ya = y(i), yb = y(i + 1);
      const int64_t e0 = floor_div(ya, scale), e1 = floor_div(yb, scale);
      const double len = static_cast<double>(p) / static_cast<double>(M);
      auto at = [&](int64_t b) {  // clocks after tick n where the sub-chord reaches boundary b
        const double f = static_cast<double>(static_cast<__int128>(b) * scale - ya) / static_cast<double>(yb - ya);
        return (static_cast<double>(i) + f) * len;
      };
      for (int64_t b = e0 + 1; b <= e1; ++b) steps_.push_back({n, static_cast<double>(ticks_[n]) + at(b), b, true});
      for (int64_t b = e0; b > e1; --b) steps_.push_back({n, static_cast<double>(ticks_[n]) + at(b), b, false});
    }
  }

  // The predicted steps against the decoded edges, one for one, in order.
  // One exception: the generator nets its steps before it pulses them (a
  // signed count of steps due), so a step and the opposite step across the
  // same boundary that follow within less than a pulse and a direction turn
  // (pair_clocks_) may make no edge at all (the path touched the boundary);
  // such a pair is skipped when the next edge does not belong to it.
  void match() {
    a_.expected = steps_.size();
    size_t e = 0;
    for (size_t j = 0; j < steps_.size(); ++j) {
      const Step& p = steps_[j];
      const bool pair = j + 1 < steps_.size() && steps_[j + 1].up != p.up &&
                        steps_[j + 1].boundary == p.boundary && steps_[j + 1].at - p.at <= pair_clocks_;
      const bool fits = e < edges_.size() && edges_[e].up == p.up &&
                        static_cast<double>(edges_[e].cycle) - p.at <= kPairLateClocks;
      if (pair && !fits) {
        ++a_.cancelled;
        ++j;
        continue;
      }
      if (e >= edges_.size() || edges_[e].up != p.up) {
        problem("tick " + std::to_string(p.n) + ": predicted step " + std::to_string(j) + (p.up ? " up" : " down") +
                (e >= edges_.size() ? " not on the pins" : " decoded in the other direction"));
        return;
      }
      const double delay = (static_cast<double>(edges_[e].cycle) - p.at) / BoardBuild::kClkHz * 1e6;
      if (e == 0 || delay < a_.delay_min_us) a_.delay_min_us = delay, a_.delay_min_tick = p.n;
      if (e == 0 || delay > a_.delay_max_us) a_.delay_max_us = delay, a_.delay_max_tick = p.n;
      ++e;
    }
  }

  struct Step {
    size_t n;         // tick
    double at;        // cycle the path crosses the boundary
    int64_t boundary;
    bool up;
  };
  // An edge later than this after a step of a fast pair is not that step's.
  static constexpr double kPairLateClocks = 2000;
  void problem(const std::string& what) {
    if (c_.mismatches++ == 0) c_.first_problem = what;
  }
  const std::vector<uint64_t>& ticks_;
  const std::vector<StepDecoder::Edge>& edges_;
  int sh_;
  StepCheck& c_;
  AxisSteps& a_;
  double pair_clocks_;
  uint64_t period_;
  std::vector<Step> steps_;
};

}  // namespace

StepCheck check_steps(const stream::ReadResult& expected, const std::vector<int>& shifts,
                      const SimulatedBoard& board) {
  StepCheck c;
  // sample n at the tick it answered: a tick at an underrun (a program
  // pause) answers none, and the ticks before and after it are its neighbours
  const std::vector<uint64_t>& ticks = board.sample_tick_cycles();
  c.ticks_seen = ticks.size();
  const int axes = std::min(expected.header.axes, BoardBuild::kAxes);
  c.axes.resize(axes);
  for (int a = 0; a < axes; ++a) {
    const auto s = predicted_samples(expected, a);
    c.ticks_expected = s.size();
    AxisChecker(ticks, board.axis(a), shifts.at(a), c, c.axes[a]).run(s);
    c.violations += board.axis(a).violations();
    if (board.axis(a).violations() && c.first_problem.empty())
      c.first_problem = "axis " + std::to_string(a) + ": " + board.axis(a).first_violation();
  }
  if (c.ticks_seen < c.ticks_expected && c.first_problem.empty())
    c.first_problem = "the board's engine gave " + std::to_string(c.ticks_seen) + " samples, the stream has " +
                      std::to_string(c.ticks_expected) + " ticks";
  return c;
}

StepCheck check_steps_scaled(const std::vector<int>& shifts, const SimulatedBoard& board) {
  StepCheck c;
  c.scaled = true;
  const std::vector<uint64_t>& at = board.sample_cycles();
  c.ticks_seen = c.ticks_expected = at.size();
  c.axes.resize(BoardBuild::kAxes);
  for (int a = 0; a < BoardBuild::kAxes; ++a) {
    std::vector<int64_t> s(at.size());
    for (size_t n = 0; n < at.size(); ++n) s[n] = board.samples()[n * BoardBuild::kAxes + a];
    AxisChecker(at, board.axis(a), shifts.at(a), c, c.axes[a], board.tick_clocks()).run(s);
    c.violations += board.axis(a).violations();
    if (board.axis(a).violations() && c.first_problem.empty())
      c.first_problem = "axis " + std::to_string(a) + ": " + board.axis(a).first_violation();
  }
  return c;
}

PathCheck check_on_path(const std::vector<int64_t>& engine, const std::vector<int64_t>& out, int axes,
                        double tol_lsb, double max_advance) {
  PathCheck c;
  const uint64_t n = engine.size() / axes, m = out.size() / axes;
  c.samples = m;
  if (n == 0 || m == 0) {
    c.first_problem = "no samples";
    return c;
  }
  auto y = [&](uint64_t k, int a) { return engine[k * axes + a]; };
  // The places on the engine interval [k, k+1] (positions k + f, f in [0, 1]; the last sample: k)
  // where the polyline is within tol of output o on every axis: an interval, since each axis bounds f
  // to an interval; nullopt if there is none. off: the distance there (per axis, LSB) at the fraction
  // of the axis that moves most, taken into the interval. Distances come from differences (small
  // integers): the positions themselves (up to 2^47 LSB) would lose 1e-4 LSB in a double.
  struct Place {
    double lo, hi, off;  // positions (engine ticks), and the distance from the path there (LSB)
  };
  const double tol = tol_lsb + 1e-6;
  auto place = [&](const int64_t* o, uint64_t k) -> std::optional<Place> {
    double lo = 0, hi = k + 1 < n ? 1.0 : 0.0, f_big = 0, d_big = 0;
    for (int a = 0; a < axes; ++a) {
      const double d = k + 1 < n ? static_cast<double>(y(k + 1, a) - y(k, a)) : 0.0;
      const double e = static_cast<double>(o[a] - y(k, a));
      if (d == 0) {
        if (std::fabs(e) > tol) return std::nullopt;
        continue;
      }
      const double f0 = (e - tol) / d, f1 = (e + tol) / d;
      lo = std::max(lo, std::min(f0, f1));
      hi = std::min(hi, std::max(f0, f1));
      if (std::fabs(d) > std::fabs(d_big)) d_big = d, f_big = e / d;
    }
    if (lo > hi) return std::nullopt;
    const double f = std::clamp(f_big, lo, hi);
    double off = 0;
    for (int a = 0; a < axes; ++a) {
      const double d = k + 1 < n ? static_cast<double>(y(k + 1, a) - y(k, a)) : 0.0;
      off = std::max(off, std::fabs(f * d - static_cast<double>(o[a] - y(k, a))));
    }
    return Place{static_cast<double>(k) + lo, static_cast<double>(k) + hi, off};
  };
  // Every place each output may be at: intervals of positions (engine ticks) on the path within
  // tol of it that some place of the output before reaches (not behind it, at most max_advance
  // ahead). A single guess per output goes wrong where the path comes back near itself (out and back
  // along a line) or rests (every sample of the rest matches): the sets keep every choice until the
  // outputs that follow decide. The check fails where the set becomes empty.
  const double slack = 1e-6, step = max_advance + 0.01;
  const uint64_t reach = static_cast<uint64_t>(std::ceil(max_advance)) + 2;
  std::vector<std::vector<Place>> sets(m);
  for (uint64_t t = 0; t < m && c.first_problem.empty(); ++t) {
    const int64_t* o = &out[t * axes];
    const uint64_t k0 = t == 0 ? 0 : static_cast<uint64_t>(std::max(0.0, std::floor(sets[t - 1].front().lo)));
    const uint64_t k1 = (t == 0 ? 0 : static_cast<uint64_t>(std::floor(sets[t - 1].back().hi))) + reach;
    std::optional<double> beyond;  // the nearest matching place too far ahead
    for (uint64_t k = k0; k < n && k <= k1; ++k) {
      const auto p = place(o, k);
      if (!p) continue;
      const Place& cand = *p;
      if (t == 0) {
        sets[t].push_back(cand);
        continue;
      }
      for (const Place& q : sets[t - 1]) {
        const double lo = std::max(cand.lo, q.lo - slack), hi = std::min(cand.hi, q.hi + step);
        if (lo > hi) {
          if (cand.lo > q.hi + step && (!beyond || cand.lo - q.hi < *beyond)) beyond = cand.lo - q.hi;
          continue;
        }
        if (!sets[t].empty() && lo <= sets[t].back().hi) {
          sets[t].back().hi = std::max(sets[t].back().hi, hi);
          sets[t].back().off = std::max(sets[t].back().off, cand.off);
        } else {
          sets[t].push_back({lo, hi, cand.off});
        }
      }
    }
    if (sets[t].empty())
      c.first_problem = beyond ? "the output advanced " + std::to_string(*beyond) + " engine ticks in one sample (at most " +
                                     std::to_string(max_advance) + ")"
                               : "output sample " + std::to_string(t) + " is not on the path within " +
                                     std::to_string(tol_lsb) + " LSB after engine tick " + std::to_string(k0);
  }
  // One assignment, for the figures (the distance from the path, the largest advance): the places
  // from which the outputs after can still be placed (a pass from the end back), then from the
  // start the one nearest the position the last advance predicts (s changes slowly).
  if (c.first_problem.empty()) {
    for (uint64_t t = m - 1; t-- > 0;) {
      std::vector<Place> keep;
      for (const Place& q : sets[t])
        for (const Place& b : sets[t + 1]) {
          const double lo = std::max(q.lo, b.lo - step), hi = std::min(q.hi, b.hi + slack);
          if (lo > hi) continue;
          if (!keep.empty() && lo <= keep.back().hi) keep.back().hi = std::max(keep.back().hi, hi);
          else keep.push_back({lo, hi, q.off});
        }
      sets[t] = std::move(keep);
    }
    double at = 0, advance = 0;
    for (uint64_t t = 0; t < m; ++t) {
      const double want = at + advance, lo = t == 0 ? -INFINITY : at - slack, hi = t == 0 ? INFINITY : at + step;
      std::optional<double> best;
      double off = 0;
      for (const Place& q : sets[t]) {
        const double l = std::max(q.lo, lo), h = std::min(q.hi, hi);
        if (l > h) continue;
        const double x = std::clamp(want, l, h);
        if (!best || std::fabs(x - want) < std::fabs(*best - want)) best = x, off = q.off;
      }
      if (!best) {  // cannot happen: every place kept reaches one of the next output's
        c.first_problem = "output sample " + std::to_string(t) + ": no place left (check_on_path)";
        break;
      }
      if (t > 0) {
        advance = *best - at;
        c.largest_advance = std::max(c.largest_advance, advance);
      }
      c.worst_lsb = std::max(c.worst_lsb, off);
      at = *best;
    }
  }
  c.ends_on_last = std::equal(out.end() - axes, out.end(), engine.end() - axes);
  if (c.first_problem.empty() && !c.ends_on_last) c.first_problem = "the last output is not the trajectory's last sample";
  return c;
}

std::string describe(const PathCheck& c) {
  char line[512];
  std::snprintf(line, sizeof line,
                "output samples on the path of the exact prediction (re-timed): %s: %llu samples within %.2f LSB of "
                "the polyline through the engine samples, at most %.3f engine ticks apart, %s\n",
                c.ok() ? "yes" : "NO", static_cast<unsigned long long>(c.samples), c.worst_lsb, c.largest_advance,
                c.ends_on_last ? "ending on the last sample" : "NOT ending on the last sample");
  std::string s = line;
  if (!c.first_problem.empty()) s += "  first problem: " + c.first_problem + "\n";
  return s;
}

std::string describe(const StepCheck& c) {
  std::string s = c.scaled ? "step/dir pins decoded against the board's time-scaled output samples (" +
                                 std::to_string(c.ticks_seen) + " servo ticks): " + (c.ok() ? "identical" : "DIFFERENT") +
                                 "\n"
                           : "step/dir pins decoded against the exact prediction of " + std::to_string(c.ticks_expected) +
                                 " ticks (" + std::to_string(c.ticks_seen) + " samples seen): " +
                                 (c.ok() ? "identical" : "DIFFERENT") + "\n";
  for (size_t a = 0; a < c.axes.size(); ++a) {
    const auto& x = c.axes[a];
    char line[256];
    std::snprintf(line, sizeof line,
                  "  axis %zu: %llu steps predicted, %llu decoded (%llu pairs netted out), net %lld / %lld; edge after "
                  "its path crossing %.3f .. %.3f us (ticks %llu, %llu)\n",
                   a, static_cast<unsigned long long>(x.expected), static_cast<unsigned long long>(x.decoded),
                   static_cast<unsigned long long>(x.cancelled),
                   static_cast<long long>(x.final_expected), static_cast<long long>(x.final_decoded), x.delay_min_us,
                   x.delay_max_us, static_cast<unsigned long long>(x.delay_min_tick),
                   static_cast<unsigned long long>(x.delay_max_tick));
    s += line;
  }
  if (!c.first_problem.empty()) s += "  first problem: " + c.first_problem + "\n";
  return s;
}

}  // namespace traj::board
