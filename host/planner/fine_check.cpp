// SPDX-License-Identifier: Apache-2.0
#include "planner/fine_check.hpp"

#include <algorithm>
#include <cmath>

#include "planner/sampled.hpp"

namespace traj::plan {

namespace {

constexpr int kMaxDeg = 14;  // the largest degree of the products below

// C(n, k) for n <= kMaxDeg.
struct Binomials {
  double c[kMaxDeg + 1][kMaxDeg + 1] = {};
  constexpr Binomials() {
    for (int n = 0; n <= kMaxDeg; ++n) {
      c[n][0] = c[n][n] = 1;
      for (int k = 1; k < n; ++k) c[n][k] = c[n - 1][k - 1] + c[n - 1][k];
    }
  }
};
constexpr Binomials kB;

// The polynomial c(t) re-expanded at t0: c(t0 + x).
void shifted(const double* c, int n, double t0, double* out) {
  for (int j = 0; j <= n; ++j) out[j] = c[j];
  for (int i = 0; i < n; ++i)
    for (int j = n - 1; j >= i; --j) out[j] += t0 * out[j + 1];
}

// A polynomial in scaled Bernstein form on an interval (x in [0, 1] over
// it): f = sum_i c_i x^i (1 - x)^(n - i), c_i = C(n, i) b_i with b_i its
// Bernstein coefficients, so that a product is a plain convolution.
struct BPoly {
  int n = -1;  // degree; -1: zero
  double c[kMaxDeg + 1] = {};
  double b(int i) const { return c[i] / kB.c[n][i]; }
  double lo() const {
    double m = n < 0 ? 0 : b(0);
    for (int i = 1; i <= n; ++i) m = std::min(m, b(i));
    return m;
  }
  double hi() const {
    double m = n < 0 ? 0 : b(0);
    for (int i = 1; i <= n; ++i) m = std::max(m, b(i));
    return m;
  }
  double abs_max() const { return std::max(std::fabs(lo()), std::fabs(hi())); }
};

BPoly bpoly_on(const double* p, int n, double a, double w) {
  BPoly f;
  f.n = n;
  bernstein_on(p, n, a, w, f.c);
  for (int i = 0; i <= n; ++i) f.c[i] *= kB.c[n][i];
  return f;
}

BPoly elevated(const BPoly& f, int m) {
  BPoly g = f;
  if (g.n < 0) {
    g.n = m;  // zero
    return g;
  }
  for (; g.n < m; ++g.n) {  // f (x + (1 - x)), one degree at a time
    g.c[g.n + 1] = g.c[g.n];
    for (int k = g.n; k > 0; --k) g.c[k] += g.c[k - 1];
  }
  return g;
}

// f + sg g
BPoly plus(const BPoly& f, const BPoly& g, double sg = 1) {
  const int m = std::max(f.n, g.n);
  if (m < 0) return BPoly{};
  const BPoly a = elevated(f, m), b = elevated(g, m);
  BPoly r;
  r.n = m;
  for (int i = 0; i <= m; ++i) r.c[i] = a.c[i] + sg * b.c[i];
  return r;
}

BPoly times(const BPoly& f, const BPoly& g) {
  if (f.n < 0 || g.n < 0) return BPoly{};
  BPoly r;
  r.n = f.n + g.n;
  for (int i = 0; i <= f.n; ++i)
    for (int j = 0; j <= g.n; ++j) r.c[i + j] += f.c[i] * g.c[j];
  return r;
}

// d/dx (x in [0, 1] over the interval)
BPoly derivative(const BPoly& f) {
  BPoly r;
  if (f.n <= 0) return r;
  r.n = f.n - 1;
  for (int k = 0; k < f.n; ++k) r.c[k] = (k + 1) * f.c[k + 1] - (f.n - k) * f.c[k];
  return r;
}

// The difference polynomials of a segment, per axis (coefficients in tau,
// seconds from the segment's start): D1(t) = (q(t+h) - q(t))/h, V(t) =
// D1(t) + D1(t+h) (the direction the normal acceleration is taken against),
// M(t) = D1(t+h) (that of the normal jerk), D2, D3.
struct AxisPolys {
  double D1[5] = {}, V[5] = {}, M[5] = {}, D2[4] = {}, D3[3] = {};
};

class Checker {
 public:
  Checker(const TimeSegment& seg, int dim, double h, const Limits& L, FineCheckStats* st)
      : seg_(seg), d_(dim), h_(h), L_(L), st_(st), n_(seg.degree) {
    K_ = static_cast<long long>(seg.K);
    for (int a = 0; a < d_; ++a) {
      AxisPolys& p = ax_[a];
      forward_difference(seg.coef[a].data(), n_, h, p.D1);
      shifted(p.D1, n_ - 1, h, p.M);
      for (int j = 0; j < n_; ++j) p.V[j] = p.D1[j] + p.M[j];
      forward_difference(p.D1, n_ - 1, h, p.D2);
      forward_difference(p.D2, n_ - 2, h, p.D3);
    }
    chord_max_ = L.feed * h * (1 + 1e-9);
    min_chord_ = 1e-9 * L.feed * h;
  }

