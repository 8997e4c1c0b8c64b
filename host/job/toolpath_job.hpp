// SPDX-License-Identifier: Apache-2.0
// A toolpath (G-code, SVG, DXF) as the planner's input: the path of its moves,
// and each move's speed as a speed cap over its arc length.
//
//   feed move   its programmed feed (F / 60), or the job's feed where the file
//               programs none (SVG, DXF);
//   rapid       the rapid speed (ToolpathOptions::rapid; by default the
//               smallest velocity limit of X Y Z, which every direction can
//               take; a further axis's own limit binds through the
//               planner's per-axis bounds);
//   feed move   with further axes: F of X Y Z, else U V W, else A B C
//               (input::Move::feed_scale);
//   exact stop  the speed is 0 at the end of a move that asks for it (every
//               rapid, G61): a cap of speed 0 over the junction point.
// The planner's own speed limit (Limits::feed) becomes the largest of these
// speeds, so the caps, not it, set the speed of each move.
//
// Corners between feed moves are blended (ToolpathOptions::blend,
// host/corners: curvature-continuous transitions) within blend_share of the
// path tolerance (the move's G64 P, else the job's --tol), and the fit gets
// the rest of --tol, so the output stays within the tolerance of the
// programmed toolpath. The fit of quintic segments to the plan needs little
// (a few % of the tolerance on the benchmark toolpaths), so the blends get
// most of it: longer blends and runs, gentler curvature.
#pragma once
#include <cstddef>
#include <vector>

#include "input/gcode.hpp"
#include "input/toolpath.hpp"
#include "job/job.hpp"

namespace traj::job {

struct ToolpathOptions {
  input::GcodeOptions gcode;  // the reader's (the tool table G43 takes lengths from)
  double rapid = 0;   // mm/s; 0: the smallest velocity limit of X Y Z (the further axes' own limits hold through the planner)
  bool blend = true;  // blend the corners between feed moves (host/corners)
  double blend_share = 0.9;  // share of the tolerance for the blends; the fit gets the rest
  bool wide_blends = true;   // corners::BlendOptions::wide (host/corners, "Wide blends")
  // A line-line corner of more than 20 degrees is left an exact stop where that is faster at the
  // job's limits than its blend (corners::BlendOptions::stop_if_faster; both planned locally).
  bool faster_stops = true;
  // A corner next to a stop is blended from the stop (corners::BlendOptions::from_stops; host/corners,
  // "Corners next to a stop").
  bool stop_blends = true;
  // Vertices between corners too sharp for a run move outward within the tolerance, so that their
  // blends cut deeper (corners::BlendOptions::offset_share; host/corners, "Offset corners").
  bool offset_corners = true;
};

struct ToolpathPlan {
  plan::Path path;
  JobConfig cfg;     // the job's configuration with the caps and the feed limit of the toolpath
  size_t feed_moves = 0, rapids = 0, stops = 0;
  std::vector<char> rapid_curve;  // per curve of path: a rapid move (the plots draw it so)
  int corners_blended = 0;     // corners replaced by a G2 transition
  int wide_blends = 0;         // of them, line-line corners with a wide blend (host/corners, "Wide blends")
  double blend_deviation = 0;  // largest distance of a transition from its corner, mm
  size_t corner_stops = 0;     // corners left as stops (rapids, exact stops, reversals, arc ends, faster so)
  size_t faster_stops = 0;     // of them, corners where a stop is faster than the blend
};

// PlanError naming the move if the moves do not chain (a reader's bug) or a
// feed is not positive.
ToolpathPlan toolpath_plan(const input::Toolpath& tp, const JobConfig& cfg, const ToolpathOptions& o = {});

// Parts of toolpath_plan, for a toolpath streamed in chunks (job/toolpath_stream.hpp):
// the corners blended within o.blend_share of each move's tolerance (default:
// of cfg.limits.tol; cfg's limits also decide the faster stops), with r's corner
// counts and largest deviation set; and the rapid speed. starts_at_rest
// (ends_at_rest): whether the machine rests where tp starts (ends), false
// where a chunk was cut inside a move (corners::BlendOptions).
input::Toolpath blend_toolpath(const input::Toolpath& tp, const JobConfig& cfg, const ToolpathOptions& o,
                               ToolpathPlan& r, bool starts_at_rest = true, bool ends_at_rest = true);
double rapid_speed(const JobConfig& cfg, int axes, const ToolpathOptions& o);

}  // namespace traj::job
