// SPDX-License-Identifier: Apache-2.0
#include "corners/corners.hpp"

#include <algorithm>
#include <cmath>
#include <array>
#include <memory>
#include <optional>
#include <unordered_map>
#include <stdexcept>

#include <Eigen/SparseCholesky>

#include "geometry/curve.hpp"

namespace traj::corners {
namespace {

using Vec = Point;
using Kind = input::Move::Kind;

// A piece of the toolpath between two joins: one straight segment of a degree-1 move, or a whole
// curved move (cut only where a corner next to it is blended).
struct Element {
  size_t move = 0;
  bool segment = false;
  Vec a, b;               // ends
  double length = 0;      // arc length
  Vec t_start, t_end;     // unit tangents at the ends
  Vec k_start, k_end;     // curvature vectors at the ends (zero on a segment)
  bool last_of_move = false;
  std::shared_ptr<const geo::Curve> curve;  // curved moves only
};

enum class JoinKind { kPass, kStop, kBlend };
struct Join {
  JoinKind kind = JoinKind::kPass;
  double turn = 0;
  double d = 0;
  // A leg is curved: where each curved leg is cut (u_in on the arriving leg, u_out on the leaving one)
  // and the blend's five control points (rows).
  bool curved = false;
  double u_in = 0, u_out = 0;
  Eigen::MatrixXd ctrl;
  // Length each leg loses: kBlendReach d (line-line), kCurvedReach d (a curved leg), l0 (wide).
  double cut = 0;
  // Both legs straight and the wide blend chosen (README.md, "Wide blends"): its curve (d = l0 / 2).
  bool wide = false;
  geo::BSpline wide_curve;
  // The vertex moved outward by this much (mm; README.md, "Offset corners") from `programmed`; 0:
  // where programmed.
  double shift = 0;
  Vec programmed;
};

// Turning angle between unit tangents, accurate near 0 and near pi.
double turning_angle(const Vec& t_in, const Vec& t_out) {
  return 2 * std::atan2((t_out - t_in).norm(), (t_out + t_in).norm());
}

Vec unit_tangent(const geo::Curve& c, double u) {
  const Eigen::MatrixXd e = c.eval(u, 1);
  return e.col(1).normalized();
}

double speed(const geo::Curve& c, double u) { return c.eval(u, 1).col(1).norm(); }

Vec curvature_vector(const geo::Curve& c, double u) {
  const Eigen::MatrixXd e = c.eval(u, 2);
  const Vec d1 = e.col(1), d2 = e.col(2);
  const double a = d1.squaredNorm();
  return a > 0 ? Vec((d2 - (d2.dot(d1) / a) * d1) / a) : Vec::Zero(d1.size());
}

// Arc length of c on [u0, u1]: 5-point Gauss-Legendre on 4 sub-intervals of each knot span (the
// speed is smooth inside a span; rational arcs may change speed at a double knot).
double arc_length(const geo::Curve& c, double u0, double u1) {
  static const double x[5] = {0, -0.5384693101056831, 0.5384693101056831, -0.9061798459386640, 0.9061798459386640};
  static const double w[5] = {0.5688888888888889, 0.4786286704993665, 0.4786286704993665, 0.2369268850561891,
                              0.2369268850561891};
  double total = 0;
  for (const geo::BezierPiece& piece : c.bezier()) {
    const double a = std::max(u0, piece.u0), b = std::min(u1, piece.u1);
    if (!(b > a)) continue;
    const int n = 4;
    const double h = (b - a) / n;
    for (int i = 0; i < n; ++i) {
      const double mid = a + (i + 0.5) * h;
      for (int k = 0; k < 5; ++k) total += 0.5 * h * w[k] * speed(c, mid + 0.5 * h * x[k]);
    }
  }
  return total;
}

// Parameter at arc length s from the curve's end (from_end) or its start: safeguarded Newton on the
// arc length, s strictly inside (0, length).
double param_at_length(const geo::Curve& c, double s, bool from_end) {
  double lo = c.u_begin(), hi = c.u_end();
  const double total = arc_length(c, lo, hi);
  // g(u): arc length from the start to u minus the target, increasing in u.
  const double target = from_end ? total - s : s;
  double u = lo + (hi - lo) * target / total;
  for (int it = 0; it < 100; ++it) {
    const double g = arc_length(c, c.u_begin(), u) - target;
    if (std::abs(g) <= 1e-13 * total) break;
    (g > 0 ? hi : lo) = u;
    const double v = speed(c, u);
    const double next = v > 0 ? u - g / v : 0.5 * (lo + hi);
    u = (next > lo && next < hi) ? next : 0.5 * (lo + hi);
    if (hi - lo <= 1e-15 * (c.u_end() - c.u_begin())) break;
  }
  return u;
}

// Largest curvature of c on [u0, u1], sampled at n + 1 points (exact for a circular arc, whose
// curvature is constant; an estimate for other curves).
double max_curvature(const geo::Curve& c, double u0, double u1, int n = 16) {
  double k = 0;
  for (int i = 0; i <= n; ++i) {
    const Eigen::MatrixXd e = c.eval(u0 + (u1 - u0) * i / n, 2);
    const Vec d1 = e.col(1), d2 = e.col(2);
    const double a = d1.squaredNorm();
    if (a > 0) k = std::max(k, (d2 - (d2.dot(d1) / a) * d1).norm() / a);
  }
  return k;
}

// The curve's point at u, on the stack.
Vec point_at(const geo::Curve& c, double u) {
  Vec p(c.dim());
  c.eval(u, 0, p.data());
  return p;
}

// Squared distance of p to the segment [a, b], in plain loops (the run and blend searches call it
// millions of times; a minimum over segments takes one square root, of the minimum).
double dist2_to_segment(const Vec& p, const Vec& a, const Vec& b) {
  const int n = static_cast<int>(p.size());
  double ab[8], L2 = 0, dot = 0;
  for (int i = 0; i < n; ++i) {
    ab[i] = b[i] - a[i];
    L2 += ab[i] * ab[i];
    dot += (p[i] - a[i]) * ab[i];
  }
  const double t = L2 > 0 ? std::clamp(dot / L2, 0.0, 1.0) : 0.0;
  double d2 = 0;
  for (int i = 0; i < n; ++i) {
    const double e = p[i] - (a[i] + t * ab[i]);
    d2 += e * e;
  }
  return d2;
}

double dist_to_segment(const Vec& p, const Vec& a, const Vec& b) { return std::sqrt(dist2_to_segment(p, a, b)); }

// Distance of p to the polygon's edges lo..hi-1 (edge e from poly[e] to poly[e + 1]).
double dist_to_edges(const Vec& p, const std::vector<Vec>& poly, size_t lo, size_t hi) {
  double best2 = INFINITY;
  for (size_t e = lo; e < hi; ++e) best2 = std::min(best2, dist2_to_segment(p, poly[e], poly[e + 1]));
  return std::sqrt(best2);
}

// Golden-section minimum of f on [a, b] (f unimodal there), to 4e-9 of the interval: at a smooth
// extremum the value is then off by the square of that (nothing a tolerance sees), at a distance
// that reaches 0 by at most 4e-9 of the interval times the curve's speed, on the safe side.
template <class F>
double golden_min(F f, double a, double b) {
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = b - g * (b - a), x2 = a + g * (b - a), f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < 40; ++it) {  // 0.618^40 = 4e-9 of the interval
    if (f1 < f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a), f1 = f(x1);
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a), f2 = f(x2);
    }
  }
  return std::min({f1, f2, f(0.5 * (a + b))});
}

// One side of a blend at corner v with spacing d: its end point and inner control point, and where a
// curved leg is cut (u). A segment (the straight leg of a curved corner) gives v -/+ 2d t and v -/+ d t. A
// curved leg is cut at arc length 2d from v (point a, unit tangent t_a, curvature kappa_a); the inner
// point is a + e t_a. The blend's curvature at a is h / (3 e^2), h the distance of v (the blend's
// middle control point) from the tangent line at a, so e = sqrt(h / (3 kappa_a)) makes the join G2
// where the curve's normal at a points towards v (always for a circular arc); elsewhere e = d (G1).
// A blend next to a curved leg keeps end points 2d from the corner (not kBlendReach d): its side on a
// curve is built on the curve's tangent at the cut with its own inner spacing (G2 below), and the
// deviation budget of fit_curved is derived for this reach.
constexpr double kCurvedReach = 2;
struct LegCut {
  Vec end, inner;
  double u = 0;
  bool g2 = true;
};
LegCut cut_leg(const Element& e, bool arriving, const Vec& v, const Vec& t, double d) {
  const double sign = arriving ? -1 : 1;
  LegCut cut;
  cut.end = v + sign * kCurvedReach * d * t;
  cut.inner = v + sign * d * t;
  if (e.segment) return cut;
  const geo::Curve& c = *e.curve;
  cut.u = param_at_length(c, kCurvedReach * d, arriving);
  const Eigen::MatrixXd ev = c.eval(cut.u, 2);
  const Vec a = ev.col(0), t_a = ev.col(1).normalized();
  const Vec d2 = ev.col(2);
  const Vec curv = (d2 - d2.dot(t_a) * t_a) / ev.col(1).squaredNorm();  // curvature vector at a
  const Vec off = (v - a) - (v - a).dot(t_a) * t_a;                     // v from the tangent line at a
  const double kappa = curv.norm(), h = off.norm();
  double step = d;
  cut.g2 = false;
  if (kappa > 0 && h > 0 && curv.dot(off) >= (1 - 1e-9) * kappa * h) {
    const double e_g2 = std::sqrt(h / (3 * kappa));
    if (e_g2 > 0.25 * d && e_g2 < 1.5 * d) step = e_g2, cut.g2 = true;
  }
  cut.end = a;
  cut.inner = a - sign * step * t_a;
  return cut;
}

