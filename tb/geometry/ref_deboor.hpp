// SPDX-License-Identifier: Apache-2.0
// Independent reference evaluators for tests and benchmarks (tb only; shares no code with
// host/geometry). Everything here is the textbook form, written separately:
//  * cox_de_boor_derivs<R>: the plain Cox-de Boor recursion (in precision R: double or long double) of the basis functions
//      N_{i,0}(u) = [t_i <= u < t_{i+1}],
//      N_{i,p}(u) = (u - t_i)/(t_{i+p} - t_i) N_{i,p-1} + (t_{i+p+1} - u)/(t_{i+p+1} - t_{i+1}) N_{i+1,p-1},
//    and of their derivatives
//      N^(k)_{i,p} = p ( N^(k-1)_{i,p-1}/(t_{i+p} - t_i) - N^(k-1)_{i+1,p-1}/(t_{i+p+1} - t_{i+1}) ),
//    with 0/0 := 0; the curve C^(k)(u) = sum_i N^(k)_{i,p}(u) P_i over the p+1 active functions.
//  * ders_basis_funs: The NURBS Book (Piegl & Tiller) algorithm A2.3, the efficient De Boor-Cox
//    triangular scheme (used for the operation count; templated on the scalar).
//  * rational: C^(k) = (A^(k) - sum_{i=1..k} binom(k,i) w^(i) C^(k-i)) / w (NURBS Book eq. 4.8).
#pragma once
#include <cmath>
#include <vector>

