// SPDX-License-Identifier: Apache-2.0
// trajcore hls: BCU (Basic Calculation Unit), one de Casteljau mid-subdivision
// of a cubic Bernstein polynomial in the scaled form ([BCU], eq. 8).
// Mirrors rtl/traj_bcu.sv.
//
// Input: the four Bernstein coefficients (A, B, C, D) of a cubic on [t0, t1],
// each an InWidth-bit two's-complement integer.
// Output: the coefficients of the two halves [t0, m] and [m, t1], multiplied
// by 8 so that no division (right shift) is needed:
//
//   L = ( 8A, 4(A+B), 2(A+2B+C), A+3B+3C+D )
//   R = ( A+3B+3C+D, 2(B+2C+D), 4(C+D), 8D )
//
// Bit growth: exactly 3 bits per level (OutWidth = InWidth + 3). Every output
// is a combination of the inputs with non-negative weights summing to 8, so
// for any inputs in [-2^(w-1), 2^(w-1)-1] every output lies in
// [-2^(w+2), 2^(w+2)-8]: it always fits w+3 bits, no bit is ever lost.
// Cost: six adders (s1=A+B, s2=B+C, s3=C+D, t1=s1+s2, t2=s2+s3, m=t1+t2);
// the multiplications by 2, 4, 8 are wiring.
#pragma once
#include "traj_common.hpp"

namespace traj {

constexpr int kBcuGrowth = 3;  // bits added by one scaled mid-subdivision

struct BcuOut {
  u128 l[4];  // left half (A_l, B_l, C_l, D_l), InWidth+3 bits each
  u128 r[4];  // right half (A_r, B_r, C_r, D_r), A_r == D_l
};

// in[] canonical InWidth-bit values; outputs canonical (InWidth+3)-bit values.
inline BcuOut bcu_split(const u128 in[4], int in_width) {
  const int w = in_width + kBcuGrowth;
  const u128 a = wrap(static_cast<u128>(sext(in[0], in_width)), w);
  const u128 b = wrap(static_cast<u128>(sext(in[1], in_width)), w);
  const u128 c = wrap(static_cast<u128>(sext(in[2], in_width)), w);
  const u128 d = wrap(static_cast<u128>(sext(in[3], in_width)), w);
  const u128 s1 = wrap(a + b, w);
  const u128 s2 = wrap(b + c, w);
  const u128 s3 = wrap(c + d, w);
  const u128 t1 = wrap(s1 + s2, w);
  const u128 t2 = wrap(s2 + s3, w);
  const u128 m = wrap(t1 + t2, w);
  BcuOut o{};
  o.l[0] = wrap(a << 3, w);
  o.l[1] = wrap(s1 << 2, w);
  o.l[2] = wrap(t1 << 1, w);
  o.l[3] = m;
  o.r[0] = m;
  o.r[1] = wrap(t2 << 1, w);
  o.r[2] = wrap(s3 << 2, w);
  o.r[3] = wrap(d << 3, w);
  return o;
}

}  // namespace traj
