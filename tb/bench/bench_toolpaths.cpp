// SPDX-License-Identifier: Apache-2.0
// Toolpath benchmark: trajcore's motion time on CAM-like toolpaths against an
// acceleration-only junction-deviation planner (the reference, as in GRBL).
//   usage: bench_toolpaths [--short] [--prepare NAME] [--only SUBSTRING]
//     --short     checks the reference against closed forms, then runs the
//                 small cases only (the CTest test bench.short.toolpaths)
//     --prepare   the step applied to each toolpath before trajcore plans it
//                 (default "none"; an unknown name lists the known ones)
//     --only      runs the cases whose name contains SUBSTRING
//     --file      instead of the built-in cases, a program of the user's (G-code,
//                 SVG or DXF, axes X Y Z; repeatable): its own F and G64 P
//                 where it has them, the limit set's feed and tolerance elsewhere
//
// The toolpaths, generated here, are feed moves only:
//   outline   a closed irregular pocket outline (a lobed curve cut by a flat
//             side), sampled as CAM does: chords within 5 um, 0.2 to 2 mm long
//   zigzag    a 3-D surface-finishing raster over z = f(x, y): rows of 40 G1
//             chords along x, short step-over chords along y between rows
//   pocket    a square spiral pocket: 90-degree corners between long legs
//             (40 mm down to 4 mm), the corners blended on their own
//   360-gon   a circle of radius 20 mm as 360 chords
//   circle    the same circle exact (one arc of four quarter pieces), for the
//             ratio of the 360-gon to the circle it stands for
//   line+arc  a line meeting a tangent arc of radius 10 mm (curvature jumps
//             from 0 to 1/10 at the junction): the speed there is printed
//
// Limit sets:
//   (i)  "fast": feed 100 mm/s, acceleration 3000 mm/s^2, jerk 60000 mm/s^3,
//        tolerance 0.05 mm, 0.5 ms ticks. A machine quoted with one
//        acceleration and one jerk: the per-axis velocity is the feed, the
//        per-axis, tangential and centripetal accelerations are all 3000 and
//        the per-axis, tangential and centripetal jerks all 60000, so that no
//        limit of trajcore is tighter than the machine's one figure (the
//        reference sees the same acceleration along the path and across it).
//   (ii) "main job": the limits of the main job (JobConfig defaults, feed 50).
//
// The reference (GrblReference below, written from the description of
// gnea/grbl planner.c): every move is a chain of straight blocks (a curve
// other than a line is cut into chords within the path tolerance, as GRBL's
// mc_arc does with its arc tolerance). A block's nominal speed is its feed,
// capped by the per-axis velocities along its unit vector u (min v_i/|u_i|);
// its acceleration is the tangential limit capped the same way by the
// per-axis accelerations (min a_i/|u_i|). The speed at a junction is
// sqrt(a_j delta sin(theta/2) / (1 - sin(theta/2))), theta the angle between
// the reversed incoming and the outgoing unit vector, delta the path
// tolerance, a_j the centripetal limit capped by the per-axis accelerations
// along the unit vector of (u_out - u_in); never above either block's nominal
// speed; 0 at an exact stop and at both ends. A backward and a forward pass
// (v^2 = v0^2 + 2 a d) and a trapezoidal profile per block give the time. It
// has no jerk limit and does not leave the vertices, so it is an optimistic
// bound for a machine with these accelerations; it runs on the toolpath as
// programmed (the preparation step is trajcore's).
//
// Columns: see print_header().
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "geometry/bspline.hpp"
#include "geometry/curve.hpp"
#include "input/toolpath.hpp"
#include "input/toolpath_file.hpp"
#include "job/job.hpp"
#include "job/toolpath_job.hpp"
#include "limit_sets.hpp"
#include "report/report.hpp"

