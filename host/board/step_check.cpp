// SPDX-License-Identifier: Apache-2.0
#include "board/step_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fd/fd_ticker.hpp"

namespace traj::board {
namespace {

int64_t floor_shift(int64_t v, int sh) { return v >= 0 ? v >> sh : -((-v - 1) >> sh) - 1; }

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
  AxisChecker(const std::vector<uint64_t>& ticks, const StepDecoder& d, int shift, StepCheck& c, AxisSteps& a)
      : ticks_(ticks), edges_(d.edges()), sh_(shift), c_(c), a_(a) {}

  void run(const std::vector<int64_t>& s) {
    const size_t n_max = std::min(s.size(), ticks_.size());
    for (size_t n = 1; n < n_max; ++n) {
      const int64_t e0 = floor_shift(s[n - 1], sh_), e1 = floor_shift(s[n], sh_);
      for (int64_t b = e0 + 1; b <= e1; ++b) expect(n, s, b, true);
      for (int64_t b = e0; b > e1; --b) expect(n, s, b, false);
    }
    if (!s.empty()) a_.final_expected = floor_shift(s[n_max - 1], sh_) - floor_shift(s[0], sh_);
    a_.decoded = edges_.size();
    for (const auto& e : edges_) a_.final_decoded += e.up ? 1 : -1;
    if (a_.decoded != a_.expected) problem("axis step count: " + std::to_string(a_.decoded) + " edges decoded, " +
                                           std::to_string(a_.expected) + " steps predicted");
  }

 private:
  void expect(size_t n, const std::vector<int64_t>& s, int64_t boundary, bool up) {
    const size_t i = a_.expected++;
    if (i >= edges_.size() || edges_[i].up != up) {
      problem("tick " + std::to_string(n) + ": predicted step " + std::to_string(i) + (up ? " up" : " down") +
              (i >= edges_.size() ? " not on the pins" : " decoded in the other direction"));
      return;
    }
    const double p = static_cast<double>(n + 1 < ticks_.size() ? ticks_[n + 1] - ticks_[n] : ticks_[n] - ticks_[n - 1]);
    const double cross = static_cast<double>(boundary) * std::ldexp(1.0, sh_);
    const double f = (cross - static_cast<double>(s[n - 1])) / static_cast<double>(s[n] - s[n - 1]);
    const double delay = (static_cast<double>(edges_[i].cycle) - (static_cast<double>(ticks_[n]) + f * p)) /
                         BoardBuild::kClkHz * 1e6;
    if (i == 0 || delay < a_.delay_min_us) a_.delay_min_us = delay;
    if (i == 0 || delay > a_.delay_max_us) a_.delay_max_us = delay;
  }
  void problem(const std::string& what) {
    if (c_.mismatches++ == 0) c_.first_problem = what;
  }
  const std::vector<uint64_t>& ticks_;
  const std::vector<StepDecoder::Edge>& edges_;
  int sh_;
  StepCheck& c_;
  AxisSteps& a_;
};

}  // namespace

StepCheck check_steps(const stream::ReadResult& expected, const std::vector<int>& shifts,
                      const SimulatedBoard& board) {
  StepCheck c;
  c.ticks_seen = board.tick_cycles().size();
  const int axes = std::min(expected.header.axes, BoardBuild::kAxes);
  c.axes.resize(axes);
  for (int a = 0; a < axes; ++a) {
    const auto s = predicted_samples(expected, a);
    c.ticks_expected = s.size();
    AxisChecker(board.tick_cycles(), board.axis(a), shifts.at(a), c, c.axes[a]).run(s);
    c.violations += board.axis(a).violations();
    if (board.axis(a).violations() && c.first_problem.empty())
      c.first_problem = "axis " + std::to_string(a) + ": " + board.axis(a).first_violation();
  }
  if (c.ticks_seen < c.ticks_expected && c.first_problem.empty())
    c.first_problem = "the board ticked " + std::to_string(c.ticks_seen) + " times, the stream has " +
                      std::to_string(c.ticks_expected) + " ticks";
  return c;
}

std::string describe(const StepCheck& c) {
  std::string s = "step/dir pins decoded against the exact prediction of " + std::to_string(c.ticks_expected) +
                  " ticks (" + std::to_string(c.ticks_seen) + " ticks seen): " + (c.ok() ? "identical" : "DIFFERENT") +
                  "\n";
  for (size_t a = 0; a < c.axes.size(); ++a) {
    const auto& x = c.axes[a];
    char line[256];
    std::snprintf(line, sizeof line, "  axis %zu: %llu steps predicted, %llu decoded, net %lld / %lld; edge after its chord crossing "
                   "%.3f .. %.3f us\n",
                   a, static_cast<unsigned long long>(x.expected), static_cast<unsigned long long>(x.decoded),
                   static_cast<long long>(x.final_expected), static_cast<long long>(x.final_decoded), x.delay_min_us,
                   x.delay_max_us);
    s += line;
  }
  if (!c.first_problem.empty()) s += "  first problem: " + c.first_problem + "\n";
  return s;
}

}  // namespace traj::board
