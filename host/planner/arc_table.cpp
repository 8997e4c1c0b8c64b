// SPDX-License-Identifier: Apache-2.0
#include "planner/arc_table.hpp"

#include <algorithm>
#include <cmath>

namespace traj::plan {
namespace {

constexpr int kN = ArcTable::kDegree;

// Chebyshev series sum_{j=0}^{n} c[j] T_j(x) (c[0] not halved), Clenshaw.
inline double clenshaw(const double* c, int n, double x) {
  double b1 = 0, b2 = 0;
  const double x2 = 2 * x;
  for (int k = n; k >= 1; --k) {
    const double b0 = c[k] + x2 * b1 - b2;
    b2 = b1;
    b1 = b0;
  }
  return c[0] + x * b1 - b2;
}

// cos(pi k / n), k = 0..2n (the DCT-I needs j k mod 2n), and the midpoints
// cos(pi (k + 1/2) / n), k = 0..n-1, for n = kN.
struct CosTable {
  double c[2 * kN + 1], mid[kN];
  CosTable() {
    for (int k = 0; k <= 2 * kN; ++k) c[k] = std::cos(M_PI * k / kN);
    for (int k = 0; k < kN; ++k) mid[k] = std::cos(M_PI * (k + 0.5) / kN);
  }
};
const CosTable& cos_table() {
  static const CosTable t;
  return t;
}

// Chebyshev coefficients (c[0] not halved) of the interpolant through f at the
// points cos(pi k / n), k = 0..n (DCT-I).
void dct1(const double* f, double* c) {
  const double* ct = cos_table().c;
  for (int j = 0; j <= kN; ++j) {
    double acc = 0.5 * (f[0] + ((j & 1) ? -f[kN] : f[kN]));
    for (int k = 1; k < kN; ++k) acc += f[k] * ct[(j * k) % (2 * kN)];
    c[j] = acc * 2.0 / kN;
  }
  c[0] *= 0.5;
  c[kN] *= 0.5;
}

// Size of the last two coefficients: what truncating the series costs.
double tail(const double* c) { return std::abs(c[kN - 1]) + std::abs(c[kN]); }

}  // namespace

ArcTable::ArcTable(const geo::Curve& c, const geo::ArcLength& al) : c_(&c), al_(&al), total_(al.total()) {
  const auto& spans = c.spans();
  pc_.reserve(spans.size() * 2);
  // Each span starts at the depth the previous span's pieces needed: the
  // spans of a curve are alike (a run's cubic), and a try at a depth the
  // previous span failed at is mostly wasted (the inverse's Newton solves
  // are the table's cost).
  int start = 0;
  for (size_t si = 0; si < spans.size(); ++si) {
    const size_t first = pc_.size();
    min_depth_ = kMaxDepth + 1;
    if (c.degree() == 1 && !c.rational()) {
      // a straight segment's speed is constant: u is linear in s, no series
      const double len = al.span_length(static_cast<int>(si), spans[si].u0, spans[si].u1);
      pc_.push_back(Piece{spans[si].u0, spans[si].u1, 0, len, len, static_cast<int>(si), false, true, 0});
    } else {
      build_span(static_cast<int>(si), spans[si].u0, spans[si].u1, 0, start);
    }
    start = min_depth_ <= kMaxDepth ? min_depth_ : 0;
    // piece starts: the library's span start, then the sum of the reference
    // lengths of the pieces before it (no accumulation across spans)
    double s = al.cumulative()[si];
    for (size_t i = first; i < pc_.size(); ++i) {
      const double len = pc_[i].s1;  // build_span left the reference length in s1
      pc_[i].s0 = s;
      s += len;
      pc_[i].s1 = s;
    }
    if (pc_.size() > first) pc_.back().s1 = al.cumulative()[si + 1];
    for (size_t i = first; i < pc_.size(); ++i)
      if (pc_[i].fallback) {
        ++fallback_spans_;
        break;
      }
  }
}

bool ArcTable::try_piece(int span, double u0, double u1, double ref, Piece& p) {
  const double m = 0.5 * (u0 + u1), r = 0.5 * (u1 - u0);
  if (!(r > 0)) return false;
  const double* ct = cos_table().c;
  // 1. speed series on [u0, u1] and its integral S(x) = s(u(x)) - s(u0)
  double u[kN + 1], sg[kN + 1], a[kN + 1];
  for (int k = 0; k <= kN; ++k) u[k] = m + r * ct[k];
  al_->speeds_span(span, u, kN + 1, sg);
  build_evals_ += kN + 1;
  for (int k = 0; k <= kN; ++k)
    if (!(std::isfinite(sg[k]) && sg[k] > 0)) return false;
  dct1(sg, a);
  // Converged to the accuracy asked for: the dropped terms change S by about
  // r * tail (x in [-1, 1]), at most a tenth of the check tolerance.
  const double tol = kCheckRel * ref + 1e-15 * total_;
  if (!(r * tail(a) <= 0.1 * tol)) return false;
  // A_j = r (c_{j-1} - c_{j+1}) / (2j), with c_0 counted twice for j = 1
  // (the integral of T_0 is T_1); A_0 from S(-1) = 0.
  double A[kN + 2];
  for (int j = 1; j <= kN + 1; ++j) {
    const double lo = j == 1 ? 2 * a[0] : a[j - 1];
    const double hi = j + 1 <= kN ? a[j + 1] : 0.0;
    A[j] = r * (lo - hi) / (2.0 * j);
  }
  double alt = 0;
  for (int j = 1; j <= kN + 1; ++j) alt += (j & 1) ? -A[j] : A[j];
  A[0] = -alt;
  const double L = clenshaw(A, kN + 1, 1.0);
  if (!(std::abs(L - ref) <= tol)) return false;
  if (!(std::abs(clenshaw(A, kN + 1, 0.0) - al_->span_length(span, u0, m)) <= tol)) return false;
  // 2. inverse: x(y) with S(x) = (y + 1) L / 2, interpolated at the Chebyshev
  // points in y (each x by safeguarded Newton on S, derivative r sigma)
  auto solve = [&](double T) {
    double lo = -1, hi = 1, x = std::clamp(-1 + 2 * T / L, -1.0, 1.0);
    for (int it = 0; it < 100; ++it) {
      const double f = clenshaw(A, kN + 1, x) - T;
      if (f == 0) break;
      (f < 0 ? lo : hi) = x;
      const double dS = r * clenshaw(a, kN, x);
      double xn = dS > 0 ? x - f / dS : 0.5 * (lo + hi);
      const bool newton = xn > lo && xn < hi;
      if (!newton) xn = 0.5 * (lo + hi);
      // Newton converges quadratically: after a Newton step below 1e-8 the
      // error is of the order of its square, below the rounding of x (and
      // the inverse is checked against S between its nodes below)
      const bool done = (newton && std::abs(xn - x) <= 1e-8) || hi - lo <= 4e-16;
      x = xn;
      if (done) break;
    }
    return x;
  };
  double xs[kN + 1], b[kN + 1];
  for (int k = 0; k <= kN; ++k) xs[k] = k == 0 ? 1.0 : k == kN ? -1.0 : solve(0.5 * (ct[k] + 1) * L);
  dct1(xs, b);
  // the same for the inverse: an error dx moves S by up to r max(sigma) dx
  const double smax = *std::max_element(sg, sg + kN + 1);
  if (!(r * smax * tail(b) <= 0.1 * tol)) return false;
  // 3. check the inverse between its nodes: |S(x(y)) - T(y)| <= tol
  for (int k = 0; k < kN; ++k) {
    const double y = cos_table().mid[k];
    const double x = clenshaw(b, kN, y);
    if (!(std::abs(clenshaw(A, kN + 1, x) - 0.5 * (y + 1) * L) <= tol)) return false;
  }
  p.u0 = u0;
  p.u1 = u1;
  p.s0 = 0;
  p.s1 = ref;  // the constructor turns this into the end arc length
  p.len = L;
  p.span = span;
  p.fallback = false;
  p.linear = false;
  p.off = static_cast<int>(coef_.size());
  coef_.insert(coef_.end(), b, b + kN + 1);
  return true;
}

void ArcTable::build_span(int span, double u0, double u1, int depth, int start) {
  const double m = 0.5 * (u0 + u1);
  const bool halve = depth < kMaxDepth && u0 < m && m < u1;
  if (depth < start && halve) {
    build_span(span, u0, m, depth + 1, start);
    build_span(span, m, u1, depth + 1, start);
    return;
  }
  const double ref = al_->span_length(span, u0, u1);
  Piece p{};
  if (try_piece(span, u0, u1, ref, p)) {
    pc_.push_back(p);
    min_depth_ = std::min(min_depth_, depth);
    return;
  }
  if (halve) {
    build_span(span, u0, m, depth + 1, start);
    build_span(span, m, u1, depth + 1, start);
    return;
  }
  p = Piece{u0, u1, 0, ref, ref, span, true, false, 0};
  pc_.push_back(p);
}

double ArcTable::u_at(double s, int& hint) const {
  if (!(s > 0)) return c_->u_begin();
  if (s >= total_) return c_->u_end();
  const int np = static_cast<int>(pc_.size());
  int i = std::clamp(hint, 0, np - 1);
  while (i + 1 < np && s > pc_[i].s1) ++i;
  while (i > 0 && s < pc_[i].s0) --i;
  hint = i;
  const Piece& p = pc_[i];
  if (p.fallback) return al_->u_at(s);
  if (p.linear) return std::clamp(p.u0 + (s - p.s0) / (p.s1 - p.s0) * (p.u1 - p.u0), p.u0, p.u1);
  const double y = std::clamp(2 * (s - p.s0) / p.len - 1, -1.0, 1.0);
  const double x = clenshaw(coef_.data() + p.off, kN, y);
  const double m = 0.5 * (p.u0 + p.u1), r = 0.5 * (p.u1 - p.u0);
  return std::clamp(m + r * x, p.u0, p.u1);
}

double ArcTable::span_end(int span) const {
  const auto it = std::upper_bound(pc_.begin(), pc_.end(), span, [](int sp, const Piece& p) { return sp < p.span; });
  return it == pc_.begin() ? 0.0 : std::prev(it)->s1;
}

}  // namespace traj::plan