namespace {

using namespace traj;
using Eigen::VectorXd;

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------- preparation

// A step applied to a toolpath before trajcore plans it, given the path
// tolerance (e.g. corner blending within it).
using Prepare = std::function<input::Toolpath(const input::Toolpath&, double tol)>;

struct Preparation {
  const char* name;
  const char* what;
  Prepare fn;
  bool blend = false;  // job::ToolpathOptions::blend: corner blending within blend_share of the tolerance
  bool wide = true;    // job::ToolpathOptions::wide_blends
  bool faster_stops = true;  // job::ToolpathOptions::faster_stops
  bool stop_blends = true;   // job::ToolpathOptions::stop_blends
  bool offset = true;        // job::ToolpathOptions::offset_corners
};

// The preparations --prepare can name; corner blending plugs in as one more entry.
const std::vector<Preparation>& preparations() {
  static const std::vector<Preparation> list = {
      {"none", "identity: the toolpath as programmed", [](const input::Toolpath& tp, double) { return tp; }, false},
      {"blend", "corners and curvature steps blended within 90 % of the tolerance (host/corners), the fit within the rest",
       [](const input::Toolpath& tp, double) { return tp; }, true},
      {"blend5", "as blend, with the five-point blend at every corner blended on its own (no wide blends)",
       [](const input::Toolpath& tp, double) { return tp; }, true, false},
      {"blend-all", "as blend, with every corner blended (none left a stop where that is faster)",
       [](const input::Toolpath& tp, double) { return tp; }, true, true, false},
      {"blend-at-v", "as blend, with a corner next to a stop blended at its vertex (none blended from the stop)",
       [](const input::Toolpath& tp, double) { return tp; }, true, true, true, false},
      {"blend-unshifted", "as blend, with every blend at its programmed vertex (no offset corners)",
       [](const input::Toolpath& tp, double) { return tp; }, true, true, true, true, false},
  };
  return list;
}

// ---------------------------------------------------------------- toolpaths

input::Move feed_move(geo::BSpline curve, double feed, const std::string& where) {
  input::Move m;
  m.kind = input::Move::Kind::kFeed;
  m.curve = std::move(curve);
  m.feed = feed;
  m.where = where;
  return m;
}

input::Toolpath polyline_toolpath(const std::vector<VectorXd>& pts, double feed, const std::string& name) {
  input::Toolpath tp;
  tp.axes = static_cast<int>(pts.front().size());
  for (size_t i = 1; i < pts.size(); ++i)
    tp.moves.push_back(feed_move(geo::make_line(pts[i - 1], pts[i]), feed, name + ": G1 " + std::to_string(i)));
  return tp;
}

double point_segment_distance(const VectorXd& p, const VectorXd& a, const VectorXd& b) {
  const VectorXd ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

// CAM-like chords of a dense polyline: each chord as long as it may be while
// every dense point it spans stays within `sag` of it and it is at most
// `max_len` long (the dense step sets the shortest chord).
std::vector<VectorXd> cam_chords(const std::vector<VectorXd>& dense, double sag, double max_len) {
  std::vector<VectorXd> out{dense.front()};
  size_t i = 0;
  while (i + 1 < dense.size()) {
    size_t best = i + 1;
    for (size_t j = i + 2; j < dense.size(); ++j) {
      if ((dense[j] - dense[i]).norm() > max_len) break;
      bool within = true;
      for (size_t k = i + 1; k < j && within; ++k) within = point_segment_distance(dense[k], dense[i], dense[j]) <= sag;
      if (!within) break;
      best = j;
    }
    out.push_back(dense[best]);
    i = best;
  }
  return out;
}

// (a) A closed pocket outline: a lobed curve r(phi) cut by the flat side x = -11.
input::Toolpath outline_toolpath(double feed) {
  std::vector<VectorXd> dense;
  const int n = 6000;
  for (int k = 0; k <= n; ++k) {
    const double phi = 2 * kPi * k / n;
    const double r = 15 * (1 + 0.15 * std::sin(3 * phi) + 0.07 * std::cos(5 * phi + 0.4));
    const double x = std::max(r * std::cos(phi), -11.0), y = r * std::sin(phi);
    if (!dense.empty() && std::hypot(x - dense.back()[0], y - dense.back()[1]) < 0.2) continue;  // shortest chord 0.2 mm
    dense.push_back(VectorXd::Zero(2));
    dense.back() << x, y;
  }
  dense.back() = dense.front();  // closed exactly
  return polyline_toolpath(cam_chords(dense, 0.005, 2.0), feed, "outline");
}

// (b) Surface finishing: rows along x (alternating), step-over along y.
input::Toolpath zigzag_toolpath(double feed) {
  auto z = [](double x, double y) { return 2 * std::sin(x / 6) * std::cos(y / 5) + 0.03 * x * y / 10; };
  const int rows = 8, per_row = 40;
  const double dx = 0.75, dy = 1.0;
  std::vector<VectorXd> pts;
  auto add = [&](double x, double y) {
    VectorXd p(3);
    p << x, y, z(x, y);
    pts.push_back(p);
  };
  for (int r = 0; r < rows; ++r) {
    const double y = r * dy;
    for (int k = 0; k <= per_row; ++k) add((r % 2 == 0 ? k : per_row - k) * dx, y);
    if (r + 1 < rows) {  // step-over: two short chords on the surface
      const double x = (r % 2 == 0 ? per_row : 0) * dx;
      add(x, y + dy / 2);
    }
  }
  return polyline_toolpath(pts, feed, "zigzag");
}

// (c) A regular n-gon inscribed in the circle of radius r about the origin.
input::Toolpath polygon_toolpath(int n, double r, double feed) {
  std::vector<VectorXd> pts;
  for (int k = 0; k <= n; ++k) {
    VectorXd p(2);
    const double a = 2 * kPi * (k % n) / n;
    p << r * std::cos(a), r * std::sin(a);
    pts.push_back(p);
  }
  return polyline_toolpath(pts, feed, std::to_string(n) + "-gon");
}

// (d) A square spiral pocket: 90-degree corners between long legs (40 mm down to 4 mm, 2 mm step).
input::Toolpath pocket_toolpath(double feed) {
  std::vector<VectorXd> pts;
  double x = 0, y = 0, len = 40;
  const double dx[4] = {1, 0, -1, 0}, dy[4] = {0, 1, 0, -1};
  auto add = [&]() {
    VectorXd p(2);
    p << x, y;
    pts.push_back(p);
  };
  add();
  for (int k = 0; len >= 4; ++k) {
    x += len * dx[k % 4];
    y += len * dy[k % 4];
    add();
    if (k % 2 == 1) len -= 2;
  }
  return polyline_toolpath(pts, feed, "pocket");
}

input::Toolpath circle_toolpath(double r, double feed) {
  input::Toolpath tp;
  tp.axes = 2;
  tp.moves.push_back(feed_move(geo::make_arc(Eigen::Vector2d(0, 0), r, 0, 2 * kPi), feed, "circle: G2"));
  return tp;
}

// (d) A 20 mm line along +x, then a tangent arc of radius 10 turning left.
input::Toolpath line_arc_toolpath(double feed) {
  input::Toolpath tp;
  tp.axes = 2;
  VectorXd a(2), b(2);
  a << 0, 0;
  b << 20, 0;
  tp.moves.push_back(feed_move(geo::make_line(a, b), feed, "line+arc: G1"));
  tp.moves.push_back(feed_move(geo::make_arc(Eigen::Vector2d(20, 10), 10, -kPi / 2, 0), feed, "line+arc: G3"));
  return tp;
}

// ---------------------------------------------------------------- limit sets

struct LimitSet {
  const char* name;
  job::JobConfig cfg;
};

// ---------------------------------------------------------------- the reference

// Vertices of a curve: a degree-1 curve's control points; any other curve cut
// into chords within `tol` (bisection of each knot span).
void append_chords(const geo::BSpline& spline, double tol, std::vector<VectorXd>& out) {
  const geo::Curve c(spline);
  const geo::BSpline& s = c.spline();
  if (s.degree == 1 && !s.rational()) {
    for (int i = 1; i < s.n_ctrl(); ++i) out.push_back(s.ctrl.row(i).transpose());
    return;
  }
  std::function<void(double, double, int)> cut = [&](double u0, double u1, int depth) {
    const VectorXd p0 = c.point(u0), p1 = c.point(u1);
    double dev = 0;
    for (double f : {0.25, 0.5, 0.75}) dev = std::max(dev, point_segment_distance(c.point(u0 + f * (u1 - u0)), p0, p1));
    if (dev > tol && depth < 30) {
      const double um = 0.5 * (u0 + u1);
      cut(u0, um, depth + 1);
      cut(um, u1, depth + 1);
    } else {
      out.push_back(p1);
    }
  };
  for (const auto& piece : c.bezier()) cut(piece.u0, piece.u1, 0);
}

struct RefBlock {
  double len = 0, v_nom = 0, acc = 0;
  VectorXd u;
};

struct RefResult {
  double time = 0;
  std::vector<double> v_vertex;        // speed at every vertex (block ends), size blocks + 1
  std::vector<size_t> move_end_vertex;  // vertex index at the end of each move
};

// Largest value along unit vector u that keeps every axis within its limit (GRBL's limit_value_by_axis_maximum).
double along(const double* axis_limit, const VectorXd& u) {
  double v = std::numeric_limits<double>::infinity();
  for (int i = 0; i < u.size(); ++i)
    if (std::abs(u[i]) > 1e-15) v = std::min(v, axis_limit[i] / std::abs(u[i]));
  return v;
}

// tol: the junction's path tolerance. jerk > 0: the junction speed is also capped by a jerk-limited
// turn within it.
double junction_speed_sq(const VectorXd& u_in, const VectorXd& u_out, const plan::Limits& L, double tol,
                         double jerk = 0) {
  const double cos_theta = -u_in.dot(u_out);
  if (cos_theta > 0.999999) return 0;                                         // reversal
  if (cos_theta < -0.999999) return std::numeric_limits<double>::infinity();  // straight on
  const VectorXd ju = (u_out - u_in).normalized();
  const double a = std::min(L.a_cen, along(L.a_axis, ju));
  const double sin_half = std::sqrt(0.5 * (1 - cos_theta));
  const double v2 = a * tol * sin_half / (1 - sin_half);
  if (!(jerk > 0)) return v2;
  // The velocity changes by dw = |u_out - u_in| v across the corner. Done as one bang-bang jerk
  // pulse of jerk J along u_out - u_in (duration 2 sqrt(dw / J), the speed along the bisector
  // unchanged), the path leaves the corner by dw^1.5 / (6 sqrt J) at its middle (integrate the
  // velocity change w(t) = J t^2 / 2 over the first half: dw/2 (T/2) / 3). Within the tolerance:
  // dw <= (6 tol sqrt J)^(2/3).
  const double dw = std::pow(6 * tol * std::sqrt(jerk), 2.0 / 3.0);
  const double vj = dw / (u_out - u_in).norm();
  return std::min(v2, vj * vj);
}

// Time over a block from v0 to v1 under nominal speed vn and acceleration a
// (trapezoid, or triangle where vn is not reached).
double trapezoid_time(double len, double v0, double v1, double vn, double a) {
  const double d_acc = (vn * vn - v0 * v0) / (2 * a), d_dec = (vn * vn - v1 * v1) / (2 * a);
  if (d_acc + d_dec <= len) return (vn - v0) / a + (vn - v1) / a + (len - d_acc - d_dec) / vn;
  const double vp = std::sqrt(std::max(0.0, (2 * a * len + v0 * v0 + v1 * v1) / 2));
  return (vp - v0) / a + (vp - v1) / a;
}

// jerk > 0: every junction also within a jerk-limited turn (junction_speed_sq); still no jerk on
// the blocks' speed changes. A move's own tolerance (G64 P) replaces the limits' where it has one,
// and a junction takes the smaller of its two moves' (as trajcore's blends); a move's dwell (G4)
// adds its seconds at rest.
RefResult grbl_reference(const input::Toolpath& tp, const job::JobConfig& cfg, double jerk = 0) {
  const plan::Limits& L = cfg.limits;
  std::vector<RefBlock> blocks;
  std::vector<double> vmax_sq{0};  // allowed speed^2 at each vertex; the start is a stop
  RefResult res;
  VectorXd prev = tp.moves.front().curve.ctrl.row(0).transpose();
  double rapid = L.v_axis[0];
  for (int a = 1; a < tp.axes && a < plan::kMaxAxes; ++a) rapid = std::min(rapid, L.v_axis[a]);
  double tol_before = L.tol;  // the tolerance of the move before the current one
  for (const input::Move& m : tp.moves) {
    const double speed = m.kind == input::Move::Kind::kRapid ? rapid : (m.feed > 0 ? m.feed : L.feed);
    const double tol = m.tolerance < 0 ? L.tol : m.tolerance;
    std::vector<VectorXd> pts;
    append_chords(m.curve, tol, pts);
    bool first_block = true;
    for (const VectorXd& p : pts) {
      RefBlock b;
      b.len = (p - prev).norm();
      if (b.len <= 0) continue;
      b.u = (p - prev) / b.len;
      b.v_nom = std::min(speed, along(L.v_axis, b.u));
      b.acc = std::min(L.a_tan, along(L.a_axis, b.u));
      if (!blocks.empty()) {
        const RefBlock& in = blocks.back();
        const double cap = std::min(in.v_nom, b.v_nom);
        const double junction_tol = first_block ? std::min(tol_before, tol) : tol;
        vmax_sq.back() = std::min({vmax_sq.back(), junction_speed_sq(in.u, b.u, L, junction_tol, jerk), cap * cap});
      }
      first_block = false;
      blocks.push_back(b);
      vmax_sq.push_back(std::numeric_limits<double>::infinity());
      prev = p;
    }
    if (m.exact_stop) vmax_sq.back() = 0;
    res.move_end_vertex.push_back(blocks.size());
    res.time += m.dwell;
    tol_before = tol;
  }
  vmax_sq.back() = 0;  // the end is a stop
  const size_t n = blocks.size();
  std::vector<double> v2 = vmax_sq;
  for (size_t i = n; i-- > 0;) v2[i] = std::min(v2[i], v2[i + 1] + 2 * blocks[i].acc * blocks[i].len);
  for (size_t i = 0; i < n; ++i) v2[i + 1] = std::min(v2[i + 1], v2[i] + 2 * blocks[i].acc * blocks[i].len);
  for (size_t i = 0; i < n; ++i)
    res.time += trapezoid_time(blocks[i].len, std::sqrt(v2[i]), std::sqrt(v2[i + 1]), blocks[i].v_nom, blocks[i].acc);
  for (double x : v2) res.v_vertex.push_back(std::sqrt(x));
  return res;
}

// ---------------------------------------------------------------- trajcore

// Junctions where the tangent turns by more than the planner's corner angle.
int count_corners(const input::Toolpath& tp, double corner_tol) {
  int n = 0;
  for (size_t i = 1; i < tp.moves.size(); ++i) {
    const auto& a = tp.moves[i - 1].curve.ctrl;
    const auto& b = tp.moves[i].curve.ctrl;
    const VectorXd t_in = (a.row(a.rows() - 1) - a.row(a.rows() - 2)).transpose().normalized();
    const VectorXd t_out = (b.row(1) - b.row(0)).transpose().normalized();
    if (std::acos(std::clamp(t_in.dot(t_out), -1.0, 1.0)) > corner_tol) ++n;
  }
  return n;
}

// Nearest-chord search over a polyline: its chords cut into pieces no longer than a cell of a grid
// over the first two axes, each piece filed in the cells its ends fall in (a piece spans at most two
// cells per axis, so the cells of both ends and the ones between them: the bounding box of the
// cells). A query searches rings of cells around the point's cell until a ring lies farther than
// the nearest piece found (the distance in x-y bounds the whole distance from below): exact, and
// programs of thousands of moves against 10^5 samples take well under a second.
class NearestChord {
 public:
  NearestChord(const std::vector<std::array<double, 3>>& poly, int dim) : dim_(dim) {
    double lo[2] = {poly[0][0], poly[0][1]}, hi[2] = {lo[0], lo[1]}, length = 0;
    for (size_t i = 0; i < poly.size(); ++i) {
      for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], poly[i][k]), hi[k] = std::max(hi[k], poly[i][k]);
      if (i > 0) length += distance(poly[i - 1], poly[i]);
    }
    const double n = static_cast<double>(std::max<size_t>(poly.size(), 2) - 1);
    // about one piece per cell over the bounding box, and at most about 4 n pieces in all
    cell_ = std::max({std::sqrt((hi[0] - lo[0]) * (hi[1] - lo[1]) / n), length / (4 * n), 1e-9});
    origin_[0] = lo[0], origin_[1] = lo[1];
    rings_ = 2 + static_cast<long>(std::max(hi[0] - lo[0], hi[1] - lo[1]) / cell_);
    for (size_t i = 1; i < poly.size(); ++i) {
      const int parts = std::max(1, static_cast<int>(std::ceil(distance(poly[i - 1], poly[i]) / cell_)));
      for (int p = 0; p < parts; ++p) {
        Piece piece{lerp(poly[i - 1], poly[i], static_cast<double>(p) / parts),
                    lerp(poly[i - 1], poly[i], static_cast<double>(p + 1) / parts)};
        const long ax = cell_of(piece.a[0], 0), ay = cell_of(piece.a[1], 1);
        const long bx = cell_of(piece.b[0], 0), by = cell_of(piece.b[1], 1);
        for (long cx = std::min(ax, bx); cx <= std::max(ax, bx); ++cx)
          for (long cy = std::min(ay, by); cy <= std::max(ay, by); ++cy) cells_[key(cx, cy)].push_back(pieces_.size());
        pieces_.push_back(piece);
      }
    }
  }

