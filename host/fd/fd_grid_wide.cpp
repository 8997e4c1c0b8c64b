// SPDX-License-Identifier: Apache-2.0
// The forward-difference compiler's grid path on 3 or 4 limbs (wider values,
// or a rounding the 2-limb grid left open): see detail/fd_grid.hpp.
#include <algorithm>
#include <cstdlib>

#include "fd/detail/fd_grid.hpp"

namespace traj::fd::detail {
namespace {

template <int L>
bool grid_axes(const Format& f, const PolySegment& seg, const std::vector<mpz_class>* start, const HPowers& hp,
               const Dyadic (*d)[8], const u128* binlo, double q2_d, const Dyadic& htol, long double scale_ld,
               long double limit_ld, double& carried, GridOut& o) {
  const int N = f.degree;
  const int G = f.guard_bits;
  const long sigma = G + f.frac_bits;
  const uint64_t K = seg.ticks;
  const long double T_ld = static_cast<long double>(seg.h) * static_cast<long double>(K);

  for (int a = 0; a < f.axes; ++a) {
    const std::vector<double>& cf = seg.coef[a];
    const Dyadic* da = d[a];
    // c0 = x(0) 2^sigma + 2^(G-1) on the grid.
    uint64_t c0[L] = {};
    if (da[0].m) {
      const uint64_t am = static_cast<uint64_t>(da[0].m < 0 ? -da[0].m : da[0].m);
      const long s0 = da[0].e + sigma + 64;
      for (int l = 0; l < L; ++l) c0[l] = mw::get64(&am, 1, 64 * l - s0);
      if (da[0].m < 0) mw::neg(c0, L);
    }
    mw::add_u64_at(c0, uint64_t(1) << ((G + 63) % 64), (G + 63) / 64, L);
    // r0 and e0 = r0 - c0 (grid units).
    uint64_t e0[L];
    u128 r0lo;
    if (start) {
      mpz_srcptr z = (*start)[a].get_mpz_t();
      e0[0] = 0;  // r0 on the grid: r0 2^64
      mw::from_mpz(e0 + 1, z, false, L - 1);
      mw::sub(e0, c0, L);
      r0lo = mw::low128(z);
    } else {
      uint64_t zz[L];
      for (int l = 0; l < L; ++l) zz[l] = c0[l];
      mw::add_u64_at(zz, uint64_t(1) << 63, 0, L);
      for (int l = 1; l < L; ++l) o.reg[a][0][l - 1] = zz[l];
      r0lo = (static_cast<u128>(zz[2]) << 64) | zz[1];
      // e0 = 2^63 - (low limb of c0 + 2^63), in (-2^63, 2^63]
      const uint64_t low = zz[0];
      const uint64_t v = (uint64_t(1) << 63) - low;  // modulo 2^64
      const bool negv = low > (uint64_t(1) << 63);
      e0[0] = v;
      for (int l = 1; l < L; ++l) e0[l] = negv ? ~uint64_t(0) : 0;
    }
    uint64_t e0m[L];
    mw::abs_to(e0, e0m, L);
    const bool e0zero = mw::is_zero(e0, L);
    // Continuity (refused by the reference: compile_exact() words it).
    if (start && !e0zero && mw::cmp_m2e(e0m, L, static_cast<uint64_t>(htol.m), htol.e + G + 64) > 0) return false;
    double e0_lsb;
    if (!mw::trunc_double(e0m, L, -(64L + G), e0_lsb)) return false;
    carried = std::max(carried, e0_lsb);

    // Range: the same long double Bernstein bound as compile_exact().
    {
      uint64_t r0l[L];  // r0 (register units), L limbs
      if (start) {
        mw::from_mpz(r0l, (*start)[a].get_mpz_t(), false, L);
      } else {
        for (int l = 0; l < L - 1; ++l) r0l[l] = o.reg[a][0][l];
        r0l[L - 1] = static_cast<int64_t>(r0l[L - 2]) < 0 ? ~uint64_t(0) : 0;
      }
      if (!range_ok(N, cf, scale_ld, T_ld, mw::to_long_double(r0l, L), mw::to_long_double(e0, L) * 0x1p-64L, q2_d,
                    limit_ld))
        return false;
    }

    // Terms on the grid.
    uint64_t u[8][L];
    uint64_t off[8];  // all ones if term j is off the grid (then its error is below one grid unit)
    for (int j = 1; j <= N; ++j) {
      off[j] = 0;
      if (!da[j].m) {
        for (int l = 0; l < L; ++l) u[j][l] = 0;
        continue;
      }
      const uint64_t am = static_cast<uint64_t>(da[j].m < 0 ? -da[j].m : da[j].m);
      // prod = |m_j| m_h^j (at most 7 limbs) at buf[4..], zeros around it.
      uint64_t buf[16];
      buf[0] = buf[1] = buf[2] = buf[3] = 0;
      const int pn = hp.n[j];
      buf[4 + pn] = mw::mul1(buf + 4, hp.p[j], am, pn);
      for (int l = 0; l < L; ++l) buf[5 + pn + l] = 0;  // read up to buf[4 + q + L], q <= pn
      // u_j = prod 2^s truncated: limb l holds bits [64 l - s, 64 l - s + 64)
      // of prod, i.e. words q + l, q + l + 1 of buf + 4 with q = floor(-s/64).
      // The size bound of compile_grid (bitlen(prod) + s - 64 + 3 + 67 <= 255)
      // gives s <= 248, so q >= -4.
      const long s = da[j].e + sigma + static_cast<long>(j) * hp.hd.e + 64;
      const long q = (-s) >> 6;  // floor
      const unsigned r = static_cast<unsigned>((-s) & 63);
      if (q > pn) {
        for (int l = 0; l < L; ++l) u[j][l] = 0;
      } else {
        const uint64_t* w0 = buf + 4 + q;
        for (int l = 0; l < L; ++l) u[j][l] = (w0[l] >> r) | ((w0[l + 1] << 1) << (63 - r));
      }
      off[j] = s < 0 ? ~uint64_t(0) : 0;
      if (da[j].m < 0) mw::neg(u[j], L);
    }
    // e0 = K qd + rd, 0 <= rd < K (floor division).
    uint64_t qd[L] = {};
    uint64_t rd = 0;
    if (!e0zero) {
      for (int l = 0; l < L; ++l) qd[l] = e0m[l];
      const uint64_t r = mw::div_small(qd, L, K);
      if (mw::is_neg(e0, L)) {
        if (r) mw::add_u64_at(qd, 1, 0, L);
        mw::neg(qd, L);
        rd = r ? K - r : 0;
      } else {
        rd = r;
      }
    }
    u128 end = r0lo;
    for (int i = 1; i <= N; ++i) {
      // X_i = sum_{j >= i} surj(j,i) u_j (modulo 2^(64 L); each limb column
      // below 7 2^79, so one u128 per column), err_i as above.
      u128 acc[L] = {};
      uint64_t err = 0;
      for (int j = i; j <= N; ++j) {
        const uint64_t sj = kSurj.v[j][i];
        for (int l = 0; l < L; ++l) acc[l] += static_cast<u128>(u[j][l]) * sj;
        err += off[j] & sj;
      }
      uint64_t x[L];
      u128 c = 0;
      for (int l = 0; l < L; ++l) {
        c += acc[l];
        x[l] = static_cast<uint64_t>(c);
        c >>= 64;
      }
      mw::add_u64_at(x, uint64_t(1) << 63, 0, L);
      uint64_t below = 0;  // 1 if the exact value lies below x by a fraction of a grid unit
      if (i == 1) {
        mw::sub(x, qd, L);
        below = rd != 0;
      }
      if (err == 0) {
        mw::sub_u64(x, below, L);
      } else if (x[0] < err + below || x[0] > uint64_t(0) - err) {
        return false;  // within the truncation error of a rounding boundary
      }
      for (int l = 1; l < L; ++l) o.reg[a][i][l - 1] = x[l];
      end += ((static_cast<u128>(x[2]) << 64) | x[1]) * binlo[i];
    }
    // |end| < 2^(W-1) by the range check; anything else would be a bug, and
    // compile_exact() would then compute it exactly.
    const u128 lim = static_cast<u128>(1) << (f.width - 1);  // W <= 128: 2^127 at most
    if (end + lim - 1 > 2 * (lim - 1)) return false;
    o.end[a] = end;
  }
  return true;
}

}  // namespace

bool grid_wide_axes(int L, const Format& f, const PolySegment& seg, const std::vector<mpz_class>* start,
                    const HPowers& hp, const Dyadic (*d)[8], const u128* binlo, double q2_d, const Dyadic& htol,
                    long double scale_ld, long double limit_ld, double& carried, GridOut& o) {
  return L == 3 ? grid_axes<3>(f, seg, start, hp, d, binlo, q2_d, htol, scale_ld, limit_ld, carried, o)
                : grid_axes<4>(f, seg, start, hp, d, binlo, q2_d, htol, scale_ld, limit_ld, carried, o);
}

}  // namespace traj::fd::detail
