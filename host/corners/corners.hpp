// SPDX-License-Identifier: Apache-2.0
// Corner blending: the feed moves of a toolpath turned into a curvature-continuous (G2) chain of
// curves within the path tolerance (README.md: method, formulas, limits). Corners next to a curved
// move are blended with the same five-point form built on the curved leg's tangent at a cut
// (README.md, "Curved legs").
//
// At each corner where two straight feed segments meet with a tangent break, a piece of length
// kBlendReach d = 1.5 d of each segment is replaced by a symmetric cubic B-spline of five control points
//   P0 = V - 1.5d t_in, P1 = V - d t_in, P2 = V, P3 = V + d t_out, P4 = V + 1.5d t_out,
//   knots {0,0,0,0,1/2,1,1,1,1},
// tangent to both legs with curvature 0 at both joins (P0, P1, P2 collinear, and P2, P3, P4): the path
// of a velocity turn by one bang-bang jerk pulse along t_out - t_in (kBlendReach). With
// theta the turning angle (0: straight on, pi: reversal), in closed form:
//   deviation (distance from the corner V to the blend, = Hausdorff distance to the polyline)
//     delta = (d / 2) sin(theta / 2),
//   peak curvature (at u = 1/2)   kappa_max = (4/3) sin(theta/2) / (d cos^2(theta/2)).
// d is the largest value with delta <= tol and kBlendReach d <= share * (length of each leg).
#pragma once
#include <Eigen/Dense>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "geometry/bspline.hpp"
#include "input/toolpath.hpp"