  double distance_to(const std::array<double, 3>& p) const {
    const long px = cell_of(p[0], 0), py = cell_of(p[1], 1);
    double best2 = std::numeric_limits<double>::infinity();
    for (long r = 0; r <= rings_; ++r) {
      for (long cx = px - r; cx <= px + r; ++cx)
        for (long cy = py - r; cy <= py + r; ++cy) {
          if (std::max(std::abs(cx - px), std::abs(cy - py)) != r) continue;  // the ring only
          const auto it = cells_.find(key(cx, cy));
          if (it == cells_.end()) continue;
          for (size_t i : it->second) best2 = std::min(best2, segment_distance2(p, pieces_[i]));
        }
      // every cell beyond ring r is at least r cells from p in x or y
      if (best2 <= (r * cell_) * (r * cell_)) break;
    }
    if (best2 == std::numeric_limits<double>::infinity())  // p farther out than the rings reach
      for (const Piece& piece : pieces_) best2 = std::min(best2, segment_distance2(p, piece));
    return std::sqrt(best2);
  }

 private:
  struct Piece {
    std::array<double, 3> a, b;
  };
  double distance(const std::array<double, 3>& a, const std::array<double, 3>& b) const {
    double d2 = 0;
    for (int k = 0; k < dim_; ++k) d2 += (b[k] - a[k]) * (b[k] - a[k]);
    return std::sqrt(d2);
  }
  std::array<double, 3> lerp(const std::array<double, 3>& a, const std::array<double, 3>& b, double t) const {
    std::array<double, 3> r{0, 0, 0};
    for (int k = 0; k < dim_; ++k) r[k] = a[k] + t * (b[k] - a[k]);
    return r;
  }
  double segment_distance2(const std::array<double, 3>& p, const Piece& s) const {
    double ab2 = 0, t = 0;
    for (int k = 0; k < dim_; ++k) ab2 += (s.b[k] - s.a[k]) * (s.b[k] - s.a[k]), t += (p[k] - s.a[k]) * (s.b[k] - s.a[k]);
    t = ab2 > 0 ? std::clamp(t / ab2, 0.0, 1.0) : 0.0;
    double d2 = 0;
    for (int k = 0; k < dim_; ++k) d2 += (s.a[k] + t * (s.b[k] - s.a[k]) - p[k]) * (s.a[k] + t * (s.b[k] - s.a[k]) - p[k]);
    return d2;
  }
  long cell_of(double x, int axis) const { return static_cast<long>(std::floor((x - origin_[axis]) / cell_)); }
  static int64_t key(long cx, long cy) { return (static_cast<int64_t>(cx) << 32) ^ (static_cast<int64_t>(cy) & 0xffffffff); }

