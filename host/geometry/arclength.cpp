// SPDX-License-Identifier: Apache-2.0
#include "geometry/arclength.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include <unsupported/Eigen/Polynomials>

#include "geometry/error.hpp"
#include "util/format.hpp"

namespace traj::geo {

void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
  x.assign(n, 0);
  w.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = z;  // Legendre recurrence: P_{k+1} = ((2k+1) z P_k - k P_{k-1}) / (k+1)
      for (int k = 1; k < n; ++k) {
        const double p2 = ((2 * k + 1) * z * p1 - k * p0) / (k + 1);
        p0 = p1;
        p1 = p2;
      }
      if (n == 1) p0 = 1;
      dp = n * (z * p1 - p0) / (z * z - 1);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    x[i] = -z;  // ascending
    w[i] = 2 / ((1 - z * z) * dp * dp);
  }
}

namespace {
struct GL6 {
  std::vector<double> x, w;
  GL6() { gauss_legendre(6, x, w); }
};
const GL6& gl6rule() {
  static const GL6 r;
  return r;
}
}  // namespace

namespace {
// Relative rounding noise of the speed on one span. The rational speed |A' w - A w'| / w^2 cancels
// where the weight peaks (a conic with a large middle weight): its rounding grows like the span's
// weight ratio squared (measured: a rational quadratic with middle weight 300 has no level of
// refinement at which two GL6 halves agree to 1e-14). Below this level two estimates cannot agree,
// so the adaptive rule accepts a difference that small instead of halving until the budget is spent.
double speed_noise(const Curve& c, int span) {
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  if (!c.rational()) return 0;
  const Eigen::MatrixXd& h = c.bezier()[static_cast<size_t>(span)].hom;
  const Eigen::VectorXd w = h.col(h.cols() - 1);
  const double ratio = w.maxCoeff() / w.minCoeff();
  return 8 * kEps * ratio * ratio;
}
}  // namespace

namespace {
constexpr double kDeepDip = 1e-2;
constexpr int kDipSamples = 32;

// Local minima of the speed inside a polynomial span where it falls below kDeepDip of the span's
// largest sampled speed: the real roots of d/dtau |r'(tau)|^2, ascending (see the header).
std::vector<double> speed_dips(const Curve& c, int span) {
  std::vector<double> out;
  if (c.rational()) return out;
  const PowerSpan& sp = c.spans()[static_cast<size_t>(span)];
  const int p = sp.degree, cols = sp.cols;
  if (p < 2) return out;
  // g = |r'|^2: r' has p coefficients per axis (tau^0..tau^{p-1}), g 2p - 1
  std::vector<double> g(static_cast<size_t>(2 * p - 1), 0.0);
  for (int a = 0; a < cols; ++a)
    for (int i = 0; i < p; ++i)
      for (int j = 0; j < p; ++j)
        g[static_cast<size_t>(i + j)] += sp.coef[sp.offset(1) + i * cols + a] * sp.coef[sp.offset(1) + j * cols + a];
  Eigen::VectorXd dg(2 * p - 2);
  for (int k = 1; k < 2 * p - 1; ++k) dg[k - 1] = k * g[static_cast<size_t>(k)];
  int top = static_cast<int>(dg.size()) - 1;
  while (top > 0 && dg[top] == 0) --top;
  if (top < 1) return out;
  auto speed2 = [&](double tau) {
    double v = 0;
    for (int k = static_cast<int>(g.size()) - 1; k >= 0; --k) v = v * tau + g[static_cast<size_t>(k)];
    return v;
  };
  const double t0 = sp.u0 - sp.uc, t1 = sp.u1 - sp.uc;
  double vmax2 = 0;
  for (int j = 0; j <= kDipSamples; ++j) vmax2 = std::max(vmax2, speed2(t0 + (t1 - t0) * j / kDipSamples));
  Eigen::PolynomialSolver<double, Eigen::Dynamic> solver;
  solver.compute(dg.head(top + 1));
  for (const auto& z : solver.roots()) {
    const double tau = z.real();
    // a root of a real polynomial is real to rounding: its imaginary part far below the span
    if (!(std::abs(z.imag()) <= 1e-6 * (t1 - t0)) || !(tau > t0 && tau < t1)) continue;
    if (speed2(tau) <= kDeepDip * kDeepDip * vmax2) out.push_back(sp.uc + tau);
  }
  std::sort(out.begin(), out.end());
  return out;
}
}  // namespace

