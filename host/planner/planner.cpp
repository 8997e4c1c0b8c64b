// SPDX-License-Identifier: Apache-2.0
#include "planner/planner.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "util/format.hpp"
#include "util/tick_period.hpp"

namespace traj::plan {
namespace {

using util::num;

void check_positive(double v, const std::string& name) {
  if (!std::isfinite(v) || !(v > 0)) throw PlanError("limit " + name + " = " + num(v) + " must be positive and finite");
}

}  // namespace

void Limits::validate() const {
  if (axis_names.size() != static_cast<size_t>(kMaxAxes))
    throw PlanError("axis names '" + axis_names + "': " + std::to_string(kMaxAxes) + " letters expected");
  check_positive(feed, "feed");
  for (int a = 0; a < kMaxAxes; ++a) {
    const std::string ax = axis(a);
    check_positive(v_axis[a], "v_axis." + ax);
    check_positive(a_axis[a], "a_axis." + ax);
    check_positive(j_axis[a], "j_axis." + ax);
  }
  check_positive(a_tan, "a_tan");
  check_positive(j_tan, "j_tan");
  check_positive(a_cen, "a_cen");
  check_positive(j_cen, "j_cen");
  check_positive(tol, "tol");
}

PathCurve::PathCurve(const geo::BSpline& spline, const std::string& w) : where(w) {
  curve = std::make_unique<geo::Curve>(spline, where);
  if (curve->dim() < 1 || curve->dim() > kMaxAxes)
    throw PlanError(where + ": " + std::to_string(curve->dim()) + " axes; the planner drives 1.." +
                    std::to_string(kMaxAxes));
  al = std::make_unique<geo::ArcLength>(*curve, 1e-12);
  if (!(al->total() > 1e-9)) throw PlanError(where + ": zero-length curve (arc length " + num(al->total()) + ")");
  table = std::make_unique<ArcTable>(*curve, *al);
  cusp_start_ = end_is_cusp(true);
  cusp_end_ = end_is_cusp(false);
}

namespace {
constexpr int kCuspSamples = 32;
constexpr double kCusp = 1e-7;  // a speed this far below the span's largest is zero
}  // namespace

double PathCurve::speed_at(double u) const {
  const int d = curve->dim();
  double buf[2 * kMaxAxes];
  curve->eval(u, 1, buf);
  double ss = 0;
  for (int a = 0; a < d; ++a) ss += buf[d + a] * buf[d + a];
  return std::sqrt(ss);
}

bool PathCurve::end_is_cusp(bool start) const {
  const auto& sp = start ? curve->spans().front() : curve->spans().back();
  double vmax = 0;
  for (int j = 0; j <= kCuspSamples; ++j) vmax = std::max(vmax, speed_at(sp.u0 + (sp.u1 - sp.u0) * j / kCuspSamples));
  return speed_at(start ? curve->u_begin() : curve->u_end()) <= kCusp * vmax;
}

const std::vector<double>& PathCurve::split_s() const {
  if (!split_done_) {
    for (double u : geo::split_params(*curve)) split_s_.push_back(al->s(u));
    std::sort(split_s_.begin(), split_s_.end());
    split_done_ = true;
  }
  return split_s_;
}

// Interior points where the curve's speed |C'(u)| falls to zero (to 1e-7 of
// the span's largest sampled speed): the tangent turns back there, so the
// machine must stop. Each span's speed is sampled at kSamples + 1 points and
// each local minimum below a quarter of the largest sample refined by
// golden-section search (|C'| is V-shaped at a cusp), also at a span's ends:
// a cusp a few nm after a line's end (simple-icons' furrynetwork.svg: a
// handle pointing 5 um back) lies inside the span's first sample interval.
// The curve's own ends are not interior: a zero speed there is
// cusp_at_start / cusp_at_end.
const std::vector<double>& PathCurve::cusp_s() const {
  if (cusp_done_) return cusp_s_;
  cusp_done_ = true;
  const double u_lo = curve->u_begin(), u_hi = curve->u_end(), margin = 1e-9 * (u_hi - u_lo);
  for (const auto& sp : curve->spans()) {
    auto u_of = [&](int j) { return sp.u0 + (sp.u1 - sp.u0) * j / kCuspSamples; };
    std::array<double, kCuspSamples + 1> v{};
    double vmax = 0;
    for (int j = 0; j <= kCuspSamples; ++j) vmax = std::max(vmax, v[j] = speed_at(u_of(j)));
    for (int j = 0; j <= kCuspSamples; ++j) {
      // a cusp's V leaves a sample within 1/32 of the span's speed range;
      // a flat speed (a line) is no minimum to refine
      const bool left = j == 0 || v[j] <= v[j - 1], right = j == kCuspSamples || v[j] <= v[j + 1];
      if (!(left && right && v[j] < 0.25 * vmax)) continue;
      double a = u_of(std::max(j - 1, 0)), b = u_of(std::min(j + 1, kCuspSamples));
      double best = u_of(j), vbest = v[j];
      for (int it = 0; it < 100 && b - a > 1e-15 * (1 + std::fabs(a)); ++it) {
        const double m1 = b - 0.618033988749895 * (b - a), m2 = a + 0.618033988749895 * (b - a);
        const double v1 = speed_at(m1), v2 = speed_at(m2);
        if (v1 < vbest) vbest = v1, best = m1;
        if (v2 < vbest) vbest = v2, best = m2;
        (v1 < v2 ? b : a) = v1 < v2 ? m2 : m1;
      }
      if (vbest <= kCusp * vmax && best > u_lo + margin && best < u_hi - margin) cusp_s_.push_back(al->s(best));
    }
  }
  std::sort(cusp_s_.begin(), cusp_s_.end());
  // a cusp at a knot is found from both of its spans
  cusp_s_.erase(std::unique(cusp_s_.begin(), cusp_s_.end(), [](double x, double y) { return y - x <= 1e-12; }),
                cusp_s_.end());
  return cusp_s_;
}

void check_join(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const std::string& where) {
  if (b.size() != a.size())
    throw PlanError(where + ": " + std::to_string(b.size()) + " axes, the path so far has " + std::to_string(a.size()));
  if ((a - b).norm() > 1e-9 * std::max(1.0, a.norm()))
    throw PlanError(where + ": starts " + num((a - b).norm()) + " units away from the previous curve's end");
}

void Path::add(const geo::BSpline& spline, const std::string& where) {
  add(std::make_shared<const PathCurve>(spline, where));
}

void Path::add(std::shared_ptr<const PathCurve> c) {
  // joins: end of the previous curve must meet this one's start
  if (!curves_.empty()) {
    const geo::Curve& prev = *curves_.back()->curve;
    check_join(prev.point(prev.u_end()), c->curve->point(c->curve->u_begin()), c->where);
  }
  dim_ = c->curve->dim();
  if (offsets_.empty()) offsets_.push_back(0);
  offsets_.push_back(offsets_.back() + c->al->total());
  curves_.push_back(std::move(c));
}

size_t Path::curve_at(double s) const {
  auto it = std::upper_bound(offsets_.begin() + 1, offsets_.end() - 1, s);
  return static_cast<size_t>(it - (offsets_.begin() + 1));
}

namespace {

// How far inside a curve's end with zero parametric speed its frame is
// taken: at least 1e-9 of the span in u, and at least the rounding of an arc
// length (`eps`) along the curve. A tick whose s rounds onto such an end lies
// up to that far from it; nearer the end the curvature grows as the inverse
// square root of the distance (a handle retracted onto a cubic's end: the
// curve leaves as s^(3/2)), and a tick 6 us before a stop on LinuxCNC's
// LatheMacro.svg, at 2e-7 mm/s, read 29 times the jerk limit from the frame
// at 1e-9 of the span (a curvature of 1e9 mm^-1) round after round.
double singular_end_step(const geo::Curve& c, int span, double u, bool at_start, double eps) {
  const geo::PowerSpan& sp = c.spans()[span];
  const double width = sp.u1 - sp.u0;
  const int d = c.dim();
  double at[kMaxAxes], in[kMaxAxes];
  c.eval_span(span, u, 0, at);
  double du = 1e-9 * width;
  while (du > 0 && du < 1e-3 * width) {
    c.eval_span(span, at_start ? u + du : u - du, 0, in);
    double d2 = 0;
    for (int a = 0; a < d; ++a) d2 += (in[a] - at[a]) * (in[a] - at[a]);
    if (d2 >= eps * eps) break;
    du *= 2;
  }
  return du;
}

}  // namespace

Frame frame_at(const Path& p, size_t ci, double u, double s, int span) {
  const geo::Curve& c = p.curve(ci);
  const int d = c.dim();
  double buf[4 * kMaxAxes];
  // the hint is used only strictly inside its span (at a knot find_span's
  // convention, the span on the right, decides)
  if (!(span >= 0 && u > c.spans()[span].u0 && u < c.spans()[span].u1)) span = c.find_span(u);
  c.eval_span(span, u, 3, buf);
  const double* C0 = buf;
  const double* C1 = buf + d;
  const double* C2 = buf + 2 * d;
  const double* C3 = buf + 3 * d;
  double s11 = 0, s12 = 0, s22 = 0, s13 = 0;
  for (int a = 0; a < d; ++a) {
    s11 += C1[a] * C1[a];
    s12 += C1[a] * C2[a];
    s22 += C2[a] * C2[a];
    s13 += C1[a] * C3[a];
  }
  const double sig = std::sqrt(s11);
  const bool at_start = u <= c.u_begin(), at_end = u >= c.u_end();
  if (!(sig > 0) || (at_start && p.entry(ci).cusp_at_start()) || (at_end && p.entry(ci).cusp_at_end())) {
    // A curve may start or end with zero parametric speed (a repeated end
    // control point), or one rounding leaves a hair above zero (relative
    // coordinates): its tangent there is the limit from inside, so the
    // frame is taken inside (at the end itself the curvature of such a
    // curve is without bound, 1e33 mm^-1 in simple-icons' endeavouros.svg,
    // and a tick there at 5e-12 mm/s read 1e28 times a limit; the planner
    // stops there). Inside a curve, zero speed is a cusp.
    const double du = singular_end_step(c, span, u, at_start, arc_length_rounding(p.length()));
    if (at_start && du > 0) return frame_at(p, ci, u + du, s, span);
    if (at_end && du > 0) return frame_at(p, ci, u - du, s, span);
    // Inside, a cusp (PathCurve::cusp_s): the planner stops there, and the
    // frame is the incoming one.
    if (du > 0 && u - du > c.u_begin()) return frame_at(p, ci, u - du, s, span);
    throw PlanError(p.entry(ci).where + ": zero parametric speed at u = " + num(u) +
                    " (a cusp: the tangent turns back; split the curve there)");
  }
  const double sig1 = s12 / sig;
  const double sig2 = (s22 + s13) / sig - s12 * s12 / (sig * s11);
  const double us = 1 / sig;
  const double uss = -sig1 / (sig * sig * sig);
  const double usss = us * (-sig2 / (sig * sig * sig) + 3 * sig1 * sig1 / (s11 * s11));
  Frame f;
  f.s = s;
  f.u = u;
  f.curve = ci;
  double kk = 0, qq = 0;
  for (int a = 0; a < d; ++a) {
    f.C[a] = C0[a];
    f.T[a] = C1[a] * us;
    f.K[a] = C2[a] * us * us + C1[a] * uss;
    f.Q[a] = C3[a] * us * us * us + 3 * C2[a] * us * uss + C1[a] * usss;
    kk += f.K[a] * f.K[a];
    qq += f.Q[a] * f.Q[a];
  }
  f.kappa = std::sqrt(kk);
  f.q_norm = std::sqrt(qq);
  f.sig[0] = sig;
  f.sig[1] = sig1;
  f.sig[2] = sig2;
  return f;
}

namespace {

// Largest v >= 0 with p v^3 + q v <= r (p, q >= 0): the one real root of the
// depressed cubic (Cardano), polished by Newton; infinity if p = q = 0.
double cubic_speed(double p, double q, double r) {
  if (!(r > 0)) return 0;
  if (!(p > 0)) return q > 0 ? r / q : std::numeric_limits<double>::infinity();
  const double P = q / p, R = r / p;
  const double disc = std::sqrt(R * R / 4 + P * P * P / 27);
  double v = std::cbrt(R / 2 + disc) + std::cbrt(R / 2 - disc);
  for (int it = 0; it < 3; ++it) {
    const double fp = 3 * v * v + P;
    if (fp > 0) v -= (v * v * v + P * v - R) / fp;
  }
  v = std::max(v, 0.0);
  while (v > 0 && p * v * v * v + q * v > r) v *= 1 - 1e-12;
  return v;
}

}  // namespace

namespace {

// Largest speed at which the per-axis and centripetal sums hold with the
// tangential acceleration A.
double speed_with(const Frame& f, const Limits& L, const PlanOptions& o, double A, double J_t, int dim) {
  double v = L.feed;
  auto cap = [&](double x) {
    if (x >= 0 && x < v) v = x;
  };
  // p v^3 + q v <= r: its root only where it does not hold at the speed so
  // far (the sum grows with v), which saves most of the cube roots
  auto cap_cubic = [&](double p, double q, double r) {
    if (!(p * v * v * v + q * v <= r)) cap(cubic_speed(p, q, r));
  };
  for (int a = 0; a < dim; ++a) {
    const double T = std::fabs(f.T[a]), K = std::fabs(f.K[a]), Q = std::fabs(f.Q[a]);
    const double ab = o.axis_a_share * L.a_axis[a], jb = o.axis_j_share * L.j_axis[a];
    if (T > 0) cap(o.axis_v_share * L.v_axis[a] / T);
    if (K > 0) cap(std::sqrt(std::max(0.0, ab - T * A) / K));
    cap_cubic(Q, 3 * K * A, jb - T * J_t);
  }
  if (f.kappa > 0) cap(std::sqrt(o.cen_a_share * L.a_cen / f.kappa));
  cap_cubic(f.q_norm, 3 * f.kappa * A, o.axis_j_share * L.j_cen);
  return v;
}

// Largest tangential acceleration the sums leave at speed v (at most A_t).
double accel_at(const Frame& f, const Limits& L, const PlanOptions& o, double v, double A_t, double J_t, int dim) {
  double A = A_t;
  for (int a = 0; a < dim; ++a) {
    const double T = std::fabs(f.T[a]), K = std::fabs(f.K[a]), Q = std::fabs(f.Q[a]);
    const double ab = o.axis_a_share * L.a_axis[a], jb = o.axis_j_share * L.j_axis[a];
    if (T > 0) A = std::min(A, (ab - K * v * v) / T);
    if (K > 0 && v > 0) A = std::min(A, (jb - T * J_t - Q * v * v * v) / (3 * K * v));
  }
  if (f.kappa > 0 && v > 0) A = std::min(A, (o.axis_j_share * L.j_cen - f.q_norm * v * v * v) / (3 * f.kappa * v));
  return A;
}

}  // namespace

double speed_limit(const Frame& f, const Limits& L, const PlanOptions& o, double A_t, double J_t, int dim,
                   double* A_loc) {
  if (!A_loc) return speed_with(f, L, o, A_t, J_t, dim);
  // The sums trade speed against tangential acceleration. The speed bound
  // is the larger of: the speed that leaves half of A_t, and speed_share of
  // the speed that leaves only the floor (a_local_floor A_t), which still
  // leaves the profile a useful acceleration (a jerk-bound turn at 0.9 of
  // its top speed leaves 27 % of the jerk for the coupling).
  const double A_f = o.a_local_floor * A_t;
  const double v_top = speed_with(f, L, o, A_f, J_t, dim);
  const double A_top = accel_at(f, L, o, v_top, A_t, J_t, dim);
  // where the top speed still leaves A_t/2, it is also the speed that leaves A_t/2
  double v = v_top, A = A_top;
  if (A_top < 0.5 * A_t) {
    v = std::max(speed_with(f, L, o, 0.5 * A_t, J_t, dim), o.speed_share * v_top);
    A = accel_at(f, L, o, v, A_t, J_t, dim);
  }
  *A_loc = std::clamp(A, A_f, A_t);
  return v;
}

namespace {

// Profile speed at arc length s (pieces sorted, s monotone in time).
struct SpeedAtS {
  const std::vector<Piece>& p;
  size_t i = 0;
  double operator()(double s) {
    while (i + 1 < p.size() && p[i].s(p[i].T) < s) ++i;
    const Piece& q = p[i];
    if (s <= q.s0) return q.v0;
    if (s >= q.s(q.T)) return q.v(q.T);
    // s(tau) is increasing: Newton inside the bracket, bisection fallback
    double lo = 0, hi = q.T, t = q.T * (s - q.s0) / std::max(q.s(q.T) - q.s0, 1e-300);
    for (int it = 0; it < 60 && hi - lo > 1e-15 * (1 + q.T); ++it) {
      const double f = q.s(t) - s;
      // |f| <= 1e-13 (1 + s): the speed there differs from the exact one by
      // at most a * 1e-13 (1 + s) / v, far below anything checked
      if (std::fabs(f) <= 1e-13 * (1 + std::fabs(s))) break;
      if (f < 0) lo = t;
      else hi = t;
      const double v = q.v(t);
      double tn = v > 0 ? t - f / v : 0.5 * (lo + hi);
      if (!(tn > lo && tn < hi)) tn = 0.5 * (lo + hi);
      if (std::fabs(tn - t) <= 1e-15 * (1 + q.T)) {
        t = tn;
        break;
      }
      t = tn;
    }
    return q.v(t);
  }
};

// Speed through a tangent break (a corner) from tangent T1 to T2. The
// velocity turns within one tick: on the samples (and in the one-tick quintic
// that joins them) per axis a velocity step dv_a = v |T2_a - T1_a| in a tick
// h is an acceleration of about 1.9 dv_a / h and a jerk of about 10 dv_a / h^2
// (quintic Hermite, zero end accelerations); the normal part of the sampled
// acceleration is about v |T2 - T1| / h, of the jerk v |T2 - T1| / h^2. The
// speed is the largest that keeps each within its limit (with the jerk
// factor 10); the fit's checks at every tick decide, and the repair loop
// slows down further if one fails. A right angle at 1 ms and 50 000 mm/s^3
// gives 0.005 mm/s (a stop in practice); 1e-5 rad gives the feed.
// Speed at a curvature jump (a C1 knot, or G1 curves meeting): the axis's
// acceleration steps by dk v^2 within a tick. A quintic Hermite that takes a
// step da of the acceleration over one tick T has a jerk peak of 9 da / T
// (the third derivative of the end-acceleration basis (t^3 - 2 t^4 + t^5)/2
// peaks at 9, at t = 1), so 9 dk v^2 / h <= jump_j_share j_axis: at a station
// the tangential acceleration is zero, the rest is left for the profile's
// jerk there and for the one-tick fits around the step (a window's commit
// may end next to it).
double jump_speed(double dk, double j_axis, const PlanOptions& o) {
  return std::sqrt(o.jump_j_share * j_axis * o.period / (9 * dk));
}

double corner_speed(const double* T1, const double* T2, int d, const Limits& L, const PlanOptions& o) {
  if (o.corner_stops) return 0;
  const double h = o.period;
  double v = L.feed, dn2 = 0;
  for (int a = 0; a < d; ++a) {
    const double dt = std::fabs(T2[a] - T1[a]);
    dn2 += dt * dt;
    if (dt > 0) v = std::min({v, L.j_axis[a] * h * h / (10 * dt), L.a_axis[a] * h / (1.9 * dt)});
  }
  const double dn = std::sqrt(dn2);
  // the speed's own second derivative through the turn (the sampled
  // tangential jerk): the polynomial that turns the velocity within the tick
  // slows down and speeds up again, |x'''.u| up to 10 v |dT| / h^2 plus
  // |x''_n|^2 / v of about 3.6 v |dT|^2 / h^2; 30 covers both for a
  // right angle (the fit checks it at every tick, or at every engine tick
  // where the fit tick is coarser: there the turn's speed dip is seen whole)
  if (dn > 0) v = std::min({v, o.cen_a_share * L.a_cen * h / dn, L.j_cen * h * h / (10 * dn), L.j_tan * h * h / (30 * dn)});
  return v;
}

// Speed bound at the knot starting span `sp` of curve ci: the corner speed at
// a tangent break; where only the curvature jumps (a C1 knot), the per-axis acceleration
// steps by |dK_a| v^2 within one tick, so the jerk over that tick is about
// |dK_a| v^2 / h (times ~1.9 for the quintic that smooths it):
// v <= sqrt(g1 j_axis h / (2 |dK_a|)). feed if the curve is C2 there.
double knot_speed_bound(const Path& p, size_t ci, int sp, const Limits& L, const PlanOptions& o) {
  const geo::Curve& c = p.curve(ci);
  const int d = c.dim();
  const double u = c.spans()[sp].u0;
  double l[4 * kMaxAxes], r[4 * kMaxAxes];
  c.eval_span(sp - 1, u, 2, l);
  c.eval_span(sp, u, 2, r);
  auto frame2 = [&](const double* b, double* T, double* K) {
    double s11 = 0, s12 = 0;
    for (int a = 0; a < d; ++a) {
      s11 += b[d + a] * b[d + a];
      s12 += b[d + a] * b[2 * d + a];
    }
    const double sig = std::sqrt(s11);
    for (int a = 0; a < d; ++a) {
      T[a] = b[d + a] / sig;
      K[a] = (b[2 * d + a] - T[a] * s12 / sig) / s11;
    }
  };
  double Tl[kMaxAxes], Kl[kMaxAxes], Tr[kMaxAxes], Kr[kMaxAxes];
  frame2(l, Tl, Kl);
  frame2(r, Tr, Kr);
  double dot = 0, kscale = 0;
  for (int a = 0; a < d; ++a) {
    dot += Tl[a] * Tr[a];
    kscale = std::max({kscale, std::fabs(Kl[a]), std::fabs(Kr[a])});
  }
  if (std::acos(std::clamp(dot, -1.0, 1.0)) > o.corner_tol) return corner_speed(Tl, Tr, d, L, o);
  double v = L.feed;
  for (int a = 0; a < d; ++a) {
    const double dk = std::fabs(Kr[a] - Kl[a]);
    if (dk > 1e-9 * (1 + kscale)) v = std::min(v, jump_speed(dk, L.j_axis[a], o));
  }
  return v;
}

// Fractions of v_lim(s) at which the grid also keeps what the sums leave for
// the tangential acceleration (Grid::A_below): a block whose top speed is
// below one of them at a point may accelerate at that level's A there.
constexpr std::array<double, 4> kALevels = {0.2, 0.4, 0.6, 0.8};
using ALevels = std::array<float, kALevels.size()>;

ALevels min_levels(const ALevels& a, const ALevels& b) {
  ALevels m{};
  for (size_t k = 0; k < m.size(); ++k) m[k] = std::min(a[k], b[k]);
  return m;
}

struct Grid {
  std::vector<double> s, vlim;
  std::vector<double> A;        // local tangential acceleration bound (speed_limit)
  std::vector<ALevels> A_below;  // the bound at speed kALevels[k] v_lim (rounded down to float)
  std::vector<double> A_first;   // A as first taken, once raise_accels has raised it: stations stay
  std::vector<char> corner;     // forced stop
};

// What the sums leave at the speeds kALevels[k] v (at most A_t), rounded down.
ALevels accels_below(const Frame& f, const Limits& L, const PlanOptions& o, double v, double A_t, double J_t,
                     int dim) {
  ALevels out{};
  for (size_t k = 0; k < kALevels.size(); ++k) {
    const double A = std::min(A_t, accel_at(f, L, o, kALevels[k] * v, A_t, J_t, dim));
    float a = static_cast<float>(std::max(A, 0.0));
    if (static_cast<double>(a) > A) a = std::nextafter(a, 0.0f);
    out[k] = a;
  }
  return out;
}

// The grid of one plan is held in memory: beyond kMaxGridPoints points
// (about 1.7 GB) the path is refused naming the curve where the count passes it,
// before the points are built.
void check_grid_size(double points, const std::string& where, double len, double ds_max) {
  if (points <= kMaxGridPoints) return;
  throw PlanError(where + ": the arc-length grid would pass " + num(kMaxGridPoints) + " points (this curve is " +
                  num(len) + " units long, a grid step is at most " + num(ds_max) +
                  " units and shorter where the curve turns); split the path (plan --window plans it in parts)");
}

constexpr double kReversalCos = -0.99984770;  // cos 179 deg: a turn this sharp is a reversal, a stop

// Speed bound where curve ci - 1 (frame e at its end) meets curve ci (frame
// f at its start): 0 at a cusp or a reversal, the corner speed at a tangent
// break, the bound of the curvature jump at a join that is tangent but not
// curvature-continuous (as at a C1 knot), none (the feed) where both agree.
// station: the join is a station of the profile (all but the last case).
struct JoinBound {
  double v = 0;
  bool tangent = false, station = true;
};

JoinBound join_bound(const Path& p, size_t ci, const Frame& e, const Frame& f, const Limits& L, const PlanOptions& o) {
  const int d = p.dim();
  double dot = 0;
  for (int a = 0; a < d; ++a) dot += e.T[a] * f.T[a];
  JoinBound b;
  if (p.entry(ci - 1).cusp_at_end() || p.entry(ci).cusp_at_start() || dot < kReversalCos) return b;
  if (std::acos(std::clamp(dot, -1.0, 1.0)) > o.corner_tol) {
    b.v = corner_speed(e.T, f.T, d, L, o);
    return b;
  }
  b.tangent = true;
  b.station = false;
  b.v = L.feed;
  double kscale = 0;
  for (int a = 0; a < d; ++a) kscale = std::max({kscale, std::fabs(e.K[a]), std::fabs(f.K[a])});
  for (int a = 0; a < d; ++a) {
    const double dk = std::fabs(f.K[a] - e.K[a]);
    if (dk > 1e-9 * (1 + kscale)) {
      b.v = std::min(b.v, jump_speed(dk, L.j_axis[a], o));
      b.station = true;
    }
  }
  return b;
}
Grid build_grid(const Path& p, const Limits& L, const PlanOptions& o, double A_t, double J_t) {
  Grid g;
  const int d = p.dim();
  // the caps that meet the curve at hand, and those that hold the grid point
  // at hand, swept along the path (caps sorted by start; grid points come in
  // increasing s): the cost does not grow with the number of caps
  std::vector<SpeedCap> caps_by_start = o.caps, caps, caps_here;
  std::sort(caps_by_start.begin(), caps_by_start.end(),
            [](const SpeedCap& a, const SpeedCap& b) { return a.s0 < b.s0; });
  size_t next_cap = 0, next_cap_here = 0;
  // the levels of a point (of both frames where two curves meet tangentially)
  auto levels_at = [&](const Frame& f, const std::optional<Frame>& e, double v) {
    const ALevels l = accels_below(f, L, o, v, A_t, J_t, d);
    return e ? min_levels(l, accels_below(*e, L, o, v, A_t, J_t, d)) : l;
  };
  auto cap_at = [&](double s_abs, double vl) {
    while (next_cap_here < caps_by_start.size() && caps_by_start[next_cap_here].s0 <= s_abs)
      caps_here.push_back(caps_by_start[next_cap_here++]);
    caps_here.erase(std::remove_if(caps_here.begin(), caps_here.end(),
                                   [&](const SpeedCap& cp) { return cp.s1 < s_abs; }),
                    caps_here.end());
    for (const auto& cp : caps_here) vl = std::min(vl, cp.v);
    return vl;
  };
  for (size_t ci = 0; ci < p.size(); ++ci) {
    const geo::Curve& c = p.curve(ci);
    const geo::ArcLength& al = p.arclength(ci);
    const double s_off = p.offset(ci), len = al.total();
    while (next_cap < caps_by_start.size() && caps_by_start[next_cap].s0 <= s_off + len)
      caps.push_back(caps_by_start[next_cap++]);
    caps.erase(std::remove_if(caps.begin(), caps.end(), [&](const SpeedCap& cp) { return cp.s1 < s_off; }),
               caps.end());
    // mandatory points: curvature extrema and inflections, and knots where
    // the curve is not C2 (the acceleration K v^2 steps there)
    std::vector<double> must;
    must = p.entry(ci).split_s();
    std::vector<std::pair<double, double>> knot_bound;  // (s, speed bound)
    for (size_t sp = 1; sp < c.spans().size(); ++sp) {
      const double uk = c.spans()[sp].u0;
      const double sb = knot_speed_bound(p, ci, static_cast<int>(sp), L, o);
      if (sb < L.feed) {
        knot_bound.push_back({al.s(uk), sb});
        must.push_back(al.s(uk));
      }
    }
    for (double sc : p.entry(ci).cusp_s()) {  // a stop, like a corner
      knot_bound.push_back({sc, 0.0});
      must.push_back(sc);
    }
    std::sort(knot_bound.begin(), knot_bound.end());
    for (const auto& cp : caps) {
      const double mid = 0.5 * (cp.s0 + cp.s1) - s_off;
      if (mid > 0 && mid < len) must.push_back(mid);
    }
    std::vector<double> forced_here;
    for (double fs : o.force_stations)
      if (fs - s_off > 0 && fs - s_off <= len + 1e-12) {  // a station at a curve's end: offset + len rounds
        must.push_back(std::min(fs - s_off, len));
        forced_here.push_back(std::min(fs - s_off, len));
      }
    std::sort(must.begin(), must.end());
    must.push_back(len);
    size_t kb = 0;
    const ArcTable& tab = p.table(ci);
    int hint = 0;
    double s = 0, u = c.u_begin();
    size_t mi = 0;
    const double ds_max = std::min(o.max_grid_ds, len / 8);
    check_grid_size(g.s.size() + len / ds_max, p.entry(ci).where, len, ds_max);
    while (true) {
      const Frame f = frame_at(p, ci, u, s_off + s, tab.span_of(hint));
      double A_here = A_t;
      double vl = speed_limit(f, L, o, A_t, J_t, d, &A_here);
      bool corner = false;
      std::optional<Frame> e_join;  // the previous curve's end, where the two meet tangentially
      if (s == 0) {
        if (ci == 0) {
          vl = o.v_start;
          corner = true;
        } else {
          // tangent break against the previous curve's end
          const Frame e = frame_at(p, ci - 1, p.curve(ci - 1).u_end(), s_off);
          const JoinBound jb = join_bound(p, ci, e, f, L, o);
          if (jb.tangent) {
            double A_e = A_t;
            vl = std::min({vl, jb.v, speed_limit(e, L, o, A_t, J_t, d, &A_e)});
            A_here = std::min(A_here, A_e);
            e_join = e;
          } else {
            vl = jb.v;
          }
          corner = jb.station;
          if (!g.s.empty() && std::fabs(g.s.back() - (s_off + s)) < 1e-12) {
            g.vlim.back() = std::min(g.vlim.back(), vl);
            g.A.back() = std::min(g.A.back(), A_here);
            // the point's levels were taken at fractions of its old, higher v_lim: valid below the new one
            g.A_below.back() = min_levels(g.A_below.back(), levels_at(f, e_join, g.vlim.back()));
            g.corner.back() = g.corner.back() || corner;
            goto advance;
          }
        }
      }
      if (ci + 1 == p.size() && s >= len) {
        vl = 0;
        corner = true;
      }
      vl = cap_at(s_off + s, vl);
      for (double fs : forced_here)
        if (std::fabs(fs - s) <= 1e-12) corner = true;
      while (kb < knot_bound.size() && knot_bound[kb].first < s - 1e-12) ++kb;
      if (kb < knot_bound.size() && std::fabs(knot_bound[kb].first - s) <= 1e-12) {
        vl = std::min(vl, knot_bound[kb].second);
        corner = true;  // a station, like a corner
      }
      if (g.s.size() >= kMaxGridPoints) check_grid_size(g.s.size() + 1.0, p.entry(ci).where, len, ds_max);
      g.s.push_back(s_off + s);
      g.vlim.push_back(vl);
      g.A.push_back(A_here);
      g.A_below.push_back(levels_at(f, e_join, vl));
      g.corner.push_back(corner);
    advance:
      if (s >= len) break;
      double ds = ds_max;
      if (f.kappa > 0) ds = std::min(ds, o.grid_turn / f.kappa);
      ds = std::max(ds, len * 1e-9);
      while (mi < must.size() && must[mi] <= s + 1e-12) ++mi;
      double s_next = s + ds;
      if (mi < must.size() && must[mi] <= s_next) {
        s_next = must[mi];
        // from a stop to a point it must hold within one step (simple-icons'
        // furrynetwork.svg: a cusp 2e-5 mm after a reversal), a point between
        // them: the block between two stops takes its speed bound from its
        // inner points, and with none it had none and was skipped
        if (g.vlim.back() == 0 && s_next - s > 2 * len * 1e-9) s_next = 0.5 * (s + s_next);
      }
      // a point within rounding of the curve's end is its end: a cap's end
      // computed from other sums (7e-15 before it in simple-icons' gitea.svg)
      // made a second grid point there, a station 7e-15 from the end's, and
      // a block between them cruised at the cusp's 5e-30 mm/s for 1.4e15 s
      if (s_next > len - 1e-12) s_next = len;
      u = (s_next >= len) ? c.u_end() : tab.u_at(s_next, hint);
      s = s_next;
    }
  }
  return g;
}

// A station is placed where the local tangential acceleration has changed by
// this factor since the last one (stations_from).
constexpr double kAStationRatio = 3;

// Stations of the grid points lo..hi (both always stations): corners, forced
// points, and local minima of v_lim that the profile could reach; idx
// receives their grid indices. A_t, J_t, tau: the profile's largest
// tangential acceleration, its jerk and shortest jerk phase (profile.hpp).
std::vector<Station> stations_from(const Grid& g, const std::vector<char>& forced, double feed, size_t lo, size_t hi,
                                   double A_t, double J_t, double tau, std::vector<size_t>& idx) {
  std::vector<Station> st;
  idx.clear();
  double A_ref = 0;
  // where A(s) changed since: the first A (raising it inside a ramp must not split the ramp)
  const std::vector<double>& A_st = g.A_first.empty() ? g.A : g.A_first;
  // the next corner after each point (hi + 1: none)
  std::vector<size_t> next_corner(hi - lo + 2, hi + 1);
  for (size_t i = hi; i-- > lo;) next_corner[i - lo] = g.corner[i + 1] ? i + 1 : next_corner[i + 1 - lo];
  // Whether the profile could reach v at grid point i: every block starts and
  // ends at a station with acceleration 0, so its speed at i is at most what
  // the last station (at its speed bound) reaches within the distance, and
  // at most the speed from which the next corner's is reached (at A_t, the
  // largest acceleration of any block). A local minimum of v_lim above that
  // cannot bind: as a station it would only split a speed change in two
  // (before a stop, a plateau at the station's speed).
  auto reachable_at = [&](size_t i, double v) {
    if (!st.empty() && reachable(st.back().vmax, g.s[i] - st.back().s, A_t, J_t, feed, tau) < v) return false;
    const size_t c = next_corner[i - lo];
    return c > hi || reachable(g.vlim[c], g.s[c] - g.s[i], A_t, J_t, feed, tau) >= v;
  };
  for (size_t i = lo; i <= hi; ++i) {
    bool take = i == lo || i == hi || g.corner[i] || forced[i];
    // where the local tangential acceleration has changed by more than
    // kAStationRatio since the last station: a block then does not slow all of its ramp to
    // the smallest A at its far end (with hysteresis: a slowly varying A
    // makes no stations)
    if (!take && (A_st[i] < A_ref / kAStationRatio || A_st[i] > kAStationRatio * A_ref)) take = true;
    // a local minimum of v_lim, by more than rounding noise (1e-9 relative):
    // a plateau (constant curvature, straight line) makes no stations
    if (!take && g.vlim[i] < feed * (1 - 1e-9) && g.vlim[i] < g.vlim[i - 1] * (1 - 1e-9) &&
        g.vlim[i] <= g.vlim[i + 1] * (1 + 1e-9))
      take = reachable_at(i, g.vlim[i]);
    if (take) {
      st.push_back({g.s[i], g.vlim[i], 0});
      idx.push_back(i);
      A_ref = A_st[std::min(i + 1, hi)];  // the next block's first inner point (a station's own A is both sides')
    }
  }
  return st;
}

// Cruise cap of each block: the highest v_lim on it (the profile is checked
// against v_lim at every grid point afterwards).
std::vector<double> caps_for(const Grid& g, const std::vector<Station>& st, const std::vector<size_t>& idx,
                             double feed) {
  std::vector<double> cap(st.empty() ? 0 : st.size() - 1, 0.0);
  for (size_t b = 0; b + 1 < st.size(); ++b) {
    double m = std::max(st[b].vmax, st[b + 1].vmax);
    for (size_t i = idx[b]; i <= idx[b + 1]; ++i) m = std::max(m, g.vlim[i]);
    cap[b] = std::min(m, feed);
  }
  return cap;
}

// Tangential acceleration of the block between grid points a < c: the
// smallest local bound strictly inside it (at its ends, stations, the profile's
// acceleration is zero), or at its ends if it has no inner point.
double block_A(const Grid& g, size_t a, size_t c) {
  if (c <= a + 1) return std::min(g.A[a], g.A[c]);
  double m = g.A[a + 1];
  for (size_t i = a + 2; i < c; ++i) m = std::min(m, g.A[i]);
  return m;
}
std::vector<double> accels_for(const Grid& g, const std::vector<size_t>& idx) {
  std::vector<double> A(idx.empty() ? 0 : idx.size() - 1, 0.0);
  for (size_t b = 0; b + 1 < idx.size(); ++b) A[b] = block_A(g, idx[b], idx[b + 1]);
  return A;
}

// Highest speed any motion from speed v0 at acceleration 0 has after
// distance d with |a| <= A and |j| <= J: jerk J until A, then A (not back to
// acceleration 0, unlike reachable()). Backwards in time it bounds the speed
// d before a point passed at v0 with acceleration 0.
double speed_after(double v0, double d, double A, double J) {
  const double t1 = A / J, d1 = v0 * t1 + J * t1 * t1 * t1 / 6, v1 = v0 + 0.5 * J * t1 * t1;
  if (d >= d1) return std::sqrt(v1 * v1 + 2 * A * (d - d1));
  // v0 t + J t^3 / 6 = d on [0, t1]: bisection (the left side is increasing)
  double lo = 0, hi = t1;
  for (int it = 0; it < 60; ++it) {
    const double t = 0.5 * (lo + hi);
    (v0 * t + J * t * t * t / 6 < d ? lo : hi) = t;
  }
  return v0 + 0.5 * J * hi * hi;
}

// Smallest rise of a block's acceleration that raise_accels takes.
constexpr double kRaiseFactor = 1.5;

// A(s) is taken at v_lim(s), but a block that starts or ends at rest runs far
// below v_lim for much of its length (the braking for a stop after a curve),
// and its ramp takes the smallest A inside it. After the first profile, at an
// inner point of such a block the speed is at most w = the block's top speed,
// and at most what its end stations (at their bounds) reach within the
// distance at A_t and J_t. Where w is below a stored level of v_lim, the
// point takes that level's A (Grid::A_below: the sums hold with it up to the
// level's speed) and v_lim there is capped at w, so that any later profile
// keeps within the level's speed (the check against v_lim at every grid point
// enforces it); the first profile keeps within the new bounds. Only blocks
// whose A rises by kRaiseFactor at least are changed: elsewhere the stations
// placed anew cost more than the ramps gain (bench_toolpaths, set (ii)).
// memo: the first profile's blocks (plan_blocks), one per block of idx.
// Returns whether any A rose.
bool raise_accels(Grid& g, const std::vector<size_t>& idx, const std::vector<Station>& st,
                  const std::vector<BlockMemo>& memo, double A_t, double J_t) {
  bool any = false;
  std::vector<double> w, A_new;
  for (size_t b = 0; b + 1 < idx.size() && b < memo.size(); ++b) {
    const BlockMemo& m = memo[b];
    const size_t i0 = idx[b], i1 = idx[b + 1];
    if ((m.va > 0 && m.vb > 0) || i1 <= i0 + 1) continue;
    const double V = std::max({m.va, m.vb, m.vp});
    w.assign(i1 - i0, 0.0);
    A_new.assign(i1 - i0, 0.0);
    double A_old_min = std::numeric_limits<double>::infinity(), A_new_min = A_old_min;
    for (size_t i = i0 + 1; i < i1; ++i) {
      const double wi = (1 + 1e-9) * std::min({V, speed_after(st[b].vmax, g.s[i] - g.s[i0], A_t, J_t),
                                               speed_after(st[b + 1].vmax, g.s[i1] - g.s[i], A_t, J_t)});
      double Ai = g.A[i];
      for (size_t k = 0; k < kALevels.size(); ++k)
        if (kALevels[k] * g.vlim[i] >= wi) {
          Ai = std::max(Ai, static_cast<double>(g.A_below[i][k]));
          break;
        }
      w[i - i0] = wi;
      A_new[i - i0] = Ai;
      A_old_min = std::min(A_old_min, g.A[i]);
      A_new_min = std::min(A_new_min, Ai);
    }
    if (!(A_new_min >= kRaiseFactor * A_old_min)) continue;
    if (!any) g.A_first = g.A;
    any = true;
    for (size_t i = i0 + 1; i < i1; ++i) {
      g.A[i] = A_new[i - i0];
      g.vlim[i] = std::min(g.vlim[i], w[i - i0]);
    }
  }
  return any;
}

// Marks as forced stations the local maxima, over the grid points lo..hi, of
// the ratio (profile speed / v_lim) where it exceeds 1; points for which
// `check(i)` is false count as ratio 0. Returns the points marked (only the
// first one with first_only).
template <class Check>
std::vector<size_t> mark_violations(const Grid& g, std::vector<char>& forced, SpeedAtS& v_at, size_t lo, size_t hi,
                                    double feed, const Check& check, bool first_only = false) {
  std::vector<size_t> marked;
  double r_prev2 = 0, r_prev = 0;
  size_t i_prev = lo;
  for (size_t i = lo; i <= hi + 1; ++i) {
    double r = 0;
    if (i <= hi && !(g.corner[i] || forced[i]) && check(i)) {
      // at a station the profile has the station's speed by construction
      r = v_at(g.s[i]) / std::max(g.vlim[i], 1e-9 * feed);  // below 1e-9 feed counts as a stop
    }
    if (r_prev > 1 + 1e-9 && r_prev >= r_prev2 && r_prev >= r) {
      marked.push_back(i_prev);
      if (first_only) break;
    }
    r_prev2 = r_prev;
    r_prev = r;
    i_prev = i;
  }
  for (size_t i : marked) forced[i] = 1;
  return marked;
}

}  // namespace

namespace {

// Each dwell before the first piece that starts at rest within 1e-6 of its
// arc length (the stop its cap of speed 0 makes: a station of speed 0, so
// exactly at rest), the later pieces delayed by it.
void insert_dwells(Plan& plan, std::vector<PlanOptions::Dwell> dwells) {
  std::sort(dwells.begin(), dwells.end(), [](const auto& a, const auto& b) { return a.s < b.s; });
  const double tol = 1e-6 * std::max(1.0, plan.length);
  size_t i = 0;
  for (const auto& d : dwells) {
    if (!(d.seconds > 0) || !std::isfinite(d.seconds))
      throw PlanError("dwell of " + num(d.seconds) + " s at arc length " + num(d.s) + ": must be positive and finite");
    while (i < plan.pieces.size()) {
      const Piece& q = plan.pieces[i];
      if (i > 0 && q.v0 == 0 && q.a0 == 0 && std::fabs(q.s0 - d.s) <= tol) break;
      ++i;
    }
    if (i == plan.pieces.size() && std::fabs(plan.length - d.s) <= tol) {  // at the path's end, at rest
      Piece rest;
      rest.t0 = plan.duration();
      rest.T = d.seconds;
      rest.s0 = plan.length;
      rest.dwell = true;
      plan.pieces.push_back(rest);
      continue;
    }
    if (i == plan.pieces.size())
      throw PlanError("dwell at arc length " + num(d.s) + ": the plan does not stop there (a dwell needs a stop)");
    Piece rest;
    rest.t0 = plan.pieces[i].t0;
    rest.T = d.seconds;
    rest.s0 = plan.pieces[i].s0;
    rest.dwell = true;
    for (size_t k = i; k < plan.pieces.size(); ++k) plan.pieces[k].t0 += d.seconds;
    plan.pieces.insert(plan.pieces.begin() + static_cast<long>(i), rest);
    i += 2;
  }
}

// A motion over a move of length len from speed va to speed vb (acceleration
// 0 at both ends; 0 and 0 for a move from rest to rest) with every jerk
// switch on the tick grid (period h). Each speed ramp (AlignedRamp) holds
// its jerk for nj ticks, its acceleration for na and the opposite jerk for
// nj: the ramp up to the peak speed vp and the ramp down from it each have
// their own counts and jerk, with a cruise of nc ticks between them. For
// given counts vp (N_up / 2 + nc + N_down / 2) h = len - (va N_up + vb
// N_down) h / 2 (N = na + 2 nj: each ramp is point-symmetric, so it covers
// the mean of its end speeds times its duration), a ramp's jerk
// J = (vp - v_end) / (h^2 nj (nj + na)) and its peak acceleration J nj h.
// Of the counts near the continuous optimum that keep vp <= V and each ramp
// within its jerk and acceleration, the fewest ticks win.
struct AlignedRamp {
  long long nj = 0, na = 0;
  double J = 0;
  long long ticks() const { return na + 2 * nj; }
};
struct AlignedMove {
  AlignedRamp up, down;
  long long nc = 0;
  double va = 0, vp = 0, vb = 0;
  long long ticks() const { return up.ticks() + down.ticks() + nc; }
};
// The acceleration and jerk a ramp may use.
struct RampLimits {
  double A = 0, J = 0;
  // duration of a ramp from rest to v (S-curve, continuous)
  double time_to(double v) const { return v >= A * A / J ? v / A + A / J : 2 * std::sqrt(v / J); }
};

// Candidate counts of a ramp to speed v: next to its continuous optimum
// (rounding both counts up is among them).
std::array<AlignedRamp, 16> ramp_counts(double v, double h, const RampLimits& r) {
  const double tj = std::min(r.A / r.J, std::sqrt(v / r.J)), ta = std::max(0.0, v / r.A - r.A / r.J);
  const long long nj0 = std::max<long long>(1, static_cast<long long>(std::floor(tj / h)) - 1);
  const long long na0 = std::max<long long>(0, static_cast<long long>(std::floor(ta / h)) - 1);
  std::array<AlignedRamp, 16> out;
  for (int k = 0; k < 16; ++k) out[static_cast<size_t>(k)] = AlignedRamp{nj0 + k / 4, na0 + k % 4, 0};
  return out;
}

// The fastest speed a ramp of these counts allows (its jerk and acceleration at their limits).
double ramp_speed_cap(const AlignedRamp& c, double h, const RampLimits& r) {
  const double n = static_cast<double>(c.nj + c.na);
  return std::min(r.J * h * h * static_cast<double>(c.nj) * n, r.A * h * n);
}

bool aligned_move(double len, double h, double va, double vb, double V, const RampLimits& up,
                  const RampLimits& down, AlignedMove& best) {
  const double lo_peak = std::max(va, vb);
  if (!(len > 0 && h > 0 && V > 0 && V >= lo_peak && up.A > 0 && up.J > 0 && down.A > 0 && down.J > 0))
    return false;
  // the continuous optimum: the peak speed whose two ramps fit in len
  auto ramps_length = [&](double v) {
    return 0.5 * (va + v) * up.time_to(v - va) + 0.5 * (v + vb) * down.time_to(v - vb);
  };
  if (ramps_length(lo_peak) > len) return false;
  double v = V;
  if (ramps_length(v) > len) {
    double lo = lo_peak;
    for (int it = 0; it < 60; ++it) (ramps_length(0.5 * (lo + v)) > len ? v : lo) = 0.5 * (lo + v);
    v = lo;
  }
  if (!(std::max(up.time_to(v - va), down.time_to(v - vb)) / h < 1e9)) return false;  // ticks far finer than the motion
  const auto cu = ramp_counts(v - va, h, up), cd = ramp_counts(v - vb, h, down);
  bool found = false;
  for (const AlignedRamp& ru : cu)
    for (const AlignedRamp& rd : cd) {
      const double N2 = 0.5 * static_cast<double>(ru.ticks() + rd.ticks());
      const double rest = len - 0.5 * (va * static_cast<double>(ru.ticks()) + vb * static_cast<double>(rd.ticks())) * h;
      const double vcap = std::min({V, va + ramp_speed_cap(ru, h, up), vb + ramp_speed_cap(rd, h, down)});
      const double ticks_at_vcap = rest / (h * vcap);
      if (!(rest > 0 && ticks_at_vcap < 1e12)) continue;  // a move of more than 1e12 ticks: left as planned
      AlignedMove m{ru, rd, std::max<long long>(0, static_cast<long long>(std::ceil(ticks_at_vcap - N2 - 1e-9))), va,
                    0, vb};
      if (found && m.ticks() >= best.ticks()) continue;
      bool ok = false;
      for (int more = 0; more < 4; ++more, ++m.nc) {  // a tick more where rounding put vp above a bound
        m.vp = rest / (h * (N2 + static_cast<double>(m.nc)));
        auto fits = [&](AlignedRamp& c, double v_end, const RampLimits& r) {
          c.J = (m.vp - v_end) / (h * h * static_cast<double>(c.nj * (c.nj + c.na)));
          return c.J <= r.J && c.J * static_cast<double>(c.nj) * h <= r.A;
        };
        ok = m.vp <= V && m.vp >= lo_peak && fits(m.up, va, up) && fits(m.down, vb, down);
        if (ok) break;
      }
      if (!ok || (found && m.ticks() >= best.ticks())) continue;
      best = m;
      found = true;
    }
  return found;
}

// One stretch of a move on the tick grid: n ticks at jerk j. Where `pin`,
// the state after it is set exactly (acceleration 0, speed v, arc length
// sa + ds from the move's start sa), so that rounding does not drift over a
// long move.
struct TickPhase {
  long long n = 0;
  double j = 0;
  bool pin = false;
  double v = 0, ds = 0;
};

// The phases of an AlignedMove: the ramp up, the cruise, the ramp down;
// the cruise's ends pinned at vp, the end at vb.
std::vector<TickPhase> phases_of(const AlignedMove& m, double len, double h) {
  const double s_up = 0.5 * (m.va + m.vp) * static_cast<double>(m.up.ticks()) * h;
  return {{m.up.nj, m.up.J},
          {m.up.na, 0},
          {m.up.nj, -m.up.J, true, m.vp, s_up},
          {m.nc, 0, true, m.vp, s_up + m.vp * static_cast<double>(m.nc) * h},
          {m.down.nj, -m.down.J},
          {m.down.na, 0},
          {m.down.nj, m.down.J, true, m.vb, len}};
}

long long ticks_of(const std::vector<TickPhase>& ph) {
  long long n = 0;
  for (const TickPhase& f : ph) n += f.n;
  return n;
}

// The pieces of a move on the tick grid from arc length sa at time t, at
// speed v0 with acceleration 0; returns the end time.
double append_phases(std::vector<Piece>& out, double t, double sa, double v0, const std::vector<TickPhase>& ph,
                     double h) {
  double v = v0, a = 0, sc = sa;
  for (const TickPhase& f : ph) {
    if (f.n == 0) continue;
    Piece q;
    q.t0 = t;
    q.T = static_cast<double>(f.n) * h;
    q.s0 = sc;
    q.v0 = v;
    q.a0 = a;
    q.j = f.j;
    q.on_tick = true;
    out.push_back(q);
    t += q.T;
    sc = q.s(q.T);
    v = q.v(q.T);
    a = q.a(q.T);
    if (f.pin) sc = sa + f.ds, v = f.v, a = 0;
  }
  return t;
}

// The largest speed at which each per-axis and centripetal term that grows
// with the speed stays within its share when the speed is constant
// (acceleration and jerk along the path 0): the bound a cruise through
// frame f may hold.
double cruise_speed_bound(const Frame& f, const Limits& L, const PlanOptions& o, int dim) {
  auto root = [](double lim, double c, double k) { return c > 0 ? std::pow(lim / c, 1.0 / k) : 1e300; };
  double v = std::min(root(o.cen_a_share * L.a_cen, f.kappa, 2), root(o.axis_j_share * L.j_cen, f.q_norm, 3));
  for (int x = 0; x < dim; ++x)
    v = std::min({v, root(o.axis_v_share * L.v_axis[x], std::fabs(f.T[x]), 1),
                  root(o.axis_a_share * L.a_axis[x], std::fabs(f.K[x]), 2),
                  root(o.axis_j_share * L.j_axis[x], std::fabs(f.Q[x]), 3)});
  return v;
}

// Whether a move on the tick grid from arc length sa (at speed v0) keeps every per-axis
// and centripetal sum within the share speed_with fills: the exact
// trajectory's per-axis velocity, acceleration and jerk (dx = T v,
// ddx = K v^2 + T a, dddx = Q v^3 + 3 K v a + T j, with their signs), the
// centripetal acceleration and its jerk bound, at every tick and half tick,
// each side of a jerk switch. Where not, *fail_s (if given) receives the
// first arc length where a sum is exceeded. Adds the frames it evaluates to
// `frames` (Plan::check_frames).
bool phases_within_limits(const Path& p, double sa, double v0, const std::vector<TickPhase>& ph, double h,
                          const Limits& L, const PlanOptions& o, long long& frames, double* fail_s = nullptr) {
  std::vector<Piece> pcs;
  append_phases(pcs, 0, sa, v0, ph, h);
  const int d = p.dim();
  size_t ci = p.curve_at(sa);
  auto within = [&](double s, double v, double acc, double jerk) {
    while (ci + 1 < p.size() && s > p.offset(ci + 1)) ++ci;
    const double off = p.offset(ci), len = p.offset(ci + 1) - off;
    const Frame f = frame_at(p, ci, p.table(ci).u_at(std::clamp(s - off, 0.0, len)), s);
    if (f.kappa * v * v > o.cen_a_share * L.a_cen ||
        f.q_norm * v * v * v + 3 * f.kappa * v * std::fabs(acc) > o.axis_j_share * L.j_cen)
      return false;
    for (int x = 0; x < d; ++x)
      if (std::fabs(f.T[x] * v) > o.axis_v_share * L.v_axis[x] ||
          std::fabs(f.K[x] * v * v + f.T[x] * acc) > o.axis_a_share * L.a_axis[x] ||
          std::fabs(f.Q[x] * v * v * v + 3 * f.K[x] * v * acc + f.T[x] * jerk) > o.axis_j_share * L.j_axis[x])
        return false;
    return true;
  };
  for (const Piece& q : pcs) {
    const long long n = std::llround(q.T / h);
    for (long long k = 0; k <= 2 * n; ++k) {
      const double tau = 0.5 * h * static_cast<double>(k);
      ++frames;
      if (within(q.s(tau), q.v(tau), q.a(tau), q.j)) continue;
      if (fail_s) *fail_s = q.s(tau);
      return false;
    }
  }
  return true;
}

// Fewest ticks of a speed change by dv > 0 within r (AlignedRamp's counts,
// its jerk for dv).
AlignedRamp change_ramp(double dv, double h, const RampLimits& r) {
  AlignedRamp best;
  for (const AlignedRamp& c : ramp_counts(dv, h, r))
    if (ramp_speed_cap(c, h, r) >= dv && (best.nj == 0 || c.ticks() < best.ticks())) best = c;
  best.J = dv / (h * h * static_cast<double>(best.nj * (best.nj + best.na)));
  return best;
}

// A speed a move on the tick grid holds over [s0, s1] (arc length from the
// move's start); a level with s0 > s1 holds it wherever the dips before and
// after it leave room.
struct SpeedLevel {
  double w = 0, s0 = 1, s1 = 0;
  bool dip() const { return s0 <= s1; }
};

// The phases of a rest-to-rest move of length len through the levels: each
// change of speed a ramp (`up` where it rises, `down` where it falls), a
// fall ending before the lower level's stretch, a rise starting after the
// lower level's stretch, each cruise whole ticks. The level speeds (and the
// jerks with them) are then scaled by len / (the length they cover, at least
// len: the last cruise is rounded up), so that the move ends at len on a
// tick. Returns the index of a level with no room for its changes (the
// caller merges it away), or -1.
long long level_phases(const std::vector<SpeedLevel>& lv, double len, double h, const RampLimits& up,
                       const RampLimits& down, std::vector<TickPhase>& out) {
  struct Step {
    long long n;
    double dv;  // nominal change over the step (0: a cruise), signed
    AlignedRamp r;
    double s_end, v_end;  // nominal
  };
  std::vector<Step> steps;
  double s = 0, v = 0;
  auto change = [&](double to) {
    if (to == v) return;
    const AlignedRamp r = change_ramp(std::fabs(to - v), h, to > v ? up : down);
    s += 0.5 * (v + to) * static_cast<double>(r.ticks()) * h;
    steps.push_back({r.ticks(), to - v, r, s, to});
    v = to;
  };
  auto change_length = [&](double from, double to) {
    return 0.5 * (from + to) * static_cast<double>(change_ramp(std::fabs(to - from), h, to > from ? up : down).ticks()) * h;
  };
  for (size_t k = 0; k < lv.size(); ++k) {
    change(lv[k].w);
    const bool last = k + 1 == lv.size();
    const double next = last ? 0 : lv[k + 1].w;
    double end = 0;  // where the cruise at this level must end (no later where `fall`)
    bool fall = next < lv[k].w;
    if (fall) end = (last ? len : lv[k + 1].s0) - change_length(lv[k].w, next);
    else end = lv[k].s1;
    const double n_real = (end - s) / (lv[k].w * h);
    if (fall && n_real < -1e-9 && !last) return static_cast<long long>(k);
    if (last && n_real < -1e-9) return static_cast<long long>(k);
    long long n = fall && !last ? static_cast<long long>(std::floor(n_real + 1e-9)) : static_cast<long long>(std::ceil(n_real - 1e-9));
    n = std::max<long long>(0, n);
    s += lv[k].w * static_cast<double>(n) * h;
    steps.push_back({n, 0, {}, s, v});
  }
  change(0);
  const double lambda = len / s;
  out.clear();
  for (const Step& st : steps) {
    if (st.dv == 0) {
      out.push_back({st.n, 0, true, lambda * st.v_end, lambda * st.s_end});
      continue;
    }
    const double J = lambda * st.dv / (h * h * static_cast<double>(st.r.nj * (st.r.nj + st.r.na)));
    out.push_back({st.r.nj, J});
    out.push_back({st.r.na, 0});
    out.push_back({st.r.nj, -J, true, lambda * st.v_end, lambda * st.s_end});
  }
  return -1;
}

// The levels under the cruise bound g (samples at x, each lowered by its
// factor in mult): a dip over each run of samples below `high` (widened by
// pad, overlapping ones joined) at the lowest bound in the run, `high`
// between the dips and at the ends where a dip does not reach them.
std::vector<SpeedLevel> levels_below(const std::vector<double>& x, const std::vector<double>& g,
                                     const std::vector<double>& mult, double high, double pad, double len) {
  std::vector<SpeedLevel> dips;
  for (size_t i = 0; i < x.size();) {
    if (mult[i] * g[i] >= high) {
      ++i;
      continue;
    }
    SpeedLevel dip{high, std::max(0.0, x[i] - pad), 0};
    for (; i < x.size() && mult[i] * g[i] < high; ++i) dip.w = std::min(dip.w, mult[i] * g[i]);
    dip.s1 = std::min(len, x[i - 1] + pad);
    if (!dips.empty() && dips.back().s1 >= dip.s0) {
      dips.back().s1 = dip.s1;
      dips.back().w = std::min(dips.back().w, dip.w);
    } else {
      dips.push_back(dip);
    }
  }
  std::vector<SpeedLevel> out;
  for (const SpeedLevel& dip : dips) {
    if (dip.s0 > 0) out.push_back({high});
    out.push_back(dip);
  }
  if (out.empty() || out.back().s1 < len) out.push_back({high});
  return out;
}

// Removes the level k that has no room for its changes (level_phases):
// a level at `high` between two dips joins them into one at the lower
// speed; at either end it gives its place to the dip next to it; a dip at
// the end gives its place to the ramp down from the level before it.
// False where nothing is left to remove.
bool merge_level(std::vector<SpeedLevel>& lv, size_t k, double len) {
  if (lv.size() < 2) return false;
  if (lv[k].dip()) {
    if (k + 1 != lv.size()) return false;
    lv.pop_back();
    return true;
  }
  if (k == 0) {
    lv.erase(lv.begin());
    lv.front().s0 = 0;
  } else if (k + 1 == lv.size()) {
    lv.pop_back();
    lv.back().s1 = len;
  } else {
    lv[k - 1].s1 = lv[k + 1].s1;
    lv[k - 1].w = std::min(lv[k - 1].w, lv[k + 1].w);
    lv.erase(lv.begin() + static_cast<std::ptrdiff_t>(k), lv.begin() + static_cast<std::ptrdiff_t>(k) + 2);
  }
  return true;
}

// The slowest one-speed move curved_move checks, in times the move as
// planned (one slower than planned is not taken, but guides the level
// move; 4 keeps the Ferris drawing's plan at set (i) as with no bound).
constexpr double kSlowestCandidate = 4;

// One search of curved_move (retime_moves_between_stops) and what its
// result depended on beyond the path, the limits and the options: the
// move's ends and speed bound, and max_T, the time the move took as
// planned. max_T entered in two ways only: while no one-speed move had
// passed, each candidate's time t was compared with kSlowestCandidate max_T
// (those compared below it are up to below_max, the others from
// not_below_min); and where none passed, the level move was given
// ceil(max_T / h) ticks (level_ticks; -1 where one passed and the level move
// got its ticks). The last comparison, of the result with max_T, is the
// caller's.
struct CurvedSearch {
  bool found = false;
  std::vector<TickPhase> phases;
  double below_max = -std::numeric_limits<double>::infinity();
  double not_below_min = std::numeric_limits<double>::infinity();
  long long level_ticks = -1;
  // the ticks the level move gets where no one-speed move passed
  static long long level_ticks_of(double max_T, double h) {
    return static_cast<long long>(std::min(std::ceil(max_T / h - 1e-9), 1e15));
  }
  // whether the search would make every comparison the same for max_T
  bool holds_for(double max_T, double h) const {
    const double bound = kSlowestCandidate * max_T;
    return below_max < bound && !(not_below_min < bound) &&
           (level_ticks < 0 || level_ticks == level_ticks_of(max_T, h));
  }
};

}  // namespace

struct RetimeMemo::Searches {
  // by the move's ends and speed bound; several where max_T changed a comparison
  std::map<std::array<double, 3>, std::vector<CurvedSearch>> by_move;
};
RetimeMemo::RetimeMemo() : searches(std::make_unique<Searches>()) {}
RetimeMemo::~RetimeMemo() = default;

namespace {

// Candidate top levels of level_move, and the rounds of lowering the bound
// (or the changes' share of the limits) where the check failed, per top
// level; the lowest share the changes take.
constexpr int kTopLevels = 5, kLevelRounds = 24;
constexpr double kMinRamp = 0.4;

// Whether arc length s lies where the phases from sa (at rest) change the
// speed: in a piece with a jerk or an acceleration.
bool in_speed_change(double sa, const std::vector<TickPhase>& ph, double h, double s) {
  std::vector<Piece> pcs;
  append_phases(pcs, 0, sa, 0, ph, h);
  for (const Piece& q : pcs)
    if (s <= q.s(q.T)) return q.j != 0 || q.a0 != 0;
  return false;
}
// The factor by which a level with too little room for its changes is
// lowered, each time, before it is merged away.
constexpr double kLevelStep = 0.98;

// A rest-to-rest move on the tick grid over [sa, sb] that cruises at a top
// level and dips to a lower one over each stretch where the cruise bound
// (cruise_speed_bound) is below it: faster than one cruise speed for the
// whole move where that bound is low in a few places only (the tight spots
// of a smooth lobe, where the move would otherwise crawl from end to end).
// Checked as any aligned move (phases_within_limits); where the check fails
// (a change of speed where the curve turns), the bound is lowered around
// that place and the levels built anew. `single`: the fastest move with one
// cruise speed if one was found (its ramps lose at least `lost` seconds
// against cruising), which a result must beat: fewer than max_ticks ticks,
// a top level above v_floor. Returns whether one does.
bool level_move(const Path& p, const Limits& L, const PlanOptions& o, double sa, double sb, double V,
                const RampLimits& up, const RampLimits& down, long long max_ticks, double lost, double v_floor,
                std::vector<TickPhase>& best, long long& frames) {
  const double h = o.period, len = sb - sa;
  const int d = p.dim();
  const size_t n = static_cast<size_t>(std::clamp(std::ceil(len / (0.5 * V * h)), 8.0, 20000.0));
  std::vector<double> x(n + 1), g(n + 1);
  size_t ci = p.curve_at(sa);
  double t_bound = 0;  // no move is faster than this: cruising at the bound
  for (size_t i = 0; i <= n; ++i) {
    x[i] = len * static_cast<double>(i) / static_cast<double>(n);
    const double s = sa + x[i];
    while (ci + 1 < p.size() && s > p.offset(ci + 1)) ++ci;
    const double off = p.offset(ci), cl = p.offset(ci + 1) - off;
    const Frame f = frame_at(p, ci, p.table(ci).u_at(std::clamp(s - off, 0.0, cl)), s);
    g[i] = std::min(V, cruise_speed_bound(f, L, o, d));
    if (i > 0) t_bound += (x[i] - x[i - 1]) / std::max(g[i], g[i - 1]);
  }
  // the top level: the highest bound of the geometry (the ends, lifted to V
  // below, are ramps from and to rest and never reach it)
  const double top = *std::max_element(g.begin(), g.end()), pad = 2 * top * h;
  // near the ends no move from or to rest within up, down is faster than
  // speed_after: a bound above that holds whatever the levels
  for (size_t i = 0; i <= n && g[i] < V; ++i)
    if (g[i] >= speed_after(0, x[i], up.A, up.J)) g[i] = V;
    else if (x[i] > 0) break;
  for (size_t i = n + 1; i-- > 0 && g[i] < V;)
    if (g[i] >= speed_after(0, len - x[i], down.A, down.J)) g[i] = V;
    else if (x[i] < len) break;
  if (static_cast<double>(max_ticks) * h - t_bound - lost < 4 * h) return false;
  bool found = false;
  // where the check fails in a change of speed, the remedy is either to
  // lower the bound around the place (the dip moves the change away) or to
  // lower the changes' share of the limits: each is tried
  for (int c = 0; c < 2 * kTopLevels; ++c) {
    const double high = top * (1 - 0.05 * (c / 2));
    const bool lower_changes = c % 2 == 1;
    if (high <= v_floor) break;
    std::vector<double> mult(n + 1, 1.0);
    double ramp = 1;  // the share of up and down the changes of level take
    for (int round = 0; round < kLevelRounds; ++round) {
      std::vector<SpeedLevel> lv = levels_below(x, g, mult, high, pad, len);
      std::vector<TickPhase> ph;
      bool built = false;
      const RampLimits up_r{up.A * ramp, up.J * ramp}, down_r{down.A * ramp, down.J * ramp};
      for (long long k; !built;) {
        k = level_phases(lv, len, h, up_r, down_r, ph);
        built = k < 0;
        if (built) break;
        // a level between dips (or a dip and an end) with too little room
        // for its changes goes lower while it stays above its neighbours
        const size_t u = static_cast<size_t>(k);
        double below = 0;
        if (u > 0) below = lv[u - 1].w;
        if (u + 1 < lv.size()) below = std::max(below, lv[u + 1].w);
        if (!lv[u].dip() && kLevelStep * lv[u].w > below) lv[u].w *= kLevelStep;
        else if (!merge_level(lv, u, len)) break;
      }
      if (!built || ticks_of(ph) >= max_ticks) break;  // lowering the bound only slows the move
      double fail_s = 0;
      if (phases_within_limits(p, sa, 0, ph, h, L, o, frames, &fail_s)) {
        best = std::move(ph);
        max_ticks = ticks_of(best);
        found = true;
        break;
      }
      // a change of speed where the curve turns takes a lower jerk and
      // acceleration; a cruise, a lower bound around the place
      if (lower_changes && ramp > kMinRamp && in_speed_change(sa, ph, h, fail_s)) {
        ramp *= 0.85;
        continue;
      }
      for (size_t i = 0; i <= n; ++i)
        if (std::fabs(x[i] - (fail_s - sa)) <= 2 * pad) mult[i] *= 0.95;
    }
  }
  return found;
}

// Speed caps sorted by start, with the largest end so far, to visit the
// caps that overlap an interval without going through all of them (a
// toolpath has a cap per move: on a drawing of 27 000 moves and 3 600 stops
// the loop over every cap for every move between stops took a fifth of the
// planning).
class CapsByStart {
 public:
  explicit CapsByStart(std::vector<SpeedCap> caps) : caps_(std::move(caps)) {
    std::sort(caps_.begin(), caps_.end(), [](const SpeedCap& a, const SpeedCap& b) { return a.s0 < b.s0; });
    double m = -std::numeric_limits<double>::infinity();
    for (const SpeedCap& c : caps_) max_end_.push_back(m = std::max(m, c.s1));
  }
  // Calls f(cap) for every cap with s1 > lo and s0 < hi.
  template <class F>
  void overlapping(double lo, double hi, F&& f) const {
    size_t i = static_cast<size_t>(std::lower_bound(caps_.begin(), caps_.end(), hi,
                                                    [](const SpeedCap& c, double x) { return c.s0 < x; }) -
                                   caps_.begin());
    while (i > 0 && max_end_[i - 1] > lo) {
      --i;
      if (caps_[i].s1 > lo) f(caps_[i]);
    }
  }