namespace ref {

struct Spline {
  int p = 0;
  std::vector<double> U;               // knots
  std::vector<std::vector<double>> P;  // control points (Cartesian)
  std::vector<double> W;               // weights, empty if non-rational
  int n() const { return static_cast<int>(P.size()); }
  int dim() const { return static_cast<int>(P[0].size()); }
};

// Span index s with U[s] <= u < U[s+1], p <= s <= n-1 (u = U[n] -> n-1).
inline int find_span(const Spline& c, double u) {
  int s = c.p;
  while (s + 1 < c.n() && c.U[s + 1] <= u) ++s;
  return s;
}

// R: the working precision of the reference (double, or long double to make the reference's own
// rounding negligible next to the code under test).
template <class R>
inline R safe_div(R a, R b) { return b == 0 ? R(0) : a / b; }

// Plain recursion. `span` selects which degree-0 function is 1 (half-open convention).
template <class R>
inline R N(const Spline& c, int i, int p, R u, int span) {
  if (p == 0) return i == span ? R(1) : R(0);
  const auto& U = c.U;
  return safe_div<R>(u - U[i], R(U[i + p]) - U[i]) * N<R>(c, i, p - 1, u, span) +
         safe_div<R>(R(U[i + p + 1]) - u, R(U[i + p + 1]) - U[i + 1]) * N<R>(c, i + 1, p - 1, u, span);
}
template <class R>
inline R dN(const Spline& c, int i, int p, int k, R u, int span) {
  if (k == 0) return N<R>(c, i, p, u, span);
  if (p == 0) return R(0);
  const auto& U = c.U;
  return p * (safe_div<R>(dN<R>(c, i, p - 1, k - 1, u, span), R(U[i + p]) - U[i]) -
              safe_div<R>(dN<R>(c, i + 1, p - 1, k - 1, u, span), R(U[i + p + 1]) - U[i + 1]));
}

// Derivatives 0..nd of the curve (rational handled by the Leibniz quotient formula), computed and
// returned in precision R. out[k][d]. span >= 0 forces the knot span whose polynomial is evaluated
// (e.g. a span's right end from inside: the half-open convention would pick the next span).
// The recursion N / dN above is evaluated bottom-up with every N^(k)_{i,q} computed once (the same
// expressions in the same order, so bitwise the same result as the plain recursion, but O(p^2) instead
// of O(2^p) work: usable at high degree). Only i in [span-q, span] can be non-zero.
template <class R>
inline std::vector<std::vector<R>> basis_derivs_table(const Spline& c, R u, int span, int nd) {
  const int p = c.p;
  const auto& U = c.U;
  // T[k][q][i - (span - q)], i = span-q..span.
  std::vector<std::vector<std::vector<R>>> T(nd + 1, std::vector<std::vector<R>>(p + 1));
  auto at = [&](int k, int q, int i) -> R {
    if (i < span - q || i > span) return R(0);
    return T[k][q][i - (span - q)];
  };
  for (int q = 0; q <= p; ++q)
    for (int k = 0; k <= nd; ++k) {
      T[k][q].assign(q + 1, R(0));
      for (int i = span - q; i <= span; ++i) {
        R v;
        if (q == 0) v = (k == 0 && i == span) ? R(1) : R(0);
        else if (k == 0)
          v = safe_div<R>(u - U[i], R(U[i + q]) - U[i]) * at(0, q - 1, i) +
              safe_div<R>(R(U[i + q + 1]) - u, R(U[i + q + 1]) - U[i + 1]) * at(0, q - 1, i + 1);
        else
          v = q * (safe_div<R>(at(k - 1, q - 1, i), R(U[i + q]) - U[i]) -
                   safe_div<R>(at(k - 1, q - 1, i + 1), R(U[i + q + 1]) - U[i + 1]));
        T[k][q][i - (span - q)] = v;
      }
    }
  std::vector<std::vector<R>> out(nd + 1);
  for (int k = 0; k <= nd; ++k) out[k] = T[k][p];  // out[k][j] = N^(k)_{span-p+j, p}
  return out;
}

template <class R>
inline std::vector<std::vector<R>> cox_de_boor_derivs_r(const Spline& c, double u, int nd, int span_in = -1) {
  const int span = span_in >= 0 ? span_in : find_span(c, u), dim = c.dim();
  const bool rat = !c.W.empty();
  std::vector<std::vector<R>> A(nd + 1, std::vector<R>(dim, R(0)));
  std::vector<R> w(nd + 1, R(0));
  const auto Nt = basis_derivs_table<R>(c, R(u), span, nd);
  for (int k = 0; k <= nd; ++k)
    for (int i = span - c.p; i <= span; ++i) {
      const R b = Nt[k][i - (span - c.p)];
      const R wi = rat ? R(c.W[i]) : R(1);
      for (int d = 0; d < dim; ++d) A[k][d] += b * wi * c.P[i][d];
      w[k] += b * wi;
    }
  std::vector<std::vector<R>> C(nd + 1, std::vector<R>(dim, R(0)));
  for (int k = 0; k <= nd; ++k)
    for (int d = 0; d < dim; ++d) {
      if (!rat) {
        C[k][d] = A[k][d];
        continue;
      }
      R v = A[k][d];
      for (int i = 1; i <= k; ++i) {
        R b = 1;  // binom(k, i)
        for (int j = 1; j <= i; ++j) b = b * (k - i + j) / j;
        v -= b * w[i] * C[k - i][d];
      }
      C[k][d] = v / w[0];
    }
  return C;
}

// The same, computed in precision R and returned as double.
template <class R = double>
inline std::vector<std::vector<double>> cox_de_boor_derivs(const Spline& c, double u, int nd) {
  const auto C = cox_de_boor_derivs_r<R>(c, u, nd);
  std::vector<std::vector<double>> out(C.size(), std::vector<double>(C.empty() ? 0 : C[0].size()));
  for (size_t k = 0; k < C.size(); ++k)
    for (size_t d = 0; d < C[k].size(); ++d) out[k][d] = static_cast<double>(C[k][d]);
  return out;
}

// The NURBS Book A2.3 (DersBasisFuns): ders[k][j] = N^(k)_{span-p+j,p}(u), k <= n, p < M. M = 8 (up to
// degree 7) is what bench_eval_ops uses: larger arrays cost the De Boor-Cox side extra instructions
// (measured: 577 instead of 499 per point at M = 32), so the compared kernel keeps the book's size.
template <class T, int M = 8>
void ders_basis_funs(int span, const T& u, int p, int n, const double* U, T ders[][M]) {
  T ndu[M][M], a[2][M], left[M], right[M];
  ndu[0][0] = T(1.0);
  for (int j = 1; j <= p; ++j) {
    left[j] = u - T(U[span + 1 - j]);
    right[j] = T(U[span + j]) - u;
    T saved = T(0.0);
    for (int r = 0; r < j; ++r) {
      ndu[j][r] = right[r + 1] + left[j - r];
      T temp = ndu[r][j - 1] / ndu[j][r];
      ndu[r][j] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    ndu[j][j] = saved;
  }
  for (int j = 0; j <= p; ++j) ders[0][j] = ndu[j][p];
  for (int r = 0; r <= p; ++r) {
    int s1 = 0, s2 = 1;
    a[0][0] = T(1.0);
    for (int k = 1; k <= n; ++k) {
      T d = T(0.0);
      const int rk = r - k, pk = p - k;
      if (r >= k) {
        a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
        d = a[s2][0] * ndu[rk][pk];
      }
      const int j1 = (rk >= -1) ? 1 : -rk;
      const int j2 = (r - 1 <= pk) ? k - 1 : p - r;
      for (int j = j1; j <= j2; ++j) {
        a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
        d = d + a[s2][j] * ndu[rk + j][pk];
      }
      if (r <= pk) {
        a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
        d = d + a[s2][k] * ndu[r][pk];
      }
      ders[k][r] = d;
      std::swap(s1, s2);
    }
  }
  double r = p;
  for (int k = 1; k <= n; ++k) {
    for (int j = 0; j <= p; ++j) ders[k][j] = ders[k][j] * T(r);
    r *= (p - k);
  }
}

// Curve derivatives 0..nd with A2.3 + the linear combination (NURBS Book A3.2), non-rational.
// P: control points row-major n x dim. out[k*dim + d].
template <class T>
void deboor_cox_derivs(int p, const double* U, const double* P, int dim, int span, const T& u, int nd, T* out) {
  T ders[8][8];
  ders_basis_funs<T>(span, u, p, nd, U, ders);
  for (int k = 0; k <= nd; ++k)
    for (int d = 0; d < dim; ++d) {
      T acc = ders[k][0] * T(P[(span - p) * dim + d]);
      for (int j = 1; j <= p; ++j) acc = acc + ders[k][j] * T(P[(span - p + j) * dim + d]);
      out[k * dim + d] = acc;
    }
}

}  // namespace ref
