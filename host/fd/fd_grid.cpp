// SPDX-License-Identifier: Apache-2.0
// The forward-difference compiler's fixed-point grid path: compile_grid()
// bounds the segment, picks the 2-, 3- or 4-limb grid and writes the result;
// see detail/fd_grid.hpp.
#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "fd/detail/fd_grid.hpp"

namespace traj::fd::detail {

const HPowers& h_powers(double h) {
  thread_local HPowers c;
  uint64_t key;
  std::memcpy(&key, &h, sizeof key);
  if (c.key != key) {
    c.key = key;
    c.hd = dyadic(h);
    const uint64_t m = static_cast<uint64_t>(c.hd.m);
    c.p[0][0] = 1;
    c.n[0] = 1;
    for (int j = 1; j < 8; ++j) {
      const uint64_t carry = mw::mul1(c.p[j], c.p[j - 1], m, c.n[j - 1]);
      c.n[j] = c.n[j - 1];
      if (carry) c.p[j][c.n[j]++] = carry;
    }
    for (int j = 0; j < 8; ++j) {
      c.bits[j] = mw::bitlen_limbs(c.p[j], c.n[j]);
      c.tshift[j] = c.bits[j] - 128;
      const uint64_t lo = mw::get64(c.p[j], c.n[j], c.tshift[j]), hi = mw::get64(c.p[j], c.n[j], c.tshift[j] + 64);
      c.top[j] = (static_cast<u128>(hi) << 64) | lo;
    }
  }
  return c;
}

bool compile_grid(const Format& f, long double scale_ld, long double limit_ld, const PolySegment& seg,
                  const std::vector<mpz_class>* start, double start_tol_lsb, Compiled& out) {
  const int N = f.degree;
  const int A = f.axes;
  const int G = f.guard_bits;
  const long sigma = G + f.frac_bits;
  const HPowers& hp = h_powers(seg.h);
  // Decompose the coefficients and bound every quantity in bits of register
  // units: c0 (and its bias 2^(G-1)), r0, and each term u_j times the largest
  // surj(j,i) (bitlen 1, 2, 3, 6, 8, 11, 15 for j = 1..7), plus 3 for a sum of
  // at most 7. Then |X_i|, |c0|, |r0| < 2^bits, |e0|, |qd| < 2^(bits+2), and
  // X_i + 2^(g-1) - qd stays below 2^(bits+3) in magnitude: the 2-limb grid
  // takes g = min(64, 124 - bits) >= 32 fraction bits, the 3- and 4-limb grids
  // 64 (bits + 67 <= 191, 255). c0 must lie on the grid: g >= gmin.
  static constexpr int kSurjBits[8] = {0, 1, 2, 3, 6, 8, 11, 15};
  Dyadic d[8][8];
  long tb[8][8];  // bits of |u_j| (register units), a large negative number if u_j = 0
  long bits = G, gmin = 1;
  for (int a = 0; a < A; ++a) {
    const std::vector<double>& cf = seg.coef[a];
    for (int j = 0; j <= N; ++j) d[a][j] = j < static_cast<int>(cf.size()) ? dyadic(cf[j]) : Dyadic{0, 0};
    if (d[a][0].m) {
      gmin = std::max<long>(gmin, -(d[a][0].e + sigma));
      bits = std::max<long>(bits, mw::bitlen_u64(static_cast<uint64_t>(std::abs(d[a][0].m))) + d[a][0].e + sigma);
    }
    for (int j = 1; j <= N; ++j) {
      tb[a][j] = d[a][j].m ? mw::bitlen_u64(static_cast<uint64_t>(std::abs(d[a][j].m))) + hp.bits[j] + d[a][j].e +
                                 sigma + static_cast<long>(j) * hp.hd.e
                           : -(1L << 30);
      bits = std::max<long>(bits, tb[a][j] + kSurjBits[j] + 3);
    }
    if (start) {
      mpz_srcptr z = (*start)[a].get_mpz_t();
      bits = std::max<long>(bits, mw::bitlen_limbs(z->_mp_d, std::abs(z->_mp_size)));
    }
  }
  const KData& kd = k_data(N, seg.ticks, f.tol_lsb);
  const double q2_d = kd.q2_d;
  const Dyadic htol = dyadic(start_tol_lsb);
  GridOut o;
  double carried = 0;
  int L1 = 0;  // limbs of a register, 0: not settled
  const long g2 = std::min<long>(64, 124 - bits);
  const bool ok2 = g2 >= 32 && g2 >= gmin &&
                   grid2_axes(f, seg, start, hp, d, tb, kd.binlo, q2_d, htol, scale_ld, limit_ld, static_cast<int>(g2),
                              carried, o);
  if (ok2) {
    ++path_counts().grid2;
    L1 = 2;
  } else if (gmin <= 64) {
    const long need = bits + 64 + 3;
    carried = 0;
    if (need <= 191 &&
        grid_wide_axes(3, f, seg, start, hp, d, kd.binlo, q2_d, htol, scale_ld, limit_ld, carried, o)) {
      ++path_counts().grid3;
      L1 = 2;
    } else if (need > 191 && need <= 255 &&
               grid_wide_axes(4, f, seg, start, hp, d, kd.binlo, q2_d, htol, scale_ld, limit_ld, carried, o)) {
      ++path_counts().grid4;
      L1 = 3;
    }
  }
  if (!L1) return false;

  out.ticks = static_cast<uint32_t>(seg.ticks);
  out.regs.resize(A);
  out.end.resize(A);
  const mw::GmpAlloc alloc = mw::gmp_alloc_func();
  auto set_reg = [&](mpz_ptr z, const uint64_t* x) {  // L1 a constant in each call, so it unrolls
    if (L1 == 2) mw::mpz_set_limbs(z, x, 2, alloc);
    else mw::mpz_set_limbs(z, x, 3, alloc);
  };
  for (int a = 0; a < A; ++a) {
    std::vector<mpz_class>& r = out.regs[a];
    r.resize(N + 1);
    if (start) {
      mpz_srcptr z = (*start)[a].get_mpz_t();
      mw::mpz_set_mag(r[0].get_mpz_t(), z->_mp_d, std::abs(z->_mp_size), z->_mp_size < 0, alloc);
    } else {
      set_reg(r[0].get_mpz_t(), o.reg[a][0]);
    }
    for (int i = 1; i <= N; ++i) set_reg(r[i].get_mpz_t(), o.reg[a][i]);
    mw::mpz_set_s128(out.end[a].get_mpz_t(), o.end[a], alloc);
  }
  out.carried_lsb = carried;
  // = quant_bound_lsb(K): q2_d 2^-(G+1), exact (q2_d >= 1, G + 1 <= 127: normal)
  double scale;
  const uint64_t sbits = static_cast<uint64_t>(1023 - (G + 1)) << 52;
  std::memcpy(&scale, &sbits, sizeof scale);
  out.bound_lsb = carried + q2_d * scale;
  set_needs(out.needs, N, kd.needs);
  return true;
}

}  // namespace traj::fd::detail