// A cut-off piece of the programmed path next to a corner: a segment [a, b] or a curve on [u0, u1].
struct Piece {
  const geo::Curve* curve = nullptr;
  Vec a, b;
  double u0 = 0, u1 = 0;
  Vec at(double s) const { return curve ? point_at(*curve, u0 + (u1 - u0) * s) : Vec(a + s * (b - a)); }
};

// Distance of p to c(u), u in [0, 1] of f's parameter: 16 samples, then golden section around the best.
template <class F>
double dist_sampled(const Vec& p, const F& f) {
  const int n = 16;
  int arg = 0;
  double best = INFINITY;
  for (int i = 0; i <= n; ++i) {
    const double dd = (f(double(i) / n) - p).norm();
    if (dd < best) best = dd, arg = i;
  }
  return std::min(best, golden_min([&](double s) { return (f(s) - p).norm(); }, std::max(0, arg - 1) / double(n),
                                   std::min(n, arg + 1) / double(n)));
}
double dist_to_piece(const Vec& p, const Piece& q) {
  if (!q.curve) return dist_to_segment(p, q.a, q.b);
  return dist_sampled(p, [&](double s) { return q.at(s); });
}

// Largest distance of curve c from what dist measures (a point's distance), sampled at samples + 1
// parameters, then refined by golden section around the worst sample.
template <class F>
double farthest_point(const geo::Curve& c, const F& dist, int samples) {
  const double u0 = c.u_begin(), u1 = c.u_end();
  auto off = [&](double f) { return dist(point_at(c, u0 + f * (u1 - u0))); };
  int arg = 0;
  double worst = -1;
  for (int i = 0; i <= samples; ++i) {
    const double dd = off(double(i) / samples);
    if (dd > worst) worst = dd, arg = i;
  }
  return std::max(worst, -golden_min([&](double u) { return -off(u); }, std::max(0, arg - 1) / double(samples),
                                     std::min(samples, arg + 1) / double(samples)));
}

// Measured deviation of a blend from the two pieces it replaces: the larger of the blend's largest
// distance from them (farthest_point) and the largest distance of their points (the corner and
// samples along each) from the blend.
double curved_blend_deviation(const geo::BSpline& blend, const Piece& in, const Piece& out, int samples) {
  const geo::Curve c(blend, "corner blend");
  double worst = farthest_point(
      c, [&](const Vec& p) { return std::min(dist_to_piece(p, in), dist_to_piece(p, out)); }, samples);
  auto to_blend = [&](const Vec& p) {
    return dist_sampled(p, [&](double u) { return point_at(c, u); });
  };
  for (int i = 1; i <= 8; ++i) {
    worst = std::max(worst, to_blend(in.at(i / 8.0)));
    worst = std::max(worst, to_blend(out.at((i - 1) / 8.0)));
  }
  return worst;
}

// The blend at a corner with a curved leg (README.md, "Curved legs"): each leg loses arc length 2d,
// a curved leg's side of the blend is built on its tangent at the cut (LegCut). d starts from
// (d/2) sin(turn/2) + 4 kappa d^2 = tol (kappa: the largest curvature on the longest cut pieces; the
// leg departs from its tangent at the corner by <= kappa s^2 / 2 over arc length s), within the share
// of each leg, and shrinks by 10 % until the measured deviation (curved_blend_deviation) is within tol.
constexpr double kMinCurvedSpacing = 1e-6;  // of the tolerance: the smallest blend spacing tried at a curved corner
struct CurvedFit {
  bool ok = false, shortened = false;
  double d = 0, deviation = 0;
  LegCut in, out;
  geo::BSpline blend;
};
CurvedFit fit_curved(const Element& l, const Element& r, double turn, double tol, const BlendOptions& o) {
  CurvedFit f;
  const Vec& v = l.b;
  // A curved leg keeps a little of its length between two cuts (split_at needs u strictly inside).
  auto cap_of = [&](const Element& e) { return o.share * e.length * (e.segment ? 1 : 0.999) / kCurvedReach; };
  const double cap = std::min(cap_of(l), cap_of(r));
  if (!(cap > 0)) return f;
  auto piece_curvature = [&](const Element& e, bool arriving) {
    if (e.segment) return 0.0;
    const double u = param_at_length(*e.curve, kCurvedReach * cap, arriving);
    return arriving ? max_curvature(*e.curve, u, e.curve->u_end()) : max_curvature(*e.curve, e.curve->u_begin(), u);
  };
  const double kappa = std::max(piece_curvature(l, true), piece_curvature(r, false));
  const double s = std::sin(0.5 * turn);
  const double c2 = kCurvedReach * kCurvedReach * kappa;  // (d/2) s + c2 d^2 = tol
  const double d_tol = kappa > 0 ? (-(0.5 * s) + std::sqrt(0.25 * s * s + 4 * c2 * tol)) / (2 * c2)
                                 : blend_spacing_for(tol, turn);
  // the blend at spacing d, measured
  auto at = [&](double d) {
    CurvedFit g;
    g.d = d;
    g.shortened = d >= cap;
    g.in = cut_leg(l, true, v, l.t_end, d);
    g.out = cut_leg(r, false, v, r.t_start, d);
    g.blend = corner_blend(v, l.t_end, r.t_start, d);
    g.blend.ctrl.row(0) = g.in.end.transpose();
    g.blend.ctrl.row(1) = g.in.inner.transpose();
    g.blend.ctrl.row(3) = g.out.inner.transpose();
    g.blend.ctrl.row(4) = g.out.end.transpose();
    Piece in, out;
    if (l.segment) in.a = g.in.end, in.b = v;
    else in.curve = l.curve.get(), in.u0 = g.in.u, in.u1 = l.curve->u_end();
    if (r.segment) out.a = v, out.b = g.out.end;
    else out.curve = r.curve.get(), out.u0 = r.curve->u_begin(), out.u1 = g.out.u;
    g.deviation = curved_blend_deviation(g.blend, in, out, 2 * o.run_samples);
    g.ok = g.deviation <= tol;
    return g;
  };
  // A blend that meets the tolerance only when next to nothing (d below kMinCurvedSpacing tol: a
  // cusp or a near reversal of a drawing's curves) leaves the corner a stop; so does a cut that
  // rounds to a leg's end (split_at needs u strictly inside).
  auto cuts_inside = [&](const CurvedFit& g) {
    auto inside = [](const Element& e, double u) {
      return e.segment || (u > e.curve->u_begin() && u < e.curve->u_end());
    };
    return inside(l, g.in.u) && inside(r, g.out.u);
  };
  // A leg whose curvature is unbounded at the corner (a Bezier whose handle there is retracted, as
  // drawings have at cusp nodes: curvature ~ 1/sqrt(s)) gives d_tol ~ 0; the blend may still meet
  // the tolerance a little way along it, so the search starts from the straight legs' spacing.
  double d = std::min(cap, d_tol >= kMinCurvedSpacing * tol ? d_tol : blend_spacing_for(tol, turn));
  for (int it = 0; it < 200 && d >= kMinCurvedSpacing * tol && !f.ok; ++it, d *= 0.9) {
    f = at(d);
    if (f.ok && !cuts_inside(f)) f.ok = false, d = 0;
  }
  if (!f.ok) return f;
  f.shortened = f.d >= cap || cap < d_tol;
  // At a tangent join (a curvature step) the starting d is far inside the tolerance (the turn costs
  // nothing): a longer blend ramps the curvature more gently, so d grows by 20 % while it measures
  // within tol and the legs allow.
  if (turn <= o.kink)
    for (int it = 0; it < 20 && !f.shortened; ++it) {
      const CurvedFit g = at(std::min(cap, 1.2 * f.d));
      if (!g.ok || !cuts_inside(g)) break;
      f = g;
    }
  return f;
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
      e.k_start = e.k_end = Vec::Zero(e.a.size());
      out.push_back(std::move(e));
    }
  } else {
    auto c = std::make_shared<const geo::Curve>(spline, m.where);
    Element e;
    e.move = index;
    e.a = c->point(c->u_begin());
    e.b = c->point(c->u_end());
    e.length = arc_length(*c, c->u_begin(), c->u_end());
    e.t_start = unit_tangent(*c, c->u_begin());
    e.t_end = unit_tangent(*c, c->u_end());
    e.k_start = curvature_vector(*c, c->u_begin());
    e.k_end = curvature_vector(*c, c->u_end());
    e.curve = std::move(c);
    out.push_back(std::move(e));
  }
  if (out.size() > first) out.back().last_of_move = true;
}

double move_tol(const input::Move& m, double default_tol) { return m.tolerance < 0 ? default_tol : m.tolerance; }

// What happens at the join between elements k and k+1 (d left 0 for blends; set later).
// Largest height of a vertex above the chord of its neighbours, in tolerances, for it to join a run.
constexpr double kRunHeight = 7;
// Fewest corners a smoothed run takes (shorter runs interpolate their vertices).
constexpr size_t kMinSmoothedRun = 4;

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
    // tangent, but the curvature steps (a line meeting an arc): blended like a corner, so that the
    // curvature ramps instead of stepping within one tick
    const bool step = (!l.segment || !r.segment) && (l.k_end - r.k_start).norm() > o.curvature_step;
    if (!(step && o.blend_curved && !(ml.kind == Kind::kRapid || mr.kind == Kind::kRapid))) {
      ++res.joins_passed;
      return j;
    }
    j.kind = JoinKind::kBlend;
    return j;
  }
  if ((!l.segment || !r.segment) && !o.blend_curved) return stop(StopReason::kCurvedMove);
  if (j.turn > o.max_turn) return stop(StopReason::kReversal);
  j.kind = JoinKind::kBlend;
  return j;
}

// Shortest leg, in tolerances, next to a vertex that moves outward (README.md, "Offset corners"): the
// legs then tilt by at most about 1/10 rad where a neighbour stays.
constexpr double kOffsetLeg = 10;

