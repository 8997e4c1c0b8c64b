// SPDX-License-Identifier: Apache-2.0
#include "planner/segments.hpp"

#include "planner/fine_check.hpp"
#include "planner/sampled.hpp"

#include <algorithm>
#include <cmath>

namespace traj::plan {
namespace {

double poly_val(const double* c, int n, double t) {
  double v = 0;
  for (int j = n; j >= 0; --j) v = v * t + c[j];
  return v;
}

// q(t) - q(0) = c[1] t + ... + c[n] t^n: rounded at the scale of the travel, not of c[0].
double travel(const double* c, int n, double t) { return t * poly_val(c + 1, n - 1, t); }

}  // namespace

double TimeSegment::eval(int axis, double tau, int deriv) const {
  const auto& c = coef[axis];
  double d[6];
  for (int j = 0; j < 6; ++j) d[j] = c[j];
  for (int r = 0; r < deriv; ++r)
    for (int j = 0; j < 6; ++j) d[j] = j + 1 < 6 ? d[j + 1] * (j + 1) : 0;
  double v = 0;
  for (int j = 5; j >= 0; --j) v = v * tau + d[j];
  return v;
}

double TimeSegment::travel(int axis, double tau) const { return plan::travel(coef[axis].data(), degree, tau); }

long double TimeSegment::travel_ld(int axis, long double tau) const {
  long double v = 0;
  for (int j = degree; j >= 1; --j) v = v * tau + coef[axis][j];
  return v * tau;
}

namespace {

// Real roots of c[0..n] (n <= 5) in the open interval (a, b), ascending.
// Recursive isolation: the roots of the derivative split (a, b) into pieces
// where the polynomial is monotone; each piece with a sign change holds one
// root, found by a bracketing Illinois (regula falsi) iteration.
int roots_in(const double* c, int n, double a, double b, double* out) {
  while (n > 0 && c[n] == 0) --n;
  if (n <= 0) return 0;
  if (n == 1) {
    const double r = -c[0] / c[1];
    if (r > a && r < b) {
      out[0] = r;
      return 1;
    }
    return 0;
  }
  double d[6];
  for (int j = 0; j < n; ++j) d[j] = c[j + 1] * (j + 1);
  double pts[8];
  pts[0] = a;
  const int m = roots_in(d, n - 1, a, b, pts + 1);
  pts[m + 1] = b;
  int k = 0;
  for (int i = 0; i <= m; ++i) {
    double x0 = pts[i], x1 = pts[i + 1];
    double f0 = poly_val(c, n, x0), f1 = poly_val(c, n, x1);
    if (i > 0 && f0 == 0) {  // root exactly at a critical point
      out[k++] = x0;
      continue;
    }
    if ((f0 < 0) == (f1 < 0) || f1 == 0) continue;
    int side = 0;
    for (int it = 0; it < 200 && x1 - x0 > 1e-15 * (1 + std::fabs(x0) + std::fabs(x1)); ++it) {
      const double x = (x0 * f1 - x1 * f0) / (f1 - f0);
      const double f = poly_val(c, n, x);
      if (f == 0) {
        x0 = x1 = x;
        break;
      }
      if ((f < 0) == (f0 < 0)) {
        x0 = x;
        f0 = f;
        if (side == -1) f1 /= 2;
        side = -1;
      } else {
        x1 = x;
        f1 = f;
        if (side == 1) f0 /= 2;
        side = 1;
      }
    }
    out[k++] = 0.5 * (x0 + x1);
  }
  return k;
}

}  // namespace

double max_abs_poly(const double* c, int n, double T) {
  double m = std::max(std::fabs(poly_val(c, n, 0)), std::fabs(poly_val(c, n, T)));
  if (n < 2) return m;
  double d[6], r[6];
  for (int j = 0; j < n; ++j) d[j] = c[j + 1] * (j + 1);
  const int k = roots_in(d, n - 1, 0, T, r);
  for (int i = 0; i < k; ++i) m = std::max(m, std::fabs(poly_val(c, n, r[i])));
  return m;
}

SegmentPeaks segment_peaks(const TimeSegment& seg, int dim, double period) {
  SegmentPeaks pk;
  const double T = seg.K * period;
  for (int a = 0; a < dim; ++a) {
    double c1[5], c2[4], c3[3];
    for (int j = 0; j < 5; ++j) c1[j] = seg.coef[a][j + 1] * (j + 1);
    for (int j = 0; j < 4; ++j) c2[j] = c1[j + 1] * (j + 1);
    for (int j = 0; j < 3; ++j) c3[j] = c2[j + 1] * (j + 1);
    pk.v[a] = max_abs_poly(c1, seg.degree - 1, T);
    pk.a[a] = max_abs_poly(c2, seg.degree - 2, T);
    pk.j[a] = max_abs_poly(c3, seg.degree - 3, T);
  }
  return pk;
}

std::vector<std::array<double, kMaxAxes>> fitted_tail(const std::vector<TimeSegment>& segs, int dim, double period,
                                                      int count) {
  std::vector<std::array<double, kMaxAxes>> t;
  long double to_end[kMaxAxes] = {};  // the end of segment i relative to the sequence's end
  for (size_t i = segs.size(); i-- > 0 && static_cast<int>(t.size()) < count;) {
    const TimeSegment& sg = segs[i];
    long double end[kMaxAxes] = {};
    for (int a = 0; a < dim; ++a) end[a] = sg.travel_ld(a, static_cast<long double>(sg.K) * period);
    for (uint32_t k = sg.K; k-- > 0 && static_cast<int>(t.size()) < count;) {
      std::array<double, kMaxAxes> q{};
      for (int a = 0; a < dim; ++a)
        q[a] = static_cast<double>(sg.travel_ld(a, static_cast<long double>(k) * period) - end[a] + to_end[a]);
      t.insert(t.begin(), q);
    }
    for (int a = 0; a < dim; ++a) to_end[a] -= end[a];
  }
  return t;
}

double bernstein_bound(const double* c, int n, double T) {
  // d_j = c_j T^j (q on x in [0, 1]); b_i = sum_{j <= i} C(i,j) / C(n,j) d_j.
  static const double binom[6][6] = {{1, 0, 0, 0, 0, 0}, {1, 1, 0, 0, 0, 0}, {1, 2, 1, 0, 0, 0},
                                     {1, 3, 3, 1, 0, 0}, {1, 4, 6, 4, 1, 0}, {1, 5, 10, 10, 5, 1}};
  double dj[6], tp = 1;
  for (int j = 0; j <= n; ++j, tp *= T) dj[j] = c[j] * tp / binom[n][j];
  double m = 0;
  for (int i = 0; i <= n; ++i) {
    double b = 0;
    for (int j = 0; j <= i; ++j) b += binom[i][j] * dj[j];
    m = std::max(m, std::fabs(b));
  }
  return m;
}

namespace {

// Quintic (or cubic) Hermite coefficients on [0, T].
std::array<double, 6> hermite(int degree, double x0, double v0, double a0, double x1, double v1, double a1, double T) {
  std::array<double, 6> c{};
  const double dx = x1 - x0, T2 = T * T, T3 = T2 * T;
  if (degree == 3) {
    c[0] = x0;
    c[1] = v0;
    c[2] = (3 * dx - (2 * v0 + v1) * T) / T2;
    c[3] = (-2 * dx + (v0 + v1) * T) / T3;
    return c;
  }
  const double T4 = T3 * T, T5 = T4 * T;
  c[0] = x0;
  c[1] = v0;
  c[2] = a0 / 2;
  c[3] = (20 * dx - (8 * v1 + 12 * v0) * T - (3 * a0 - a1) * T2) / (2 * T3);
  c[4] = (-30 * dx + (14 * v1 + 16 * v0) * T + (3 * a0 - 2 * a1) * T2) / (2 * T4);
  c[5] = (12 * dx - 6 * (v1 + v0) * T + (a1 - a0) * T2) / (2 * T5);
  return c;
}

// Whether the exact maxima over [0, T] of |x'|, |x''|, |x'''| of every axis
// are within the per-axis limits (the Bernstein bound, >= the exact maximum,
// only skips the root search where it already shows the limit holds). jmax,
// if given, gets each axis's largest |x'''| bound (the Bernstein bound, or
// the exact maximum where that was needed).
bool axes_within(const TimeSegment& seg, int d, double T, const Limits& L, double* jmax = nullptr) {
  for (int a = 0; a < d; ++a) {
    double c1[5], c2[4], c3[3];
    for (int j = 0; j < 5; ++j) c1[j] = seg.coef[a][j + 1] * (j + 1);
    for (int j = 0; j < 4; ++j) c2[j] = c1[j + 1] * (j + 1);
    for (int j = 0; j < 3; ++j) c3[j] = c2[j + 1] * (j + 1);
    auto within = [&](const double* c, int n, double lim, double* peak) {
      const double b = bernstein_bound(c, n, T) * (1 + 1e-12);
      if (b <= lim) {
        if (peak) *peak = b;
        return true;
      }
      const double m = max_abs_poly(c, n, T);
      if (peak) *peak = m;
      return m <= lim;
    };
    if (!within(c1, seg.degree - 1, L.v_axis[a], nullptr) || !within(c2, seg.degree - 2, L.a_axis[a], nullptr))
      return false;
    if (seg.degree == 5 && !within(c3, seg.degree - 3, L.j_axis[a], jmax ? &jmax[a] : nullptr)) return false;
  }
  return true;
}

// The ticks of `ts` where a piece of the plan that starts on a tick
// (Piece::on_tick: its jerk switches there) starts: segments end there, so
// that each holds one jerk of the re-timed move and reproduces it exactly.
std::vector<long long> switch_ticks(const Plan& plan, const std::vector<TickSample>& ts, double period) {
  std::vector<long long> out;
  for (const Piece& q : plan.pieces) {
    if (!q.on_tick) continue;
    const auto it = std::lower_bound(ts.begin(), ts.end(), q.t0 - 1e-6 * period,
                                     [](const TickSample& x, double t) { return x.tp < t; });
    if (it != ts.end() && std::fabs(it->tp - q.t0) <= 1e-6 * period) out.push_back(it - ts.begin());
  }
  return out;
}

// fit_segments where the fit tick is fine_ticks > 1 engine ticks (below).
std::vector<TimeSegment> fit_segments_fine(const Path& p, const Plan& plan, const std::vector<TickSample>& ts,
                                           const Limits& L, const SegmentOptions& o, long long k_base);

}  // namespace

std::vector<TimeSegment> fit_segments(const Path& p, const Plan& plan, const std::vector<TickSample>& ts,
                                      const Limits& L, const SegmentOptions& o, double period, double t_offset,
                                      long long k_base) {
  if (o.degree != 3 && o.degree != 5) throw PlanError("segment degree must be 3 or 5");
  if (o.fine_ticks > 1) {
    if (ts.size() < 2) throw PlanError("motion shorter than one tick");
    return fit_segments_fine(p, plan, ts, L, o, k_base);
  }
  const int d = p.dim();
  const long long n = static_cast<long long>(ts.size()) - 1;
  if (n < 1) throw PlanError("motion shorter than one tick");
  // break candidates
  std::vector<long long> brk = {0, n};
  // Jerk switches of the profile are not forced breaks: a fit across one is
  // kept only if its exact jerk maximum passes the check below (else split);
  // but those of a move re-timed on the tick grid are (switch_ticks).
  (void)t_offset;
  for (long long k : switch_ticks(plan, ts, period)) brk.push_back(k);
  for (long long k = 0; k < n; ++k) {
    // a first sample carried from the previous window (just before the
    // path's start) is no break: the first segment may start there and cross
    // the junction, as a whole-path fit would
    if (k == 0 && ts[0].curve >= p.size()) continue;
    if (ts[k].curve >= p.size() || ts[k + 1].curve >= p.size()) {
      brk.push_back(k + 1);
      continue;
    }
    if (ts[k].curve != ts[k + 1].curve || ts[k].span != ts[k + 1].span)
      brk.push_back(k + 1);
  }
  std::sort(brk.begin(), brk.end());
  brk.erase(std::unique(brk.begin(), brk.end()), brk.end());
  brk.erase(std::remove_if(brk.begin(), brk.end(), [&](long long k) { return k < 0 || k > n; }), brk.end());

  std::vector<TimeSegment> out;
  const double chord_max = L.feed * period * (1 + 1e-9);  // 1e-9: rounding of a chord planned at exactly the feed
  // Does a fit over [k0, k1] pass? The peak test is exactly "exact maximum <=
  // limit"; the Bernstein bound (>= the exact maximum) only skips the root
  // search where it already shows that the limit holds.
  // The sampled checks below take differences of positions over up to three
  // ticks: they work on positions relative to the segment's start, whose
  // rounding is that of the segment's travel, not of the coordinates (at
  // 1 us ticks the third difference of absolute doubles is noise above the
  // jerk limits). `tail`: the fitted positions of the ticks before the next
  // segment's start, relative to it (at first the history).
  std::vector<std::array<double, kMaxAxes>> tail = o.history, pos;
  if (tail.size() > 3) tail.erase(tail.begin(), tail.end() - 3);
  const double min_chord = 1e-9 * L.feed * period;  // below: at rest, no direction
  std::string fail_why;
  auto try_fit = [&](long long k0, long long k1, TimeSegment& seg) {
    fail_why.clear();
    const double T = (k1 - k0) * period;
    seg.k0 = k0 + k_base;
    seg.K = static_cast<uint32_t>(k1 - k0);
    seg.degree = o.degree;
    seg.coef = {};
    seg.max_dev = 0;
    const TickSample& A = ts[k0];
    const TickSample& B = ts[k1];
    for (int a = 0; a < d; ++a) seg.coef[a] = hermite(o.degree, A.x[a], A.dx[a], A.ddx[a], B.x[a], B.dx[a], B.ddx[a], T);
    // At every tick inside: deviation from the plan (on the curve) within
    // fit_tol and within feed_rel of the tick's travel; every chord between
    // consecutive fitted ticks at most feed * h (the plan's chords are
    // shorter than its arcs).
    // The fitted positions go into pos (after the tail of accepted ones), for
    // the sampled checks below.
    const int hn = static_cast<int>(tail.size());
    const int m = hn + 1 + static_cast<int>(k1 - k0);
    pos.resize(m);
    for (int i = 0; i < hn; ++i) pos[i] = tail[i];
    for (int a = 0; a < d; ++a) pos[hn][a] = 0;
    double prev[kMaxAxes] = {};
    for (long long k = k0 + 1; k <= k1; ++k) {
      const double tau = (k - k0) * period;
      double e2 = 0, c2 = 0;
      auto& q = pos[hn + (k - k0)];
      for (int a = 0; a < d; ++a) {
        const double r = k == k1 ? B.x[a] - A.x[a] : travel(seg.coef[a].data(), o.degree, tau);
        q[a] = r;
        const double e = (A.x[a] + r) - ts[k].x[a], c = r - prev[a];
        e2 += e * e;
        c2 += c * c;
        prev[a] = r;
      }
      if (k < k1) {
        const double e = std::sqrt(e2);
        seg.max_dev = std::max(seg.max_dev, e);
        if (e > std::max(o.feed_rel * ts[k].v * period - o.feed_quant / 2, o.feed_abs) || e > o.fit_tol) return false;
      }
      if (std::sqrt(c2) > chord_max) return false;
    }
    // Sampled tangential and normal quantities (sampled.hpp) over every tick
    // window that contains a tick of this segment after k0; the ticks before
    // k0 are the fitted positions already accepted (tail).
    {
      for (int i = std::max(0, hn - 2); i + 2 < m; ++i) {
        const double* x3 = (i + 3 < m && o.degree == 5) ? pos[i + 3].data() : nullptr;
        const SampledWindow w = sampled_window(pos[i].data(), pos[i + 1].data(), pos[i + 2].data(), x3, d, period,
                                               min_chord);
        if (i >= hn - 1 && (w.at > L.a_tan || w.an > L.a_cen)) {
          fail_why = "sampled tangential acceleration " + std::to_string(w.at) + ", normal " + std::to_string(w.an);
          return false;
        }
        if (w.jt > L.j_tan || w.jn > L.j_cen) {
          fail_why = "sampled tangential jerk " + std::to_string(w.jt) + ", normal " + std::to_string(w.jn);
          return false;
        }
      }
    }
    return axes_within(seg, d, T, L);
  };
  // A kept segment: its fitted positions before its end become the tail.
  auto accept = [&](TimeSegment& seg) {
    // the tail so far and the segment's last ticks, relative to its end (the next start)
    const TickSample& A = ts[seg.k0 - k_base];
    const TickSample& B = ts[seg.k0 - k_base + seg.K];
    for (auto& q : tail)
      for (int a = 0; a < d; ++a) q[a] -= B.x[a] - A.x[a];
    for (uint32_t k = seg.K > 3 ? seg.K - 3 : 0; k < seg.K; ++k) {
      std::array<double, kMaxAxes> q{};
      for (int a = 0; a < d; ++a) q[a] = travel(seg.coef[a].data(), seg.degree, k * period) - (B.x[a] - A.x[a]);
      tail.push_back(q);
    }
    if (tail.size() > 3) tail.erase(tail.begin(), tail.end() - 3);
    out.push_back(std::move(seg));
  };
  // Greedy: from each start, the longest segment that passes (binary search
  // over its length; a failing fit is never accepted, so the result is valid
  // even where pass/fail is not monotone in the length).
  for (size_t b = 0; b + 1 < brk.size(); ++b) {
    long long k0 = brk[b];
    long long last_len = 16;
    while (k0 < brk[b + 1]) {
      const long long kmax = std::min<long long>(k0 + o.max_ticks, brk[b + 1]);
      TimeSegment seg, best;
      // exponential search from twice the previous length, then bisection
      long long lo = k0, hi = kmax + 1;  // lo: longest known to pass (k0: none yet), hi: fails (kmax+1: unknown)
      long long probe = std::min(kmax, k0 + std::max<long long>(1, 2 * last_len));
      while (true) {
        if (try_fit(k0, probe, seg)) {
          lo = probe;
          best = std::move(seg);
          if (probe == kmax) break;
          probe = std::min(kmax, k0 + 2 * (probe - k0));
        } else {
          hi = probe;
          break;
        }
      }
      if (lo == kmax) {
        accept(best);
        last_len = lo - k0;
        k0 = lo;
        continue;
      }
      // bisection to within 1/8 of the length found (a segment up to 1/8
      // shorter than the longest that passes: fewer fits, a few more segments)
      while (hi - lo > std::max<long long>(1, (lo - k0) / 8)) {
        const long long mid = lo + (hi - lo) / 2;
        if (try_fit(k0, mid, seg)) {
          lo = mid;
          best = std::move(seg);
        } else {
          hi = mid;
        }
      }
      if (lo == k0) {
        const SegmentPeaks pk = segment_peaks(seg, d, period);
        std::string why = fail_why.empty() ? "deviation " + std::to_string(seg.max_dev) : fail_why;
        for (int a = 0; a < d; ++a)
          why += "; axis " + std::to_string(a) + ": v " + std::to_string(pk.v[a]) + " a " + std::to_string(pk.a[a]) +
                 " j " + std::to_string(pk.j[a]);
        throw FitError("tick " + std::to_string(k0 + k_base) + " (t = " + std::to_string((k0 + k_base) * period) +
                           " s): no one-tick segment meets the limits (" + why + ")",
                       k0 + k_base);
      }
      accept(best);
      last_len = lo - k0;
      k0 = lo;
    }
  }
  return out;
}

namespace {

// Samples whose addresses stay put as more are added (chunks of 256).
class SampleStore {
 public:
  const TickSample* add(const TickSample& s) {
    if (chunks_.empty() || chunks_.back().size() == kChunk) {
      chunks_.emplace_back();
      chunks_.back().reserve(kChunk);
    }
    chunks_.back().push_back(s);
    return &chunks_.back().back();
  }