  int dim_;
  double cell_ = 1, origin_[2] = {0, 0};
  long rings_ = 0;
  std::vector<Piece> pieces_;
  std::unordered_map<int64_t, std::vector<size_t>> cells_;
};

// Largest distance of the output samples to the programmed toolpath (its
// curves cut into chords within 1e-4 of the tolerance).
double deviation_from(const input::Toolpath& programmed, const std::vector<std::array<double, 3>>& x, int dim,
                      double tol) {
  std::vector<VectorXd> chords{programmed.moves.front().curve.ctrl.row(0).transpose()};
  for (const auto& m : programmed.moves) append_chords(m.curve, 1e-4 * (m.tolerance < 0 ? tol : m.tolerance), chords);
  std::vector<std::array<double, 3>> poly(chords.size(), {0, 0, 0});
  for (size_t i = 0; i < chords.size(); ++i)
    for (int a = 0; a < dim && a < 3; ++a) poly[i][a] = chords[i][a];
  const NearestChord nearest(poly, std::min(dim, 3));
  double worst = 0;
  for (const auto& p : x) worst = std::max(worst, nearest.distance_to(p));
  return worst;
}

// --dump PREFIX: every tick's t, s, v, a_t, curve (with its kind), the speed bound v_lim there, the
// local tangential acceleration A(s) and the curvature, to PREFIX_<case>_<limits>.txt.
std::string g_dump, g_case;