ArcLength::ArcLength(const Curve& c, double rel_tol) : c_(&c), rel_tol_(rel_tol) {
  if (!(rel_tol > 0)) throw GeometryError("ArcLength: rel_tol must be positive");
  const auto& spans = c.spans();
  cum_.assign(spans.size() + 1, 0.0);
  span_tol_.assign(spans.size(), 0.0);
  noise_.assign(spans.size(), 0.0);
  dips_.resize(spans.size());
  for (size_t i = 0; i < spans.size(); ++i) {
    noise_[i] = speed_noise(c, static_cast<int>(i));
    dips_[i] = speed_dips(c, static_cast<int>(i));
  }
  for (size_t i = 0; i < spans.size(); ++i) {
    const double est = gl6(static_cast<int>(i), spans[i].u0, spans[i].u1);
    span_tol_[i] = 1e-3 * rel_tol * std::abs(est);  // absolute floor for sub-interval tolerances
    cum_[i + 1] = cum_[i] + split_length(static_cast<int>(i), spans[i].u0, spans[i].u1,
                                         std::max(rel_tol * std::abs(est), std::numeric_limits<double>::min()));
  }
}

// Calls piece(from, to) for the pieces of [a, b] (a < b, inside the span) between the span's deep
// speed minima, in order; stops at the first that returns false.
template <class F>
bool ArcLength::each_piece(int span, double a, double b, F piece) const {
  double from = a;
  for (double u : dips_[static_cast<size_t>(span)])
    if (u > a && u < b) {
      if (!piece(from, u)) return false;
      from = u;
    }
  return piece(from, b);
}

// Length of [a, b] by the adaptive rule on each piece between deep speed minima; whole_tol is
// shared out by the pieces' parameter widths.
double ArcLength::split_length(int span, double a, double b, double whole_tol) const {
  double sum = 0;
  each_piece(span, a, b, [&](double from, double to) {
    sum += adapt(span, from, to, gl6(span, from, to), whole_tol * (to - from) / (b - a));
    return true;
  });
  return sum;
}

namespace {
// Horner over n points at once (the loop over points vectorises): out[i] = sum_j c[j*stride] tau[i]^j.
inline void horner_n(const double* c, int nterms, int stride, const double* tau, int n, double* out) {
  const double top = c[(nterms - 1) * stride];
  for (int i = 0; i < n; ++i) out[i] = top;
  for (int j = nterms - 2; j >= 0; --j) {
    const double cj = c[j * stride];
    for (int i = 0; i < n; ++i) out[i] = out[i] * tau[i] + cj;
  }
}
constexpr int kBatch = 16;
}  // namespace

// Speed from the span's power-basis tables: non-rational |A'|; rational |C'| = |A' w - A w'| / w^2
// (the quotient rule on the first derivative only, one division per point).
void ArcLength::speeds_span(int span, const double* u, int n, double* out) const {
  if (n > kBatch) {
    for (int k = 0; k < n; k += kBatch) speeds_span(span, u + k, std::min(kBatch, n - k), out + k);
    return;
  }
  const PowerSpan& sp = c_->spans()[span];
  const int p = sp.degree, cols = sp.cols, dim = c_->dim();
  const double* c0 = sp.coef.data() + sp.offset(0);
  const double* c1 = sp.coef.data() + sp.offset(1);
  double tau[kBatch], s2[kBatch], a1[kBatch];
  for (int i = 0; i < n; ++i) {
    tau[i] = u[i] - sp.uc;
    s2[i] = 0;
  }
  stats_.integrand_evals += n;
  if (!c_->rational()) {
    for (int d = 0; d < dim; ++d) {
      horner_n(c1 + d, p, cols, tau, n, a1);
      for (int i = 0; i < n; ++i) s2[i] += a1[i] * a1[i];
    }
    for (int i = 0; i < n; ++i) out[i] = std::sqrt(s2[i]);
    return;
  }
  double w[kBatch], w1[kBatch], a0[kBatch];
  horner_n(c0 + dim, p + 1, cols, tau, n, w);
  horner_n(c1 + dim, p, cols, tau, n, w1);
  for (int d = 0; d < dim; ++d) {
    horner_n(c0 + d, p + 1, cols, tau, n, a0);
    horner_n(c1 + d, p, cols, tau, n, a1);
    for (int i = 0; i < n; ++i) {
      const double num = a1[i] * w[i] - a0[i] * w1[i];
      s2[i] += num * num;
    }
  }
  for (int i = 0; i < n; ++i) out[i] = std::sqrt(s2[i]) / (w[i] * w[i]);
}

