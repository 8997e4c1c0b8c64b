// SPDX-License-Identifier: Apache-2.0
// [ARC]'s three test curves. The paper shows them (Fig. 2_01) but prints no control points, so they
// are chosen here (units mm) to reproduce its "step fluctuation" (max/min chord at n = 20 uniform
// parameter steps): curve 1 (asymmetric, with an inflection) 1 : 2.271, curve 3 (asymmetric, without
// inflection) 1 : 11.108; one control coordinate of each is tuned to hit the printed ratio (to 4
// digits). Curve 2 is the circle of three 120-degree cubic Beziers (k = 4/3 tan 30deg), radius 50 mm.
#pragma once
#include "geometry/geometry.hpp"

namespace seedcurves {

inline traj::geo::BSpline curve1() {
  Eigen::MatrixXd P(4, 2);
  P << 0, 0, 25, 71.5, 60, -42.9, 100, 0;
  auto c = traj::geo::make_bezier(P);
  c.name = "[ARC] curve 1 (inflection)";
  return c;
}
inline traj::geo::BSpline curve2() {
  auto c = traj::geo::make_bezier_circle(Eigen::Vector2d(0, 0), 50.0, 3);
  c.name = "[ARC] curve 2 (circle 3x120deg)";
  return c;
}
inline traj::geo::BSpline curve3() {
  Eigen::MatrixXd P(4, 2);
  P << 0, 0, 10, 90, 90, 100, 94.15, 100;
  auto c = traj::geo::make_bezier(P);
  c.name = "[ARC] curve 3 (no inflection)";
  return c;
}

}  // namespace seedcurves