double join_tol(const input::Toolpath& tp, const std::vector<Element>& el, size_t k, double default_tol) {
  return std::min(move_tol(tp.moves[el[k].move], default_tol), move_tol(tp.moves[el[k + 1].move], default_tol));
}

// Moves each vertex that offset_share allows outward, along the bisector of its turn, so far that it
// lies offset_share tolerances from both its legs' lines (README.md, "Offset corners"); joins[k].shift
// records it. The elements next to it are re-cut and the turns around it re-measured.
void offset_vertices(const input::Toolpath& tp, double default_tol, const BlendOptions& o, std::vector<Element>& el,
                     std::vector<Join>& joins) {
  const size_t n = joins.size();
  auto sharp_line_corner = [&](size_t k) {
    const Join& j = joins[k];
    if (j.kind != JoinKind::kBlend || !el[k].segment || !el[k + 1].segment || j.turn > o.stop_turn) return false;
    const double tol = join_tol(tp, el, k, default_tol);
    return std::min(el[k].length, el[k + 1].length) >= kOffsetLeg * tol &&
           dist_to_segment(el[k].b, el[k].a, el[k + 1].b) > kRunHeight * tol;
  };
  std::vector<char> sharp(n);
  for (size_t k = 0; k < n; ++k) sharp[k] = sharp_line_corner(k);
  std::vector<size_t> moved;
  std::vector<Vec> to;
  for (size_t k = 1; k + 1 < n; ++k) {
    if (!(sharp[k - 1] && sharp[k] && sharp[k + 1])) continue;
    const double e = o.offset_share * join_tol(tp, el, k, default_tol);
    joins[k].shift = e;
    joins[k].programmed = el[k].b;
    moved.push_back(k);
    to.push_back(el[k].b + e / std::cos(0.5 * joins[k].turn) * (el[k].t_end - el[k + 1].t_start).normalized());
  }
  auto recut = [](Element& e) {
    e.length = (e.b - e.a).norm();
    e.t_start = e.t_end = (e.b - e.a) / e.length;
  };
  for (size_t i = 0; i < moved.size(); ++i) el[moved[i]].b = el[moved[i] + 1].a = to[i];
  for (size_t k : moved) recut(el[k]), recut(el[k + 1]);
  for (size_t k : moved)
    for (size_t jk = k - 1; jk <= k + 1; ++jk) joins[jk].turn = turning_angle(el[jk].t_end, el[jk + 1].t_start);
}

// Whether join k or a join next to it moved its vertex (README.md, "Offset corners").
bool shift_near(const std::vector<Join>& joins, size_t k) {
  for (size_t jk = k > 0 ? k - 1 : 0; jk <= k + 1 && jk < joins.size(); ++jk)
    if (joins[jk].shift > 0) return true;
  return false;
}

// Deviation of a line-line blend from the corner's legs as programmed: the larger of its largest
// distance from them and the programmed vertex's distance from it.
double deviation_from_legs(const geo::BSpline& blend, const Element& l, const Element& r, int samples) {
  const geo::Curve c(blend, "corner blend");
  const double u0 = c.u_begin(), u1 = c.u_end();
  return std::max(
      farthest_point(
          c, [&](const Vec& p) { return std::min(dist_to_segment(p, l.a, l.b), dist_to_segment(p, r.a, r.b)); },
          samples),
      dist_sampled(l.b, [&](double f) { return point_at(c, u0 + f * (u1 - u0)); }));
}

std::string blend_where(const input::Move& l, const input::Move& r, const std::string& what = "corner blend") {
  return (l.where == r.where ? l.where : l.where + " / " + r.where) + ": " + what;
}

// Measured deviation of a run's curve from the programmed polygon `poly` (one point per control point
// of s: the entry and exit points on the legs and the vertices): the larger of (1) the largest
// distance of a curve point from the polygon, sampled `samples` times per knot span and refined by
// golden section at the worst sample, and (2) the distance of each vertex and each edge midpoint to
// the curve, searched near its Greville abscissa the same way.
double run_deviation(const geo::BSpline& s, const std::vector<Vec>& poly, int samples) {
  const geo::Curve c(s, "run");
  const int n = s.n_ctrl();
  const int spans = n - 3;
  // The curve on knot span j lies in the hull of control points j..j+3, each near its polygon point:
  // the polygon edges j-2..j+4 around it.
  auto dist_poly = [&](double u, int j) {
    const Vec p = point_at(c, u);
    return dist_to_edges(p, poly, static_cast<size_t>(std::max(0, j - 2)), static_cast<size_t>(std::min(n - 2, j + 4)) + 1);
  };
  double worst = 0;
  for (int j = 0; j < spans; ++j) {
    const double u0 = s.knots[j + 3], u1 = s.knots[j + 4];
    int arg = 0;
    double w = -1;
    for (int i = 0; i <= samples; ++i) {
      const double d = dist_poly(u0 + (u1 - u0) * i / samples, j);
      if (d > w) w = d, arg = i;
    }
    const double h = (u1 - u0) / samples;
    const double ua = u0 + h * std::max(0, arg - 1), ub = u0 + h * std::min(samples, arg + 1);
    worst = std::max({worst, w, -golden_min([&](double u) { return -dist_poly(u, j); }, ua, ub)});
  }
  // Points of the programmed polyline: each vertex (points 2..n-3) and the midpoint of each edge
  // between two vertices, against the curve between the Greville abscissae of the neighbouring
  // control points (a B-spline is nearest its control point i about its Greville abscissa
  // xi_i = (t_{i+1} + t_{i+2} + t_{i+3}) / 3, also next to the clamped ends).
  auto greville = [&](int i) { return (s.knots[i + 1] + s.knots[i + 2] + s.knots[i + 3]) / 3; };
  auto dist_curve = [&](const Vec& p, double ua, double ub) {
    double best = INFINITY, arg = ua;
    for (int k = 0; k <= 2 * samples; ++k) {
      const double u = ua + (ub - ua) * k / (2 * samples);
      const double d = (point_at(c, u) - p).norm();
      if (d < best) best = d, arg = u;
    }
    const double h = (ub - ua) / (2 * samples);
    return std::min(best, golden_min([&](double u) { return (point_at(c, u) - p).norm(); }, std::max(ua, arg - h),
                                     std::min(ub, arg + h)));
  };
  for (int i = 2; i <= n - 3; ++i) {
    worst = std::max(worst, dist_curve(poly[i], greville(i - 1), greville(i + 1)));
    if (i < n - 3) worst = std::max(worst, dist_curve(0.5 * (poly[i] + poly[i + 1]), greville(i - 1), greville(i + 2)));
  }
  return worst;
}

// Cumulative chord length along a polygon.
std::vector<double> chord_lengths(const std::vector<Vec>& poly) {
  std::vector<double> S(poly.size(), 0.0);
  for (size_t i = 1; i < poly.size(); ++i) S[i] = S[i - 1] + (poly[i] - poly[i - 1]).norm();
  return S;
}

