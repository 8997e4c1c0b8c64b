#include "geometry/arclength.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/error.hpp"

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

ArcLength::ArcLength(const Curve& c, double rel_tol) : c_(&c), rel_tol_(rel_tol) {
  if (!(rel_tol > 0)) throw GeometryError("ArcLength: rel_tol must be positive");
  const auto& spans = c.spans();
  cum_.assign(spans.size() + 1, 0.0);
  span_tol_.assign(spans.size(), 0.0);
  for (size_t i = 0; i < spans.size(); ++i) {
    const double est = gl6(static_cast<int>(i), spans[i].u0, spans[i].u1);
    span_tol_[i] = 1e-3 * rel_tol * std::abs(est);  // absolute floor for sub-interval tolerances
    cum_[i + 1] = cum_[i] + adapt(static_cast<int>(i), spans[i].u0, spans[i].u1, est,
                                  std::max(rel_tol * std::abs(est), std::numeric_limits<double>::min()), 0);
  }
}

double ArcLength::speed_span(int span, double u) const {
  const int dim = c_->dim();
  double buf[2 * 16];
  std::vector<double> heap;
  double* b = buf;
  if (dim > 16) {
    heap.resize(2 * dim);
    b = heap.data();
  }
  c_->eval_span(span, u, 1, b);
  ++stats_.integrand_evals;
  double s2 = 0;
  for (int d = 0; d < dim; ++d) s2 += b[dim + d] * b[dim + d];
  return std::sqrt(s2);
}

double ArcLength::speed(double u) const { return speed_span(c_->find_span(u), u); }

double ArcLength::gl6(int span, double a, double b) const {
  const GL6& r = gl6rule();
  const double m = 0.5 * (a + b), h = 0.5 * (b - a);
  double acc = 0;
  for (int i = 0; i < 6; ++i) acc += r.w[i] * speed_span(span, m + h * r.x[i]);
  ++stats_.intervals;
  return acc * h;
}

double ArcLength::adapt(int span, double a, double b, double whole, double tol, int depth) const {
  const double m = 0.5 * (a + b);
  const double l = gl6(span, a, m), r = gl6(span, m, b);
  const double sum = l + r;
  const double umin = 1e-14 * (c_->spans()[span].u1 - c_->spans()[span].u0);
  if (std::abs(sum - whole) <= tol || depth >= 60 || (b - a) <= umin) return sum;
  return adapt(span, a, m, l, 0.5 * tol, depth + 1) + adapt(span, m, b, r, 0.5 * tol, depth + 1);
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
  return adapt(span, a, b, whole, std::max(tol, std::numeric_limits<double>::min()), 0);
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

double ArcLength::advance(double u_from, double ds, double u_guess, double s_tol) const {
  const auto& spans = c_->spans();
  u_from = std::clamp(u_from, c_->u_begin(), c_->u_end());
  if (!(ds > 0)) return u_from;
  if (s_tol <= 0) s_tol = 1e-12 * ds;
  int si = c_->find_span(u_from);
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
