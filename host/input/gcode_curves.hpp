// SPDX-License-Identifier: Apache-2.0
// The curves of G-code moves, in 3-D (X, Y, Z), as geo::BSpline, and the
// machine's further axes (A B C U V W) appended to them.
//
// Arcs (G2/G3) live in a plane given by two axes (first, second: XY for G17,
// ZX for G18, YZ for G19, LinuxCNC's order) and a normal axis; a positive
// sweep turns from the first axis towards the second.
//
// * A planar arc is an exact rational quadratic NURBS, one piece per <= 90
//   degrees, the middle control point where the tangents at the piece's ends
//   meet and weight cos(half the piece's angle). When the end radius differs
//   from the start radius (LinuxCNC accepts a small difference), the piece ends
//   lie on the spiral whose radius changes linearly with the angle, and the
//   tangents are the spiral's: the curve is then a tangent-continuous chain of
//   conics through those points, within the radius difference of the spiral.
// * A helical arc (the normal axis moves) cannot be a NURBS exactly: the helix
//   is transcendental, and in a rational quadratic the angle is not a rational
//   function of the parameter, so the linear axis cannot follow it. Measured in
//   the error of z against the angle, an exact-circle rational quadratic piece
//   with linear control values is off by about 0.064 dz h^2 (h the piece's half
//   angle), which would need pieces of ~1e-4 rad for 1e-9 mm. Instead the helix
//   is parameterised by its angle, so the normal axis is exactly linear, and
//   cos/sin are replaced by their Taylor polynomials of degree 11 about each
//   piece's middle angle: a non-rational Bezier of degree 12 per piece (the
//   radius, linear in the angle, makes the 12th degree). Lagrange's remainder
//   bounds the distance from the true helix point at the same angle by
//   r_max (h^12/12! + h^13/13!) per piece; pieces are made short enough for
//   this to be <= kHelixBound (and at most 45 degrees). Piece ends shared by
//   two pieces are set to the exact point (the first and last to the
//   programmed points), which adds at most the same bound.
// * The further axes move linearly with the move's progress, as LinuxCNC
//   moves them: on a line with its parameter, on an arc with its angle. An
//   arc that moves them takes the helix form (its parameter is proportional
//   to the angle) even when its normal axis stays.
#pragma once
#include <Eigen/Dense>
#include <vector>

#include "geometry/bspline.hpp"

namespace traj::input::gcode {

constexpr double kHelixBound = 1e-12;  // mm (or inch: the same relative size), truncation error per helix
constexpr int kHelixTaylorDegree = 11;

struct ArcSpec {
  int first = 0, second = 1, normal = 2;  // axis indices 0..2 (X, Y, Z)
  Eigen::Vector3d start, end;             // programmed points
  double c1 = 0, c2 = 0;                  // centre in (first, second)
  double sweep = 0;                       // signed angle, radians (> 0 from first towards second)
  bool helix_form = false;                // the helix form even when the normal axis stays (further axes move)
};

// The pieces helical_arc cuts a helix into: the least m >= ceil(|sweep| /
// 45 degrees) with r_max (h^12/12! + h^13/13!) <= kHelixBound, h = |sweep| /
// (2m); kMaxHelixPieces + 1 where more would be needed (a radius beyond
// about 1e22 units: the reader refuses it rather than allocate for it).
constexpr int kMaxHelixPieces = 10000;
int helix_pieces(const ArcSpec& a);

geo::BSpline line3(const Eigen::Vector3d& a, const Eigen::Vector3d& b);
// Planar (start.normal == end.normal) or helical, chosen by the spec.
geo::BSpline arc3(const ArcSpec& a);
// The Taylor truncation bound of a helix piece of half angle h and largest radius r.
double helix_piece_bound(double r, double h);
// `xyz` with the further axes appended as columns, from e0 at its start to e1
// at its end, linear in its parameter: the control values at the Greville
// abscissae, exact for a non-rational B-spline. A rational one (a planar arc,
// a NURBS) only takes constant columns (e0 == e1; throws otherwise).
geo::BSpline with_further_axes(geo::BSpline xyz, const Eigen::VectorXd& e0, const Eigen::VectorXd& e1);
// Bezier through the given control points (rows), non-rational.
geo::BSpline bezier3(const Eigen::MatrixXd& ctrl);
// LinuxCNC's G5.2 NURBS: order k (degree k-1), the knot vector 0 (k times),
// 1, 2, ..., n-k+1, n-k+2 (k times) for control points 0..n.
geo::BSpline nurbs3(const Eigen::MatrixXd& ctrl, const Eigen::VectorXd& weights, int order);

}  // namespace traj::input::gcode