void dump_ticks(const std::string& prefix, const job::JobResult& r, const job::ToolpathPlan& tpp) {
  FILE* f = std::fopen((prefix + "_" + g_case + ".txt").c_str(), "w");
  if (!f) return;
  const plan::Limits& L = tpp.cfg.limits;
  const plan::PlanOptions& o = tpp.cfg.plan;
  const int dim = tpp.path.dim();
  double jmin = L.j_axis[0];
  for (int a = 1; a < dim; ++a) jmin = std::min(jmin, L.j_axis[a]);
  const double A_t = o.tan_a_share * L.a_tan, J_t = o.tan_j_share * std::min(L.j_tan, jmin);
  for (const auto& tk : r.ticks) {
    const std::string& w = tpp.path.entry(tk.curve).where;
    const char* kind = w.find("run of") != std::string::npos ? "run" : w.find("blend") != std::string::npos ? "blend" : "move";
    const plan::Frame fr = plan::frame_at(tpp.path, tk.curve, tk.u, tk.s);
    double A_loc = 0;
    const double vlim = plan::speed_limit(fr, L, o, A_t, J_t, dim, &A_loc);
    std::fprintf(f, "%.6f %.6f %.4f %.1f %zu %s %.3f %.1f %.4f\n", tk.t, tk.s, tk.v, tk.a, tk.curve, kind, vlim, A_loc,
                 fr.kappa);
  }
  std::fclose(f);
}

