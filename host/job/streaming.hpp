// SPDX-License-Identifier: Apache-2.0
// Bounded-memory streaming over paths of any length.
//
// Curves come one at a time from a CurveSource. The planner holds a window of
// at most `window` curves and plans it as if the machine had to stop at the
// window's end (always safe: it can). It then commits the motion up to the
// junction after the first `commit` curves (a forced station, so the
// acceleration is zero there), emits the compiled segments of the committed
// ticks, and carries into the next window exactly: the speed at the junction,
// the last committed tick sample, and the compiler's integer end state. The
// next window re-plans from there with more look-ahead. Memory is bounded by
// the window, not by the path.
#pragma once
#include <functional>
#include <string>

#include "fd/fd_compiler.hpp"
#include "input/curve_source.hpp"
#include "job/job.hpp"

namespace traj::job {

using input::CurveSource;

struct StreamOptions {
  size_t window = 64;  // curves held at once
  size_t commit = 48;  // curves committed per window (< window); the rest is look-ahead, planned again
};

struct StreamStats {
  size_t curves = 0, windows = 0, segments = 0, caps = 0;
  long long ticks = 0;            // samples emitted
  double motion_time = 0;         // s
  double wall = 0;                // host seconds, planning + compilation
  double first_segment = -1;      // host seconds until the first compiled segment
  size_t max_window_ticks = 0;    // largest tick buffer held
};

// Called for every compiled segment, in order.
using SegmentSink = std::function<void(const fd::Compiled&, const plan::TimeSegment&)>;

StreamStats run_streaming(CurveSource& src, const JobConfig& cfg, const StreamOptions& so, const SegmentSink& sink,
                          const Progress& progress = {});

}  // namespace traj::job
