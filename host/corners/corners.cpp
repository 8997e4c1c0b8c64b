#include "corners/corners.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "geometry/curve.hpp"

namespace traj::corners {
namespace {

using Vec = Eigen::VectorXd;
using Kind = input::Move::Kind;

// A piece of the toolpath between two joins: one straight segment of a degree-1 move, or a whole
// curved move (kept as it is).
struct Element {
  size_t move = 0;
  bool segment = false;
  Vec a, b;               // segment ends (segments only)
  double length = 0;      // segments only
  Vec t_start, t_end;     // unit tangents at the ends
  bool last_of_move = false;
};

enum class JoinKind { kPass, kStop, kBlend };
struct Join {
  JoinKind kind = JoinKind::kPass;
  double turn = 0;
  double d = 0;
};

// Turning angle between unit tangents, accurate near 0 and near pi.
double turning_angle(const Vec& t_in, const Vec& t_out) {
  return 2 * std::atan2((t_out - t_in).norm(), (t_out + t_in).norm());
}

Vec unit_tangent(const geo::Curve& c, double u) {
  const Eigen::MatrixXd e = c.eval(u, 1);
  return e.col(1).normalized();
}

void add_move_elements(const input::Move& m, size_t index, std::vector<Element>& out) {
  const size_t first = out.size();
  const geo::BSpline spline = geo::clamp(m.curve);
  if (spline.degree == 1) {
    // A polyline: one element per non-degenerate span (knot spans map to control-point pairs).
    for (int i = 0; i + 1 < spline.n_ctrl(); ++i) {
      Element e;
      e.move = index;
      e.segment = true;
      e.a = spline.ctrl.row(i).transpose();
      e.b = spline.ctrl.row(i + 1).transpose();
      e.length = (e.b - e.a).norm();
      if (!(e.length > 0)) continue;
      e.t_start = e.t_end = (e.b - e.a) / e.length;
      out.push_back(std::move(e));
    }
  } else {
    const geo::Curve c(spline, m.where);
    Element e;
    e.move = index;
    e.t_start = unit_tangent(c, c.u_begin());
    e.t_end = unit_tangent(c, c.u_end());
    out.push_back(std::move(e));
  }
  if (out.size() > first) out.back().last_of_move = true;
}

double move_tol(const input::Move& m, double default_tol) { return m.tolerance < 0 ? default_tol : m.tolerance; }

// What happens at the join between elements k and k+1 (d left 0 for blends; set later).
Join classify(const input::Toolpath& tp, const Element& l, const Element& r, const BlendOptions& o,
              BlendResult& res) {
  Join j;
  j.turn = turning_angle(l.t_end, r.t_start);
  const input::Move& ml = tp.moves[l.move];
  const input::Move& mr = tp.moves[r.move];
  auto stop = [&](StopReason why) {
    j.kind = JoinKind::kStop;
    if (why == StopReason::kExactStop || j.turn > o.kink) res.stops.push_back({l.move, ml.where, why, j.turn});
    return j;
  };
  if (l.last_of_move && ml.exact_stop) return stop(StopReason::kExactStop);
  if (ml.kind == Kind::kRapid || mr.kind == Kind::kRapid) return stop(StopReason::kRapid);
  if (j.turn <= o.kink) {
    ++res.joins_passed;
    return j;
  }
  if (!l.segment || !r.segment) return stop(StopReason::kCurvedMove);
  if (j.turn > o.max_turn) return stop(StopReason::kReversal);
  j.kind = JoinKind::kBlend;
  return j;
}

std::string blend_where(const input::Move& l, const input::Move& r) {
  return (l.where == r.where ? l.where : l.where + " / " + r.where) + ": corner blend";
}

}  // namespace

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::kRapid: return "rapid";
    case StopReason::kExactStop: return "exact stop";
    case StopReason::kReversal: return "reversal";
    case StopReason::kCurvedMove: return "curved move";
  }
  return "?";
}

double blend_deviation(double d, double turn) { return 0.5 * d * std::sin(0.5 * turn); }

double blend_spacing_for(double tol, double turn) { return 2 * tol / std::sin(0.5 * turn); }

double blend_peak_curvature(double d, double turn) {
  const double c = std::cos(0.5 * turn);
  return 4.0 / 3.0 * std::sin(0.5 * turn) / (d * c * c);
}

