// SPDX-License-Identifier: Apache-2.0
// Decodes one axis's step/dir pins, cycle by cycle, independently of the RTL
// that drives them: a step is a rising edge of `step`, counted +1 when `dir`
// is high and -1 when low. It checks the driver's timing contract: the pulse
// stays high at least `pulse` cycles, stays low at least `pulse` cycles
// between pulses, and `dir` is stable `setup` cycles before and after each
// rising edge. Every edge's cycle is kept for the timing comparison.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace traj::board {

struct StepTiming {
  uint32_t pulse = 1;  // minimum high and low time, cycles
  uint32_t setup = 0;  // dir stable before and after a rising step edge, cycles
};

class StepDecoder {
 public:
  explicit StepDecoder(StepTiming t) : t_(t) {}
  const StepTiming& timing() const { return t_; }

  void sample(uint64_t cycle, bool step, bool dir) {
    if (dir != dir_) {
      if (cycle - last_rise_ < t_.setup && rises_ > 0) fail(cycle, "direction changed within the hold time");
      dir_ = dir;
      dir_change_ = cycle;
    }
    if (step && !step_) {
      if (cycle - dir_change_ < t_.setup && dir_changed_once()) fail(cycle, "step within the direction setup time");
      if (rises_ > 0 && cycle - last_fall_ < t_.pulse) fail(cycle, "step low time below the pulse width");
      position_ += dir ? 1 : -1;
      ++rises_;
      last_rise_ = cycle;
      edges_.push_back({cycle, dir});
    } else if (!step && step_) {
      if (cycle - last_rise_ < t_.pulse) fail(cycle, "step pulse shorter than the pulse width");
      last_fall_ = cycle;
    }
    step_ = step;
  }

  int64_t position() const { return position_; }
  struct Edge {
    uint64_t cycle;
    bool up;
  };
  const std::vector<Edge>& edges() const { return edges_; }
  const std::string& first_violation() const { return violation_; }
  uint64_t violations() const { return violations_; }

 private:
  bool dir_changed_once() const { return dir_change_ != kNever; }
  void fail(uint64_t cycle, const char* what) {
    if (violations_++ == 0) violation_ = "cycle " + std::to_string(cycle) + ": " + what;
  }
  static constexpr uint64_t kNever = ~uint64_t{0};
  StepTiming t_;
  bool step_ = false, dir_ = false;
  uint64_t dir_change_ = kNever, last_rise_ = 0, last_fall_ = 0, rises_ = 0;
  int64_t position_ = 0;
  std::vector<Edge> edges_;
  uint64_t violations_ = 0;
  std::string violation_;
};

}  // namespace traj::board
