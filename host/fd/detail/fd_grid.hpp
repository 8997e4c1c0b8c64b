// SPDX-License-Identifier: Apache-2.0
// trajcore host: the forward-difference compiler's fixed-point grid path
// (fd_grid.cpp: compile_grid and its per-h cache; fd_grid2.cpp: the 2-limb
// grid; fd_grid_wide.cpp: the 3- and 4-limb grids). Internal.
//
// Fixed-point grid path (the common case: no GMP, no heap until the result).
//
// The same dyadic sums as compile_exact(), but each term
//     u_j = c_j 2^sigma h^j = m_j m_h^j 2^(e_j + sigma + j e_h)
// is taken on a grid of 2^-64 register LSB (truncated towards zero: error
// below one grid unit, and none if the term lies on the grid), in L = 3 or 4
// limbs of two's complement (L chosen per segment from a bound on every
// quantity; larger segments go to compile_exact()). Since m_j and m_h are odd,
// a term is off the grid exactly when its exponent is below -64. Then
//     X_i = sum_j surj(j,i) u_j   differs from the exact Delta^i by less than
//     err_i = sum of surj(j,i) over the terms off the grid (< 2^15 grid units),
// and r_i = floor(X_i/2^64 + 1/2) is certain unless X_i + 2^63 lies within
// err_i of a multiple of 2^64 (probability ~2^-49 for arbitrary data; exact
// ties, e.g. dyadic h, have err_i = 0 and are decided exactly). r_1 also
// carries the blend -e0/K: with e0 (exact on the grid) = K qd + rd,
// 0 <= rd < K, the exact value is X_1 - qd - rd/K, i.e. within (-1, 0] of
// X_1 - qd. An undecided rounding sends the segment to compile_exact().
// The start error e0 = r0 - c0 is exact on the grid (c0 = x(0) 2^sigma +
// 2^(G-1) must lie on it, else compile_exact()), so the continuity check,
// carried_lsb (truncated to a double as mpq_get_d does) and the range check's
// inputs are those of compile_exact(). The end state r0 + sum r_i C(K,i) is
// taken modulo 2^128: the range check bounds the exact value below
// 2^(W-1) <= 2^127 in magnitude (|r0(K) - q(T)| <= Q(K), README), so the
// residue read as a signed 128-bit integer is the exact value.
#pragma once
#include <vector>

#include "fd/detail/fd_internal.hpp"

namespace traj::fd::detail {

// m_h^j, j = 0..7, of the tick period's odd mantissa m_h < 2^53 (at most 371
// bits: 6 limbs), cached per thread for the last h.
struct HPowers {
  uint64_t key = 0;  // bit pattern of h (h > 0, so 0 means empty)
  Dyadic hd{0, 0};
  uint64_t p[8][6] = {};
  int n[8] = {};     // limbs in use
  int bits[8] = {};  // bit length
  u128 top[8] = {};  // m_h^j ~ top 2^tshift, top normalised to 128 bits (exact if bits <= 128)
  int tshift[8] = {};
};
const HPowers& h_powers(double h);

struct GridOut {
  uint64_t reg[8][8][3];  // [axis][i] r[i] as L-1 limbs (i = 0 only if no start)
  u128 end[8];
};

// The axes of one segment on the grid of 2^-64 register LSB in L = 3 or 4
// limbs (fd_grid_wide.cpp); false if a rounding is not certain or anything
// else is left to compile_exact().
bool grid_wide_axes(int L, const Format& f, const PolySegment& seg, const std::vector<mpz_class>* start,
                    const HPowers& hp, const Dyadic (*d)[8], const u128* binlo, double q2_d, const Dyadic& htol,
                    long double scale_ld, long double limit_ld, double& carried, GridOut& o);

// The axes on the 2-limb grid of 2^-g register LSB (fd_grid2.cpp; 32 <= g <=
// 64, the caller's bound keeping every quantity below 2^127 grid units, every
// term below 2^124; tb[a][j] bounds the bits of |u_j| in register units):
// as grid_wide_axes, on native 128-bit integers.
bool grid2_axes(const Format& f, const PolySegment& seg, const std::vector<mpz_class>* start, const HPowers& hp,
                const Dyadic (*d)[8], const long (*tb)[8], const u128* binlo, double q2_d, const Dyadic& htol,
                long double scale_ld, long double limit_ld, int g, double& carried, GridOut& o);

}  // namespace traj::fd::detail
