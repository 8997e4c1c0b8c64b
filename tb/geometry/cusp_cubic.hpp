// SPDX-License-Identifier: Apache-2.0
// A planar cubic with a cusp at u = uc and its arc length in closed form: C(u) = A t^2/2 + B t^3/3,
// t = u - uc, A = (a, 0), B = (0, b), so |C'(u)| = |t| sqrt(a^2 + b^2 t^2) and the length from 0 to
// u is F(uc) - F(0) + sign(t) (F(t) - F(0)), F(t) = (a^2 + b^2 t^2)^(3/2) / (3 b^2).
// (GeometryArcLength.CuspJustInsideTheSpan, PlannerCore.ReversalIntoACuspJustInsideACurveStopsAtBoth.)
#pragma once
#include <Eigen/Dense>
#include <cmath>

namespace geotest {

struct CuspCubic {
  double a, b, uc;
  // Bezier control points (4 x 2) of the power form c0 + c1 u + c2 u^2 + c3 u^3
  Eigen::MatrixXd bezier() const {
    const Eigen::Vector2d A(a, 0), B(0, b);
    const Eigen::Vector2d c0 = uc * uc / 2 * A - uc * uc * uc / 3 * B, c1 = -uc * A + uc * uc * B,
                          c2 = A / 2 - uc * B, c3 = B / 3;
    Eigen::MatrixXd P(4, 2);
    P.row(0) = c0;
    P.row(1) = c0 + c1 / 3;
    P.row(2) = c0 + 2 * c1 / 3 + c2 / 3;
    P.row(3) = c0 + c1 + c2 + c3;
    return P;
  }
  double F(double t) const { return std::pow(a * a + b * b * t * t, 1.5) / (3 * b * b); }
  double back() const { return F(uc) - F(0); }  // length from the start to the cusp
  double s(double u) const {
    const double t = u - uc;
    return back() + (t < 0 ? -1 : 1) * (F(t) - F(0));
  }
};

}  // namespace geotest