double ArcLength::speed_span(int span, double u) const {
  double v;
  speeds_span(span, &u, 1, &v);
  return v;
}

void ArcLength::speed_derivs(int span, double u, double* d) const {
  const int dim = c_->dim();
  double buf[4 * 16];
  std::vector<double> heap;
  double* b = buf;
  if (dim > 16) {
    heap.resize(4 * dim);
    b = heap.data();
  }
  c_->eval_span(span, u, 3, b);
  ++stats_.integrand_evals;
  double s11 = 0, s12 = 0, s22 = 0, s13 = 0;
  for (int k = 0; k < dim; ++k) {
    const double r1 = b[dim + k], r2 = b[2 * dim + k], r3 = b[3 * dim + k];
    s11 += r1 * r1;
    s12 += r1 * r2;
    s22 += r2 * r2;
    s13 += r1 * r3;
  }
  d[0] = std::sqrt(s11);
  d[1] = s12 / d[0];                        // sigma'  = r'.r'' / sigma
  d[2] = (s22 + s13 - d[1] * d[1]) / d[0];  // sigma'' = (|r''|^2 + r'.r''' - sigma'^2) / sigma
}

double ArcLength::speed(double u) const { return speed_span(c_->find_span(u), u); }

double ArcLength::gl6(int span, double a, double b) const {
  const GL6& r = gl6rule();
  const double m = 0.5 * (a + b), h = 0.5 * (b - a);
  double x[6], v[6];
  for (int i = 0; i < 6; ++i) x[i] = m + h * r.x[i];
  speeds_span(span, x, 6, v);
  double acc = 0;
  for (int i = 0; i < 6; ++i) acc += r.w[i] * v[i];
  ++stats_.intervals;
  return acc * h;
}

double ArcLength::adapt(int span, double a, double b, double whole, double tol) const {
  long budget = kAdaptBudget;
  const double v = adapt(span, a, b, whole, tol, 0, budget);
  if (!std::isfinite(v)) refuse(span, "the speed overflows the double range");
  return v;
}

double ArcLength::adapt(int span, double a, double b, double whole, double tol, int depth, long& budget) const {
  if (--budget < 0)
    refuse(span, "no convergence within " + std::to_string(12 * kAdaptBudget) + " speed evaluations");
  const double m = 0.5 * (a + b);
  const double l = gl6(span, a, m), r = gl6(span, m, b);
  const double sum = l + r;
  if (!std::isfinite(sum)) return sum;
  const double umin = 1e-14 * (c_->spans()[span].u1 - c_->spans()[span].u0);
  const double noise = noise_[span] * (std::abs(l) + std::abs(r));
  if (std::abs(sum - whole) <= std::max(tol, noise) || depth >= 60 || (b - a) <= umin) return sum;
  return adapt(span, a, m, l, 0.5 * tol, depth + 1, budget) + adapt(span, m, b, r, 0.5 * tol, depth + 1, budget);
}

void ArcLength::refuse(int span, const std::string& why) const {
  const PowerSpan& sp = c_->spans()[span];
  throw GeometryError("arc length of the knot span [" + util::shortest(sp.u0) + ", " + util::shortest(sp.u1) +
                      "]: " + why + " (control points, weights or knot spacing too extreme for double precision)");
}