namespace traj::corners {

// Distance of the five-point blend's end points from the corner, in units of its inner spacing d.
// At 1.5 the cubic's third derivative along u is t_out - t_in times the same constant on both spans
// with opposite signs: the blend is the path that a velocity turn by one bang-bang jerk pulse
// traces, whose peak |d3x/ds3| (which bounds the speed a jerk limit allows through it) is lower than
// at reach 2 (README.md, "The reach of the end points": the speed through it 1.14x at small turns,
// 1.08x at 45 degrees, 1.02x at 90) and the least of the reaches tried up to 45. The deviation and the
// peak curvature depend on P1, P2, P3 only, so their closed forms hold for any r.
constexpr double kBlendReach = 1.5;

// Shape of a run's curve (run_spline).
struct RunShape {
  // Share of its gap by which each inner vertex's control point moves towards the vertex: the curve
  // then passes between the vertices and the edges (on a regular polygon, 5/8 leaves 1/16 of the
  // vertex's second difference to either side instead of 1/6 inside).
  double pull = 0.625;
  // Spans (mm of chord length) of the smoothed run (README.md, "Runs"): a least-squares cubic over the
  // polygon, tried first; 0: runs interpolate their vertices.
  double fit_span = 2.0;
};

// A point or direction of at most 8 coordinates (the core's axes), held on the stack: the blend
// searches evaluate millions of them, and a heap vector would allocate for each.
using Point = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 8, 1>;

// A line-line corner about to be blended on its own, as BlendOptions::stop_if_faster sees it.
struct CornerCandidate {
  geo::BSpline blend;              // the transition it would take (five-point or wide), from leg to leg
  Point v, t_in, t_out;            // the corner and the unit directions of the legs
  double leg_in = 0, leg_out = 0;  // the legs' lengths, mm
  // The straight-on path before and after (mm): the leg and the segments beyond it joined by turns of
  // at most stop_turn, where the motion may speed up towards the corner and after it.
  double run_in = 0, run_out = 0;
  double feed = 0;                 // the smaller of the two moves' feeds (0: none programmed)
  double turn = 0;                 // rad
};

struct BlendOptions {
  double share = 0.5;         // largest share of a segment one blend may take (from each leg): no overlaps
  double kink = 1e-6;         // turning angle (rad) up to which a join is passed as it is (the planner's corner_tol)
  double max_turn = 3.12413936106985;  // turning angle (rad, 179 degrees) above which the corner is an exact stop
  double min_line = 1e-6;     // mm: a segment remnant shorter than this is dropped (the blends meet directly)
  // Runs of consecutive line-line corners at smooth vertices (each near the chord of its neighbours)
  // become one cubic B-spline over the run's vertices (run_spline), entered and left like a single
  // blend (README.md, "Runs"). Its deviation is measured (sampled, then refined), not closed-form; a
  // run that measures above the tolerance is halved until one passes.
  bool merge_runs = true;
  int run_samples = 32;       // samples per knot span for a run's deviation check
  RunShape run_shape;
  // Corners next to a curved move (arc, helix, spline) are blended too (README.md, "Curved legs"):
  // the curved leg is cut at arc length 2d from the corner and the blend is built on its tangent there,
  // with the leg's departure from its tangent line in the deviation budget. false: left as stops
  // (StopReason::kCurvedMove).
  bool blend_curved = true;
  // A tangent join (turn <= kink) next to a curved move whose curvature vector steps by more than this
  // (1/mm) is blended too (README.md, "Curvature steps").
  double curvature_step = 1e-6;
  // A line-line corner takes the seven-point wide blend (README.md, "Wide blends") where its peak
  // |d3x/ds3| is at least 5 % below the five-point blend's; false: the five-point blend always.
  bool wide = true;
  // A line-line corner blended on its own next to a stop (the chain's start or end where it is at
  // rest, a corner left a stop, an exact stop) is blended from the stop: at a virtual vertex on the
  // far leg, the curve starting (ending) at the stop (README.md, "Corners next to a stop"). false:
  // the five-point or wide blend at the corner.
  bool from_stops = true;
  // A line-line corner turning by at most stop_turn between two such corners, each vertex more than
  // kRunHeight tolerances from the chord of its neighbours (too sharp for a run; CAM chords whose sag
  // exceeds the tolerance), moves outward by offset_share of the tolerance: the legs between such
  // corners run up to that far outside the programmed polyline, and the blend, measured against the
  // programmed legs, cuts that much deeper and is that much flatter (README.md, "Offset corners").
  // 0: every blend at its programmed vertex.
  double offset_share = 0.9;
  // Asked for each line-line corner turning by more than stop_turn that would be blended on its own
  // (a run's corners are not asked): true leaves it an exact stop (StopReason::kFaster). Under a jerk
  // limit a sharp corner's blend is passed slowly over its whole length, and at a high feed that can
  // take longer than stopping at the corner (README.md, "Stops that are faster"); the caller knows
  // the limits (job/toolpath_job plans both locally). Unset: every such corner is blended.
  std::function<bool(const CornerCandidate&)> stop_if_faster;
  double stop_turn = 0.35;  // rad (20 degrees)
  // Whether the machine is at rest where the toolpath starts (ends): a whole program, or a part of
  // one cut at a rest. A run at a rest takes the segment there whole (README.md, "Smoothed runs"); a
  // part cut inside a move (job/toolpath_stream) continues at speed there and keeps a straight end.
  bool starts_at_rest = true, ends_at_rest = true;
};

// One curve of the output chain, with what it inherits from its move.
struct ChainCurve {
  geo::BSpline curve;  // clamped, mm
  std::string where;   // the move's where; blends: "<where in> / <where out>: corner blend"
  double feed = 0;     // the move's feed (a blend: the smaller of its two moves' feeds)
  input::Move::Kind kind = input::Move::Kind::kFeed;
  bool exact_stop = false;  // stop at the end of this curve (the move's exact_stop, on its last curve)
  bool blend = false;       // a corner transition (a single corner's blend or a run's curve)
  double dwell = 0;         // seconds at rest after it (the move's G4, on its last curve)
  plan::ProgramPause pause{};  // the move's program pause (input::Move::pause), on its last curve
};

enum class StopReason { kRapid, kExactStop, kReversal, kCurvedMove, kFaster };
const char* to_string(StopReason r);

// A corner (tangent break) left as it is: the planner stops there (or passes it at its corner speed).
struct CornerStop {
  size_t move = 0;      // index of the move that ends at the corner
  std::string where;
  StopReason reason = StopReason::kExactStop;
  double turn = 0;      // turning angle, rad
};

// A blended corner.
struct Blend {
  size_t move = 0;          // index of the move that ends at (or contains) the corner
  double turn = 0;          // turning angle, rad
  double d = 0;             // control-point spacing; each leg loses kBlendReach d (2d at a curved leg, l0 = 2d wide)
  double deviation = 0;     // (d/2) sin(turn/2)
  double tol = 0;           // tolerance that applied (the smaller of the two moves')
  bool shortened = false;   // d limited by a leg's share: deviation < tol
  double peak_curvature = 0;  // of the separate blend (not of a run)
  bool in_run = false;      // part of a merged run: deviation is the measured distance of the vertex to the run
  // A leg is curved (README.md, "Curved legs"): deviation is measured (sampled, then refined) against
  // the pieces the blend replaces; peak_curvature is that of the line-line blend at the same corner
  // (an estimate). g2: curvature continuous at both joins (else G1 with a curvature step at a curved leg).
  bool curved = false;
  bool g2 = true;
  // Both legs straight and the seven-point wide blend taken (README.md, "Wide blends"): d is half its
  // l0, deviation and peak_curvature are measured.
  bool wide = false;
  // Next to a stop, blended at a virtual vertex on the far leg from the stop (README.md, "Corners
  // next to a stop"): d is that blend's spacing, deviation measured against the two legs.
  bool at_stop = false;
};

// A run of corners merged into one curve.
struct Run {
  size_t first_blend = 0, corners = 0;  // indices into BlendResult::blends
  double deviation = 0;                 // measured: the larger of vertex-to-curve and curve-to-polyline
};

struct BlendResult {
  std::vector<ChainCurve> curves;
  int corners_blended = 0;
  int joins_passed = 0;        // collinear or nearly (turn <= kink): left as they are
  double max_deviation = 0;    // largest blend deviation, mm
  std::vector<Blend> blends;
  std::vector<Run> runs;
  std::vector<CornerStop> stops;
};

// Closed forms of the five-point blend (README.md derives them).
double blend_deviation(double d, double turn);
double blend_spacing_for(double tol, double turn);  // d with blend_deviation(d, turn) == tol
double blend_peak_curvature(double d, double turn);
// The blend at corner v between unit directions t_in (arriving) and t_out (leaving), spacing d.
geo::BSpline corner_blend(const Point& v, const Point& t_in, const Point& t_out, double d);

// One cubic B-spline over a run of vertices v[0..m-1] (m >= 1), entered from direction t_in with
// spacing d_first and left along t_out with spacing d_last: control points
//   v0 - kBlendReach d_first t_in, v0 - d_first t_in, v0, ..., v_{m-1}, v_{m-1} + d_last t_out,
//   v_{m-1} + kBlendReach d_last t_out,
// clamped knots with the m interior knots uniform, the inner vertices' control points pulled as
// RunShape says. m = 1 with d_first = d_last is corner_blend.
geo::BSpline run_spline(const std::vector<Point>& v, const Point& t_in, double d_first, const Point& t_out,
                        double d_last, const RunShape& shape = {});

// Blend every corner between two feed moves (degree-1 moves are split at their vertices: a degree-1
// curve of many points is a polyline; curved moves are cut where a corner next to them is blended).
// Rapids and their joins pass through unchanged. default_tol applies where a move's tolerance is < 0. Throws std::invalid_argument on a
// non-positive tolerance or share outside (0, 1].
BlendResult blend_corners(const input::Toolpath& tp, double default_tol, const BlendOptions& o = {});

// Append the chain to a planner path (plan::Path::add(spline, where) checks each join), or to any
// type with that member: this library does not depend on the planner.
// The blended chain as a toolpath (each curve a move with its kind, feed, exact stop and where), for
// the job (job/toolpath_job.hpp). `axes` and `notes` are the original toolpath's.
input::Toolpath to_toolpath(const BlendResult& r, const input::Toolpath& original);

template <class PathT>
void append_to(PathT& path, const BlendResult& r) {
  for (const ChainCurve& c : r.curves) path.add(c.curve, c.where);
}

}  // namespace traj::corners