 private:
  std::vector<SpeedCap> caps_;
  std::vector<double> max_end_;  // the largest s1 of caps_[0..i]
};

// Moves between two stops, re-timed on the tick grid
// (PlanOptions::align_straight_moves). The profile of a block between two
// stops switches its jerk anywhere within a tick; a polynomial fitted to the
// tick's samples then overshoots the jerk (up to about 1.5x), which is why
// the profile keeps its jerk at tan_j_share of the limits. On a straight
// move each axis is x0 + T_a s(t): where the jerk switches only on ticks,
// s(t) is one cubic per tick, which the quintic of each tick (and of each
// run of ticks at one jerk) reproduces exactly, so the move may use the
// per-axis jerk at axis_j_share (and j_tan at the same share). A move is
// re-timed only where that is faster, including the rest (under a tick)
// that puts its start on a tick; a move with a speed cap over a part of it
// (a repair's) or a forced station inside (a window's commit) is left as
// planned.
// A curved move between two stops (align_curved_moves: curves joined
// tangentially, such as a run of CAM chords fitted by one smoothing curve, a
// raster row over a surface, a leg, a blend and a leg) is re-timed the same
// way where the exact trajectory of the aligned move keeps every per-axis
// and centripetal sum within its share at every tick and half tick
// (phases_within_limits); of a few shares of the jerk and the acceleration,
// each with its largest such speed, the fastest move is taken, and the knots
// and joins inside cap its speed as in the plan (knot_speed_bound,
// join_bound), or through speed levels where that is faster (level_move).
// Each block of the profile between two stations (acceleration 0 at both)
// is re-timed the same way on its own, from its station's speed to the
// next (align_blocks), and the move as a whole only where it is faster
// than its blocks. Between ticks the trajectory is smooth (its jerk
// switches on ticks), so the quintic of each tick follows it closely; the
// fit's checks at every tick decide, as for any plan.
void retime_moves_between_stops(const Path& p, const Limits& L, const PlanOptions& o, Plan& plan, RetimeMemo* memo) {
  const double h = o.period, tol = 1e-9 * std::max(1.0, plan.length);
  const int d = p.dim();
  auto at_rest = [](const Piece& q) { return q.v0 == 0 && q.a0 == 0; };
  // the speed caps over the whole of [sa, sb] lower V; one over a part of it
  // (a repair's), or a forced station inside (a window's commit), keeps the move as planned
  const CapsByStart caps(o.caps);
  auto caps_allow = [&](double sa, double sb, double& V) {
    bool whole = true;
    caps.overlapping(sa + tol, sb - tol, [&](const SpeedCap& c) {
      if (!(c.v > 0)) return;
      if (c.s0 > sa + tol || c.s1 < sb - tol) whole = false;
      V = std::min(V, c.v);
    });
    if (!whole) return false;
    for (double fs : o.force_stations)
      if (fs > sa + tol && fs < sb - tol) return false;
    return true;
  };
  // the spans of curve ci at both ends of its part of [sa, sb]
  auto spans = [&](size_t ci, double sa, double sb, int& s0, int& s1) {
    const ArcTable& tab = p.table(ci);
    const double off = p.offset(ci), len = p.offset(ci + 1) - off;
    s0 = p.curve(ci).find_span(tab.u_at(std::clamp(sa - off + tol, 0.0, len)));
    s1 = p.curve(ci).find_span(tab.u_at(std::clamp(sb - off - tol, 0.0, len)));
  };
  // the speed bounds of the knots and of the joins of curves inside [sa, sb]
  // lower V (as in the plan: knot_speed_bound, join_bound); false where a
  // join is not tangent (a corner, a cusp: a move ends there)
  auto joins_allow = [&](double sa, double sb, double& V) {
    const size_t c0 = p.curve_at(sa + tol), c1 = p.curve_at(sb - tol);
    for (size_t ci = c0; ci <= c1; ++ci) {
      if (ci > c0) {
        const Frame e = frame_at(p, ci - 1, p.curve(ci - 1).u_end(), p.offset(ci));
        const Frame f = frame_at(p, ci, p.curve(ci).u_begin(), p.offset(ci));
        const JoinBound jb = join_bound(p, ci, e, f, L, o);
        if (!jb.tangent) return false;
        V = std::min(V, jb.v);
      }
      int s0 = 0, s1 = 0;
      spans(ci, sa, sb, s0, s1);
      for (int sp = s0 + 1; sp <= s1; ++sp) V = std::min(V, knot_speed_bound(p, ci, sp, L, o));
    }
    return V > 0;
  };
  // the unit tangent of the straight span holding [sa, sb], if one does
  auto straight = [&](double sa, double sb, double* T) {
    const size_t ci = p.curve_at(0.5 * (sa + sb));
    const geo::Curve& c = p.curve(ci);
    int s0 = 0, s1 = 0;
    if (p.curve_at(sa + tol) != ci || p.curve_at(sb - tol) != ci || c.degree() != 1 || c.rational()) return false;
    spans(ci, sa, sb, s0, s1);
    if (s0 != s1) return false;
    const Frame f = frame_at(p, ci, p.table(ci).u_at(0.5 * (sa + sb) - p.offset(ci)), 0.5 * (sa + sb));
    for (int a = 0; a < d; ++a) T[a] = f.T[a];
    return true;
  };
  // the fastest aligned move over [sa, sb] within the limits
  // (phases_within_limits), if it is shorter than max_T: for
  // each of a few shares of the tangential jerk and acceleration, given to
  // both ramps, the largest speed by bisection (a lower speed lowers every
  // term); then, at that speed, each ramp on its own takes the share that
  // makes the move fastest (the geometry where a move speeds up is not
  // where it slows down); then a move through speed levels (level_move),
  // where it is faster still
  auto search_curved_move = [&](double sa, double sb, double V, double max_T) {
    CurvedSearch cs;
    AlignedMove best;
    const double A0 = o.tan_a_share * L.a_tan, J0 = o.axis_j_share * L.j_tan;
    std::vector<RampLimits> shares;
    for (double jf : {1.0, 0.95, 0.9, 0.85, 0.7, 0.55})
      for (double af : {1.0, 0.75, 0.5}) shares.push_back({af * A0, jf * J0});
    bool found = false;
    RampLimits best_up, best_down;
    // a one-speed move slower than the planned one (max_T) is not taken,
    // but its shares and speed guide the level move; one slower than
    // kSlowestCandidate times that is not checked, so that the checks' work
    // stays within a multiple of the move's planned ticks (host/planner/README.md,
    // step 5; where no speed passed, the bisection went on down to 1/1024 of V)
    double best_v = 0, best_T = kSlowestCandidate * max_T;
    // a candidate's time against best_T (while none passed, against max_T: recorded)
    auto faster_than_best = [&](const AlignedMove& m) {
      const double t = static_cast<double>(m.ticks()) * h;
      const bool below = t < best_T;
      if (!found) (below ? cs.below_max = std::max(cs.below_max, t) : cs.not_below_min = std::min(cs.not_below_min, t));
      return below;
    };
    auto try_move = [&](double v, const RampLimits& up, const RampLimits& down, bool& faster) {
      AlignedMove m;
      faster = aligned_move(sb - sa, h, 0, 0, v, up, down, m) && faster_than_best(m);
      if (!faster || !phases_within_limits(p, sa, 0, phases_of(m, sb - sa, h), h, L, o, plan.check_frames))
        return false;
      best = m, best_T = static_cast<double>(m.ticks()) * h, found = true;
      best_up = up, best_down = down, best_v = v;
      return true;
    };
    for (const RampLimits& r : shares) {
      bool faster = false;
      if (try_move(V, r, r, faster) || !faster) continue;  // within the limits, or not faster even at V
      double lo = 0, hi = V;  // hi: beyond the limits; lo: within them, or too slow
      for (int it = 0; it < 10; ++it) {
        const double mid = 0.5 * (lo + hi);
        (try_move(mid, r, r, faster) || !faster ? lo : hi) = mid;
      }
    }
    if (found) {
      for (int ramp = 0; ramp < 2; ++ramp) {
        const RampLimits up = best_up, down = best_down;
        for (const RampLimits& r : shares) {
          bool faster = false;
          try_move(best_v, ramp == 0 ? r : up, ramp == 0 ? down : r, faster);
        }
      }
      cs.phases = phases_of(best, sb - sa, h);
    } else {
      best_up = best_down = shares.front();
      cs.level_ticks = CurvedSearch::level_ticks_of(max_T, h);
    }
    // a level move must take fewer ticks than the one-speed move, or than max_T
    const long long max_ticks = found ? best.ticks() : cs.level_ticks;
    const double lost = found ? 0.5 * static_cast<double>(best.up.ticks() + best.down.ticks()) * h : 0;
    if (o.align_level_moves &&
        level_move(p, L, o, sa, sb, V, best_up, best_down, max_ticks, lost, found ? best.vp : 0, cs.phases,
                   plan.check_frames))
      found = true;
    cs.found = found;
    return cs;
  };
  // The search of an earlier plan where it holds (RetimeMemo), else a new one.
  auto curved_move = [&](double sa, double sb, double V, double max_T, std::vector<TickPhase>& phases) {
    std::vector<CurvedSearch>* earlier = memo ? &memo->searches->by_move[{sa, sb, V}] : nullptr;
    const CurvedSearch* cs = nullptr;
    if (earlier)
      for (const CurvedSearch& e : *earlier)
        if (e.holds_for(max_T, h)) cs = &e;
    CurvedSearch fresh;
    if (cs) {
      ++memo->reused;
    } else {
      fresh = search_curved_move(sa, sb, V, max_T);
      if (memo) ++memo->searched;
      cs = earlier ? &earlier->emplace_back(std::move(fresh)) : &fresh;
    }
    phases = cs->phases;
    return cs->found && static_cast<double>(ticks_of(phases)) * h < max_T;
  };
  // The time from t to the next tick (ticks at m h - tick_offset).
  auto rest_to_tick = [&](double t) {
    const double ph = (t + o.tick_offset) / h;
    return std::max(0.0, (std::ceil(ph - 1e-9) - ph) * h);
  };
  // That rest (at speed v, acceleration 0, from arc length s at time t),
  // appended to dst; returns its duration.
  auto to_tick = [&](std::vector<Piece>& dst, double t, double s, double v) {
    const double rest = rest_to_tick(t);
    if (rest > 0) {
      Piece r;
      r.t0 = t;
      r.T = rest;
      r.s0 = s;
      r.v0 = v;
      dst.push_back(r);
    }
    return rest;
  };
  // The fastest phases of a block from va to vb over [sa, sb] within the
  // limits (phases_within_limits) of fewer than max_ticks ticks: for each of
  // a few shares of the tangential jerk, the largest peak speed by
  // bisection.
  auto curved_block = [&](double sa, double sb, double va, double vb, double V, long long max_ticks,
                          std::vector<TickPhase>& best) {
    const double A0 = o.tan_a_share * L.a_tan, J0 = o.axis_j_share * L.j_tan;
    bool found = false;
    for (double jf : {1.0, 0.85, 0.7}) {
      const RampLimits r{A0, jf * J0};
      std::vector<TickPhase> ph;
      auto fits = [&](double v) {
        AlignedMove m;
        if (!aligned_move(sb - sa, h, va, vb, v, r, r, m) || m.ticks() >= max_ticks) return false;
        ph = phases_of(m, sb - sa, h);
        if (!phases_within_limits(p, sa, va, ph, h, L, o, plan.check_frames)) return false;
        best = ph, max_ticks = ticks_of(ph), found = true;
        return true;
      };
      if (fits(V)) continue;
      double lo = std::max(va, vb), hi = V;
      for (int it = 0; it < 6; ++it) {
        const double mid = 0.5 * (lo + hi);
        (fits(mid) ? lo : hi) = mid;
      }
    }
    return found;
  };
  std::vector<double> station_s;
  for (const Station& st : plan.stations) station_s.push_back(st.s);
  std::sort(station_s.begin(), station_s.end());
  auto at_station = [&](const Piece& q) {
    if (q.a0 != 0) return false;
    const auto it = std::lower_bound(station_s.begin(), station_s.end(), q.s0 - tol);
    return it != station_s.end() && *it <= q.s0 + tol;
  };
  // The pieces [i0, i1) (up to the next rest), from time t, into dst, each
  // block of the profile between two stations (acceleration 0 at both; the
  // rest at the end) re-timed on the tick grid on its own where that is
  // faster, after a rest of less than a tick at the station's speed that
  // puts it on a tick; any other piece as planned. Returns the end time.
  auto retime_blocks = [&](size_t i0, size_t i1, double t, std::vector<Piece>& dst) {
    for (size_t k = i0; k < i1;) {
      const Piece& qa = plan.pieces[k];
      size_t kb = k + 1;  // the piece that starts the next block
      while (kb < i1 && !at_station(plan.pieces[kb])) ++kb;
      const double sa = qa.s0, sb = kb < plan.pieces.size() ? plan.pieces[kb].s0 : plan.length;
      const double va = qa.v0, vb = kb < plan.pieces.size() ? plan.pieces[kb].v0 : 0;
      const double t_old = plan.pieces[kb - 1].t0 + plan.pieces[kb - 1].T - qa.t0;
      double V = L.feed;
      bool use = o.align_blocks && !qa.dwell && (k == i0 || at_station(qa)) && qa.a0 == 0 && t_old > 6 * h &&
                 sb - sa > tol && caps_allow(sa, sb, V) && joins_allow(sa, sb, V) && V >= std::max(va, vb);
      std::vector<TickPhase> ph;
      if (use) {
        const double rest = rest_to_tick(t);
        const long long max_ticks = static_cast<long long>(std::ceil((t_old - rest) / h - 1e-9));
        use = curved_block(sa + va * rest, sb, va, vb, V, max_ticks, ph);
      }
      if (use) {
        const double rest = to_tick(dst, t, sa, va);
        t = append_phases(dst, t + rest, sa + va * rest, va, ph, h);
      } else {
        for (size_t m = k; m < kb; ++m) {
          dst.push_back(plan.pieces[m]);
          dst.back().t0 += t - qa.t0;
        }
        t += t_old;
      }
      k = kb;
    }
    return t;
  };
  std::vector<Piece> out, blocks;
  out.reserve(plan.pieces.size());
  double shift = 0;  // time gained (negative) or lost so far
  size_t i = 0;
  while (i < plan.pieces.size()) {
    const Piece& q0 = plan.pieces[i];
    size_t i1 = i + 1;
    if (!q0.dwell)
      while (i1 < plan.pieces.size() && !plan.pieces[i1].dwell && !at_rest(plan.pieces[i1])) ++i1;
    const double sa = q0.s0, sb = i1 < plan.pieces.size() ? plan.pieces[i1].s0 : plan.length;
    const double t_start = q0.t0 + shift, old_T = plan.pieces[i1 - 1].t0 + plan.pieces[i1 - 1].T - q0.t0;
    // each block on its own (or the pieces as planned)
    blocks.clear();
    double t_end = retime_blocks(i, i1, t_start, blocks);
    // the whole move from rest to rest at once, where that is faster still
    double T[kMaxAxes] = {};
    AlignedMove m;
    std::vector<TickPhase> phases;
    double V = L.feed;
    bool use = !q0.dwell && at_rest(q0) && sb - sa > tol && caps_allow(sa, sb, V);
    const double rest = rest_to_tick(t_start);
    const double max_T = std::min(old_T, t_end - t_start);
    if (use && straight(sa, sb, T)) {
      double A = o.tan_a_share * L.a_tan, J = o.axis_j_share * L.j_tan;
      for (int a = 0; a < d; ++a) {
        const double ta = std::fabs(T[a]);
        if (ta == 0) continue;
        V = std::min(V, o.axis_v_share * L.v_axis[a] / ta);
        A = std::min(A, o.axis_a_share * L.a_axis[a] / ta);
        J = std::min(J, o.axis_j_share * L.j_axis[a] / ta);
      }
      use = aligned_move(sb - sa, h, 0, 0, V, {A, J}, {A, J}, m) &&
            rest + static_cast<double>(m.ticks()) * h < max_T - 1e-12;
      if (use) phases = phases_of(m, sb - sa, h);
    } else if (use) {
      // no curve runs faster than the axes together: a program's F far above them (LinuxCNC's
      // 3D_Chips.ngc: F2250000) would otherwise leave the bisections and the level move's
      // samples of the cruise bound a thousand times too coarse
      V = std::min(V, L.top_speed(d));
      use = o.align_curved_moves && joins_allow(sa, sb, V) && curved_move(sa, sb, V, max_T - rest - 1e-12, phases);
    }
    if (use) {
      double t = t_start + to_tick(out, t_start, sa, 0);
      t_end = append_phases(out, t, sa, 0, phases, h);
    } else {
      out.insert(out.end(), blocks.begin(), blocks.end());
    }
    shift += (t_end - t_start) - old_T;
    i = i1;
  }
  plan.pieces = std::move(out);
}

}  // namespace

Plan plan_path(const Path& p, const Limits& limits, const PlanOptions& o, RetimeMemo* retimed) {
  limits.validate();
  Limits L = limits;
  L.feed *= o.feed_share;
  if (const std::string m = util::tick_period_problem(o.period); !m.empty()) throw PlanError(m);
  if (p.size() == 0) throw PlanError("empty path");
  const int d = p.dim();
  double amin = L.a_axis[0], jmin = L.j_axis[0];
  for (int a = 1; a < d; ++a) {
    amin = std::min(amin, L.a_axis[a]);
    jmin = std::min(jmin, L.j_axis[a]);
  }
  Plan plan;
  // the tangential limits; the per-axis sums (speed_limit) take what each
  // axis has left after the geometry, point by point
  plan.A_t = o.tan_a_share * L.a_tan;
  plan.J_t = o.tan_j_share * std::min(L.j_tan, jmin);
  plan.length = p.length();
  Grid g = build_grid(p, L, o, plan.A_t, plan.J_t);
  plan.grid_points = static_cast<int>(g.s.size());
  const size_t n = g.s.size();
  std::vector<char> forced(n, 0);
  std::vector<BlockMemo> memo;  // blocks of the previous pass (most are unchanged by new stations)
  std::vector<char> changed;
  std::vector<size_t> idx, lidx;
  const double tau = o.jerk_phase_ticks * o.period;
  bool raise_tried = false;
  std::vector<Piece> first_pieces;  // the profile before raise_accels, while the raised one is planned
  std::vector<Station> first_stations;
  for (int iter = 0; iter < 10000; ++iter) {
    plan.stations = stations_from(g, forced, L.feed, 0, n - 1, plan.A_t, plan.J_t, tau, idx);
    const auto cap = caps_for(g, plan.stations, idx, L.feed);
    const auto acc = accels_for(g, idx);
    plan.pieces = plan_blocks(plan.stations, cap, acc, plan.J_t, memo, changed, tau);
    // The profile must stay under v_lim at every grid point. Every local
    // maximum of the violation ratio becomes a station. A block identical to
    // one of the previous pass had no violation then (else it would have a
    // new station), so only the grid points of changed blocks are evaluated.
    SpeedAtS v_at{plan.pieces};
    size_t blk = 0;
    const auto marked = mark_violations(g, forced, v_at, 0, n - 1, L.feed, [&](size_t i) {
      while (blk + 1 < changed.size() && idx[blk + 1] <= i) ++blk;
      return changed.empty() || changed[blk] != 0;
    });
    if (marked.empty() && o.accel_at_profile_speed && !raise_tried) {
      raise_tried = true;
      if (raise_accels(g, idx, plan.stations, memo, plan.A_t, plan.J_t)) {
        first_pieces = std::move(plan.pieces);
        first_stations = std::move(plan.stations);
        continue;
      }
    }
    if (marked.empty()) {
      // the profile with the raised accelerations is kept only if it is
      // faster as a whole (both keep every bound; its stations, placed
      // anew, may cost more than its ramps gain)
      if (!first_pieces.empty() && first_pieces.back().t0 + first_pieces.back().T <= plan.duration()) {
        plan.pieces = std::move(first_pieces);
        plan.stations = std::move(first_stations);
      }
      std::vector<PlanOptions::Dwell> dwells = o.dwells;
      if (o.corner_stops && o.corner_rest > 0) {
        // one rest per stop (a G4 dwell there already is one)
        const double tol = 1e-6 * std::max(1.0, plan.length);
        auto rests_at = [&](double s) {
          for (const auto& dw : dwells)
            if (std::fabs(dw.s - s) <= tol) return true;
          return false;
        };
        for (size_t i = 0; i < n; ++i)
          if (g.corner[i] && g.vlim[i] == 0 && g.s[i] > 0 && g.s[i] < plan.length && !rests_at(g.s[i]))
            dwells.push_back({g.s[i], o.corner_rest});
      }
      insert_dwells(plan, std::move(dwells));
      if (retimed && retimed->path != &p) {  // searches of another path hold nothing here
        retimed->searches->by_move.clear();
        retimed->path = &p;
      }
      if (o.align_straight_moves) retime_moves_between_stops(p, L, o, plan, retimed);
      return plan;
    }
    plan.refinements += static_cast<int>(marked.size());
    // Local refinement: a block that violated is re-planned alone, between
    // its two stations at this pass's speeds, adding stations until it is
    // under v_lim (where v_lim rises slowly this is a staircase of many
    // steps: done here, each step costs the block, not the whole path). The
    // next global pass re-checks everything with the propagated speeds.
    std::vector<size_t> blocks;
    for (size_t i : marked) blocks.push_back(static_cast<size_t>(std::upper_bound(idx.begin(), idx.end(), i) - idx.begin()) - 1);
    blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
    // The block is swept from the left: each round plans from the last
    // station before the first violation found (at its planned speed) to the
    // block's end and stops scanning at that violation, so a staircase of k
    // steps over m grid points costs O(m + k) evaluations, not O(m k).
    for (size_t b : blocks) {
      size_t lo = idx[b];
      double v_lo = plan.stations[b].v;
      const size_t ib = idx[b + 1];
      // the local stations, their grid indices and block caps are kept up to
      // date incrementally (the same lists stations_from / caps_for would build)
      auto loc = stations_from(g, forced, L.feed, lo, ib, plan.A_t, plan.J_t, tau, lidx);
      auto lcap = caps_for(g, loc, lidx, L.feed);
      auto lacc = accels_for(g, lidx);
      loc.back().vmax = plan.stations[b + 1].v;
      for (int it = 0; it < 100000 && lo + 1 < ib; ++it) {
        loc.front().vmax = v_lo;
        const auto lp = plan_blocks(loc, lcap, lacc, plan.J_t, tau);
        SpeedAtS lv{lp};
        const auto lm = mark_violations(g, forced, lv, lo + 1, ib - 1, L.feed, [](size_t) { return true; }, true);
        if (lm.empty()) break;
        ++plan.refinements;
        const size_t i1 = lm[0];
        const size_t k = static_cast<size_t>(std::upper_bound(lidx.begin(), lidx.end(), i1) - lidx.begin()) - 1;
        lo = lidx[k];
        v_lo = loc[k].v;
        // drop the stations before lo; the new station i1 splits block 0
        loc.erase(loc.begin(), loc.begin() + k);
        lidx.erase(lidx.begin(), lidx.begin() + k);
        lcap.erase(lcap.begin(), lcap.begin() + k);
        lacc.erase(lacc.begin(), lacc.begin() + k);
        loc.insert(loc.begin() + 1, Station{g.s[i1], g.vlim[i1], 0});
        lidx.insert(lidx.begin() + 1, i1);
        auto cap_of = [&](size_t a, size_t c) {
          double m = std::max(g.vlim[a], g.vlim[c]);
          for (size_t i = a; i <= c; ++i) m = std::max(m, g.vlim[i]);
          return std::min(m, L.feed);
        };
        lcap[0] = cap_of(lidx[1], lidx[2]);
        lcap.insert(lcap.begin(), cap_of(lidx[0], lidx[1]));
        lacc[0] = block_A(g, lidx[1], lidx[2]);
        lacc.insert(lacc.begin(), block_A(g, lidx[0], lidx[1]));
      }
    }
  }
  throw PlanError("feed planning did not converge");
}

PathState state_at(const Plan& plan, double t, int* hint) {
  if (plan.pieces.empty() || t >= plan.duration()) return {plan.length, 0, 0, 0};
  if (t <= 0) return {0, plan.pieces.front().v0, plan.pieces.front().a0, plan.pieces.front().j};
  const int i = piece_at(plan.pieces, t, hint ? *hint : 0);
  if (hint) *hint = i;
  const Piece& q = plan.pieces[i];
  const double tau = t - q.t0;
  return {std::min(q.s(tau), plan.length), std::max(0.0, q.v(tau)), q.a(tau), q.j};
}

std::vector<TickSample> sample_ticks(const Path& p, const Plan& plan, double period) {
  std::vector<TickSample> out;
  sample_ticks(p, plan, period, out);
  return out;
}

void sample_ticks(const Path& p, const Plan& plan, double period, std::vector<TickSample>& out) {
  const long long n = static_cast<long long>(std::ceil(plan.duration() / period - 1e-9));
  out.clear();
  append_ticks_range(p, plan, period, 0.0, 0, n, out);
}

std::vector<TickSample> sample_ticks_range(const Path& p, const Plan& plan, double period, double t_offset,
                                           long long k_first, long long k_last) {
  std::vector<TickSample> out;
  append_ticks_range(p, plan, period, t_offset, k_first, k_last, out);
  return out;
}

TickSample sample_plan(const Path& p, const Plan& plan, double tp, double t, SampleHints& hints) {
  const PathState ps = state_at(plan, tp, &hints.piece);
  const size_t cj = std::min(p.curve_at(ps.s), p.size() - 1);
  const double sl = std::clamp(ps.s - p.offset(cj), 0.0, p.arclength(cj).total());
  if (cj != hints.curve) {
    hints.curve = cj;
    hints.table = 0;
  }
  const size_t ci = cj;
  const double u = p.table(ci).u_at(sl, hints.table);
  const int span = p.table(ci).span_of(hints.table);
  const Frame f = frame_at(p, ci, u, ps.s, span);
  TickSample ts{};
  ts.t = t;
  ts.tp = tp;
  ts.s = ps.s;
  ts.v = ps.v;
  ts.a = ps.a;
  ts.j = ps.j;
  ts.u = u;
  ts.curve = ci;
  ts.span = span;
  for (int a = 0; a < p.dim(); ++a) {
    ts.x[a] = f.C[a];
    ts.dx[a] = f.T[a] * ps.v;
    ts.ddx[a] = f.K[a] * ps.v * ps.v + f.T[a] * ps.a;
    ts.dddx[a] = f.Q[a] * ps.v * ps.v * ps.v + 3 * f.K[a] * ps.v * ps.a + f.T[a] * ps.j;
  }
  ts.a_cen = f.kappa * ps.v * ps.v;
  ts.j_cen_geo = f.q_norm * ps.v * ps.v * ps.v + 3 * f.kappa * ps.v * std::fabs(ps.a);
  return ts;
}

void append_ticks_range(const Path& p, const Plan& plan, double period, double t_offset, long long k_first,
                        long long k_last, std::vector<TickSample>& out, long long k_origin) {
  if (k_last < k_first) return;
  const size_t need = out.size() + static_cast<size_t>(k_last - k_first + 1);
  if (out.capacity() < need) out.reserve(need + need / 8);
  SampleHints hints;
  for (long long k = k_first; k <= k_last; ++k)
    out.push_back(sample_plan(p, plan, static_cast<double>(k - k_origin) * period - t_offset, k * period, hints));
}

Peaks peaks_of(const std::vector<TickSample>& ts, int dim) {
  Peaks pk;
  for (const auto& t : ts) {
    for (int a = 0; a < dim; ++a) {
      pk.v_axis[a] = std::max(pk.v_axis[a], std::fabs(t.dx[a]));
      pk.a_axis[a] = std::max(pk.a_axis[a], std::fabs(t.ddx[a]));
      pk.j_axis[a] = std::max(pk.j_axis[a], std::fabs(t.dddx[a]));
    }
    pk.feed = std::max(pk.feed, t.v);
    pk.a_tan = std::max(pk.a_tan, std::fabs(t.a));
    pk.j_tan = std::max(pk.j_tan, std::fabs(t.j));
    pk.a_cen = std::max(pk.a_cen, t.a_cen);
    pk.j_cen = std::max(pk.j_cen, t.j_cen_geo);
  }
  return pk;
}

double tick_ratio(const TickSample& t, const Limits& L, int dim) {
  double w = std::max({t.v / L.feed, std::fabs(t.a) / L.a_tan, std::fabs(t.j) / L.j_tan, t.a_cen / L.a_cen,
                       t.j_cen_geo / L.j_cen});
  for (int a = 0; a < dim; ++a)
    w = std::max({w, std::fabs(t.dx[a]) / L.v_axis[a], std::fabs(t.ddx[a]) / L.a_axis[a],
                  std::fabs(t.dddx[a]) / L.j_axis[a]});
  return w;
}

double Limits::top_speed(int dim) const {
  double v2 = 0;
  for (int a = 0; a < dim; ++a) v2 += v_axis[a] * v_axis[a];
  return std::min(feed, std::sqrt(v2));
}

double worst_ratio(const Peaks& pk, const Limits& L, int dim, std::string* which) {
  double w = 0;
  auto chk = [&](double v, double lim, const std::string& name) {
    if (v / lim > w) {
      w = v / lim;
      if (which) *which = name;
    }
  };
  for (int a = 0; a < dim; ++a) {
    const std::string ax = L.axis(a);
    chk(pk.v_axis[a], L.v_axis[a], "v_axis." + ax);
    chk(pk.a_axis[a], L.a_axis[a], "a_axis." + ax);
    chk(pk.j_axis[a], L.j_axis[a], "j_axis." + ax);
  }
  chk(pk.feed, L.feed, "feed");
  chk(pk.a_tan, L.a_tan, "a_tan");
  chk(pk.j_tan, L.j_tan, "j_tan");
  chk(pk.a_cen, L.a_cen, "a_cen");
  chk(pk.j_cen, L.j_cen, "j_cen");
  return w;
}

}  // namespace traj::plan
