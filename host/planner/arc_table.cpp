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

// The same series at M points at once, each with the arithmetic of clenshaw:
// the recurrences are independent, so their latencies overlap (one
// recurrence alone waits on every step). Groups of 8 points keep the state in
// registers.
template <int M>
inline void clenshaw_at(const double* c, int n, const double* x, double* out) {
  static_assert(M % 8 == 0, "groups of 8 points");
  for (int g = 0; g < M; g += 8) {
    double b1[8], b2[8], x2[8];
    for (int i = 0; i < 8; ++i) {
      b1[i] = b2[i] = 0;
      x2[i] = 2 * x[g + i];
    }
    for (int k = n; k >= 1; --k)
      for (int i = 0; i < 8; ++i) {
        const double b0 = c[k] + x2[i] * b1[i] - b2[i];
        b2[i] = b1[i];
        b1[i] = b0;
      }
    for (int i = 0; i < 8; ++i) out[g + i] = c[0] + x[g + i] * b1[i] - b2[i];
  }
}

// cos(pi k / n), k = 0..2n (the DCT-I needs j k mod 2n), and the midpoints
// cos(pi (k + 1/2) / n), k = 0..n-1, for n = kN.
// dct[k][j] = c[(j k) mod 2n], the DCT-I's matrix.
struct CosTable {
  double c[2 * kN + 1], mid[kN], dct[kN + 1][kN + 1];
  CosTable() {
    for (int k = 0; k <= 2 * kN; ++k) c[k] = std::cos(M_PI * k / kN);
    for (int k = 0; k < kN; ++k) mid[k] = std::cos(M_PI * (k + 0.5) / kN);
    for (int k = 0; k <= kN; ++k)
      for (int j = 0; j <= kN; ++j) dct[k][j] = c[(j * k) % (2 * kN)];
  }
};
const CosTable& cos_table() {
  static const CosTable t;
  return t;
}

// Chebyshev coefficients (c[0] not halved) of the interpolant through f at the
// points cos(pi k / n), k = 0..n (DCT-I).
void dct1(const double* f, double* c) {
  const auto& dct = cos_table().dct;
  double acc[kN + 1];
  for (int j = 0; j <= kN; ++j) acc[j] = 0.5 * (f[0] + ((j & 1) ? -f[kN] : f[kN]));
  // each acc[j] sums its terms in the order k = 1..n-1; the j run side by side
  for (int k = 1; k < kN; ++k)
    for (int j = 0; j <= kN; ++j) acc[j] += f[k] * dct[k][j];
  for (int j = 0; j <= kN; ++j) c[j] = acc[j] * 2.0 / kN;
  c[0] *= 0.5;
  c[kN] *= 0.5;
}

// Size of the last two coefficients: what truncating the series costs.
double tail(const double* c) { return std::abs(c[kN - 1]) + std::abs(c[kN]); }

