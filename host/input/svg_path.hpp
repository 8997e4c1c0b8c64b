// SPDX-License-Identifier: Apache-2.0
// SVG geometry in user units (y down, as in the file): path data ("d"), elliptical arcs, transforms.
// The SVG reader (svg.hpp) maps the result to millimetres.
#pragma once
#include <Eigen/Dense>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "geometry/bspline.hpp"

namespace traj::input::svg {

// A path data error; `offset` is the character offset in the attribute value (0-based).
class PathDataError : public std::runtime_error {
 public:
  PathDataError(std::size_t offset, const std::string& why)
      : std::runtime_error("offset " + std::to_string(offset) + ": " + why), offset(offset) {}
  std::size_t offset;
};

// One subpath: segments in order, each a clamped 2-D curve starting where the previous one ends
// (lines degree 1, quadratic and cubic Beziers, arcs as rational quadratic NURBS). Segments of zero
// length are left out, so a subpath can be empty.
struct Subpath {
  std::vector<geo::BSpline> segments;
  bool closed = false;
};

// Parses SVG path data: M L H V C S Q T A Z, absolute and relative, implicit repetition (extra pairs
// after M/m are L/l), numbers as in the SVG grammar ("1.5.5" = 1.5 0.5, "-.5", "1e-3", "10-5" =
// 10 -5), arc flags as single digits ("a1 1 0 00 1 1"). Throws PathDataError.
std::vector<Subpath> parse_path_data(const std::string& d);

// Elliptical arc from p0 to p1 (SVG "A" parameters; rotation in degrees), converted to centre form
// (SVG 1.1 F.6.5), radii scaled up if too small (F.6.6), as rational quadratic pieces of at most
// 90 degrees (the affine image of make_arc's unit circle; exact up to rounding). Its end points are
// exactly p0 and p1. Zero radius: a straight line. Equal end points: an empty curve (n_ctrl 0).
geo::BSpline arc_segment(const Eigen::Vector2d& p0, double rx, double ry, double rotation_deg,
                         bool large_arc, bool sweep, const Eigen::Vector2d& p1);

// The ellipse centre c, radii rx, ry, from parametric angle t0 to t1 (radians, signed sweep, y down
// as in SVG: t grows from +x towards +y), rotated by `rotation` (radians).
geo::BSpline ellipse_arc(const Eigen::Vector2d& c, double rx, double ry, double rotation, double t0,
                         double t1);

// 2-D affine map as a 3x3 matrix [a c e; b d f; 0 0 1] (SVG's matrix(a b c d e f)).
using Affine = Eigen::Matrix3d;

// Parses an SVG transform list ("translate(10 20) rotate(30, 5 5) scale(2)"): matrix, translate,
// scale, rotate (with optional centre), skewX, skewY; the list composes left to right (the first
// transform is outermost). Throws PathDataError (offset into the attribute).
Affine parse_transform(const std::string& s);

// The curve with every control point mapped by `m` (exact for B-splines and NURBS: both are affine
// invariant).
geo::BSpline transformed(const geo::BSpline& c, const Affine& m);

// A number (SVG grammar) followed by optional whitespace and a unit ("12.5mm", "3 in", "50%"): the
// number and the unit text ("" if none); throws PathDataError.
std::pair<double, std::string> parse_length(const std::string& s);

// Number lists as in the "points" attribute of polyline/polygon and in viewBox; throws PathDataError.
std::vector<double> parse_number_list(const std::string& s);

}  // namespace traj::input::svg