struct TrajResult {
  bool ok = false;
  std::string error;
  double motion = 0, host = 0, dev = 0, dev_prog = 0, worst_out = 0;
  std::string worst_what;
  double v_at_point = -1;  // planned speed at the tick nearest the probe point
};

TrajResult run_trajcore(const input::Toolpath& programmed, const input::Toolpath& prepared, const job::JobConfig& cfg,
                        const job::ToolpathOptions& opts, const VectorXd* probe) {
  TrajResult t;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const job::ToolpathPlan tpp = job::toolpath_plan(prepared, cfg, opts);
    const job::JobResult r = job::run_job(tpp.path, tpp.cfg);
    t.host = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const report::Samples s = report::predicted_samples(r);
    const report::Report rep = report::make_report(tpp.path, tpp.cfg, r, s);
    t.motion = rep.motion_time;
    t.dev = rep.max_deviation;
    t.worst_out = rep.worst_out;
    t.worst_what = rep.worst_out_what;
    const double lsb = std::ldexp(1.0, -r.header.frac_bits);
    std::vector<std::array<double, 3>> x(s.v.size());
    for (size_t k = 0; k < x.size(); ++k)
      for (int a = 0; a < 3; ++a) x[k][a] = static_cast<double>(s.v[k][a]) * lsb;
    t.dev_prog = deviation_from(programmed, x, tpp.path.dim(), cfg.limits.tol);
    if (!g_dump.empty()) dump_ticks(g_dump, r, tpp);
    if (probe) {
      double best = std::numeric_limits<double>::infinity();
      for (const auto& tk : r.ticks) {
        double d2 = 0;
        for (int a = 0; a < probe->size(); ++a) d2 += (tk.x[a] - (*probe)[a]) * (tk.x[a] - (*probe)[a]);
        if (d2 < best) best = d2, t.v_at_point = tk.v;
      }
    }
    t.ok = true;
  } catch (const std::exception& e) {
    t.error = e.what();
    t.host = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return t;
}

// ---------------------------------------------------------------- the table

void print_header(const Preparation& prep) {
  std::printf(
      "trajcore against an acceleration-only junction-deviation planner (GRBL-like reference, no jerk limit)\n"
      "preparation before trajcore plans: %s (%s)\n"
      "limits (i): feed = v_axis 100, a 3000, j 60000 (per axis, tangential, centripetal), tol 0.05 mm, 0.5 ms\n"
      "limits (ii): the main job's (feed 50, v_axis 200, a_axis 2000, j_axis 50000, a_tan 1000, j_tan 20000,\n"
      "  a_cen 1000, j_cen 50000, tol 0.001 mm, 1 ms ticks)\n"
      "columns: moves = feed moves after preparation; corners = junctions whose tangent turns, before the\n"
      "  job's blending (the job blends them or stops where that is faster; unblended, trajcore stops at\n"
      "  each); traj_s = trajcore's motion time (output samples); ref_s = the reference's time on the\n"
      "  programmed toolpath (same feed, accelerations, delta = path tolerance); ratio = traj_s / ref_s;\n"
      "  refj_s = the reference with every junction speed also capped by a bang-bang jerk turn within the\n"
      "  tolerance (jerk min(j_cen, j_axis); still no jerk on the speed changes), ratio_j = traj_s / refj_s;\n"
      "  host_s = toolpath_plan + run_job wall time (plan, ticks, fit, compile; until the error if it\n"
      "  fails); dev_mm = report.max_deviation (output to the planned path); prog_dev_mm = output to the\n"
      "  programmed toolpath (curves as chords within 1e-4 tol); worst = largest output peak / limit\n",
      prep.name, prep.what);
  std::printf("%-10s %-5s %6s %7s %9s %9s %7s %9s %7s %8s %11s %11s %s\n", "case", "lims", "moves", "corners", "traj_s",
              "ref_s", "ratio", "refj_s", "ratio_j", "host_s", "dev_mm", "prog_dev_mm", "worst (what)");
}

struct Row {
  TrajResult traj;
  RefResult ref;
  double ref_jerk_time = 0;  // the reference with jerk-limited junction turns (junction_speed_sq)
};

// The jerk that bounds a turn across the path: the centripetal limit and every axis's.
double turn_jerk(const job::JobConfig& cfg, int axes) {
  double j = cfg.limits.j_cen;
  for (int a = 0; a < axes && a < plan::kMaxAxes; ++a) j = std::min(j, cfg.limits.j_axis[a]);
  return j;
}

