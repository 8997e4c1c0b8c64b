// SPDX-License-Identifier: Apache-2.0
// traj::bcu: the C1 interpolating cubic Bezier spline of [BCU] (eq. 9-16).
//
// Points P_0..P_{N+1} (rows; one column per axis). P_0 and P_{N+1} are the
// extra boundary points the paper asks for. Segment i (1 <= i <= N-1) joins
// P_i and P_{i+1}; its Bezier control points are (eq. 9)
//   b0 = P_i
//   b1 = P_i     + lambda (P_{i+1} - P_{i-1})
//   b2 = P_{i+1} - mu     (P_{i+2} - P_i)
//   b3 = P_{i+1}
// so r_i(0) = P_i, r_i(1) = P_{i+1} (eq. 10) and, because the derivative of a
// cubic Bezier at its ends is 3(b1-b0) and 3(b3-b2),
//   r_i'(0) = 3 lambda (P_{i+1} - P_{i-1}),  r_i'(1) = 3 mu (P_{i+2} - P_i).
// The paper prints eq. 11 without the factor 3; the tests show the printed
// form is wrong (off by exactly 3) and this one right. r_i'(1) and
// r_{i+1}'(0) are then 3 mu (P_{i+2}-P_i) and 3 lambda (P_{i+2}-P_i): equal,
// i.e. C1, iff lambda == mu; parallel (G1) otherwise.
//
// Eq. 13-16 (decomposition into fixed Bernstein polynomials):
//   r_i(t) = P_i BZ0(t) + P_{i+1} BZ1(t) + BZ(t) with Bernstein coefficients
//   BZ0: (1, 1, mu, 0)   BZ1: (0, lambda, 1, 1)
//   BZ : (0, -lambda P_{i-1}, -mu P_{i+2}, 0)
// (our derivation; the extracted text of eq. 14-16 is not legible enough to
// check term by term, the tests check this form against eq. 9).
#pragma once
#include <Eigen/Dense>
#include <vector>

namespace traj::bcu {

// One segment: 4 rows (b0..b3), one column per axis.
using BezierSegment = Eigen::Matrix<double, 4, Eigen::Dynamic>;

// Throws std::invalid_argument for fewer than 4 points, NaN/Inf coordinates
// (naming the point and axis) and lambda/mu outside (0, 1].
std::vector<BezierSegment> c1_spline(const Eigen::MatrixXd& points, double lambda, double mu);
inline std::vector<BezierSegment> c1_spline(const Eigen::MatrixXd& points, double lambda) {
  return c1_spline(points, lambda, lambda);
}

// Evaluate a segment at t (double de Casteljau), all axes.
Eigen::VectorXd eval_segment(const BezierSegment& s, double t);
// Derivative d/dt at t.
Eigen::VectorXd eval_derivative(const BezierSegment& s, double t);
// Eq. 13: P_i BZ0(t) + P_{i+1} BZ1(t) + BZ(t) for segment i (1-based as in the paper).
Eigen::VectorXd eval_eq13(const Eigen::MatrixXd& points, int i, double lambda, double mu, double t);

}  // namespace traj::bcu