// A run smoothed instead of interpolated (README.md, "Smoothed runs"): a clamped cubic B-spline
// parameterised by chord length over the polygon poly = entry, vertices..., exit, with interior knots
// at the first and last vertex and uniform between them (spans of at most `span` mm), fitted by least
// squares to points along the polygon. The first three control points lie on the entry line and the
// last three on the exit line, at the Greville abscissae of a straight line run at constant speed, so
// the joins are G2 with curvature 0; the inner ones are free. free_in (free_out): the run starts (ends)
// at a stop, where the tangent and the curvature may step: only the end point is fixed there. A light
// second-difference penalty keeps the system definite. The normal equations are banded (a point sees 4
// control points): linear in the run's length. Returns an empty spline where the run is too short for a
// free control point.
geo::BSpline fit_run(const std::vector<Vec>& poly, const Vec& t_in, const Vec& t_out, double span, bool free_in,
                     bool free_out) {
  geo::BSpline b;
  const std::vector<double> S = chord_lengths(poly);
  const double L = S.back();
  if (poly.size() < 4 || !(L > 0)) return b;
  // knots (chord length / L): the first and last at the run's first and last vertex, uniform between;
  // at a free end (a stop) the knot at the first (last) vertex is left out: the span next to the
  // stop reaches over the first edge, which may be short (a span as short would let the curve bend
  // hard at the stop, where the machine starts from rest)
  const double a = S[1], z = S[S.size() - 2];
  const int spans = static_cast<int>(std::ceil((z - a) / span));
  std::vector<double> inner;
  for (int i = free_in ? 1 : 0; i <= (free_out ? spans - 1 : spans); ++i) inner.push_back((a + (z - a) * i / spans) / L);
  const int n = static_cast<int>(inner.size()) + 4;  // knot spans + 3
  const int f0 = free_in ? 1 : 3, f1 = free_out ? n - 2 : n - 4;  // the free control points
  if (spans < 1 || f1 < f0 || (!free_in && !free_out && spans < 2)) return b;
  const int dim = static_cast<int>(poly[0].size());
  b.degree = 3;
  b.knots.resize(n + 4);
  for (int i = 0; i < 4; ++i) b.knots[i] = 0, b.knots[n + i] = 1;
  for (size_t i = 0; i < inner.size(); ++i) b.knots[4 + i] = inner[i];
  b.ctrl.resize(n, dim);
  const Vec& E = poly.front();
  const Vec& X = poly.back();
  // a straight line at unit speed has its control points at the Greville abscissae
  auto greville = [&](int i) { return L * (b.knots[i + 1] + b.knots[i + 2] + b.knots[i + 3]) / 3; };
  b.ctrl.row(0) = E.transpose();
  b.ctrl.row(1) = (E + greville(1) * t_in).transpose();
  b.ctrl.row(2) = (E + greville(2) * t_in).transpose();
  b.ctrl.row(n - 3) = (X - (L - greville(n - 3)) * t_out).transpose();
  b.ctrl.row(n - 2) = (X - (L - greville(n - 2)) * t_out).transpose();
  b.ctrl.row(n - 1) = X.transpose();
  const int F = f1 - f0 + 1;
  // Data: the vertices and points along each edge at most span/8 apart.
  std::vector<double> us;
  std::vector<Vec> ps;
  for (size_t e = 0; e + 1 < poly.size(); ++e) {
    const double len = S[e + 1] - S[e];
    const int k = std::max(2, static_cast<int>(std::ceil(8 * len / span)));
    for (int i = 0; i < k; ++i) {
      us.push_back((S[e] + len * i / k) / L);
      ps.push_back(poly[e] + (poly[e + 1] - poly[e]) * (double(i) / k));
    }
  }
  us.push_back(1.0);
  ps.push_back(X);
  using Trip = Eigen::Triplet<double>;
  std::vector<Trip> trips;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(F, dim);
  auto add_row = [&](int first, const double* w, const Vec& target) {
    // one residual sum_k w_k C_{first+k} - target: fixed points move to the right-hand side; a row
    // may reach past the last control point with weight 0 (the smoothing stencil at the end)
    const int count = std::min(4, n - first);
    Vec t = target;
    for (int a = 0; a < count; ++a) {
      const int i = first + a;
      if (i < f0 || i > f1) t -= w[a] * b.ctrl.row(i).transpose();
    }
    for (int a = 0; a < count; ++a) {
      const int i = first + a;
      if (i < f0 || i > f1) continue;
      rhs.row(i - f0) += w[a] * t.transpose();
      for (int c = 0; c < count; ++c) {
        const int k = first + c;
        if (k < f0 || k > f1) continue;
        trips.emplace_back(i - f0, k - f0, w[a] * w[c]);
      }
    }
  };
  for (size_t q = 0; q < us.size(); ++q) {
    // knot span mu (knots[mu] <= u < knots[mu + 1]) and the cubic basis there (Cox-de Boor)
    const int mu = std::min(n - 1, static_cast<int>(std::upper_bound(b.knots.data() + 3, b.knots.data() + n, us[q]) -
                                                     b.knots.data()) - 1);
    const int j = mu - 3;
    double Nb[4] = {1, 0, 0, 0};
    double left[4], right[4];
    const double u = us[q];
    for (int r = 1; r <= 3; ++r) {
      left[r] = u - b.knots[mu + 1 - r];
      right[r] = b.knots[mu + r] - u;
      double saved = 0;
      for (int k = 0; k < r; ++k) {
        const double tmp = Nb[k] / (right[k + 1] + left[r - k]);
        Nb[k] = saved + right[k + 1] * tmp;
        saved = left[r - k] * tmp;
      }
      Nb[r] = saved;
    }
    add_row(j, Nb, ps[q]);
  }
  // smoothing: second differences of the control points, weighted lightly against the data
  const double lambda = 1e-3;
  const double w2[4] = {lambda, -2 * lambda, lambda, 0};
  for (int i = 1; i + 1 < n; ++i) add_row(i - 1, w2, Vec::Zero(dim));
  Eigen::SparseMatrix<double> A(F, F);
  A.setFromTriplets(trips.begin(), trips.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
  if (ldlt.info() != Eigen::Success) return geo::BSpline{};
  const Eigen::MatrixXd x = ldlt.solve(rhs);
  if (ldlt.info() != Eigen::Success || !x.allFinite()) return geo::BSpline{};
  b.ctrl.block(f0, 0, F, dim) = x;
  b.name = "corner run";
  return b;
}

// Hausdorff distance between a curve and a polygon whose chord-length parameter the curve follows
// (fit_run): each curve point is compared with the edges within `window` mm of chord length of its
// own (sampled per knot span, golden section at the worst sample), each vertex and edge midpoint with
// the curve near its parameter (sampled, golden section at the nearest). Linear in the run's length.
double fitted_run_deviation(const geo::BSpline& s, const std::vector<Vec>& poly, int samples, double window) {
  const geo::Curve c(s, "run");
  const std::vector<double> S = chord_lengths(poly);
  const double L = S.back();
  auto edges_near = [&](double at, size_t& lo, size_t& hi) {
    lo = std::lower_bound(S.begin(), S.end(), at - window) - S.begin();
    lo = lo > 0 ? lo - 1 : 0;
    hi = std::upper_bound(S.begin(), S.end(), at + window) - S.begin();
    hi = std::min(hi, poly.size() - 1);
  };
  auto dist_poly = [&](double u) {
    const Vec p = point_at(c, u);
    size_t lo, hi;
    edges_near(u * L, lo, hi);
    return dist_to_edges(p, poly, lo, hi);
  };
  double worst = 0;
  const int spans = s.n_ctrl() - 3;
  for (int j = 0; j < spans; ++j) {
    const double u0 = s.knots[j + 3], u1 = s.knots[j + 4];
    int arg = 0;
    double w = -1;
    for (int i = 0; i <= samples; ++i) {
      const double d = dist_poly(u0 + (u1 - u0) * i / samples);
      if (d > w) w = d, arg = i;
    }
    const double h = (u1 - u0) / samples;
    worst = std::max({worst, w, -golden_min([&](double u) { return -dist_poly(u); }, u0 + h * std::max(0, arg - 1),
                                            u0 + h * std::min(samples, arg + 1))});
  }
  // A vertex's distance is a minimum: a sample can only overstate it (the
  // safe side), and the golden section refines the best sample's basin, so
  // a quarter of the curve's sampling density suffices to find it.
  auto dist_curve = [&](const Vec& p, double at) {
    const double ua = std::max(0.0, (at - window) / L), ub = std::min(1.0, (at + window) / L);
    const int k = std::max(8, static_cast<int>(std::ceil(std::max(4, samples / 4) * spans * (ub - ua))));
    double best = INFINITY, arg = ua;
    for (int i = 0; i <= k; ++i) {
      const double u = ua + (ub - ua) * i / k;
      const double d = (point_at(c, u) - p).norm();
      if (d < best) best = d, arg = u;
    }
    const double h = (ub - ua) / k;
    return std::min(best, golden_min([&](double u) { return (point_at(c, u) - p).norm(); }, std::max(ua, arg - h),
                                     std::min(ub, arg + h)));
  };
  for (size_t i = 1; i + 1 < poly.size(); ++i) {
    worst = std::max(worst, dist_curve(poly[i], S[i]));
    worst = std::max(worst, dist_curve(0.5 * (poly[i] + poly[i + 1]), 0.5 * (S[i] + S[i + 1])));
  }
  return worst;
}

// ---------------------------------------------------------------------------------------------
// Wide blends of line-line corners (README.md, "Wide blends").

struct WideShape {
  double r1, r2, eps;  // l1 / l0, l2 / l1, e / l0
};

// Wide blends (README.md, "Wide blends"): per turn 5, 10, ..., 175 degrees, the seven-point shape
// {l1/l0, l2/l1, e/l0} of least peak |d3x/ds3| at the largest size the tolerance allows, for legs of
// 4 tolerances (kWideShort: inner shapes) and of 16 (kWideLong: from 40 degrees the curve leaves
// the legs on the outer side first). Printed by tb/bench/bench_blend_shape --cxx (Nelder-Mead);
// any row is a valid shape (the deviation is measured for the actual turn), the table only picks
// good ones.
constexpr int kWideRows = 35;
const WideShape kWideShort[kWideRows] = {
    {0.8334, 0.6002, -0.0109},  // 5 deg
    {0.8336, 0.6008, -0.0220},  // 10 deg
    {0.8340, 0.6018, -0.0332},  // 15 deg
    {0.8346, 0.6032, -0.0448},  // 20 deg
    {0.8353, 0.6050, -0.0568},  // 25 deg
    {0.8361, 0.6073, -0.0694},  // 30 deg
    {0.8372, 0.6100, -0.0825},  // 35 deg
    {0.8385, 0.6133, -0.0962},  // 40 deg
    {0.8400, 0.6170, -0.1106},  // 45 deg
    {0.8417, 0.6214, -0.1258},  // 50 deg
    {0.8436, 0.6262, -0.1418},  // 55 deg
    {0.8457, 0.6317, -0.1586},  // 60 deg
    {0.8482, 0.6378, -0.1763},  // 65 deg
    {0.8508, 0.6445, -0.1948},  // 70 deg
    {0.8469, 0.6445, -0.2089},  // 75 deg
    {0.8204, 0.6285, -0.2093},  // 80 deg
    {0.7917, 0.6140, -0.2108},  // 85 deg
    {0.7651, 0.6031, -0.2153},  // 90 deg
    {0.7608, 0.6078, -0.2304},  // 95 deg
    {0.7568, 0.6135, -0.2463},  // 100 deg
    {0.7532, 0.6203, -0.2629},  // 105 deg
    {0.7499, 0.6283, -0.2805},  // 110 deg
    {0.7533, 0.6374, -0.3015},  // 115 deg
    {0.7472, 0.6494, -0.3204},  // 120 deg
    {0.7460, 0.6616, -0.3420},  // 125 deg
    {0.7505, 0.6781, -0.3685},  // 130 deg
    {0.7609, 0.6987, -0.4007},  // 135 deg
    {0.7723, 0.7208, -0.4358},  // 140 deg
    {0.7863, 0.7453, -0.4755},  // 145 deg
    {0.8016, 0.7713, -0.5193},  // 150 deg
    {0.8201, 0.8006, -0.5696},  // 155 deg
    {0.8357, 0.8301, -0.6217},  // 160 deg
    {0.8669, 0.8670, -0.6931},  // 165 deg
    {0.8988, 0.9058, -0.7725},  // 170 deg
    {0.9451, 0.9504, -0.8754},  // 175 deg
};
const WideShape kWideLong[kWideRows] = {
    {0.8334, 0.6002, -0.0109},  // 5 deg
    {0.8336, 0.6008, -0.0220},  // 10 deg
    {0.8340, 0.6018, -0.0332},  // 15 deg
    {0.8346, 0.6032, -0.0448},  // 20 deg
    {0.8282, 0.5997, -0.0553},  // 25 deg
    {0.8259, 0.5996, -0.0667},  // 30 deg
    {0.8221, 0.5988, -0.0781},  // 35 deg
    {0.9391, 0.7032, +0.0192},  // 40 deg
    {0.9309, 0.7302, +0.0363},  // 45 deg
    {0.9260, 0.7635, +0.0556},  // 50 deg
    {0.9224, 0.8051, +0.0777},  // 55 deg
    {0.9159, 0.8596, +0.1031},  // 60 deg
    {0.8906, 0.9133, +0.1248},  // 65 deg
    {0.8920, 0.9240, +0.1426},  // 70 deg
    {0.8936, 0.9359, +0.1608},  // 75 deg
    {0.8955, 0.9488, +0.1793},  // 80 deg
    {0.8871, 0.9749, +0.1984},  // 85 deg
    {0.8971, 0.9803, +0.2172},  // 90 deg
    {0.8990, 0.9962, +0.2364},  // 95 deg
    {0.9105, 0.9993, +0.2548},  // 100 deg
    {0.9224, 1.0000, +0.2721},  // 105 deg
    {0.9332, 1.0000, +0.2885},  // 110 deg
    {0.9428, 1.0000, +0.3038},  // 115 deg
    {0.9515, 1.0000, +0.3183},  // 120 deg
    {0.9589, 1.0000, +0.3315},  // 125 deg
    {0.9657, 1.0000, +0.3439},  // 130 deg
    {0.9719, 1.0000, +0.3552},  // 135 deg
    {0.9772, 1.0000, +0.3654},  // 140 deg
    {0.9821, 1.0000, +0.3746},  // 145 deg
    {0.9863, 1.0000, +0.3826},  // 150 deg
    {0.9899, 1.0000, +0.3895},  // 155 deg
    {0.9932, 1.0000, +0.3953},  // 160 deg
    {0.9958, 1.0000, +0.3999},  // 165 deg
    {0.9979, 1.0000, +0.4033},  // 170 deg
    {0.9993, 1.0000, +0.4054},  // 175 deg
};

// The seven-point blend at corner v: P0, P1, P2 at l0, l1, l2 before v on the arriving line, P3 at
// distance e from v along the bisector (outward for e > 0), P4..P6 the mirror image on the leaving
// line; clamped cubic knots {0,0,0,0, 1/4, 1/2, 3/4, 1,1,1,1}. P0..P2 (P4..P6) collinear: the joins
// are G2 with curvature 0, as the five-point blend's.
geo::BSpline wide_blend(const Vec& v, const Vec& t_in, const Vec& t_out, double l0, const WideShape& s) {
  const Vec inward = (t_out - t_in).normalized();
  const double l1 = s.r1 * l0, l2 = s.r2 * l1, e = s.eps * l0;
  geo::BSpline b;
  b.degree = 3;
  b.ctrl.resize(7, v.size());
  b.ctrl.row(0) = (v - l0 * t_in).transpose();
  b.ctrl.row(1) = (v - l1 * t_in).transpose();
  b.ctrl.row(2) = (v - l2 * t_in).transpose();
  b.ctrl.row(3) = (v - e * inward).transpose();
  b.ctrl.row(4) = (v + l2 * t_out).transpose();
  b.ctrl.row(5) = (v + l1 * t_out).transpose();
  b.ctrl.row(6) = (v + l0 * t_out).transpose();
  b.knots.resize(11);
  b.knots << 0, 0, 0, 0, 0.25, 0.5, 0.75, 1, 1, 1, 1;
  b.name = "corner blend";
  return b;
}

// Largest of n + 1 samples of f on [0, 1], each local maximum refined by golden section.
template <class F>
double sampled_max(const F& f, int n) {
  std::vector<double> y(n + 1);
  for (int i = 0; i <= n; ++i) y[i] = f(double(i) / n);
  double worst = -INFINITY;
  for (int i = 0; i <= n; ++i) {
    worst = std::max(worst, y[i]);
    const bool peak = (i == 0 || y[i] >= y[i - 1]) && (i == n || y[i] >= y[i + 1]);
    if (peak)
      worst = std::max(worst, -golden_min([&](double u) { return -f(u); }, std::max(0, i - 1) / double(n),
                                          std::min(n, i + 1) / double(n)));
  }
  return worst;
}

// The corner's canonical plane: v = 0, arriving along x, leaving at angle `turn`.
struct CanonicalCorner {
  Vec v = Vec::Zero(2), t_in = Vec::Zero(2), t_out = Vec::Zero(2);
  explicit CanonicalCorner(double turn) {
    t_in << 1, 0;
    t_out << std::cos(turn), std::sin(turn);
  }
};

// |d3x/ds3| over n + 1 samples (the planner's |Q|: the jerk per v^3 of a pass at constant speed,
// which bounds a blend's speed under a jerk limit J at (J / |Q|)^(1/3)): its largest value and the
// integral of |Q|^(1/3) ds (the time of a pass at that bound, times J^(1/3); midpoint rule).
// from_rest: the largest |Q| s^2, s the arc length from the curve's start. A move from rest there at
// jerk J reaches (J/2)^(1/3) (6 s)^(2/3) (while its acceleration has not reached its limit), within
// the bound wherever |Q| s^2 <= 1/18: the lower, the more room the curve leaves a start from rest.
struct JerkGeometry {
  double peak = 0, pass = 0, from_rest = 0;
};
JerkGeometry jerk_geometry(const geo::Curve& c, int n) {
  JerkGeometry r;
  double s_prev = 0, g_prev = 0;
  for (int i = 0; i <= n; ++i) {
    const Eigen::MatrixXd e = c.eval(c.u_begin() + (c.u_end() - c.u_begin()) * i / n, 3);
    const Eigen::VectorXd d1 = e.col(1), d2 = e.col(2), d3 = e.col(3);
    // x_u = g T, x_uu = g' T + g^2 K, x_uuu = g'' T + 3 g g' K + g^3 Q (g = |x_u|)
    const double g = d1.norm();
    const Eigen::VectorXd T = d1 / g;
    const double g1 = d2.dot(T);
    const Eigen::VectorXd K = (d2 - g1 * T) / (g * g);
    const double g2 = K.dot(d2) * g + T.dot(d3);
    const double q = ((d3 - g2 * T - 3 * g * g1 * K) / (g * g * g)).norm();
    r.peak = std::max(r.peak, q);
    const double ds = g * (c.u_end() - c.u_begin()) / n;
    if (i > 0) s_prev += 0.5 * (g_prev + ds);
    g_prev = ds;
    r.from_rest = std::max(r.from_rest, q * s_prev * s_prev);
    r.pass += std::cbrt(q) * ds * ((i == 0 || i == n) ? 0.5 : 1.0);
  }
  return r;
}

// A line-line corner V next to a stop S (README.md, "Corners next to a stop"). The machine is at rest
// at S, where the path's direction may turn, so the near leg (from S to V) need not be followed
// straight: the corner is blended at a virtual vertex V' = V + c t_far on the far leg, with a
// five-point blend whose near end point is S: control points S, V' - d1 t', V', V' + d2 t_far,
// V' + r d2 t_far (t' the unit chord S V', d1 = |V' - S| / r, r = kBlendReach). Its turn is smaller
// than V's, and its far side may be longer than its near side (d2 >= d1): the turn then spreads
// over the far side, where the machine moves faster. Of c = |S V| {0, 1/4, ..., 3} (while the
// deviation from the two legs, measured, stays within tol) and d2 = d1 {1, 1.5, 2, 3, 4, 6}
// (while the blend's far end stays within far_reach of V), the one that leaves a start from rest
// at S the most room (the least JerkGeometry::from_rest). The curve runs from S to the far leg.
struct StopBlend {
  bool ok = false;
  geo::BSpline curve;
  double d = 0, turn = 0, reach = 0, deviation = 0;  // reach: how much of the far leg it takes
};
StopBlend stop_blend(const Vec& S, const Vec& V, const Vec& t_far, double far_reach, double tol, int samples) {
  StopBlend best;
  double best_q = INFINITY;
  const double near = (V - S).norm();
  for (double cf : {0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 3.0}) {
    const double c = cf * near;
    const Vec vv = V + c * t_far;
    const double l = (vv - S).norm(), d1 = l / kBlendReach;
    if (!(l > 0) || c + l > far_reach) break;
    const Vec t_near = (vv - S) / l;
    bool within = false;
    for (double m : {1.0, 1.5, 2.0, 3.0, 4.0, 6.0}) {
      const double d2 = m * d1, reach = c + kBlendReach * d2;
      if (reach > far_reach) break;
      geo::BSpline b = corner_blend(vv, t_near, t_far, d1);
      b.ctrl.row(0) = S.transpose();
      b.ctrl.row(3) = (vv + d2 * t_far).transpose();
      b.ctrl.row(4) = (vv + kBlendReach * d2 * t_far).transpose();
      const double dev = curved_blend_deviation(b, Piece{nullptr, S, V}, Piece{nullptr, V, Vec(V + reach * t_far)}, samples);
      if (!(dev <= tol)) continue;
      within = true;
      const double q = jerk_geometry(geo::Curve(b, "corner blend"), 64).from_rest;
      if (q < best_q) best_q = q, best = {true, b, d1, turning_angle(t_near, t_far), reach, dev};
    }
    if (!within) break;  // a farther virtual vertex only deviates more
  }
  return best;
}

// A wide blend's shape at one turn, in the corner's plane at unit size (l0 = 1): its deviation (the
// Hausdorff distance between the blend and the two legs it replaces: every blend point's distance
// to the legs and every leg point's to the blend, sampled with every local maximum refined) and
// its peak |d3x/ds3|. Both scale with the size: deviation as l0, |d3x/ds3| as 1 / l0^2.
struct WideFigures {
  double deviation = 0, peak_q = 0, pass = 0, peak_kappa = 0;
};
WideFigures wide_figures(double turn, const WideShape& s) {
  const CanonicalCorner k(turn);
  const Vec& v = k.v;
  const geo::Curve c(wide_blend(v, k.t_in, k.t_out, 1, s), "corner blend");
  const Vec a = -k.t_in, b = k.t_out;
  const int n = 64;
  WideFigures w;
  const double off = sampled_max(
      [&](double u) {
        const Vec p = point_at(c, u);
        return std::sqrt(std::min(dist2_to_segment(p, a, v), dist2_to_segment(p, v, b)));
      },
      n);
  // A leg point's distance to the blend: Newton on (C(u) - p) . C'(u) = 0 from the nearest of n
  // samples. Any curve point's distance is at least the true one, so a poor convergence can only
  // overstate the deviation (a smaller blend), never understate it.
  std::vector<Vec> at(n + 1);
  for (int i = 0; i <= n; ++i) at[i] = point_at(c, double(i) / n);
  auto to_blend = [&](const Vec& p) {
    int arg = 0;
    double best = INFINITY;
    for (int i = 0; i <= n; ++i) {
      const double d = (at[i] - p).squaredNorm();
      if (d < best) best = d, arg = i;
    }
    best = std::sqrt(best);
    double u = double(arg) / n;
    for (int it = 0; it < 8; ++it) {
      const Eigen::MatrixXd e = c.eval(u, 2);
      const Vec r = e.col(0) - p, d1 = e.col(1), d2 = e.col(2);
      best = std::min(best, r.norm());
      const double f = r.dot(d1), df = d1.squaredNorm() + r.dot(d2);
      if (!(df > 0)) break;
      const double un = std::clamp(u - f / df, 0.0, 1.0);
      if (std::fabs(un - u) < 1e-13) break;
      u = un;
    }
    return std::min(best, (point_at(c, u) - p).norm());
  };
  // the blend is symmetric about the bisector: the leaving leg's figure is the arriving one's
  const double leg = sampled_max([&](double x) { return to_blend(Vec(a * (1 - x))); }, 32);
  w.deviation = std::max(off, leg);
  const JerkGeometry jg = jerk_geometry(c, 2 * n);
  w.peak_q = jg.peak;
  w.pass = jg.pass;
  w.peak_kappa = max_curvature(c, 0, 1, 2 * n);
  return w;
}

// Jerk figures of the five-point blend at unit spacing (d = 1; the peak scales as 1 / d^2, the pass
// time as d^(1/3)).
JerkGeometry five_point_jerk(double turn) {
  const CanonicalCorner k(turn);
  return jerk_geometry(geo::Curve(corner_blend(k.v, k.t_in, k.t_out, 1), "corner blend"), 128);
}

// The wide blend chosen at a line-line corner, or none where the five-point blend of spacing d5 has
// a peak |d3x/ds3| as low (within 5 %). `leg` is the most either leg may lose.
struct WideChoice {
  bool chosen = false, shortened = false;
  double l0 = 0, deviation = 0, peak_kappa = 0;
  WideShape shape{};
};
// The figures of the table's shapes and of the five-point blend at the rows' own turns, for the
// choice (computed once, on first use).
struct RowFigures {
  WideFigures wide[2];
  JerkGeometry five;
};
const RowFigures& row_figures(int row) {
  static const std::vector<RowFigures> rows = [] {
    std::vector<RowFigures> r(kWideRows);
    for (int i = 0; i < kWideRows; ++i) {
      const double turn = (i + 1) * 5 * M_PI / 180;
      r[i] = {{wide_figures(turn, kWideShort[i]), wide_figures(turn, kWideLong[i])}, five_point_jerk(turn)};
    }
    return r;
  }();
  return rows[row];
}

// Exact figures per turn and shape (CAM programs repeat their angles: rasters, pockets).
using WideCache = std::unordered_map<double, std::array<std::optional<WideFigures>, 2>>;

WideChoice choose_wide(double turn, double tol, double leg, double d5, WideCache& cache) {
  // The choice takes the figures of the nearest row's turn (they change slowly with the turn); the
  // shape chosen is then measured at the corner's own turn, which sets its size.
  const int row = std::clamp(static_cast<int>(std::lround(turn * 36 / M_PI)) - 1, 0, kWideRows - 1);
  const WideShape* shapes[2] = {&kWideShort[row], &kWideLong[row]};
  const RowFigures& rf = row_figures(row);
  double best = 0.95 * rf.five.peak / (d5 * d5);
  const double pass5 = rf.five.pass * std::cbrt(d5);
  const double kappa5 = blend_peak_curvature(d5, turn);
  int pick = -1;
  for (int i = 0; i < 2; ++i) {
    const WideFigures& f = rf.wide[i];
    // the largest size within the tolerance (the deviation scales with l0) and the legs
    const double l0 = std::min(tol / f.deviation, leg);
    const double q = f.peak_q / (l0 * l0);
    // a lower jerk bound, no higher curvature (where the acceleration bounds the speed), and a pass
    // at the jerk bound no longer: a longer blend at a higher speed can take more time, which a
    // corner passed far below the feed cannot win back on its approach
    if (q < best && f.peak_kappa / l0 <= kappa5 && f.pass * std::cbrt(l0) <= pass5) best = q, pick = i;
  }
  WideChoice w;
  if (pick < 0) return w;
  std::optional<WideFigures>& exact = cache[turn][pick];
  if (!exact) exact = wide_figures(turn, *shapes[pick]);
  const double l0 = std::min(tol / exact->deviation * (1 - 1e-12), leg);
  return {true, l0 >= leg, l0, exact->deviation * l0, exact->peak_kappa / l0, *shapes[pick]};
}


}  // namespace

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::kRapid: return "rapid";
    case StopReason::kExactStop: return "exact stop";
    case StopReason::kReversal: return "reversal";
    case StopReason::kCurvedMove: return "curved move";
    case StopReason::kFaster: return "faster as a stop";
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
  b.ctrl.row(0) = (v - kBlendReach * d * t_in).transpose();
  b.ctrl.row(1) = (v - d * t_in).transpose();
  b.ctrl.row(2) = v.transpose();
  b.ctrl.row(3) = (v + d * t_out).transpose();
  b.ctrl.row(4) = (v + kBlendReach * d * t_out).transpose();
  b.knots.resize(9);
  b.knots << 0, 0, 0, 0, 0.5, 1, 1, 1, 1;
  b.name = "corner blend";
  return b;
}