geo::BSpline corner_blend(const Vec& v, const Vec& t_in, const Vec& t_out, double d) {
  geo::BSpline b;
  b.degree = 3;
  b.ctrl.resize(5, v.size());
  b.ctrl.row(0) = (v - 2 * d * t_in).transpose();
  b.ctrl.row(1) = (v - d * t_in).transpose();
  b.ctrl.row(2) = v.transpose();
  b.ctrl.row(3) = (v + d * t_out).transpose();
  b.ctrl.row(4) = (v + 2 * d * t_out).transpose();
  b.knots.resize(9);
  b.knots << 0, 0, 0, 0, 0.5, 1, 1, 1, 1;
  b.name = "corner blend";
  return b;
}

BlendResult blend_corners(const input::Toolpath& tp, double default_tol, const BlendOptions& o) {
  if (!(default_tol > 0)) throw std::invalid_argument("blend_corners: default tolerance must be positive");
  if (!(o.share > 0 && o.share <= 1)) throw std::invalid_argument("blend_corners: share must be in (0, 1]");
  BlendResult res;
  std::vector<Element> el;
  for (size_t i = 0; i < tp.moves.size(); ++i) add_move_elements(tp.moves[i], i, el);
  if (el.empty()) return res;

  std::vector<Join> joins(el.size() - 1);
  for (size_t k = 0; k + 1 < el.size(); ++k) joins[k] = classify(tp, el[k], el[k + 1], o, res);

  // Spacing: the tolerance's, shortened to the share of each leg.
  for (size_t k = 0; k < joins.size(); ++k) {
    Join& j = joins[k];
    if (j.kind != JoinKind::kBlend) continue;
    const input::Move& ml = tp.moves[el[k].move];
    const input::Move& mr = tp.moves[el[k + 1].move];
    const double tol = std::min(move_tol(ml, default_tol), move_tol(mr, default_tol));
    if (!(tol > 0)) throw std::invalid_argument(ml.where + ": tolerance must be positive");
    const double d_tol = blend_spacing_for(tol, j.turn);
    const double d_leg = 0.5 * o.share * std::min(el[k].length, el[k + 1].length);
    j.d = std::min(d_tol, d_leg);
    Blend b;
    b.move = el[k].move;
    b.turn = j.turn;
    b.d = j.d;
    b.deviation = blend_deviation(j.d, j.turn);
    b.tol = tol;
    b.shortened = d_leg < d_tol;
    b.peak_curvature = blend_peak_curvature(j.d, j.turn);
    res.blends.push_back(b);
    res.max_deviation = std::max(res.max_deviation, b.deviation);
    ++res.corners_blended;
  }

  // Emit: each segment trimmed by 2d at a blended end, each blend starting where the chain ends.
  Vec last_end;
  for (size_t k = 0; k < el.size(); ++k) {
    const Element& e = el[k];
    const input::Move& m = tp.moves[e.move];
    const bool stop_here = e.last_of_move && m.exact_stop;
    if (!e.segment) {
      res.curves.push_back({geo::clamp(m.curve), m.where, m.feed, m.kind, stop_here, false});
      const auto& c = res.curves.back().curve;
      last_end = c.ctrl.row(c.n_ctrl() - 1).transpose();
      continue;
    }
    const bool blend_before = k > 0 && joins[k - 1].kind == JoinKind::kBlend;
    const bool blend_after = k < joins.size() && joins[k].kind == JoinKind::kBlend;
    const double cut0 = blend_before ? 2 * joins[k - 1].d : 0;
    const double cut1 = blend_after ? 2 * joins[k].d : 0;
    const Vec a = blend_before ? last_end : Vec(e.a);
    const Vec b = e.b - cut1 * e.t_end;
    if (e.length - cut0 - cut1 >= o.min_line || !blend_after) {
      res.curves.push_back({geo::make_line(a, b), m.where, m.feed, m.kind, stop_here, false});
      last_end = b;
    } else {
      last_end = a;  // the remnant is dropped: the next blend starts here, on the same segment line
    }
    if (blend_after) {
      const Element& r = el[k + 1];
      geo::BSpline bl = corner_blend(e.b, e.t_end, r.t_start, joins[k].d);
      bl.ctrl.row(0) = last_end.transpose();
      const input::Move& mr = tp.moves[r.move];
      res.curves.push_back({bl, blend_where(m, mr), std::min(m.feed, mr.feed), Kind::kFeed, false, true});
      last_end = bl.ctrl.row(4).transpose();
    }
  }
  return res;
}

}  // namespace traj::corners