Row run_case(const char* name, const LimitSet& ls, const input::Toolpath& programmed, const Preparation& prep,
             const VectorXd* probe = nullptr) {
  Row row;
  g_case = std::string(name) + "_" + ls.name;
  row.ref = grbl_reference(programmed, ls.cfg);
  row.ref_jerk_time = grbl_reference(programmed, ls.cfg, turn_jerk(ls.cfg, programmed.axes)).time;
  input::Toolpath prepared = programmed;
  try {
    prepared = prep.fn(programmed, ls.cfg.limits.tol);
    job::ToolpathOptions opts;
    opts.blend = prep.blend;
    opts.wide_blends = prep.wide;
    opts.faster_stops = prep.faster_stops;
    opts.stop_blends = prep.stop_blends;
    opts.offset_corners = prep.offset;
    row.traj = run_trajcore(programmed, prepared, ls.cfg, opts, probe);
  } catch (const std::exception& e) {
    row.traj.error = std::string("preparation: ") + e.what();
  }
  const int corners = count_corners(prepared, ls.cfg.plan.corner_tol);
  if (row.traj.ok)
    std::printf("%-10s %-5s %6zu %7d %9.3f %9.3f %7.2f %9.3f %7.2f %8.3f %11.3g %11.3g %.3f (%s)\n", name, ls.name,
                prepared.moves.size(), corners, row.traj.motion, row.ref.time, row.traj.motion / row.ref.time,
                row.ref_jerk_time, row.traj.motion / row.ref_jerk_time, row.traj.host, row.traj.dev, row.traj.dev_prog, row.traj.worst_out, row.traj.worst_what.c_str());
  else
    std::printf("%-10s %-5s %6zu %7d %9s %9.3f %7s %9.3f %7s %8.3f   trajcore failed: %s\n", name, ls.name,
                prepared.moves.size(), corners, "-", row.ref.time, "-", row.ref_jerk_time, "-", row.traj.host,
                row.traj.error.c_str());
  std::fflush(stdout);
  return row;
}

bool selected(const char* name, const std::string& only) { return only.empty() || std::strstr(name, only.c_str()); }

// A program as a user has it (G-code, SVG, DXF; axes X Y Z): its own feeds (F) and tolerances (G64 P)
// where it has them, the set's elsewhere; rapids at the set's slowest axis velocity, stopped at their
// ends in both planners. The case is named by the file. False if trajcore failed on one.
bool run_files(const std::vector<LimitSet>& sets, const Preparation& prep, const std::vector<std::string>& files) {
  print_header(prep);
  bool ok = true;
  for (const std::string& file : files) {
    const input::Toolpath tp = input::read_toolpath(file, input::file_kind(file));
    const std::string name = file.substr(file.find_last_of('/') + 1);
    std::printf("%s: %zu moves\n", file.c_str(), tp.moves.size());
    for (const LimitSet& ls : sets) ok &= run_case(name.c_str(), ls, tp, prep).traj.ok;
  }
  return ok;
}

void run_all(const std::vector<LimitSet>& sets, const Preparation& prep, bool small, const std::string& only) {
  print_header(prep);
  const int ngon = small ? 36 : 360;
  const std::string ngon_name = std::to_string(ngon) + "-gon";
  for (const LimitSet& ls : sets) {
    const double feed = ls.cfg.limits.feed;
    if (!small && selected("outline", only)) run_case("outline", ls, outline_toolpath(feed), prep);
    if (!small && selected("zigzag", only)) run_case("zigzag", ls, zigzag_toolpath(feed), prep);
    if (!small && selected("pocket", only)) run_case("pocket", ls, pocket_toolpath(feed), prep);
    if (selected(ngon_name.c_str(), only) || selected("circle", only)) {
      const Row poly = run_case(ngon_name.c_str(), ls, polygon_toolpath(ngon, 20, feed), prep);
      const Row circ = run_case("circle", ls, circle_toolpath(20, feed), prep);
      if (poly.traj.ok && circ.traj.ok)
        std::printf("    %s / exact circle R20: trajcore %.3f s / %.3f s = %.2f; reference %.3f s / %.3f s = %.2f\n",
                    ngon_name.c_str(), poly.traj.motion, circ.traj.motion, poly.traj.motion / circ.traj.motion,
                    poly.ref.time, circ.ref.time, poly.ref.time / circ.ref.time);
    }
    if (selected("line+arc", only)) {
      const input::Toolpath tp = line_arc_toolpath(feed);
      VectorXd junction(2);
      junction << 20, 0;
      const Row r = run_case("line+arc", ls, tp, prep, &junction);
      const double v_ref = r.ref.v_vertex[r.ref.move_end_vertex.front()];
      const double v_cen = std::sqrt(ls.cfg.limits.a_cen * 10);
      if (r.traj.ok)
        std::printf("    speed at the line/arc junction: trajcore %.2f mm/s, reference %.2f mm/s "
                    "(feed %g, sqrt(a_cen R) %.1f)\n",
                    r.traj.v_at_point, v_ref, feed, v_cen);
    }
  }
}

// ---------------------------------------------------------------- reference checks (closed forms)

bool near(const char* what, double got, double want, double rel = 1e-9) {
  const bool ok = std::abs(got - want) <= rel * std::max(1.0, std::abs(want));
  std::printf("  %-58s %12.6f  closed form %12.6f  %s\n", what, got, want, ok ? "ok" : "FAILED");
  return ok;
}