geo::BSpline run_spline(const std::vector<Vec>& v, const Vec& t_in, double d_first, const Vec& t_out,
                        double d_last, const RunShape& shape) {
  const int m = static_cast<int>(v.size());
  const int n = m + 4;
  geo::BSpline b;
  b.degree = 3;
  b.ctrl.resize(n, v[0].size());
  b.ctrl.row(0) = (v[0] - kBlendReach * d_first * t_in).transpose();
  b.ctrl.row(1) = (v[0] - d_first * t_in).transpose();
  for (int i = 0; i < m; ++i) b.ctrl.row(2 + i) = v[i].transpose();
  b.ctrl.row(n - 2) = (v[m - 1] + d_last * t_out).transpose();
  b.ctrl.row(n - 1) = (v[m - 1] + kBlendReach * d_last * t_out).transpose();
  b.knots.resize(n + 4);
  for (int i = 0; i < 4; ++i) b.knots[i] = 0, b.knots[n + i] = 1;
  for (int i = 1; i <= m; ++i) b.knots[3 + i] = double(i) / (m + 1);
  b.name = m == 1 ? "corner blend" : "corner run";
  // Pull the inner control points towards their vertices: the curve at a vertex's Greville abscissa
  // moves the same share of its gap towards the vertex (the first and last vertex stay on the legs'
  // lines, which keeps the joins G2 with curvature 0).
  if (shape.pull > 0 && m > 2) {
    const geo::Curve c0(b, "run");
    std::vector<Vec> gap(m);
    for (int i = 1; i + 1 < m; ++i) {
      const int k = 2 + i;
      const double xi = (b.knots[k + 1] + b.knots[k + 2] + b.knots[k + 3]) / 3;
      gap[i] = v[i] - point_at(c0, xi);
    }
    for (int i = 1; i + 1 < m; ++i) b.ctrl.row(2 + i) += shape.pull * gap[i].transpose();
  }
  return b;
}