double ArcLength::span_length(int span, double a, double b) const {
  const PowerSpan& sp = c_->spans()[span];
  a = std::clamp(a, sp.u0, sp.u1);
  b = std::clamp(b, sp.u0, sp.u1);
  if (a == b) return 0;
  if (b < a) return -span_length(span, b, a);
  if (a == sp.u0 && b == sp.u1) return cum_[span + 1] - cum_[span];
  const double whole = gl6(span, a, b);
  const double tol = std::max(rel_tol_ * std::abs(whole), span_tol_[span]);
  return split_length(span, a, b, std::max(tol, std::numeric_limits<double>::min()));
}

double ArcLength::s(double u) const {
  u = std::clamp(u, c_->u_begin(), c_->u_end());
  const int si = c_->find_span(u);
  return cum_[si] + span_length(si, c_->spans()[si].u0, u);
}

double ArcLength::length(double u0, double u1) const {
  if (u1 < u0) return -length(u1, u0);
  u0 = std::clamp(u0, c_->u_begin(), c_->u_end());
  u1 = std::clamp(u1, c_->u_begin(), c_->u_end());
  const int si = c_->find_span(u0), sj = c_->find_span(u1);
  const auto& spans = c_->spans();
  if (si == sj) return span_length(si, u0, u1);
  return span_length(si, u0, spans[si].u1) + (cum_[sj] - cum_[si + 1]) + span_length(sj, spans[sj].u0, u1);
}

// ---- fast path of advance (see the header) ----