// The inverse of S (the integral of the speed series a, S(1) = L, slope
// r sigma with sigma = sg at the nodes ct[k]) at the Chebyshev points in y:
// xs[k] with S(xs[k]) = (ct[k] + 1) L / 2, k = 0..n. Each inner node by
// safeguarded Newton on S, all of them side by side, each with its own
// bracket and stop.
void inverse_at_nodes(const double* A, const double* a, const double* sg, double r, double L, double* xs) {
  const double* ct = cos_table().c;
  constexpr int kIn = kN - 1;  // inner nodes k = 1..n-1
  constexpr int kLanes = (kIn + 7) / 8 * 8;
  double T[kIn], x[kLanes] = {}, lo[kIn], hi[kIn], flo[kIn], fhi[kIn], f[kLanes], dS[kLanes];
  bool active[kIn];
  // First guesses: S and its slope r sigma are known at the x nodes ct[k]
  // (S in decreasing order of k); a cubic Hermite through the two nodes
  // around T, in S, is close enough where sigma is smooth that Newton
  // mostly stops after a step or two.
  constexpr int kNodes = (kN + 1 + 7) / 8 * 8;
  double Sx[kNodes];
  {
    double xn[kNodes] = {};
    std::copy(ct, ct + kN + 1, xn);
    clenshaw_at<kNodes>(A, kN + 1, xn, Sx);
  }
  for (int i = 0; i < kIn; ++i) {
    T[i] = 0.5 * (ct[i + 1] + 1) * L;
    lo[i] = -1;
    hi[i] = 1;
    flo[i] = -T[i];     // S(-1) = 0
    fhi[i] = L - T[i];  // S(1) = L
    int j = i;  // Sx[j + 1] <= T <= Sx[j]
    while (j > 0 && Sx[j] < T[i]) --j;
    while (j < kN - 1 && Sx[j + 1] > T[i]) ++j;
    const double H = Sx[j] - Sx[j + 1];
    double g = -1 + 2 * T[i] / L;
    if (H > 0) {
      const double t = (T[i] - Sx[j + 1]) / H, t2 = t * t, t3 = t2 * t;
      g = (2 * t3 - 3 * t2 + 1) * ct[j + 1] + (t3 - 2 * t2 + t) * H / (r * sg[j + 1]) + (3 * t2 - 2 * t3) * ct[j] +
          (t3 - t2) * H / (r * sg[j]);
    }
    x[i] = std::clamp(g, -1.0, 1.0);
    active[i] = true;
  }
  for (int it = 0, left = kIn; it < 100 && left > 0; ++it) {
    clenshaw_at<kLanes>(A, kN + 1, x, f);
    clenshaw_at<kLanes>(a, kN, x, dS);
    for (int i = 0; i < kIn; ++i) {
      if (!active[i]) continue;
      const double fi = f[i] - T[i];
      if (fi == 0) {
        active[i] = false;
        --left;
        continue;
      }
      if (fi < 0) {
        lo[i] = x[i];
        flo[i] = fi;
      } else {
        hi[i] = x[i];
        fhi[i] = fi;
      }
      // Newton converges quadratically: after a step below 1e-8 the error is
      // of the order of its square, at the rounding of x (and the inverse is
      // checked against S between its nodes below). Such a step is taken,
      // within the bracket, even where rounding puts it on or past an end (a
      // root at an end of the bracket, where bisection would take dozens of
      // halvings back). A larger step that leaves the bracket is replaced
      // by the secant of the bracket, else by bisection.
      const double d = r * dS[i];
      double xn = d > 0 ? x[i] - fi / d : lo[i];
      const bool done = (d > 0 && std::abs(xn - x[i]) <= 1e-8) || hi[i] - lo[i] <= 4e-16;
      if (done) {
        xn = std::clamp(xn, lo[i], hi[i]);
      } else if (!(xn > lo[i] && xn < hi[i])) {
        xn = lo[i] - flo[i] * (hi[i] - lo[i]) / (fhi[i] - flo[i]);
        if (!(xn > lo[i] && xn < hi[i])) xn = 0.5 * (lo[i] + hi[i]);
      }
      x[i] = xn;
      if (done) {
        active[i] = false;
        --left;
      }
    }
  }
  xs[0] = 1.0;
  xs[kN] = -1.0;
  std::copy(x, x + kIn, xs + 1);
}

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
  // points in y
  double xs[kN + 1], b[kN + 1];
  inverse_at_nodes(A, a, sg, r, L, xs);
  dct1(xs, b);
  // the same for the inverse: an error dx moves S by up to r max(sigma) dx
  const double smax = *std::max_element(sg, sg + kN + 1);
  if (!(r * smax * tail(b) <= 0.1 * tol)) return false;
  // 3. check the inverse between its nodes: |S(x(y)) - T(y)| <= tol
  const double* mid = cos_table().mid;
  double xm[kN], Sm[kN];
  clenshaw_at<kN>(b, kN, mid, xm);
  clenshaw_at<kN>(A, kN + 1, xm, Sm);
  for (int k = 0; k < kN; ++k)
    if (!(std::abs(Sm[k] - 0.5 * (mid[k] + 1) * L) <= tol)) return false;
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