namespace {

// The corner between segments l and r (join j, spacing d set) with the blend it takes if blended on its
// own: the wide one where choose_wide takes it (as the emission below chooses), else the five-point.
CornerCandidate candidate(const std::vector<Element>& el, const std::vector<Join>& joins, size_t k, double tol,
                          double feed, const BlendOptions& o, WideCache& cache) {
  const Element& l = el[k];
  const Element& r = el[k + 1];
  const Join& j = joins[k];
  CornerCandidate c;
  const WideChoice w = o.wide ? choose_wide(j.turn, tol, o.share * std::min(l.length, r.length), j.d, cache)
                              : WideChoice{};
  c.blend = w.chosen ? wide_blend(l.b, l.t_end, r.t_start, w.l0, w.shape) : corner_blend(l.b, l.t_end, r.t_start, j.d);
  c.v = l.b;
  c.t_in = l.t_end;
  c.t_out = r.t_start;
  c.leg_in = l.length;
  c.leg_out = r.length;
  c.feed = feed;
  c.turn = j.turn;
  // the straight-on segments before and after: joins that pass or blend a turn of at most stop_turn
  auto on = [&](size_t jk) { return joins[jk].kind != JoinKind::kStop && joins[jk].turn <= o.stop_turn; };
  c.run_in = l.length;
  for (size_t i = k; i > 0 && on(i - 1) && el[i - 1].segment; --i) c.run_in += el[i - 1].length;
  c.run_out = r.length;
  for (size_t i = k + 1; i + 1 < el.size() && on(i) && el[i + 1].segment; ++i) c.run_out += el[i + 1].length;
  return c;
}

}  // namespace

