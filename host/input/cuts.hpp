// SPDX-License-Identifier: Apache-2.0
// Cuts -> toolpath, shared by the drawing readers (SVG, DXF): each cut is a
// chain of feed moves; consecutive cuts are joined by rapid moves.
#pragma once
#include <string>
#include <vector>

#include "geometry/bspline.hpp"
#include "input/toolpath.hpp"

namespace traj::input {

struct CutPiece {
  geo::BSpline curve;  // clamped, in mm; starts where the previous piece of its cut ends
  std::string where;   // Move::where of its feed move
};
using Cut = std::vector<CutPiece>;

// The toolpath of `cuts` in order, curves with `axes` columns: a rapid (a straight line, exact stop)
// from the origin to the first cut's start and from each cut's end to the next cut's start, then the
// cut's pieces as feed moves (feed 0 = the job's feed, the job's tolerance). A rapid of zero length
// (the next cut starts where the previous one ended, or the first at the origin) is left out. Empty
// cuts are skipped; so are negligible pieces (a drawing's path closed by relative steps that return
// to its start within rounding, 1e-15 mm away, gets such a closing piece), the next piece starting
// where the last one kept ends.
Toolpath toolpath_from_cuts(const std::vector<Cut>& cuts, int axes);

// A piece whose control polygon is at most kNegligibleMm long (so is its length): below anything a
// machine can do, and at most the length the planner refuses (1e-9).
constexpr double kNegligibleMm = 1e-9;
bool negligible(const geo::BSpline& c);

// First / last point of a clamped curve (its first / last control point).
Eigen::VectorXd start_point(const geo::BSpline& c);
Eigen::VectorXd end_point(const geo::BSpline& c);
// The same curve run backwards (clamped input): control points and weights in reverse order, knots
// mirrored in the domain.
geo::BSpline reversed(const geo::BSpline& c);
// True if every control point equals the first: a curve of zero length, which a cut leaves out.
bool degenerate(const geo::BSpline& c);

}  // namespace traj::input