 private:
  static constexpr size_t kChunk = 256;
  std::vector<std::vector<TickSample>> chunks_;
};

// Tangent angle (rad) above which two curves or spans meet at a corner (the
// planner's default PlanOptions::corner_tol).
constexpr double kCornerAngle = 1e-6;

// A sample the fine fit works with: the plan at engine tick e (global).
struct FineSample {
  const TickSample* s = nullptr;
  long long e = 0;
  // A segment may end here: not within a fit tick before a change of curve
  // or span (the segment across it would turn the velocity, or step the
  // acceleration, in less than the fit tick the planner's speed there
  // allows for it).
  bool end_ok = true;
};

// The fit on a fit tick of n = o.fine_ticks engine ticks (segments.hpp,
// host/planner/README.md "Fine ticks"). Segments start and end at engine
// ticks: at the fit ticks, at breaks (a corner, where the plan rests), and,
// where no segment between fit ticks passes, at engine ticks between them
// sampled on demand; none ends within half a fit tick of a curvature step.
// A segment passes when
//   * per axis, the exact maxima of |x'|, |x''|, |x'''| are within the limits;
//   * between consecutive samples a and b it uses (delta apart), its
//     deviation e = fit - plan stays within fit_tol at every engine tick:
//     |e| <= max(|e_a|, |e_b|) + delta^2/8 E2, E2 = max(|e''_a|, |e''_b|) +
//     delta/2 E3, E3 = the fit's largest |x'''| + the plan's (its per-axis
//     jerk limits: the planner's guarantee); and its velocity error keeps
//     the chord between engine ticks within 2 feed_rel of the plan's:
//     with feed_bound, |e'| <= max(|e'_a|, |e'_b|) + delta^2/8 E3 <=
//     2 feed_rel v, v the plan's slowest speed between the two (the smaller
//     end speed less delta^2/8 of the profile's jerk); else at the samples;
//     no check below a hundredth of the top speed;
//   * its path speed and, by fine_windows_ok, the sampled tangential and
//     normal quantities and the chords at every engine tick, by per-segment
//     bounds.
// The search for the longest segment uses a screen (every third sample, no
// allowances, the fit's own path quantities at the samples); the full checks
// decide on the one it found (and, where they fail, on shorter ones).
std::vector<TimeSegment> fit_segments_fine(const Path& p, const Plan& plan, const std::vector<TickSample>& ts,
                                           const Limits& L, const SegmentOptions& o, long long k_base) {
  const int d = p.dim();
  const long long n = o.fine_ticks;
  const double h = o.fine_period;
  const bool carried = ts[0].curve >= p.size();  // ts[0] ends the previous window's committed motion
  SampleHints hints;
  SampleStore extra;  // the samples between fit ticks
  // engine tick e of the plan, placed from a later sample B (the earlier one may be carried)
  auto sample_before = [&](const FineSample& B, long long e) {
    const double back = static_cast<double>(B.e - e) * h;
    return sample_plan(p, plan, B.s->tp - back, B.s->t - back, hints);
  };
  auto same_piece = [](const TickSample& a, const TickSample& b) { return a.curve == b.curve && a.span == b.span; };
  // The first engine tick in (lo, B.e] past the curve span of `left` (at lo):
  // by bisection on the profile's arc length against where the span ends
  // (state_at only), confirmed on the two samples around it; by bisection on
  // full samples where rounding at the span's end makes them disagree.
  auto first_past = [&](const TickSample& left, long long lo, const FineSample& B) {
    const double s_end = p.offset(left.curve) + p.table(left.curve).span_end(left.span);
    int piece = 0;
    auto s_at = [&](long long e) { return state_at(plan, B.s->tp - static_cast<double>(B.e - e) * h, &piece).s; };
    long long a = lo, b = B.e;
    while (b - a > 1) {
      const long long m = a + (b - a) / 2;
      (s_at(m) <= s_end ? a : b) = m;
    }
    if ((b - 1 == lo || same_piece(sample_before(B, b - 1), left)) && (b == B.e || !same_piece(sample_before(B, b), left)))
      return b;
    a = lo;
    b = B.e;
    while (b - a > 1) {
      const long long m = a + (b - a) / 2;
      (same_piece(sample_before(B, m), left) ? a : b) = m;
    }
    return b;
  };

  double Jp = 0;  // the plan's jerk: within the per-axis limits
  for (int a = 0; a < d; ++a) Jp += L.j_axis[a] * L.j_axis[a];
  Jp = std::sqrt(Jp);
  // The feed check's allowance between samples delta apart is delta^2/8 E3,
  // E3 <= 2 Jp (the fit's jerk is within the same limits): where the plan is
  // slow, its budget 2 feed_rel v is small, and more
  // samples of the plan go between the fit ticks (at most half the budget
  // for the allowance), so that the segments there need not be short.
  // Below a hundredth of the top speed there is no feed check, as the
  // report's feed figures start there: the samples stay few near a stop,
  // and a corner passed slowly (where the plan's velocity turns within a
  // tick and the fit's over a fit tick) needs none.
  // The budget of the velocity error between two samples dl apart, plan
  // speeds va and vb there: with feed_bound the plan's speed between them is
  // within dl^2/8 J_t of [min, max] of the two. The report checks the ticks
  // whose chord is at least v_floor h: none where the fastest speed is below
  // v_floor; elsewhere the chords are at least the slowest speed's or v_floor
  // h, whichever is larger (the budget's v), and the output's rounding of the
  // chord is left out of it (feed_quant). Without feed_bound (no bound asked
  // for) the check is at the samples, where the slower one is at v_floor or
  // above: no samples added near stops.
  const double v_floor = L.feed_floor(d);
  auto feed_budget = [&](double va, double vb, double dl) {
    if (!o.feed_bound) return std::min(va, vb) < v_floor ? 1e300 : 2 * o.feed_rel * std::min(va, vb);
    const double bulge = dl * dl / 8 * plan.J_t;
    if (std::max(va, vb) + bulge < v_floor) return 1e300;
    return 2 * o.feed_rel * std::max(std::min(va, vb) - bulge, v_floor) - o.feed_quant / h;
  };

  std::vector<FineSample> W;  // the samples, in order
  W.reserve(ts.size() + 16);
  // Changes of curve or span (found by bisection) are of three kinds, by
  // the geometry on their two sides:
  //  * a corner, where the plan stops and rests (PlanOptions::corner_stops):
  //    the segments meet on a tick where it stands still (`brk`), so that
  //    each side keeps its own direction (a polynomial turning there at
  //    almost no speed would read as a large tangential jerk, a_n^2 / v, in
  //    the samples);
  //  * a step of the curvature: the engine ticks on both sides are samples,
  //    and no segment ends within w = half a fit tick of it (`cross`), so
  //    that the one across it steps the acceleration over a fit tick at
  //    least, as the planner's jump speed (for one fit tick) allows;
  //  * smooth (a G2 join, a knot of a C2 spline): passed like any point.
  std::vector<long long> brk, cross;
  const long long w = std::max<long long>(1, n / 2);
  // one-sided tangent and curvature vector at the end (end = true) or start of a sample's span
  auto geometry = [&](const TickSample& x, bool end, double* T, double* K) {
    const geo::Curve& c = p.curve(x.curve);
    const auto& sp = c.spans()[static_cast<size_t>(x.span)];
    double buf[3 * kMaxAxes];
    c.eval_span(x.span, end ? sp.u1 : sp.u0, 2, buf);
    double n1 = 0, dot = 0;
    for (int a = 0; a < d; ++a) n1 += buf[d + a] * buf[d + a];
    n1 = std::sqrt(n1);
    for (int a = 0; a < d; ++a) {
      T[a] = n1 > 0 ? buf[d + a] / n1 : 0;
      dot += buf[2 * d + a] * T[a];
    }
    for (int a = 0; a < d; ++a) K[a] = n1 > 0 ? (buf[2 * d + a] - dot * T[a]) / (n1 * n1) : 0;
  };
  enum Kind { kSmooth, kCross, kBreak };
  auto kind_of = [&](const TickSample& left, const TickSample& past) {
    double T1[kMaxAxes], K1[kMaxAxes], T2[kMaxAxes], K2[kMaxAxes];
    geometry(left, true, T1, K1);
    geometry(past, false, T2, K2);
    double dot = 0, kscale = 0, kjump = 0;
    for (int a = 0; a < d; ++a) {
      dot += T1[a] * T2[a];
      kscale = std::max({kscale, std::fabs(K1[a]), std::fabs(K2[a])});
      kjump = std::max(kjump, std::fabs(K2[a] - K1[a]));
    }
    const bool corner = std::acos(std::clamp(dot, -1.0, 1.0)) > kCornerAngle;
    const bool step = kjump > 1e-9 * (1 + kscale);
    return corner ? kBreak : step ? kCross : kSmooth;
  };
  std::vector<std::pair<long long, const TickSample*>> between;
  for (size_t i = 0; i < ts.size(); ++i) {
    W.push_back({&ts[i], (k_base + static_cast<long long>(i)) * n});
    if (i + 1 == ts.size() || (i == 0 && carried)) continue;
    const FineSample A = W.back(), B{&ts[i + 1], A.e + n};
    between.clear();
    const TickSample* left = A.s;
    long long lo = A.e;
    while (!same_piece(*left, *B.s)) {
      const long long b = first_past(*left, lo, B);
      const TickSample* past = b == B.e ? B.s : extra.add(sample_before(B, b));
      const Kind k = kind_of(*left, *past);
      if (k == kCross) {
        cross.push_back(b);
        if (b - 1 > lo) between.push_back({b - 1, extra.add(sample_before(B, b - 1))});
        if (b < B.e) between.push_back({b, past});
      }
      if (k == kBreak) {
        // The planner stops at a corner and rests there a few engine ticks
        // (PlanOptions::corner_stops, corner_rest): the segments meet on a
        // tick where the plan stands still (near the stop the arc length
        // cannot tell the curves apart to the tick, so it is looked for on
        // both sides of b); without one, just past the corner.
        long long at = b;
        const TickSample* still = past;
        for (long long m = std::max(lo + 1, b - 4); m <= std::min(B.e, b + 4); ++m) {
          const TickSample* x = m == b ? past : m == B.e ? B.s : extra.add(sample_before(B, m));
          if (x->v == 0 && x->a == 0) {
            at = m;
            still = x;
            break;
          }
        }
        brk.push_back(at);
        if (at < B.e) between.push_back({at, still});
      }
      if (b == B.e) break;
      left = past;
      lo = b;
    }
    // where slow, the samples the feed bound needs
    if (o.feed_bound) {
      const double dmax = std::sqrt(4 * feed_budget(A.s->v, B.s->v, static_cast<double>(n) * h) / (2 * Jp));
      const long long m = std::min<long long>(n, static_cast<long long>(std::ceil(n * h / std::max(dmax, 1e-300))));
      for (long long k = 1; k < m; ++k) between.push_back({A.e + n * k / m, nullptr});
    }
    std::sort(between.begin(), between.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    long long last = A.e;
    for (const auto& [e, smp] : between) {
      if (e == last) continue;
      W.push_back({smp ? smp : extra.add(sample_before(B, e)), e});
      last = e;
    }
  }
  brk.push_back(W.back().e);
  for (long long k : switch_ticks(plan, ts, o.fine_period * static_cast<double>(n)))
    brk.push_back((k_base + k) * n);
  std::sort(brk.begin(), brk.end());
  brk.erase(std::unique(brk.begin(), brk.end()), brk.end());
  // no end within w of a change crossed (FineSample::end_ok), but the path's ends and the breaks
  for (size_t j = 1, b = 0; j + 1 < W.size(); ++j) {
    while (b < cross.size() && cross[b] + w <= W[j].e) ++b;
    if (b < cross.size() && W[j].e > cross[b] - w && !std::binary_search(brk.begin(), brk.end(), W[j].e))
      W[j].end_ok = false;
  }
  // an engine tick may end a segment where no crossed change is within w of it
  auto end_allowed = [&](long long e) {
    const auto it = std::upper_bound(cross.begin(), cross.end(), e - w);
    return it == cross.end() || *it - w >= e;
  };
  std::vector<size_t> ends;  // the W indices a segment may end at
  ends.reserve(W.size());
  for (size_t j = 0; j < W.size(); ++j)
    if (W[j].end_ok) ends.push_back(j);

  std::vector<TimeSegment> out;
  std::vector<std::array<double, kMaxAxes>> tail = o.history;
  if (tail.size() > 3) tail.erase(tail.begin(), tail.end() - 3);
  std::string fail_why;
  long long fail_tick = -1;  // where fine_windows_ok found a window above a limit (ticks of the segment)

  // The checks of a segment from S to E over the samples W[j0..j1) between
  // them: kFull, all three items above; kScreen, a quicker look for the
  // search (every third sample, no allowances between samples, 0.8 of the
  // budgets), which the segment it finds must then pass in full.
  enum Mode { kScreen, kFull };
  auto try_fit = [&](const FineSample& S, const FineSample& E, size_t j0, size_t j1, Mode mode,
                     TimeSegment& seg) {
    fail_why.clear();
    fail_tick = -1;
    const double T = static_cast<double>(E.e - S.e) * h;
    seg.k0 = S.e;
    seg.K = static_cast<uint32_t>(E.e - S.e);
    seg.degree = o.degree;
    seg.coef = {};
    seg.max_dev = 0;
    for (int a = 0; a < d; ++a)
      seg.coef[a] = hermite(o.degree, S.s->x[a], S.s->dx[a], S.s->ddx[a], E.s->x[a], E.s->dx[a], E.s->ddx[a], T);
    double jq[kMaxAxes] = {};
    if (!axes_within(seg, d, T, L, jq)) {
      fail_why = "a per-axis limit";
      return false;
    }
    double Jq = 0;
    for (int a = 0; a < d; ++a) Jq += jq[a] * jq[a];
    const double E3 = std::sqrt(Jq) + Jp;
    struct Err {
      double e = 0, e1 = 0, e2 = 0;  // |fit - plan| and of its first two derivatives
    };
    // At a sample: the errors, and (`screen_ok`) whether the fit's own path
    // speed there is within the feed and its path quantities (the limits of
    // the samples' at h -> 0) within 0.97 of their limits: what the full
    // check decides later, seen at the samples, so that the search rarely
    // offers it a segment it refuses.
    bool screen_ok = true;
    auto err_at = [&](const FineSample& X) {
      const double tau = static_cast<double>(X.e - S.e) * h;
      Err r;
      double v[kMaxAxes], ac[kMaxAxes], jk[kMaxAxes], vv = 0;
      for (int a = 0; a < d; ++a) {
        // Horner for the travel and its first three derivatives at once
        const auto& c = seg.coef[a];
        double p0 = c[o.degree], p1 = 0, p2 = 0, p3 = 0;
        for (int j = o.degree - 1; j >= 0; --j) {
          p3 = p3 * tau + p2;
          p2 = p2 * tau + p1;
          p1 = p1 * tau + p0;
          p0 = p0 * tau + (j > 0 ? c[j] : 0.0);
        }
        v[a] = p1;
        ac[a] = 2 * p2;
        jk[a] = 6 * p3;
        vv += v[a] * v[a];
        const double x = (S.s->x[a] - X.s->x[a]) + p0;
        const double e1 = v[a] - X.s->dx[a], e2 = ac[a] - X.s->ddx[a];
        r.e += x * x;
        r.e1 += e1 * e1;
        r.e2 += e2 * e2;
      }
      r.e = std::sqrt(r.e);
      r.e1 = std::sqrt(r.e1);
      r.e2 = std::sqrt(r.e2);
      const double sp = std::sqrt(vv);
      if (sp > L.feed) screen_ok = false;
      if (sp > 1e-9 * L.feed) {
        double at = 0, jt = 0, an2 = 0, jn2 = 0;
        for (int a = 0; a < d; ++a) {
          at += ac[a] * v[a] / sp;
          jt += jk[a] * v[a] / sp;
        }
        for (int a = 0; a < d; ++a) {
          const double na = ac[a] - at * v[a] / sp, nj = jk[a] - jt * v[a] / sp;
          an2 += na * na;
          jn2 += nj * nj;
        }
        jt += an2 / sp;  // d2|q'|/dt2 = q'''.u + |q''_n|^2 / |q'|
        const double m = 0.97;
        if (std::fabs(at) > m * L.a_tan || an2 > m * m * L.a_cen * L.a_cen || std::fabs(jt) > m * L.j_tan ||
            jn2 > m * m * L.j_cen * L.j_cen)
          screen_ok = false;
      }
      return r;
    };
    if (mode == kScreen) {
      for (size_t j = j0 + 2; j < j1; j += 3) {
        const Err e = err_at(W[j]);
        // the allowances of the full check for the gap before the sample
        const double dl = static_cast<double>(W[j].e - W[j - 1].e) * h;
        const double fb = o.feed_bound ? dl * dl / 8 : 0;  // the feed check's allowance between samples
        if (e.e + dl * dl / 8 * (e.e2 + dl / 2 * E3) > 0.9 * o.fit_tol ||
            e.e1 + fb * E3 > 0.9 * feed_budget(W[j - 1].s->v, W[j].s->v, dl) ||
            !screen_ok)
          return false;
      }
      return true;
    }
    Err ea;  // at S: the fit interpolates the plan there
    const FineSample* A = &S;
    for (size_t j = j0; j <= j1; ++j) {
      const FineSample& B = j < j1 ? W[j] : E;
      const Err eb = j < j1 ? err_at(B) : Err{};
      const long long gap = B.e - A->e;
      double dev = std::max(ea.e, eb.e), fe = std::max(ea.e1, eb.e1);
      const double dl = static_cast<double>(gap) * h;
      if (gap > 1) {
        dev += dl * dl / 8 * (std::max(ea.e2, eb.e2) + dl / 2 * E3);
        if (o.feed_bound) fe += dl * dl / 8 * E3;
      }
      seg.max_dev = std::max(seg.max_dev, dev);
      if (dev > o.fit_tol) {
        fail_why = "deviation " + std::to_string(dev);
        fail_tick = B.e - S.e;
        return false;
      }
      if (fe > feed_budget(A->s->v, B.s->v, dl)) {
        fail_why = "velocity error " + std::to_string(fe);
        fail_tick = B.e - S.e;
        return false;
      }
      if (!screen_ok) {
        fail_why = "a path quantity of the fit at a sample";
        return false;
      }
      A = &B;
      ea = eb;
    }
    return fine_windows_ok(seg, d, h, L, tail, &fail_why, nullptr, &fail_tick);
  };
  auto accept = [&](TimeSegment& seg) {
    // the tail so far and the segment's last ticks, relative to its end (the next start)
    long double end[kMaxAxes] = {};
    for (int a = 0; a < d; ++a) end[a] = seg.travel_ld(a, static_cast<long double>(seg.K) * h);
    for (auto& q : tail)
      for (int a = 0; a < d; ++a) q[a] = static_cast<double>(q[a] - end[a]);
    for (uint32_t k = seg.K > 3 ? seg.K - 3 : 0; k < seg.K; ++k) {
      std::array<double, kMaxAxes> q{};
      for (int a = 0; a < d; ++a) q[a] = static_cast<double>(seg.travel_ld(a, static_cast<long double>(k) * h) - end[a]);
      tail.push_back(q);
    }
    if (tail.size() > 3) tail.erase(tail.begin(), tail.end() - 3);
    out.push_back(seg);
  };
  auto fit_error = [&](const FineSample& S, const TimeSegment& seg) {
    const SegmentPeaks pk = segment_peaks(seg, d, h);
    std::string why = fail_why;
    for (int a = 0; a < d; ++a)
      why += "; axis " + std::to_string(a) + ": v " + std::to_string(pk.v[a]) + " a " + std::to_string(pk.a[a]) +
             " j " + std::to_string(pk.j[a]);
    return FitError("tick " + std::to_string(S.e) + " (t = " + std::to_string(S.s->t) +
                        " s): no one-tick segment meets the limits (" + why + ")",
                    S.e / n);
  };

  // Greedy: from each start, the longest segment that passes, to a sample
  // it may end at (ends[p]).
  FineSample S = W[0];
  size_t i = 0;  // S is W[i], or lies between W[i] and W[i + 1] (an engine tick sampled on demand)
  size_t bi = 0;  // the next break
  size_t last_len = 16;  // end candidates spanned by the last segment
  TimeSegment seg, best;
  auto fits = [&](size_t p, Mode mode, TimeSegment& out_seg) { return try_fit(S, W[ends[p]], i + 1, ends[p], mode, out_seg); };
  while (S.e < W.back().e) {
    while (brk[bi] <= S.e) ++bi;
    const long long emax = std::min(brk[bi], S.e + static_cast<long long>(o.max_ticks) * n);
    // the end candidates after S and within emax: positions p0..p1 of ends
    const size_t p0 = static_cast<size_t>(std::upper_bound(ends.begin(), ends.end(), i) - ends.begin());
    size_t p1 = p0;
    while (p1 + 1 < ends.size() && W[ends[p1 + 1]].e <= emax) ++p1;
    // the longest that passes the screen: exponential search, then bisection
    // to within 1/8 of its length; then the full checks on it, and where they
    // fail, the longest that ends before what failed, or bisection below it
    bool found = false;
    size_t lo = 0;  // p0 + lo - 1: the longest known to pass (lo = 0: none)
    if (p0 < ends.size() && W[ends[p0]].e <= emax) {
      const size_t n_c = p1 - p0 + 1;  // candidates
      size_t hi = n_c + 1;
      size_t probe = std::min(n_c, std::max<size_t>(1, 2 * last_len));
      while (true) {
        if (fits(p0 + probe - 1, kScreen, seg)) {
          lo = probe;
          if (probe == n_c) break;
          probe = std::min(n_c, 2 * probe);
        } else {
          hi = probe;
          break;
        }
      }
      while (lo < n_c && hi - lo > std::max<size_t>(1, lo / 8)) {
        const size_t mid = lo + (hi - lo) / 2;
        (fits(p0 + mid - 1, kScreen, seg) ? lo : hi) = mid;
      }
      if (lo > 0 && !fits(p0 + lo - 1, kFull, best)) {
        size_t good = 0, bad = lo;
        if (fail_tick >= 0) {
          size_t c = lo;
          while (c > 1 && W[ends[p0 + c - 1]].e - S.e > fail_tick) --c;
          if (c < lo && fits(p0 + c - 1, kFull, best)) {
            good = c;
            bad = c + 1;
          } else {
            bad = std::min(bad, c);
          }
        }
        while (bad - good > 1) {
          const size_t mid = good + (bad - good) / 2;
          if (fits(p0 + mid - 1, kFull, seg)) {
            good = mid;
            best = seg;
          } else {
            bad = mid;
          }
        }
        lo = good;
      }
      found = lo > 0;
    }
    if (found) {
      last_len = lo;
      accept(best);
      i = ends[p0 + lo - 1];
      S = W[i];
      continue;
    }
    // No segment to a sample it may end at passes: the longest to an engine
    // tick between S and W[i + 1], sampled on demand (bisection), but not
    // before the plan's start (the carried tick's interval belongs to the
    // previous window) nor within w of a change crossed.
    const FineSample& B = W[i + 1];
    long long good = S.e, bad = B.e;
    {
      const auto it = std::upper_bound(cross.begin(), cross.end(), S.e - w);  // the next change near or after S
      if (it != cross.end()) bad = std::min(bad, std::max(S.e + 1, *it - w + 1));
    }
    TickSample X, R;
    while (bad - good > 1) {
      const long long m = good + (bad - good) / 2;
      X = sample_before(B, m);
      if (X.tp >= 0 && end_allowed(m) && try_fit(S, FineSample{&X, m}, i + 1, i + 1, kFull, seg)) {
        good = m;
        R = X;
        best = seg;
      } else {
        bad = m;
      }
    }
    if (good == S.e) {
      // the reason: the shortest segment it may make (to the next end, or to B)
      const size_t p_first = static_cast<size_t>(std::upper_bound(ends.begin(), ends.end(), i) - ends.begin());
      if (bad > S.e + 1 || p_first >= ends.size()) try_fit(S, B, i + 1, i + 1, kFull, seg);
      else try_fit(S, W[ends[p_first]], i + 1, ends[p_first], kFull, seg);
      throw fit_error(S, seg);
    }
    last_len = 1;
    accept(best);
    S = FineSample{extra.add(R), good};
  }
  return out;
}

}  // namespace

}  // namespace traj::plan