BlendResult blend_corners(const input::Toolpath& tp, double default_tol, const BlendOptions& o) {
  if (!(default_tol > 0)) throw std::invalid_argument("blend_corners: default tolerance must be positive");
  if (!(o.share > 0 && o.share <= 1)) throw std::invalid_argument("blend_corners: share must be in (0, 1]");
  BlendResult res;
  std::vector<Element> el;
  for (size_t i = 0; i < tp.moves.size(); ++i) add_move_elements(tp.moves[i], i, el);
  if (el.empty()) return res;

  std::vector<Join> joins(el.size() - 1);
  for (size_t k = 0; k + 1 < el.size(); ++k) joins[k] = classify(tp, el[k], el[k + 1], o, res);
  if (o.offset_share > 0) offset_vertices(tp, default_tol, o, el, joins);
  // Segment i as programmed, before offset_vertices moved its ends.
  auto programmed_leg = [&](size_t i) {
    Element e = el[i];
    if (i > 0 && joins[i - 1].shift > 0) e.a = joins[i - 1].programmed;
    if (i < joins.size() && joins[i].shift > 0) e.b = joins[i].programmed;
    return e;
  };

  // Spacing: the tolerance's, shortened to the share of each leg.
  std::vector<size_t> blend_of(joins.size(), 0);
  WideCache wide_cache;
  for (size_t k = 0; k < joins.size(); ++k) {
    Join& j = joins[k];
    if (j.kind != JoinKind::kBlend) continue;
    const input::Move& ml = tp.moves[el[k].move];
    const input::Move& mr = tp.moves[el[k + 1].move];
    const double tol = std::min(move_tol(ml, default_tol), move_tol(mr, default_tol));
    if (!(tol > 0)) throw std::invalid_argument(ml.where + ": tolerance must be positive");
    Blend b;
    if (el[k].segment && el[k + 1].segment) {
      const double d_tol = blend_spacing_for(tol + j.shift, j.turn);
      const double d_leg = o.share * std::min(el[k].length, el[k + 1].length) / kBlendReach;
      j.d = std::min(d_tol, d_leg);
      const bool offset = shift_near(joins, k);
      if (o.stop_if_faster && j.turn > o.stop_turn && !offset &&
          o.stop_if_faster(candidate(el, joins, k, tol, std::min(ml.feed, mr.feed), o, wide_cache))) {
        j.kind = JoinKind::kStop;
        res.stops.push_back({el[k].move, ml.where, StopReason::kFaster, j.turn});
        continue;
      }
      b.deviation = blend_deviation(j.d, j.turn);
      if (offset) {
        // measured against the programmed legs, the spacing shortened by 10 % until within tol (as d
        // falls the blend closes in on the vertex, at most 0.914 tolerances from the programmed one)
        const Element pl = programmed_leg(k), pr = programmed_leg(k + 1);
        for (int it = 0; it < 200; ++it, j.d *= 0.9) {
          b.deviation = deviation_from_legs(corner_blend(el[k].b, el[k].t_end, el[k + 1].t_start, j.d), pl, pr,
                                            o.run_samples);
          if (b.deviation <= tol) break;
        }
        if (!(b.deviation <= tol))
          throw std::logic_error(blend_where(ml, mr) + ": no offset blend within the tolerance");
      }
      j.cut = kBlendReach * j.d;
      b.shortened = d_leg < d_tol;
      b.peak_curvature = blend_peak_curvature(j.d, j.turn);
    } else {
      const CurvedFit f = fit_curved(el[k], el[k + 1], j.turn, tol, o);
      if (!f.ok) {
        j.kind = JoinKind::kStop;
        res.stops.push_back({el[k].move, ml.where, StopReason::kCurvedMove, j.turn});
        continue;
      }
      j.d = f.d;
      j.cut = kCurvedReach * f.d;
      j.curved = true;
      j.u_in = f.in.u;
      j.u_out = f.out.u;
      j.ctrl = f.blend.ctrl;
      b.deviation = f.deviation;
      b.g2 = f.in.g2 && f.out.g2;
      b.shortened = f.shortened;
      b.curved = true;
      b.peak_curvature = blend_peak_curvature(j.d, j.turn);
    }
    b.move = el[k].move;
    b.turn = j.turn;
    b.d = j.d;
    b.tol = tol;
    blend_of[k] = res.blends.size();
    res.blends.push_back(b);
    ++res.corners_blended;
  }

  // Emit: each segment trimmed by its join's cut at a blended end, each blend starting where the chain ends.
  Vec last_end;
  double carry = -1;  // >= 0: the next segment starts at last_end, this far along it
  // A segment between two blended line-line joins (neither moved nor next to one that moved: a run
  // measures against the segments as they are).
  auto between_blends = [&](size_t seg) {
    return seg > 0 && seg < joins.size() && el[seg].segment && joins[seg - 1].kind == JoinKind::kBlend &&
           joins[seg].kind == JoinKind::kBlend && !joins[seg - 1].curved && !joins[seg].curved &&
           !shift_near(joins, seg - 1) && !shift_near(joins, seg);
  };
  // Vertices from join k on that can share one curve: consecutive blended joins, each vertex within
  // kRunHeight tolerances of the chord of its two neighbours (on a regular polygon the pulled run's
  // curve passes 1/8 of that height from the vertex; the run is measured before it is taken).
  auto run_length = [&](size_t k) {
    auto smooth_enough = [&](size_t kk) {
      if (kk + 1 >= el.size() || !el[kk].segment || !el[kk + 1].segment) return false;
      return dist_to_segment(el[kk].b, el[kk].a, el[kk + 1].b) <= kRunHeight * res.blends[blend_of[kk]].tol;
    };
    size_t m = 1;
    if (shift_near(joins, k)) return m;
    while (k + m < joins.size() && between_blends(k + m) && smooth_enough(k + m - 1) && smooth_enough(k + m)) ++m;
    return m;
  };
  // Whether the segment after the run of joins k .. k+m-1 ends at a stop (or the chain's end).
  auto stop_after = [&](size_t k, size_t m) {
    return k + m < el.size() && el[k + m].segment &&
           (k + m == joins.size() ? o.ends_at_rest : joins[k + m].kind == JoinKind::kStop);
  };
  // Emit joins k .. k+m-1 as one curve, if it measures within tolerance.
  auto emit_run = [&](size_t k, size_t m, bool smoothed, bool free_in = false, bool free_out = false) {
    std::vector<Vec> v;
    double tol = INFINITY, feed = INFINITY;
    for (size_t i = 0; i < m; ++i) {
      v.push_back(el[k + i].b);
      tol = std::min(tol, res.blends[blend_of[k + i]].tol);
      feed = std::min(feed, tp.moves[el[k + i].move].feed);
    }
    feed = std::min(feed, tp.moves[el[k + m].move].feed);
    const Vec exit = free_out ? el[k + m].b : Vec(v[m - 1] + joins[k + m - 1].cut * el[k + m].t_start);
    // smoothed first (its spans longer than the chords, the CAM chords' curvature wobble averages out)
    geo::BSpline rs;
    double dev = INFINITY;
    if (smoothed) {
      std::vector<Vec> poly{last_end};
      poly.insert(poly.end(), v.begin(), v.end());
      poly.push_back(exit);
      rs = fit_run(poly, el[k].t_end, el[k + m].t_start, o.run_shape.fit_span, free_in, free_out);
      if (rs.n_ctrl() > 0) {
        double longest = 0;
        for (size_t i = 1; i < poly.size(); ++i) longest = std::max(longest, (poly[i] - poly[i - 1]).norm());
        dev = fitted_run_deviation(rs, poly, o.run_samples, 2 * o.run_shape.fit_span + longest);
      }
    }
    if (smoothed && !(dev <= tol)) return false;
    if (!smoothed) {
      rs = run_spline(v, el[k].t_end, joins[k].d, el[k + m].t_start, joins[k + m - 1].d, o.run_shape);
      rs.ctrl.row(0) = last_end.transpose();
      std::vector<Vec> poly{last_end, v[0] - joins[k].d * el[k].t_end};
      poly.insert(poly.end(), v.begin(), v.end());
      poly.push_back(v[m - 1] + joins[k + m - 1].d * el[k + m].t_start);
      poly.push_back(exit);
      dev = run_deviation(rs, poly, o.run_samples);
    }
    if (!(dev <= tol)) return false;
    Run run{blend_of[k], m, dev};
    for (size_t i = 0; i < m; ++i) {
      Blend& b = res.blends[blend_of[k + i]];
      b.in_run = true;
      b.wide = false;
      b.deviation = dev;
    }
    res.runs.push_back(run);
    // a run to a stop ends there: the stop's exact stop and dwell are its own
    const input::Move& last = tp.moves[el[k + m].move];
    const bool stop_end = free_out && el[k + m].last_of_move && last.exact_stop;
    res.curves.push_back({rs, blend_where(tp.moves[el[k].move], last, "run of " + std::to_string(m) + " corners"),
                          feed, Kind::kFeed, stop_end, true, stop_end ? last.dwell : 0.0,
                          stop_end ? last.pause : plan::ProgramPause{}});
    last_end = rs.ctrl.row(rs.n_ctrl() - 1).transpose();
    return true;
  };
  // The blend at join k, starting where the chain ends.
  auto emit_blend = [&](size_t k) {
    const Element& l = el[k];
    const Element& r = el[k + 1];
    geo::BSpline bl = joins[k].wide ? joins[k].wide_curve : corner_blend(l.b, l.t_end, r.t_start, joins[k].d);
    if (joins[k].curved) bl.ctrl = joins[k].ctrl;
    bl.ctrl.row(0) = last_end.transpose();
    const input::Move& ml = tp.moves[l.move];
    const input::Move& mr = tp.moves[r.move];
    res.curves.push_back({bl, blend_where(ml, mr), std::min(ml.feed, mr.feed), Kind::kFeed, false, true});
    last_end = bl.ctrl.row(bl.n_ctrl() - 1).transpose();
  };
  for (size_t k = 0; k < el.size(); ++k) {
    const Element& e = el[k];
    const input::Move& m = tp.moves[e.move];
    const bool stop_here = e.last_of_move && m.exact_stop;
    const bool blend_before = k > 0 && joins[k - 1].kind == JoinKind::kBlend;
    const bool blend_after = k < joins.size() && joins[k].kind == JoinKind::kBlend;
    if (!e.segment) {
      // Cut at the blends: the end first (u_in > u_out), so u_out stays inside the first piece.
      geo::BSpline s = geo::clamp(m.curve);
      if (blend_after) s = geo::split_at(s, joins[k].u_in).first;
      if (blend_before) {
        s = geo::split_at(s, joins[k - 1].u_out).second;
        s.ctrl.row(0) = last_end.transpose();
      }
      res.curves.push_back({s, m.where, m.feed, m.kind, stop_here, false, stop_here ? m.dwell : 0.0,
                            stop_here ? m.pause : plan::ProgramPause{}});
      last_end = s.ctrl.row(s.n_ctrl() - 1).transpose();
      if (blend_after) emit_blend(k);
      continue;
    }
    // a segment a blend next to a stop ends in (its far leg reaching over joins passed) starts there
    const double cut0 = carry >= 0 ? carry : blend_before ? joins[k - 1].cut : 0;
    const Vec a = carry >= 0 || blend_before ? last_end : Vec(e.a);
    carry = -1;
    // the segment up to its blend's start (a remnant shorter than min_line is dropped: the next blend
    // starts at a, on the same segment line); true when pushed
    auto emit_line = [&](double cut1) {
      const Vec b = e.b - cut1 * e.t_end;
      if (e.length - cut0 - cut1 >= o.min_line || !blend_after) {
        res.curves.push_back({geo::make_line(a, b), m.where, m.feed, m.kind, stop_here, false,
                              stop_here ? m.dwell : 0.0, stop_here ? m.pause : plan::ProgramPause{}});
        last_end = b;
        return true;
      }
      last_end = a;
      return false;
    };
    const bool line_pushed = emit_line(blend_after ? joins[k].cut : 0);
    // A corner on its own next to a stop (README.md, "Corners next to a stop"), after the line up to
    // its plain blend (pushed): 0 not taken; 1 taken from the stop before it; 2 taken to the stop
    // after it (segment k+1 is in the curve).
    auto emit_stop_blend = [&](bool pushed) -> size_t {
      const bool fin = !blend_before && (k == 0 ? o.starts_at_rest : joins[k - 1].kind == JoinKind::kStop);
      const bool fout = stop_after(k, 1);
      if ((!fin && !fout) || shift_near(joins, k)) return 0;
      const Element& r = el[k + 1];
      const bool from_stop = fin && (!fout || e.length <= r.length);  // the near leg: the stop's, the shorter
      Blend& bl = res.blends[blend_of[k]];
      // The far leg, from the stop: the segment after the corner and the ones straight on after it
      // (joins passed), less the share of the last one that its other end's blend may take. Towards a
      // stop after the corner: what is left of the segment before it.
      size_t last = k + 1;
      double far = r.length;
      if (from_stop) {
        while (last < joins.size() && joins[last].kind == JoinKind::kPass && el[last + 1].segment)
          far += el[++last].length;
        if (last < joins.size() && joins[last].kind == JoinKind::kBlend) far -= o.share * el[last].length;
        if (last < joins.size() && joins[last].shift > 0) return 0;
      } else {
        far = e.length - cut0;
      }
      far -= o.min_line;
      StopBlend sb = from_stop ? stop_blend(e.a, e.b, r.t_start, far, bl.tol, o.run_samples)
                               : stop_blend(r.b, e.b, -e.t_end, far, bl.tol, o.run_samples);
      if (!sb.ok) return 0;
      if (pushed) res.curves.pop_back();
      const input::Move& mr = tp.moves[r.move];
      bool stop_end = false;
      size_t skip = 1;  // the element after k the curve ends in (the ones before it it takes whole)
      if (from_stop) {
        last_end = a;
        double rest = sb.reach;
        while (rest > el[k + skip].length && k + skip < last) rest -= el[k + skip++].length;
        carry = rest;
      } else {
        emit_line(sb.reach);
        sb.curve.ctrl = sb.curve.ctrl.colwise().reverse().eval();
        sb.curve.ctrl.row(0) = last_end.transpose();
        stop_end = r.last_of_move && mr.exact_stop;
      }
      res.curves.push_back({sb.curve, blend_where(m, mr, "corner blend at a stop"), std::min(m.feed, mr.feed),
                            Kind::kFeed, stop_end, true, stop_end ? mr.dwell : 0.0,
                            stop_end ? mr.pause : plan::ProgramPause{}});
      last_end = sb.curve.ctrl.row(sb.curve.n_ctrl() - 1).transpose();
      bl.d = sb.d;
      bl.deviation = sb.deviation;
      bl.peak_curvature = blend_peak_curvature(sb.d, sb.turn);
      bl.at_stop = true;
      return from_stop ? skip : 2;
    };
    if (blend_after && o.merge_runs) {
      // the longest run from here that measures within the tolerance (halved until one does)
      size_t m = run_length(k);
      bool to_stop = false;
      // smoothed where it fits (the longest prefix, shrinking by a quarter), else interpolated
      bool done = false;
      if (o.run_shape.fit_span > 0) {
        // A smoothed run spreads each vertex's turn over about a span, which moves the curve by about
        // turn * span / 8 from the vertex: a sharper vertex ends it (and is interpolated with the
        // vertices up to the next smooth one).
        const double sharp = 8 * res.blends[blend_of[k]].tol / o.run_shape.fit_span;
        size_t smooth = 0, leading_sharp = 0;
        while (smooth < m && joins[k + smooth].turn <= sharp) ++smooth;
        while (leading_sharp < m && joins[k + leading_sharp].turn > sharp) ++leading_sharp;
        // At a stop on either side the run takes that side's segment whole, its end free (README.md,
        // "Smoothed runs"); where that does not measure within the tolerance, the straight ends.
        const bool stop_before = !blend_before && (k == 0 ? o.starts_at_rest : joins[k - 1].kind == JoinKind::kStop);
        auto emit_run_at_stops = [&](size_t mm) {
          const bool fin = stop_before, fout = stop_after(k, mm);
          if (!fin && !fout) return false;
          std::optional<ChainCurve> line;
          const Vec end = last_end;
          if (fin) {
            if (line_pushed) line = res.curves.back(), res.curves.pop_back();
            last_end = a;
          }
          if (emit_run(k, mm, true, fin, fout)) return to_stop = fout, true;
          if (line) res.curves.push_back(*line);
          last_end = end;
          return false;
        };
        for (size_t mm = smooth; mm >= kMinSmoothedRun && !done; mm = mm * 3 / 4)
          if (emit_run_at_stops(mm) || emit_run(k, mm, true)) done = true, m = mm;
        if (!done && smooth < kMinSmoothedRun) m = std::min(m, std::max<size_t>(2, leading_sharp + 1));
      }
      if (!done)
        while (m >= 2 && !emit_run(k, m, false)) m /= 2;
      if (m >= 2) {
        // segments k+1 .. k+m-1 are replaced; segment k+m starts at the run's end (or is in the run)
        k += to_stop ? m : m - 1;
        continue;
      }
    }
    if (blend_after && o.from_stops && !joins[k].curved && el[k + 1].segment) {
      // the elements the blend takes whole are skipped (towards a stop: the segment after the corner)
      const size_t taken = emit_stop_blend(line_pushed);
      if (taken) {
        k += taken - 1;
        continue;
      }
    }
    if (blend_after && o.wide && !joins[k].curved && el[k + 1].segment) {
      // a corner blended on its own: the wide blend where it is better, the segment re-cut for it
      const double leg = o.share * std::min(e.length, el[k + 1].length);
      const bool offset = shift_near(joins, k);
      const double tol = res.blends[blend_of[k]].tol;
      const WideChoice w = choose_wide(joins[k].turn, tol + joins[k].shift, leg, joins[k].d, wide_cache);
      geo::BSpline curve;
      double deviation = w.deviation;
      if (w.chosen) {
        curve = wide_blend(e.b, e.t_end, el[k + 1].t_start, w.l0, w.shape);
        if (offset) deviation = deviation_from_legs(curve, programmed_leg(k), programmed_leg(k + 1), o.run_samples);
      }
      if (w.chosen && (!offset || deviation <= tol)) {
        if (line_pushed) res.curves.pop_back();
        Join& j = joins[k];
        Blend& bl = res.blends[blend_of[k]];
        j.d = 0.5 * w.l0;
        j.cut = w.l0;
        j.wide = true;
        j.wide_curve = std::move(curve);
        bl.d = j.d;
        bl.deviation = deviation;
        bl.shortened = w.shortened;
        bl.peak_curvature = w.peak_kappa;
        bl.wide = true;
        emit_line(w.l0);
      }
    }
    if (blend_after) emit_blend(k);
  }
  for (const Blend& b : res.blends) res.max_deviation = std::max(res.max_deviation, b.deviation);
  return res;
}

input::Toolpath to_toolpath(const BlendResult& r, const input::Toolpath& original) {
  input::Toolpath tp;
  tp.axes = original.axes;
  tp.notes = original.notes;
  tp.moves.reserve(r.curves.size());
  for (const ChainCurve& c : r.curves) {
    input::Move m;
    m.kind = c.kind;
    m.curve = c.curve;
    m.feed = c.feed;
    m.exact_stop = c.exact_stop;
    m.dwell = c.dwell;
    m.pause = c.pause;
    m.where = c.where;
    tp.moves.push_back(std::move(m));
  }
  return tp;
}

}  // namespace traj::corners