bool check_reference() {
  std::printf("reference planner against closed forms:\n");
  job::JobConfig cfg;
  auto& L = cfg.limits;
  for (int a = 0; a < plan::kMaxAxes; ++a) L.v_axis[a] = 1000, L.a_axis[a] = 1000;
  L.a_tan = L.a_cen = 1e9;  // the per-axis accelerations decide
  L.tol = 0.05;
  const double v = 50, a = 1000;
  auto line = [&](std::vector<std::vector<double>> pts) {
    std::vector<VectorXd> p;
    for (const auto& q : pts) p.push_back(Eigen::Map<const VectorXd>(q.data(), static_cast<long>(q.size())));
    return polyline_toolpath(p, v, "check");
  };
  bool ok = true;
  // A straight line that reaches the feed: L/v + v/a.
  ok &= near("line 100 mm at 50 mm/s, a 1000: time", grbl_reference(line({{0, 0}, {100, 0}}), cfg).time,
             100 / v + v / a);
  // Too short to reach the feed: a triangle, 2 sqrt(L/a).
  ok &= near("line 1 mm (triangle): time", grbl_reference(line({{0, 0}, {1, 0}}), cfg).time, 2 * std::sqrt(1 / a));
  // A diagonal line: acceleration a / cos 45 (per-axis limit along the unit vector).
  const double a_diag = a * std::sqrt(2.0);
  ok &= near("diagonal 100 mm: time", grbl_reference(line({{0, 0}, {100 / std::sqrt(2.0), 100 / std::sqrt(2.0)}}), cfg).time,
             100 / v + v / a_diag);
  // Split into collinear pieces: no slow-down at the joins.
  ok &= near("line 100 mm in 7 collinear pieces: time",
             grbl_reference(line({{0, 0}, {10, 0}, {25, 0}, {40, 0}, {41, 0}, {60, 0}, {80, 0}, {100, 0}}), cfg).time,
             100 / v + v / a);
  // A right angle: junction acceleration along (u_out - u_in)/|..| = (-1, 1)/sqrt 2, so a sqrt 2;
  // theta = 90 deg, v_j^2 = a_j delta sin45 / (1 - sin45); legs long enough to reach v_j and v.
  const double s45 = std::sqrt(0.5), vj = std::sqrt(a_diag * L.tol * s45 / (1 - s45));
  const RefResult corner = grbl_reference(line({{0, 0}, {50, 0}, {50, 50}}), cfg);
  ok &= near("right-angle corner: junction speed", corner.v_vertex[1], vj);
  const double leg = (v - vj) / a + (50 - (v * v - vj * vj) / (2 * a) - v * v / (2 * a)) / v + v / a;
  ok &= near("right-angle corner: time", corner.time, 2 * leg);
  // A program's own tolerance (G64 P) on both moves replaces the limits'; on one of them, the
  // junction takes the smaller.
  input::Toolpath own_tol = line({{0, 0}, {50, 0}, {50, 50}});
  for (auto& m : own_tol.moves) m.tolerance = 4 * L.tol;
  ok &= near("right-angle corner, G64 P = 4 delta on both moves: junction speed",
             grbl_reference(own_tol, cfg).v_vertex[1], 2 * vj);
  own_tol.moves[0].tolerance = -1;
  ok &= near("right-angle corner, G64 P = 4 delta on the second move only: junction speed",
             grbl_reference(own_tol, cfg).v_vertex[1], vj);
  // A dwell (G4) adds its seconds at rest.
  input::Toolpath dwell = line({{0, 0}, {100, 0}, {200, 0}});
  dwell.moves[0].dwell = 0.5;
  dwell.moves[0].exact_stop = true;
  ok &= near("two lines of 100 mm, a stop and a dwell of 0.5 s between them: time", grbl_reference(dwell, cfg).time,
             2 * (100 / v + v / a) + 0.5);
  // A feed below the junction speed caps it.
  L.tol = 10;
  ok &= near("right-angle corner, large delta: junction speed = feed",
             grbl_reference(line({{0, 0}, {50, 0}, {50, 50}}), cfg).v_vertex[1], v);
  // A reversal stops.
  ok &= near("reversal: junction speed", grbl_reference(line({{0, 0}, {50, 0}, {20, 0}}), cfg).v_vertex[1], 0);
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  bool small = false;
  std::string prep_name = "none", only;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--short") small = true;
    else if (a == "--prepare" && i + 1 < argc) prep_name = argv[++i];
    else if (a == "--only" && i + 1 < argc) only = argv[++i];
    else if (a == "--dump" && i + 1 < argc) g_dump = argv[++i];
    else if (a == "--file" && i + 1 < argc) files.push_back(argv[++i]);
    else {
      std::fprintf(stderr, "usage: bench_toolpaths [--short] [--prepare NAME] [--only SUBSTRING] [--file PROGRAM]...\n");
      return 2;
    }
  }
  const Preparation* prep = nullptr;
  for (const auto& p : preparations())
    if (prep_name == p.name) prep = &p;
  if (!prep) {
    std::fprintf(stderr, "bench_toolpaths: unknown preparation '%s'; known:", prep_name.c_str());
    for (const auto& p : preparations()) std::fprintf(stderr, " %s (%s)", p.name, p.what);
    std::fprintf(stderr, "\n");
    return 2;
  }
  if (small && !check_reference()) {
    std::fprintf(stderr, "bench_toolpaths: the reference planner disagrees with a closed form\n");
    return 1;
  }
  const std::vector<LimitSet> sets = {{"i", bench::fast_machine()}, {"ii", bench::main_job()}};
  if (files.empty()) {
    run_all(sets, *prep, small, only);
    return 0;
  }
  try {
    return run_files(sets, *prep, files) ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_toolpaths: %s\n", e.what());
    return 1;
  }
}
