// SPDX-License-Identifier: Apache-2.0
// trajcore planner: a fast arc-length inverse for marching along one curve.
//
// The planner asks, at every servo tick and every grid point, for the curve
// parameter u at a given arc length s. geo::ArcLength answers each such query
// with adaptive quadrature and Newton (about 20 speed evaluations, 3 000
// instructions per tick on the butterfly). ArcTable answers it from a table
// built once per curve:
//
//   * each power-basis span (the speed sigma(u) = |C'(u)| is smooth inside a
//     span) is cut into pieces [u0, u1] (halved until the tests below pass);
//   * on a piece sigma is interpolated at the kDegree + 1 Chebyshev points of
//     the second kind, and the series is integrated term by term: S(x) =
//     s(u(x)) - s(u0), x in [-1, 1] the piece's local variable;
//   * the inverse x(y), y in [-1, 1] mapping S in [0, L], is interpolated the
//     same way (its values at the nodes by safeguarded Newton on S, from a
//     cubic Hermite guess through S and its slope at the x nodes, all nodes
//     side by side), and a query is one Clenshaw evaluation of it: no
//     iteration, ~100 instructions;
//   * a piece is accepted only if (a) both series have converged to the
//     accuracy asked for (the last two coefficients would move S by at most a
//     tenth of the tolerance below), (b) S agrees with
//     geo::ArcLength's adaptive Gauss-Legendre length (the library's reference)
//     over the piece and over its first half, and (c) S(x(y)) = (y+1) L/2 at the
//     kDegree midpoints between the inverse's nodes; (b) and (c) to kCheckRel of
//     the piece length plus 1e-15 of the curve length. Piece starts s(u0) are
//     sums of the reference lengths from the library's span starts, so errors
//     do not accumulate along the curve;
//   * a straight span (degree 1, not rational) has constant speed: u is
//     linear in s there, with no series;
//   * a span where this fails after kMaxDepth halvings (sigma near 0: a
//     near-cusp) keeps its unresolved pieces marked, and queries there go to
//     geo::ArcLength::u_at (slower, never less accurate).
//
// So |s(u_at(s)) - s| is within kCheckRel of the piece length (+ the
// reference's own 1e-12 relative tolerance) wherever it was checked, and
// between the check points the error of a converged interpolant is of the
// size of its dropped coefficients. tb/planner/arc_table_test.cpp compares
// u_at with an independent long-double arc length at random arc lengths on
// the butterfly, random B-splines/NURBS, lines and arcs.
#pragma once
#include <vector>

#include "geometry/arclength.hpp"
#include "geometry/curve.hpp"

namespace traj::plan {

class ArcTable {
 public:
  ArcTable(const geo::Curve& c, const geo::ArcLength& al);

  // Parameter u at curve-local arc length s (clamped to [0, total]). `hint`
  // (in/out) is the piece of the previous query: marching is O(1) per query.
  double u_at(double s, int& hint) const;
  double u_at(double s) const {
    int h = 0;
    return u_at(s, h);
  }

  // Power-basis span of the piece a query left in `hint`.
  int span_of(int hint) const { return pc_[hint].span; }
  // Curve-local arc length where power-basis span `span` ends: a query at or
  // below it (and above the span's start) is answered in that span.
  double span_end(int span) const;
  size_t pieces() const { return pc_.size(); }
  size_t fallback_spans() const { return fallback_spans_; }
  long long speed_evals() const { return build_evals_; }  // speed evaluations for the series

  static constexpr int kDegree = 16;
  static constexpr double kCheckRel = 1e-12;
  static constexpr int kMaxDepth = 14;

 private:
  struct Piece {
    double u0, u1, s0, s1;  // parameter interval and arc lengths at its ends
    double len;             // S(1): the series' length of the piece
    int span;
    bool fallback;  // answered by geo::ArcLength
    bool linear;    // a straight span (degree 1, not rational): u linear in s
    int off;        // inverse series x(y) at coef_[off .. off + kDegree]
  };
  // Pieces of [u0, u1] at `depth` halvings of the span, tried from `start` halvings on.
  void build_span(int span, double u0, double u1, int depth, int start);
  bool try_piece(int span, double u0, double u1, double ref, Piece& p);

  const geo::Curve* c_;
  const geo::ArcLength* al_;
  std::vector<Piece> pc_;
  std::vector<double> coef_;
  double total_ = 0;
  size_t fallback_spans_ = 0;
  int min_depth_ = 0;  // the fewest halvings a piece of the span being built needed
  long long build_evals_ = 0;
};

}  // namespace traj::plan