namespace {
// QUADPACK qk15: Kronrod nodes on [0, 1) largest first (xgk[1], [3], [5] and 0 are the 7-point Gauss
// nodes), Kronrod weights, Gauss weights (nodes xgk[1], xgk[3], xgk[5], 0).
constexpr double kXgk[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                            0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                            0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                            0.207784955007898467600689403773245, 0.0};
constexpr double kWgk[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                            0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                            0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                            0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
constexpr double kWg[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                           0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

// Gauss-Kronrod 3/7: Kronrod nodes on [0, 1) largest first (0.7745... = sqrt(3/5) and 0 are the
// 3-point Gauss nodes, weights 5/9 and 8/9), Kronrod weights.
constexpr double kX7[4] = {0.960491268708020283423507092629080, 0.774596669241483377035853079956480,
                           0.434243749346802558002071502844628, 0.0};
constexpr double kW7[4] = {0.104656226026467265193823857192073, 0.268488089868333440728569280666710,
                           0.401397414775962222905051818618432, 0.450916538658474142345110087045571};

// Spacing of the doubles at |u| (= nextafter(|u|, inf) - |u|), without a libm call.
inline double ulp_of(double u) {
  const double a = std::abs(u);
  if (!(a >= std::numeric_limits<double>::min())) return std::numeric_limits<double>::denorm_min();
  std::uint64_t bits;
  std::memcpy(&bits, &a, sizeof bits);
  bits &= 0x7ff0000000000000ULL;  // 2^exponent
  double p2;
  std::memcpy(&p2, &bits, sizeof p2);
  return p2 * std::numeric_limits<double>::epsilon();
}

// Parameter increment du with length(u, u + du) ~ t_s from sigma, sigma', sigma'' at u: the inverse of
// s(du) = sigma du + sigma' du^2/2 + sigma'' du^3/6 to third order,
// du = t - a t^2/2 + (3a^2 - b) t^3/6, t = t_s/sigma, a = sigma'/sigma, b = sigma''/sigma.
double inverse_series(const double* d, double t_s) {
  const double t = t_s / d[0], a = d[1] / d[0], b = d[2] / d[0];
  const double at = a * t;
  if (!(std::abs(at) < 0.5) || !(std::abs(b * t * t) < 0.5)) return t;  // far outside the series' range
  return t * (1 - 0.5 * at + (3 * a * a - b) * t * t / 6);
}
}  // namespace

void ArcLength::gk15(int span, double a, double b, double& val, double& err) const {
  const double c = 0.5 * (a + b), h = 0.5 * (b - a);
  double x[15], f[15];
  for (int j = 0; j < 7; ++j) {
    x[2 * j] = c - h * kXgk[j];
    x[2 * j + 1] = c + h * kXgk[j];
  }
  x[14] = c;
  speeds_span(span, x, 15, f);
  ++stats_.intervals;
  double k = kWgk[7] * f[14], g = kWg[3] * f[14];
  for (int j = 0; j < 7; ++j) {
    const double pair = f[2 * j] + f[2 * j + 1];
    k += kWgk[j] * pair;
    if (j & 1) g += kWg[j >> 1] * pair;
  }
  val = k * h;
  err = std::abs((k - g) * h);
}

void ArcLength::gk7(int span, double a, double b, double& val, double& err) const {
  const double c = 0.5 * (a + b), h = 0.5 * (b - a);
  const double x[7] = {c - h * kX7[0], c + h * kX7[0], c - h * kX7[1], c + h * kX7[1],
                       c - h * kX7[2], c + h * kX7[2], c};
  double f[7];
  speeds_span(span, x, 7, f);
  ++stats_.intervals;
  const double k = kW7[0] * (f[0] + f[1]) + kW7[1] * (f[2] + f[3]) + kW7[2] * (f[4] + f[5]) + kW7[3] * f[6];
  const double g = (5.0 / 9.0) * (f[2] + f[3]) + (8.0 / 9.0) * f[6];
  val = k * h;
  err = std::abs((k - g) * h);
}

bool ArcLength::gk_adapt(int span, double a, double b, double tol, int depth, double& val, double& err) const {
  if (a == b) {
    val = err = 0;
    return true;
  }
  gk15(span, a, b, val, err);
  if (!std::isfinite(val) || !std::isfinite(err)) return false;
  if (err <= tol) return true;
  const double m = 0.5 * (a + b);
  if (depth >= 12 || !(m > std::min(a, b) && m < std::max(a, b))) return false;
  double v1, e1, v2, e2;
  if (!gk_adapt(span, a, m, 0.5 * tol, depth + 1, v1, e1) || !gk_adapt(span, m, b, 0.5 * tol, depth + 1, v2, e2))
    return false;
  val = v1 + v2;
  err = e1 + e2;
  return true;
}

bool ArcLength::dip_inside(int span, double a, double b) const {
  for (double u : dips_[static_cast<size_t>(span)])
    if (u > a && u < b) return true;
  return false;
}

// gk_adapt on each piece of [a, b] between deep speed minima, the budget shared by their widths.
bool ArcLength::gk_split(int span, double a, double b, double tol, double& val, double& err) const {
  val = err = 0;
  return each_piece(span, a, b, [&](double from, double to) {
    double v, e;
    if (!gk_adapt(span, from, to, tol * (to - from) / (b - a), 0, v, e)) return false;
    val += v;
    err += e;
    return true;
  });
}

bool ArcLength::fast_advance(int si, double ua, double ds, double s_tol, double& u_out, const double* d_from) const {
  const auto& spans = c_->spans();
  const int ns = static_cast<int>(spans.size());
  double rem = ds, err = 0;  // remaining length; sum of the quadrature error estimates so far
  auto bad = [](const double* d) {
    return !(d[0] > 0) || !std::isfinite(d[0]) || !std::isfinite(d[1]) || !std::isfinite(d[2]);
  };
  for (;;) {  // one pass per span (a step may cross span ends)
    const double ub = spans[si].u1;
    double d[3];
    if (d_from) {  // given by the caller at the start point (first span only)
      d[0] = d_from[0];
      d[1] = d_from[1];
      d[2] = d_from[2];
      d_from = nullptr;
    } else {
      speed_derivs(si, ua, d);
    }
    if (bad(d)) return false;
    double uk = ua + inverse_series(d, rem);
    if (!(uk >= ua)) return false;
    // Quadrature budget: a quarter of s_tol or of the parameter's resolution (in length) at u.
    const double budget =
        0.25 * std::max(s_tol, d[0] * ulp_of(std::max(std::abs(ua), std::abs(std::min(uk, ub)))));
    const double cbudget = 0.125 * budget;  // per Newton correction
    double lo = ua, hi = ub;  // bracket: f(lo) < 0; f(hi) >= 0 once hi_known
    bool hi_known = false, crossed = false;
    double I, e;
    if (!(uk < ub)) {  // the guess leaves the span: length of the rest of it first
      if (!gk_split(si, ua, ub, budget, I, e)) return false;
      err += e;
      if (std::abs(I - rem) + err <= s_tol) {
        u_out = ub;
        return true;
      }
      if (I < rem) {  // the step crosses the span end
        rem -= I;
        if (si + 1 >= ns) {
          u_out = ub;  // past the curve end
          return true;
        }
        ++si;
        ua = spans[si].u0;
        continue;
      }
      hi_known = true;
      uk = ua + (ub - ua) * (rem / I);  // target inside: linear guess
      if (!(uk > ua && uk < ub)) return false;
    }
    // short step (the speed varies by < ~1% over it): try the cheap 3/7 pair first
    const double du = uk - ua, va = std::abs(d[1] / d[0]) * du + std::sqrt(std::abs(d[2] / d[0])) * du;
    bool done = false;
    if (va < 1e-2 && !dip_inside(si, ua, uk)) {
      gk7(si, ua, uk, I, e);
      done = std::isfinite(I) && e <= budget;
    }
    if (!done && !gk_split(si, ua, uk, budget, I, e)) return false;
    err += e;
    double f = I - rem;  // f(u) = length(ua, u) - rem at u = uk
    bool force_bisect = false;
    for (int it = 0; it < 60; ++it) {
      ++stats_.newton_iters;
      if (f < 0) lo = std::max(lo, uk);
      else {
        hi = std::min(hi, uk);
        hi_known = true;
      }
      if (std::abs(f) + err <= s_tol) {
        u_out = uk;
        return true;
      }
      if (hi - lo <= 4 * ulp_of(std::max(std::abs(lo), std::abs(hi)))) {  // bracket at the resolution
        if (err > 0.5 * std::max(s_tol, d[0] * ulp_of(uk))) return false;
        u_out = uk;
        return true;
      }
      speed_derivs(si, uk, d);
      if (bad(d)) return false;
      double u2 = uk + inverse_series(d, -f);
      bool bisect = force_bisect;
      // a Newton step at the parameter's resolution ends the iteration (checked below)
      const bool last = !bisect && std::abs(u2 - uk) <= 4 * ulp_of(uk) && u2 >= ua && u2 <= ub;
      if (!bisect && !last && !(u2 > lo && u2 < hi)) {
        if (!hi_known) {  // is the target inside this span at all?
          if (!gk_split(si, uk, ub, cbudget, I, e)) return false;
          err += e;
          const double fhi = f + I;
          if (std::abs(fhi) + err <= s_tol) {
            u_out = ub;
            return true;
          }
          if (fhi < 0) {  // no: on to the next span
            rem = -fhi;
            if (si + 1 >= ns) {
              u_out = ub;
              return true;
            }
            crossed = true;
            break;
          }
          hi_known = true;
        }
        bisect = true;
      }
      if (bisect) {
        u2 = 0.5 * (lo + hi);
        ++stats_.bisections;
      }
      if (last && err > 0.5 * std::max(s_tol, d[0] * ulp_of(uk))) return false;
      // length of [uk, u2]: 2-point Gauss, checked against the cubic Taylor integral at uk
      const double dl = u2 - uk, h = 0.5 * dl, m = uk + h;
      double C = 0, ec = 0;
      if (dl != 0 && dip_inside(si, std::min(uk, u2), std::max(uk, u2))) {  // the Taylor check fails there
        if (!gk_split(si, std::min(uk, u2), std::max(uk, u2), cbudget, C, ec)) return false;
        if (dl < 0) C = -C;
      } else if (dl != 0) {
        const double x[2] = {m - h * 0.577350269189625764509148780501958, m + h * 0.577350269189625764509148780501958};
        double v[2];
        speeds_span(si, x, 2, v);
        C = h * (v[0] + v[1]);
        const double T3 = dl * (d[0] + dl * (0.5 * d[1] + dl * d[2] / 6));
        ec = std::abs(C - T3);
        if (!(ec <= cbudget) && !gk_adapt(si, uk, u2, cbudget, 0, C, ec)) return false;
      }
      err += ec;
      const double f2 = f + C;
      if (last) {
        u_out = std::abs(f2) < std::abs(f) ? u2 : uk;
        return true;
      }
      force_bisect = !bisect && std::abs(f2) > 0.5 * std::abs(f);  // Newton not converging: bisect next
      f = f2;
      uk = u2;
    }
    if (!crossed) return false;
    ++si;
    ua = spans[si].u0;
  }
}

double ArcLength::advance(double u_from, double ds, double u_guess, double s_tol) const {
  return advance_impl(u_from, ds, u_guess, s_tol, nullptr);
}

double ArcLength::advance_from(double u_from, const double* d_from, double ds, double s_tol) const {
  return advance_impl(u_from, ds, -1, s_tol, d_from);
}

double ArcLength::advance_impl(double u_from, double ds, double u_guess, double s_tol, const double* d_from) const {
  const auto& spans = c_->spans();
  const double u_in = u_from;
  u_from = std::clamp(u_from, c_->u_begin(), c_->u_end());
  if (u_from != u_in) d_from = nullptr;  // given for another point
  if (!(ds > 0)) return u_from;
  if (s_tol <= 0) s_tol = 1e-12 * ds;
  int si = c_->find_span(u_from);
  if (fast_) {
    double u;
    if (fast_advance(si, u_from, ds, s_tol, u, d_from)) {
      ++stats_.fast_steps;
      return u;
    }
    ++stats_.fast_fallbacks;
  }
  double ua = u_from, rem = ds;
  for (;;) {
    const double u1 = spans[si].u1;
    // Known point (uk, fk), f(u) = length(ua, u) - rem; bracket [lo, hi] with f(lo) < 0.
    double uk = ua, fk = -rem, lo = ua, hi = u1;
    bool hi_known = false;
    double u_try;
    if (u_guess > ua && u_guess < u1) u_try = u_guess;
    else {
      const double v = speed_span(si, ua);
      u_try = v > 0 ? ua + rem / v : 0.5 * (ua + u1);
    }
    double f_prev = std::abs(fk);
    bool next_span = false;
    for (int it = 0; it < 200; ++it) {
      if (!(u_try > lo && u_try < hi)) {
        if (!hi_known) {
          // Is the target inside this span at all?
          const double fhi = fk + span_length(si, uk, u1);
          if (fhi < 0) {
            if (si + 1 >= static_cast<int>(spans.size())) return u1;  // past the curve end
            rem = -fhi;
            next_span = true;
            break;
          }
          hi_known = true;
          if (fhi <= s_tol) return u1;
        }
        u_try = 0.5 * (lo + hi);
        ++stats_.bisections;
      }
      fk += span_length(si, uk, u_try);
      uk = u_try;
      ++stats_.newton_iters;
      if (std::abs(fk) <= s_tol) return uk;
      if (fk < 0) lo = uk;
      else {
        hi = uk;
        hi_known = true;
      }
      if (hi - lo <= 4 * std::numeric_limits<double>::epsilon() * std::max(std::abs(lo), std::abs(hi)))
        return uk;
      const bool slow = std::abs(fk) > 0.5 * f_prev;
      f_prev = std::abs(fk);
      const double v = speed_span(si, uk);
      u_try = (v > 0 && !slow) ? uk - fk / v : 0.5 * (lo + hi);
      if (slow) ++stats_.bisections;
    }
    if (!next_span) return uk;
    ++si;
    ua = spans[si].u0;
    u_guess = -1;
  }
}

double ArcLength::u_at(double s_target, double s_tol) const {
  if (s_target <= 0) return c_->u_begin();
  if (s_target >= total()) return c_->u_end();
  if (s_tol <= 0) s_tol = 1e-14 * total();
  const int si = static_cast<int>(std::upper_bound(cum_.begin(), cum_.end(), s_target) - cum_.begin()) - 1;
  const int sc = std::clamp(si, 0, static_cast<int>(c_->spans().size()) - 1);
  return advance(c_->spans()[sc].u0, s_target - cum_[sc], -1, s_tol);
}

}  // namespace traj::geo
