// SPDX-License-Identifier: Apache-2.0
#include "input/cuts.hpp"

namespace traj::input {

Eigen::VectorXd start_point(const geo::BSpline& c) { return c.ctrl.row(0).transpose(); }
Eigen::VectorXd end_point(const geo::BSpline& c) { return c.ctrl.row(c.n_ctrl() - 1).transpose(); }

geo::BSpline reversed(const geo::BSpline& c) {
  geo::BSpline r = c;
  r.ctrl = c.ctrl.colwise().reverse();
  if (c.rational()) r.weights = c.weights.reverse();
  const double a = c.knots[0], b = c.knots[c.knots.size() - 1];
  const Eigen::Index n = c.knots.size();
  for (Eigen::Index i = 0; i < n; ++i) r.knots[i] = a + b - c.knots[n - 1 - i];
  return r;
}

bool degenerate(const geo::BSpline& c) {
  for (int i = 1; i < c.n_ctrl(); ++i)
    if (c.ctrl.row(i) != c.ctrl.row(0)) return false;
  return true;
}

Toolpath toolpath_from_cuts(const std::vector<Cut>& cuts, int axes) {
  Toolpath tp;
  tp.axes = axes;
  Eigen::VectorXd at = Eigen::VectorXd::Zero(axes);
  for (const Cut& cut : cuts) {
    if (cut.empty()) continue;
    const Eigen::VectorXd start = start_point(cut.front().curve);
    // a cut that starts where the last one ended, up to rounding (a subpath
    // after a closed one's Z, drawn with relative moves that come back to
    // its start: 4e-16 mm off in simple-icons' createreactapp.svg) needs no
    // rapid: a line that short is refused as a zero-length curve
    const bool joined = (start - at).norm() <= kNegligibleMm;
    if (!joined) {
      Move rapid;
      rapid.kind = Move::Kind::kRapid;
      rapid.curve = geo::make_line(at, start);
      rapid.exact_stop = true;
      rapid.where = cut.front().where;
      tp.moves.push_back(std::move(rapid));
    }
    Eigen::VectorXd end = joined ? at : start;
    for (const CutPiece& piece : cut) {
      if (negligible(piece.curve)) continue;
      Move m;
      m.kind = Move::Kind::kFeed;
      m.curve = piece.curve;
      m.curve.ctrl.row(0) = end.transpose();  // moves it by at most kNegligibleMm after a dropped piece
      m.where = piece.where;
      end = end_point(m.curve);
      tp.moves.push_back(std::move(m));
    }
    at = end;
  }
  return tp;
}

bool negligible(const geo::BSpline& c) {
  double polygon = 0;
  for (int i = 1; i < c.n_ctrl(); ++i) polygon += (c.ctrl.row(i) - c.ctrl.row(i - 1)).norm();
  return polygon <= kNegligibleMm;
}

}  // namespace traj::input
