// SPDX-License-Identifier: Apache-2.0
// The limits on the core's samples, measured from the samples alone, one
// sample at a time: memory is bounded however long the run. `make_report`
// (trajcore run) and `trajcore sim --check` both measure with it.
//
// From the integer samples (LSB) at ticks h apart: per axis the first, second
// and third differences over h, h^2, h^3; the path's speed, acceleration and
// jerk as the norms of those; the tangential and normal components of
// planner/sampled.hpp over every window of four samples (three steps; the
// last window two), positions taken relative to the window's first sample
// from exact integer differences. Each is compared with its limit less the
// quantisation allowance (job::sample_allowance): the samples are within q of
// a trajectory whose own figures the planner kept within the limits.
#pragma once
#include <array>
#include <string>

#include "job/machine.hpp"
#include "planner/planner.hpp"
#include "report/report.hpp"

namespace traj::report {

class SampleCheck {
 public:
  // axes: the stream's (1..kMaxAxes); lsb: units per LSB; h: tick period, s.
  SampleCheck(int axes, double lsb, double h);
  void add(const Sample& s);
  // Takes the last window (two steps); call once, after the last add.
  void finish();

  long long count() const { return n_; }
  // Per-axis v, a, j; feed (the path speed), a_tan, a_cen, j_tan, j_cen.
  const plan::Peaks& peaks() const { return pk_; }
  double path_a() const { return path_a_; }  // |second differences| / h^2, vector norm
  double path_j() const { return path_j_; }  // |third differences| / h^3, vector norm

 private:
  // (x[i] - x[0]) * lsb for the last samples x[0..m] (m <= 3), exact differences
  void window(int m);
  int axes_;
  double lsb_, h_;
  long long n_ = 0;
  std::array<Sample, 4> last_{};  // last_[3] the newest
  plan::Peaks pk_;
  double path_a_ = 0, path_j_ = 0;
};

// The worst (peak - allowance) / limit over what the samples are checked
// against: per axis v, a and (jerk_claimed) j with the per-axis allowance;
// the feed, a_tan, a_cen and (jerk_claimed) j_tan, j_cen with sqrt(axes)
// times it (vector norms). Cubic segments (C1 joins) carry no jerk claim.
struct Worst {
  double ratio = 0;
  std::string what;
};
Worst worst_of_samples(const plan::Peaks& out, const job::Allowance& al, const plan::Limits& l, int axes,
                       bool jerk_claimed);

}  // namespace traj::report
