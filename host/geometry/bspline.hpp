// SPDX-License-Identifier: Apache-2.0
// B-spline / NURBS curve description and the exact (knot-insertion) operations on it.
//
// A curve of degree p with n control points P_i (rows of `ctrl`, any number of axes), optional
// positive weights w_i (rational = NURBS) and knots t_0..t_{n+p} (non-decreasing). The parameter
// domain is [t_p, t_n]. All operations here are exact up to floating-point rounding: knot insertion
// (Boehm) is done on homogeneous points (w_i P_i, w_i), so NURBS go through unchanged.
#pragma once
#include <Eigen/Dense>
#include <string>
#include <utility>
#include <vector>

namespace traj::geo {

// Highest degrees accepted (validate, the JSON reader, Curve). The power basis about the span midpoint
// is an ill-conditioned basis: the rounding of its coefficients is amplified about 2x per degree
// relative to the bounding box of the (hodograph) control points. Measured worst relative errors
// (tb/geometry/bench_power_soak --beyond; host/geometry/README.md): ~1e-15 at degree 7, ~1e-13 at 15,
// above the 1e-12 target from about 19. Rational curves add the quotient rule, which amplifies the
// tables' rounding by up to the weight ratio; their derivatives approach the target sooner.
constexpr int kMaxDegree = 15;          // non-rational B-splines and Beziers
constexpr int kMaxDegreeRational = 7;   // NURBS / rational Beziers

// Magnitudes accepted (validate): each refused naming the field, so that no input reaches the
// geometry where its arithmetic overflows, underflows or drowns in rounding.
// Coordinates: |x| <= 1e15 (a kilometre in picometres), so that |r'|^2 |r''|^2 and the curvature
// formulas stay inside the double range for any accepted knot spacing.
constexpr double kMaxCoordinate = 1e15;
// Knots: |t| <= 1e12. Far larger parameters make the speed |r'| ~ |P| / t underflow when squared
// (knots [0, 1e300] gave a zero-length curve).
constexpr double kMaxKnot = 1e12;
// Weights: max/min <= 1e3. The rational speed |A' w - A w'| / w^2 loses about (max/min)^2 ulp to
// cancellation: at 1e3 the arc length still agrees with a long-double reference to 2e-13
// (host/geometry/README.md), at 1e8 no digit is left.
constexpr double kMaxWeightRatio = 1e3;

struct BSpline {
  int degree = 0;
  Eigen::MatrixXd ctrl;     // n_ctrl x dim: row i is control point i (Cartesian, not weighted)
  Eigen::VectorXd weights;  // empty: non-rational; else n_ctrl positive weights
  Eigen::VectorXd knots;    // n_ctrl + degree + 1, non-decreasing
  std::string name;

  bool rational() const { return weights.size() > 0; }
  int dim() const { return static_cast<int>(ctrl.cols()); }
  int n_ctrl() const { return static_cast<int>(ctrl.rows()); }
  double u_begin() const { return knots[degree]; }
  double u_end() const { return knots[n_ctrl()]; }
  // First p+1 knots equal and last p+1 knots equal.
  bool clamped() const;
  // Homogeneous control points: n_ctrl x (dim+1), rows (w P, w); w = 1 if non-rational.
  Eigen::MatrixXd homogeneous() const;
  static BSpline from_homogeneous(int degree, const Eigen::MatrixXd& hom, const Eigen::VectorXd& knots,
                                  bool rational, std::string name = {});
};

// Checks the degree (1..kMaxDegree, rational 1..kMaxDegreeRational), sizes, finite numbers,
// non-decreasing knots, positive weights, a non-empty domain. Throws GeometryError("<where>: <field>[i]:
// ..."). `where` is usually the file name. max_degree > 0 replaces both degree caps: only for
// measuring the accuracy beyond them (bench_power_soak --beyond), never for production curves.
void validate(const BSpline& c, const std::string& where = "curve", int max_degree = 0);

// The message validate() gives for a degree outside the accepted range ("degree: 16 out of range
// 1..15 (...)"), or "" if the degree is accepted; for readers that check the degree first.
// `shown` replaces the number in the message (a reader's own text of a degree beyond long long).
std::string degree_range_error(long long degree, bool rational, int max_degree = 0, const std::string& shown = {});

// Boehm knot insertion of u, `times` times (multiplicity after insertion must stay <= degree+1).
BSpline insert_knot(const BSpline& c, double u, int times = 1);
// The curve cut in two at u (strictly inside the domain): [t_p, u] and [u, t_n], each clamped, by
// inserting u up to multiplicity `degree` (exact up to rounding; NURBS through homogeneous points).
// The two share the control point at u. Throws GeometryError if u is not strictly inside.
std::pair<BSpline, BSpline> split_at(const BSpline& c, double u);
// Clamped equivalent of any B-spline on the same domain [t_p, t_n] (knot insertion at the domain
// ends, then the control points outside the domain are dropped). Identity for clamped input.
BSpline clamp(const BSpline& c);

// One Bezier piece per non-empty knot span (clamped input; see clamp()). Homogeneous control points
// (degree+1) x (dim+1), and the span [u0, u1].
struct BezierPiece {
  double u0 = 0, u1 = 0;
  Eigen::MatrixXd hom;  // (degree+1) x (dim+1): rows (w P, w)
};
std::vector<BezierPiece> bezier_pieces(const BSpline& clamped_curve);

// Constructors of common curves.
// Bezier of degree ctrl.rows()-1 on [0,1]; weights optional (rational Bezier).
BSpline make_bezier(const Eigen::MatrixXd& ctrl, const Eigen::VectorXd& weights = Eigen::VectorXd());
// Straight line a -> b, degree 1 on [0,1].
BSpline make_line(const Eigen::VectorXd& a, const Eigen::VectorXd& b);
// Exact circular arc in the plane as a rational quadratic NURBS on [0,1]: centre c, radius r, from
// angle a0 to a1 (radians, a1 > a0 counter-clockwise, a1 < a0 clockwise, |a1-a0| <= 2 pi). Split in
// pieces of at most 90 degrees, middle weight cos(half piece angle), double interior knots.
BSpline make_arc(const Eigen::Vector2d& c, double r, double a0, double a1);
// Cubic Bezier circle of `segments` equal arcs (classic k = 4/3 tan(theta/4) handles), joined C1
// into one clamped cubic B-spline with triple interior knots (each piece is that Bezier); segment i on [i/segments, (i+1)/segments].
BSpline make_bezier_circle(const Eigen::Vector2d& c, double r, int segments = 3);

}  // namespace traj::geo