  // Window starts ia..ib (ticks of the segment, 0 <= ia <= ib <= K - 1).
  bool check(long long ia, long long ib) {
    if (ib - ia + 1 <= kExactWindows) return exact(ia, ib);
    if (bounded(ia, ib)) return true;
    const long long mid = ia + (ib - ia) / 2;
    return check(ia, mid) && check(mid + 1, ib);
  }

  // Windows one by one: positions relative to tick 0 (the segment's own
  // travel), preceded by `tail` (ticks -3..-1); starts i0..i1, where i0 may
  // be negative (windows reaching into the tail).
  bool exact(long long i0, long long i1, const std::vector<std::array<double, kMaxAxes>>* tail = nullptr) {
    const int hn = tail ? static_cast<int>(tail->size()) : 0;
    // positions relative to the window's first tick, from travels in long
    // double: rounded at the scale of the window's few ticks of travel, not
    // of the segment's (at 1 us, a long segment's travel in double rounds
    // the second differences of chord speeds to percents of a jerk limit)
    long double xl[4][kMaxAxes];
    double x[4][kMaxAxes];
    auto pos = [&](long long k, long double* out) {
      if (k < 0) {
        const auto& q = (*tail)[static_cast<size_t>(hn + k)];
        for (int a = 0; a < d_; ++a) out[a] = q[a];
      } else {
        for (int a = 0; a < d_; ++a) out[a] = seg_.travel_ld(a, static_cast<long double>(k) * h_);
      }
    };
    for (long long i = i0; i <= i1; ++i) {
      if (st_) ++st_->exact_windows;
      const bool has2 = i + 2 <= K_, has3 = i + 3 <= K_ && n_ == 5;
      const int m = has3 ? 4 : has2 ? 3 : 2;
      for (int r = 0; r < m; ++r) pos(i + r, xl[r]);
      for (int r = 0; r < m; ++r)
        for (int a = 0; a < d_; ++a) x[r][a] = static_cast<double>(xl[r][a] - xl[0][a]);
      if (i >= 0 && chord_speed(x[0], x[1], d_, 1.0) > chord_max_) return fail("chord", i);
      if (!has2) continue;
      const SampledWindow w = sampled_window(x[0], x[1], x[2], has3 ? x[3] : nullptr, d_, h_, min_chord_);
      if (i >= -1 && (w.at > L_.a_tan || w.an > L_.a_cen)) return fail("sampled tangential or normal acceleration", i);
      if (w.jt > L_.j_tan || w.jn > L_.j_cen) return fail("sampled tangential or normal jerk", i);
    }
    return true;
  }

  std::string why;
  long long fail_tick = -1;

