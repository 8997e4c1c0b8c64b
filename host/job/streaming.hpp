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

// One curve of a streamed path with how it is to be run (a toolpath's move,
// or a part of one).
struct StreamCurve {
  geo::BSpline curve;
  std::string where;
  double speed = 0;   // the speed over this curve, units/s; 0: the feed limit (Limits::feed)
  bool stop = false;  // the machine stops exactly at its end
  double dwell = 0;   // and rests there this many seconds (G4)
  plan::ProgramPause pause{};  // a program pause follows: the segment that ends in the rest carries it
};

class StreamSource {
 public:
  virtual ~StreamSource() = default;
  // The next curve; false at the end of the path.
  virtual bool next(StreamCurve& c) = 0;
};

struct StreamOptions {
  size_t window = 64;  // curves held at once
  size_t commit = 48;  // curves committed per window (< window); the rest is look-ahead, planned again
  // A window also ends once its curves take this many fit ticks at their
  // speeds (and dwells), and longer curves are cut into pieces of a quarter
  // of it: a plan holds about 550 bytes a tick, so slow, long moves stream
  // in about 100 MB (LibreCAD's Complete-Lib-V.dxf through dxf2gcode, 19 m
  // at 400 mm/min: 2.8 GB with windows of 64 curves alone).
  size_t window_ticks = 100000;
  // Read, blend and build the curves (arc-length tables) on a second thread,
  // at most a window ahead (prefetch.hpp); the same curves and plan.
  bool prefetch = true;
};

struct StreamStats {
  size_t curves = 0, windows = 0, segments = 0, caps = 0;
  size_t retries = 0;             // windows planned again with half their commit (run_streaming)
  long long ticks = 0;            // samples emitted
  double motion_time = 0;         // s
  double wall = 0;                // host seconds, planning + compilation
  double first_segment = -1;      // host seconds until the first compiled segment
  size_t max_window_ticks = 0;    // largest tick buffer held
};

// Called for every compiled segment, in order.
using SegmentSink = std::function<void(const fd::Compiled&, const plan::TimeSegment&)>;
// The sink that writes each segment to `w`, and the program pause after it.
SegmentSink write_to(stream::StreamWriter& w);

// Each window plans its curves with their speeds as speed caps and their
// stops as caps of speed 0 (as toolpath_plan does for a whole toolpath).
StreamStats run_streaming(StreamSource& src, const JobConfig& cfg, const StreamOptions& so, const SegmentSink& sink,
                          const Progress& progress = {});
StreamStats run_streaming(CurveSource& src, const JobConfig& cfg, const StreamOptions& so, const SegmentSink& sink,
                          const Progress& progress = {});

}  // namespace traj::job
