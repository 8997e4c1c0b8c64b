// SPDX-License-Identifier: Apache-2.0
// The forward-difference compiler's grid path on 2 limbs (the common case):
// see detail/fd_grid.hpp.
#include <algorithm>
#include <cstring>
#include <type_traits>

#include "fd/detail/fd_grid.hpp"

namespace traj::fd::detail {
namespace {

// The axes on the 2-limb grid of 2^-g register LSB (32 <= g <= 64; the
// caller's bound keeps every quantity below 2^127 grid units, every term below
// 2^124): as grid_wide_axes, on native 128-bit integers (modular, the exact values
// fitting), with m_h^j taken to its top 128 bits, for degree N (a template
// argument: the sums unroll on constant surj(j,i)). For a term below 2^125
// grid units that truncation errs by less than m_j 2^(t+s) < 2^125 / top <=
// 1/4 grid unit, so a term off the grid errs by less than 2 units (1 if m_h^j
// has at most 128 bits).
template <int N>
bool grid2_axes_n(const Format& f, const PolySegment& seg, const std::vector<mpz_class>* start, const HPowers& hp,
                  const Dyadic (*d)[8], const long (*tb)[8], const u128* binlo, double q2_d, const Dyadic& htol,
                  long double scale_ld, long double limit_ld, int g, double& carried, GridOut& o) {
  const int G = f.guard_bits;
  const long sigma = G + f.frac_bits;
  const uint64_t K = seg.ticks;
  const long double T_ld = static_cast<long double>(seg.h) * static_cast<long double>(K);
  const long double grid_ld = g == 64 ? 0x1p-64L : 1.0L / static_cast<long double>(uint64_t(1) << g);  // 2^-g
  const u128 half = static_cast<u128>(1) << (g - 1);
  const uint64_t mask = g == 64 ? ~uint64_t(0) : (uint64_t(1) << g) - 1;  // 2^g - 1
  uint64_t wt[8];  // error weight of term j when off the grid
  for (int j = 1; j <= N; ++j) wt[j] = hp.bits[j] <= 128 ? 1 : 2;
  long sj[8];   // the exponent s of term j less e_j
  long rsb[8];  // the right shift rs of term j plus e_j
  for (int j = 1; j <= N; ++j) {
    sj[j] = sigma + static_cast<long>(j) * hp.hd.e + g;
    rsb[j] = -(sj[j] + hp.tshift[j]);
  }
  // The continuity bound tol/2 2^G in grid units, m 2^(e+G+g), as one 128-bit
  // threshold when it is an integer below 2^127 (else cmp_m2e decides).
  const long tol_sh = htol.e + G + g;
  const bool tol_fast = tol_sh >= 0 && mw::bitlen_u64(static_cast<uint64_t>(htol.m)) + tol_sh <= 127;
  const u128 tol_thr = tol_fast ? static_cast<u128>(static_cast<uint64_t>(htol.m)) << tol_sh : 0;
  const long k_bits = mw::bitlen_u64(K);
  long q2_bits;  // 2 Q(K) < 2^q2_bits (q2_d is it truncated: same binary exponent)
  {
    uint64_t qb;
    std::memcpy(&qb, &q2_d, sizeof qb);
    q2_bits = static_cast<long>((qb >> 52) & 0x7ff) - 1022;  // normal, >= 1
  }

  for (int a = 0; a < f.axes; ++a) {
    const Dyadic* da = d[a];
    // c0 = x(0) 2^sigma + 2^(G-1) on the grid (the caller checked e_0 + sigma + g >= 0).
    u128 c0 = static_cast<u128>(1) << (G - 1 + g);
    if (da[0].m) {
      const u128 t = static_cast<u128>(da[0].m < 0 ? -da[0].m : da[0].m) << (da[0].e + sigma + g);
      c0 = da[0].m < 0 ? c0 - t : c0 + t;
    }
    u128 e0, r0;
    if (start) {
      r0 = mw::low128((*start)[a].get_mpz_t());  // |r0| < 2^(125-g) (the caller's bound)
      e0 = (r0 << g) - c0;
    } else {
      const u128 z = c0 + half;
      r0 = static_cast<u128>(static_cast<i128>(z) >> g);
      e0 = half - (static_cast<uint64_t>(z) & mask);
      o.reg[a][0][0] = static_cast<uint64_t>(r0);
      o.reg[a][0][1] = static_cast<uint64_t>(r0 >> 64);
    }
    const bool eneg = static_cast<i128>(e0) < 0;
    const u128 em = eneg ? -e0 : e0;
    const uint64_t eml[2] = {static_cast<uint64_t>(em), static_cast<uint64_t>(em >> 64)};
    if (start && em && (tol_fast ? em > tol_thr : mw::cmp_m2e(eml, 2, static_cast<uint64_t>(htol.m), tol_sh) > 0))
      return false;
    double e0_lsb;
    // = mw::trunc_double(eml, 2, -(g + G)): |e0| 2^-(g+G) truncated to 53 bits, a
    // normal double for every e0 != 0 (binary exponent bitlen - 1 - (g + G)
    // in [-190, 127]).
    if (em == 0) {
      e0_lsb = 0;
    } else {
      const int bx = eml[1] ? 128 - __builtin_clzll(eml[1]) : 64 - __builtin_clzll(eml[0]);
      const uint64_t mant = static_cast<uint64_t>(bx > 53 ? em >> (bx - 53) : em << (53 - bx));
      const uint64_t eb = (static_cast<uint64_t>(bx - 1 - (g + G) + 1023) << 52) | (mant & ((uint64_t(1) << 52) - 1));
      std::memcpy(&e0_lsb, &eb, sizeof e0_lsb);
    }
    carried = std::max(carried, e0_lsb);
    // Range, first by bit lengths: the blended target's power coefficients
    // are a_0 = r0, a_1 = u_1 K - e0, a_j = u_j K^j with |u_j| < 2^(bitlen m_j +
    // bitlen m_h^j + e_j + sigma + j e_h) and K^j < 2^(j bitlen K). If those
    // bounds, 2 |e0| and 2 Q(K) stay below 2^(W-5), then sum |a_j| + |e0| +
    // 2 Q(K) + 2 (at most 11 such terms, N <= 7) is below 11/16 of the limit
    // 2^(W-1), and sum |a_j| >= max |b_i|: the reference (exact, then a few
    // roundings of relative size 2^-52 at most) accepts. Otherwise the long
    // double bound decides.
    {
      const u128 r0m = static_cast<i128>(r0) < 0 ? -r0 : r0;
      const uint64_t r0l[2] = {static_cast<uint64_t>(r0m), static_cast<uint64_t>(r0m >> 64)};
      long mb =
          std::max<long>({mw::bitlen_limbs(r0l, 2), static_cast<long>(mw::bitlen_limbs(eml, 2)) - g + 1, q2_bits});
      for (int j = 1; j <= N; ++j) mb = std::max<long>(mb, tb[a][j] + j * k_bits);  // tb: bits of |u_j|
      if (mb > f.width - 5) {
        const long double e0_ld = static_cast<long double>(eml[1]) * 0x1p64L + static_cast<long double>(eml[0]);
        const long double r0_ld = static_cast<long double>(r0l[1]) * 0x1p64L + static_cast<long double>(r0l[0]);
        if (!range_ok(N, seg.coef[a], scale_ld, T_ld, static_cast<i128>(r0) < 0 ? -r0_ld : r0_ld,
                      (eneg ? -e0_ld : e0_ld) * grid_ld, q2_d, limit_ld))
          return false;
      }
    }
    // Terms: u_j = m_j top_j 2^(tshift_j + s), s = e_j + sigma + j e_h + g,
    // truncated; m_j top_j >= 2^127 > 2^124 > u_j, so tshift_j + s < -3 (a
    // right shift).
    u128 u[N + 1];
    uint64_t off[N + 1];
    for (int j = 1; j <= N; ++j) {
      u[j] = 0;
      off[j] = 0;
      if (!da[j].m) continue;
      // m top = A + B 2^64 (A, B the products with top's halves), taken down
      // by rs bits: floor((A + B 2^64) / 2^rs), below 2^124.
      const uint64_t am = static_cast<uint64_t>(da[j].m < 0 ? -da[j].m : da[j].m);
      const u128 A = static_cast<u128>(static_cast<uint64_t>(hp.top[j])) * am;
      const u128 B = static_cast<u128>(static_cast<uint64_t>(hp.top[j] >> 64)) * am;
      const long s = da[j].e + sj[j];
      const long rs = rsb[j] - da[j].e;
      u128 v = 0;
      if (rs < 64) v = (B << (64 - rs)) + (A >> rs);  // exact below 2^128 (rs >= 4)
      else if (rs < 192) v = (B + (A >> 64)) >> (rs - 64);
      u[j] = da[j].m < 0 ? -v : v;
      off[j] = s < 0 ? wt[j] : 0;
    }
    // e0 = K qd + rd, 0 <= rd < K.
    u128 qd = 0;
    uint64_t rd = 0;
    if (em) {
      uint64_t ql[2] = {eml[0], eml[1]};
      const uint64_t r = mw::div_small(ql, 2, K);
      const u128 q = (static_cast<u128>(ql[1]) << 64) | ql[0];
      qd = eneg ? -(q + (r != 0)) : q;
      rd = eneg ? (r ? K - r : 0) : r;
    }
    // X_i = sum_j surj(j,i) u_j = i! c_i with c the coefficients of
    // sum_j u_j m^j in the falling factorials m(m-1)...(m-i+1) (surj(j,i) =
    // i! S(j,i)): c by synthetic division at the nodes 1..N-1 (ring
    // operations modulo 2^128 on the exact integers, so exact), with multiples
    // k <= 6 instead of the N(N+1)/2 products by surj(j,i). err_i the same way
    // on the error weights.
    for (int k = 1; k < N; ++k)
      for (int j = N - 1; j >= k; --j) {
        u[j] += u[j + 1] * static_cast<uint64_t>(k);
        off[j] += off[j + 1] * static_cast<uint64_t>(k);
      }
    u128 end = r0;
    for (int i = 1; i <= N; ++i) {
      u128 x = half + u[i] * kSurj.v[i][i];  // i! c_i
      const uint64_t err = off[i] * kSurj.v[i][i];
      uint64_t below = 0;
      if (i == 1) {
        x -= qd;
        below = rd != 0;
      }
      if (err == 0) {
        x -= below;
      } else {
        const uint64_t low = static_cast<uint64_t>(x) & mask;
        if (low < err + below || low > mask - (err - 1)) return false;  // within the error of a rounding boundary
      }
      const u128 ri = static_cast<u128>(static_cast<i128>(x) >> g);
      o.reg[a][i][0] = static_cast<uint64_t>(ri);
      o.reg[a][i][1] = static_cast<uint64_t>(ri >> 64);
      end += ri * binlo[i];
    }
    const u128 lim = static_cast<u128>(1) << (f.width - 1);
    if (end + lim - 1 > 2 * (lim - 1)) return false;
    o.end[a] = end;
  }
  return true;
}

// The grid path of compile() for a segment that passed the checks before any
// arithmetic and the budget check: true with `out` filled, or false (nothing

}  // namespace

bool grid2_axes(const Format& f, const PolySegment& seg, const std::vector<mpz_class>* start, const HPowers& hp,
                const Dyadic (*d)[8], const long (*tb)[8], const u128* binlo, double q2_d, const Dyadic& htol,
                long double scale_ld, long double limit_ld, int g, double& carried, GridOut& o) {
  auto run = [&](auto deg) {
    return grid2_axes_n<decltype(deg)::value>(f, seg, start, hp, d, tb, binlo, q2_d, htol, scale_ld, limit_ld, g,
                                              carried, o);
  };
  switch (f.degree) {
    case 1: return run(std::integral_constant<int, 1>());
    case 2: return run(std::integral_constant<int, 2>());
    case 3: return run(std::integral_constant<int, 3>());
    case 4: return run(std::integral_constant<int, 4>());
    case 5: return run(std::integral_constant<int, 5>());
    case 6: return run(std::integral_constant<int, 6>());
    default: return run(std::integral_constant<int, 7>());
  }
}

}  // namespace traj::fd::detail