 private:
  bool fail(const char* what, long long i) {
    fail_tick = i;
    why = std::string(what) + " above its limit at tick " + std::to_string(i) + " of the segment";
    return false;
  }

  // Bounds over the window starts ia..ib (header comment); false where they
  // cannot show every limit held.
  bool bounded(long long ia, long long ib) {
    if (st_) ++st_->intervals;
    // starts of the acceleration and jerk windows in the interval; D2 one
    // start further for the jerk bound without a direction
    const long long ib_a = std::min(ib, K_ - 2), ib_j = std::min(ib, K_ - 3), ib_d2 = std::min(ib + 1, K_ - 2);
    const long long ir = std::min(ib + 2, K_ - 1);  // D1 (the chord speed s) over starts ia..ir
    const double ra = ia * h_, rw = (ir - ia) * h_;
    const bool acc = ib_a >= ia, jerk = ib_j >= ia && n_ == 5;
    const double m = 1 + 1e-9;  // the Bernstein arithmetic's rounding
    // s^2 = P = |D1|^2; the largest |D2| and |D3| (the bounds without a direction)
    BPoly P, D3[kMaxAxes];
    double d2_max = 0, d3_max = 0;
    for (int a = 0; a < d_; ++a) {
      const AxisPolys& p = ax_[a];
      const BPoly D1 = bpoly_on(p.D1, n_ - 1, ra, rw);
      P = plus(P, times(D1, D1));
      if (acc) {
        const BPoly D2w = bpoly_on(p.D2, n_ - 2, ra, (ib_d2 - ia) * h_);
        d2_max += D2w.abs_max() * D2w.abs_max();
      }
      if (jerk) {
        D3[a] = bpoly_on(p.D3, n_ - 3, ra, (ib_j - ia) * h_);
        d3_max += D3[a].abs_max() * D3[a].abs_max();
      }
    }
    d2_max = std::sqrt(d2_max);
    d3_max = std::sqrt(d3_max);
    double at = d2_max, an = d2_max, jt = 2 * d2_max / h_, jn = d3_max;
    // s' = P'/(2 s), s'' = (2 P P'' - P'^2) / (4 s^3)
    const double p_lo = P.lo();
    if (p_lo > 0 && ((acc && at * m > L_.a_tan) || (jerk && jt * m > L_.j_tan))) {
      const BPoly P1 = derivative(P), P2 = derivative(P1);
      const double dx = 1 / rw;  // d/dt = dx d/dx
      at = std::min(at, P1.abs_max() * dx / (2 * std::sqrt(p_lo)));
      if (jerk) {
        const BPoly G = plus(times(P, P2), times(P1, P1), -0.5);  // (2 P P'' - P'^2) / 2
        jt = std::min(jt, G.abs_max() * dx * dx / (2 * p_lo * std::sqrt(p_lo)));
      }
    }
    if (acc && at * m > L_.a_tan) return false;
    if (jerk && jt * m > L_.j_tan) return false;
    // |a_n|^2 = (|D2|^2 |V|^2 - (D2.V)^2) / |V|^2 (Lagrange's identity), |j_n|^2 likewise with D3, M
    if (acc && an * m > L_.a_cen) {
      BPoly D2sq, V2, D2V;
      for (int a = 0; a < d_; ++a) {
        const BPoly D2a = bpoly_on(ax_[a].D2, n_ - 2, ra, (ib_a - ia) * h_);
        const BPoly V = bpoly_on(ax_[a].V, n_ - 1, ra, (ib_a - ia) * h_);
        D2sq = plus(D2sq, times(D2a, D2a));
        V2 = plus(V2, times(V, V));
        D2V = plus(D2V, times(D2a, V));
      }
      if (V2.lo() > 0) an = std::min(an, std::sqrt(std::max(0.0, plus(times(D2sq, V2), times(D2V, D2V), -1).hi() / V2.lo())));
      if (an * m > L_.a_cen) return false;
    }
    if (jerk && jn * m > L_.j_cen) {
      BPoly D3sq, M2, D3M;
      for (int a = 0; a < d_; ++a) {
        const BPoly M = bpoly_on(ax_[a].M, n_ - 1, ra, (ib_j - ia) * h_);
        D3sq = plus(D3sq, times(D3[a], D3[a]));
        M2 = plus(M2, times(M, M));
        D3M = plus(D3M, times(D3[a], M));
      }
      if (M2.lo() > 0) jn = std::min(jn, std::sqrt(std::max(0.0, plus(times(D3sq, M2), times(D3M, D3M), -1).hi() / M2.lo())));
      if (jn * m > L_.j_cen) return false;
    }
    return true;
  }

