// SPDX-License-Identifier: Apache-2.0
#include "planner/segments.hpp"

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
  double to_end[kMaxAxes] = {};  // the end of segment i relative to the sequence's end
  for (size_t i = segs.size(); i-- > 0 && static_cast<int>(t.size()) < count;) {
    const TimeSegment& sg = segs[i];
    double end[kMaxAxes] = {};
    for (int a = 0; a < dim; ++a) end[a] = travel(sg.coef[a].data(), sg.degree, sg.K * period);
    for (uint32_t k = sg.K; k-- > 0 && static_cast<int>(t.size()) < count;) {
      std::array<double, kMaxAxes> q{};
      for (int a = 0; a < dim; ++a) q[a] = travel(sg.coef[a].data(), sg.degree, k * period) - end[a] + to_end[a];
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

}  // namespace

std::vector<TimeSegment> fit_segments(const Path& p, const Plan& plan, const std::vector<TickSample>& ts,
                                      const Limits& L, const SegmentOptions& o, double period, double t_offset,
                                      long long k_base) {
  if (o.degree != 3 && o.degree != 5) throw PlanError("segment degree must be 3 or 5");
  const int d = p.dim();
  const long long n = static_cast<long long>(ts.size()) - 1;
  if (n < 1) throw PlanError("motion shorter than one tick");
  // break candidates
  std::vector<long long> brk = {0, n};
  // Jerk switches of the profile are not forced breaks: a fit across one is
  // kept only if its exact jerk maximum passes the check below (else split).
  (void)plan;
  (void)t_offset;
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
        if (e > std::max(o.feed_rel * ts[k].v * period, o.feed_abs) || e > o.fit_tol) return false;
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
    for (int a = 0; a < d; ++a) {
      double c1[5], c2[4], c3[3];
      for (int j = 0; j < 5; ++j) c1[j] = seg.coef[a][j + 1] * (j + 1);
      for (int j = 0; j < 4; ++j) c2[j] = c1[j + 1] * (j + 1);
      for (int j = 0; j < 3; ++j) c3[j] = c2[j + 1] * (j + 1);
      auto within = [&](const double* c, int n, double lim) {
        if (bernstein_bound(c, n, T) * (1 + 1e-12) <= lim) return true;
        return max_abs_poly(c, n, T) <= lim;
      };
      if (!within(c1, o.degree - 1, L.v_axis[a]) || !within(c2, o.degree - 2, L.a_axis[a])) return false;
      if (o.degree == 5 && !within(c3, o.degree - 3, L.j_axis[a])) return false;
    }
    return true;
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

}  // namespace traj::plan
