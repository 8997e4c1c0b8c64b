// SPDX-License-Identifier: Apache-2.0
// Per-segment-length data of the forward-difference compiler's fast paths:
// the binomials C(K, i) and the register needs derived from them (exact, on
// limbs, no GMP), cached per thread; and Compiler::register_needs.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "fd/detail/fd_internal.hpp"
#include "fd/fd_compiler.hpp"

namespace traj::fd {
namespace detail {
namespace {

using mw::Big;

// C(K, i), i = 0..N (zero for i > K), and their sum over i = 1..N, exactly.
struct Binomials {
  Big c[8];
  Big sum;
  void compute(int N, uint64_t K) {
    mw::big_set(c[0], 1);
    mw::big_set(sum, 0);
    for (int i = 1; i <= N; ++i) {
      c[i] = c[i - 1];
      if (static_cast<uint64_t>(i) > K) {
        mw::big_set(c[i], 0);
        continue;
      }
      mw::big_mul_small(c[i], K - static_cast<uint64_t>(i) + 1);  // C(K,i) = C(K,i-1) (K-i+1) / i, exact
      mw::div_small(c[i].v, c[i].n, static_cast<uint64_t>(i));
      if (c[i].v[c[i].n - 1] == 0) --c[i].n;
      mw::big_add(sum, c[i]);
    }
  }
};

// RegisterNeeds from C(K, i) (i = 1..N) and their sum, for tol = m 2^e:
// 1/2 X 2^-f <= tol/2 <=> X <= m 2^(e+f), so the least f is p - e with p from
// least_pow2_exponent (then at least 0).
NeedsArr compute_needs(int N, const Binomials& b, const Dyadic& tol) {
  const uint64_t m = static_cast<uint64_t>(tol.m);
  auto need = [&](const Big& v) {
    return v.n == 0 ? 0 : static_cast<int>(std::max(0L, mw::least_pow2_exponent(v.v, v.n, m) - tol.e));
  };
  NeedsArr nd;
  for (int i = 1; i <= N; ++i) {
    nd.alone[i] = need(b.c[i]);
    Big x = b.c[i];
    mw::big_mul_small(x, static_cast<uint64_t>(N));
    nd.share[i] = need(x);
    if (mw::big_cmp(b.c[i], b.c[nd.binding]) >= 0) nd.binding = i;  // the largest, highest i on ties
  }
  nd.common = need(b.sum);
  return nd;
}

constexpr int kKCacheBits = 10;
struct KCacheOwner {
  KData* p = nullptr;
  ~KCacheOwner() { delete[] p; }
};

}  // namespace

void set_needs(RegisterNeeds& nd, int N, const NeedsArr& a) {
  nd.alone.assign(a.alone, a.alone + N + 1);
  nd.share.assign(a.share, a.share + N + 1);
  nd.binding = a.binding;
  nd.common = a.common;
}

// A planner's segments repeat a few hundred lengths, so the cache is
// direct-mapped per thread; a miss costs one exact computation on limbs.
const KData& k_data(int N, uint64_t K, double tol_lsb) {
  thread_local KData* cache = nullptr;
  if (!cache) {
    thread_local KCacheOwner owner;
    cache = owner.p = new KData[size_t(1) << kKCacheBits];
  }
  uint64_t tb;
  std::memcpy(&tb, &tol_lsb, sizeof tb);
  const uint64_t h = (K * 0x9E3779B97F4A7C15ull) ^ (tb * 0xC2B2AE3D27D4EB4Full) ^ static_cast<uint64_t>(N);
  KData& e = cache[h >> (64 - kKCacheBits)];
  if (e.N == N && e.K == K && e.tol == tb) return e;
  Binomials b;
  b.compute(N, K);
  e.K = K;
  e.tol = tb;
  e.N = N;
  mw::trunc_double(b.sum.v, b.sum.n, 0, e.q2_d);  // >= 1 and < 2^448: always a normal double
  for (int i = 0; i < 8; ++i)
    e.binlo[i] = i > N || b.c[i].n == 0 ? 0 : (static_cast<u128>(b.c[i].n > 1 ? b.c[i].v[1] : 0) << 64) | b.c[i].v[0];
  e.needs = compute_needs(N, b, dyadic(tol_lsb));
  return e;
}

}  // namespace detail

RegisterNeeds Compiler::register_needs(int degree, uint64_t k, double tol_lsb) {
  if (!(tol_lsb > 0) || !std::isfinite(tol_lsb))
    throw CompileError("register_needs: tol_lsb=" + detail::fmt_double(tol_lsb) + " must be positive and finite");
  if (degree < 1 || degree > 7) throw CompileError("register_needs: degree out of range 1..7");
  RegisterNeeds nd;
  detail::set_needs(nd, degree, detail::k_data(degree, k, tol_lsb).needs);
  return nd;
}

}  // namespace traj::fd