  const TimeSegment& seg_;
  int d_;
  double h_;
  const Limits& L_;
  FineCheckStats* st_;
  int n_;
  long long K_ = 0;
  AxisPolys ax_[kMaxAxes];
  double chord_max_ = 0, min_chord_ = 0;
};

}  // namespace

void forward_difference(const double* p, int n, double h, double* out) {
  for (int m = 0; m < n; ++m) {
    double s = 0, hp = 1;  // h^(j-m-1)
    for (int j = m + 1; j <= n; ++j, hp *= h) s += p[j] * kB.c[j][m] * hp;
    out[m] = s;
  }
}

void bernstein_on(const double* c, int n, double a, double w, double* b) {
  double d[kMaxDeg + 1];
  shifted(c, n, a, d);
  double wp = 1;
  for (int j = 0; j <= n; ++j, wp *= w) d[j] *= wp / kB.c[n][j];
  for (int i = 0; i <= n; ++i) {
    double s = 0;
    for (int j = 0; j <= i; ++j) s += kB.c[i][j] * d[j];
    b[i] = s;
  }
}

bool speed_within(const TimeSegment& seg, int dim, double T, double v_max) {
  // |q'|^2 over [0, T] in Bernstein form, halved where its hull is above v_max^2
  double c1[kMaxAxes][5];
  const int n = seg.degree - 1;
  for (int a = 0; a < dim; ++a)
    for (int j = 0; j <= n; ++j) c1[a][j] = seg.coef[a][j + 1] * (j + 1);
  const double lim = v_max * v_max;
  auto within = [&](auto&& self, double a, double w, int depth) -> bool {
    BPoly S;
    for (int ax = 0; ax < dim; ++ax) {
      const BPoly v = bpoly_on(c1[ax], n, a, w);
      S = plus(S, times(v, v));
    }
    if (S.hi() <= lim) return true;
    if (std::max(S.c[0], S.c[S.n]) > lim || depth == 0) return false;  // an end is above it, or no more halving
    return self(self, a, w / 2, depth - 1) && self(self, a + w / 2, w / 2, depth - 1);
  };
  return within(within, 0, T, 6);
}

bool fine_windows_ok(const TimeSegment& seg, int dim, double h, const Limits& L,
                     const std::vector<std::array<double, kMaxAxes>>& tail, std::string* why, FineCheckStats* stats,
                     long long* fail_tick) {
  if (fail_tick) *fail_tick = -1;
  // the chords: within the path speed's bound (speed_within), as means of it
  if (!speed_within(seg, dim, seg.K * h, L.feed)) {
    if (why) *why = "the path speed above the feed";
    return false;
  }
  Checker c(seg, dim, h, L, stats);
  const long long K = seg.K;
  // the windows that reach back into the previous segment: starts -2, -1
  const long long back = -std::min<long long>(2, static_cast<long long>(tail.size()));
  bool ok = back >= 0 || c.exact(back, -1, &tail);
  if (ok) ok = c.check(0, K - 1);
  if (!ok && fail_tick) *fail_tick = c.fail_tick;
  if (!ok && why) *why = c.why.empty() ? "sampled tangential or normal bound above its limit" : c.why;
  return ok;
}

}  // namespace traj::plan
