// SPDX-License-Identifier: Apache-2.0
// trajcore hls: shared widths and bit helpers for every hardware model.
//
// Subset rules for everything under hls/: fixed-width integers only, no floating
// point, no heap, every loop has a compile-time bound. The container for a
// register of up to 128 bits is `traj::u128` (the natural host type for an HLS
// ap_uint<128>); helpers keep values canonical (wrapped to W bits).
#pragma once
#include <cstdint>

namespace traj {

using u128 = unsigned __int128;
using i128 = __int128;

constexpr int kMaxWidth = 128;

// All-ones mask of the low w bits (0 <= w <= 128).
constexpr u128 mask(int w) {
  return w >= 128 ? ~u128(0) : ((u128(1) << w) - 1);
}

// Wrap an unsigned value to w bits (two's complement modulo 2^w).
constexpr u128 wrap(u128 v, int w) { return v & mask(w); }

// Interpret the low w bits of v as a signed two's-complement number.
constexpr i128 sext(u128 v, int w) {
  v = wrap(v, w);
  if (w < 128 && ((v >> (w - 1)) & 1)) v |= ~mask(w);
  return static_cast<i128>(v);
}

// Bits [lo, lo+n) of v, as an unsigned value.
constexpr u128 bits(u128 v, int lo, int n) { return (v >> lo) & mask(n); }

// Arithmetic shift right of a w-bit two's-complement value by s bits,
// returning the w-s bit result wrapped (floor division by 2^s).
constexpr u128 asr(u128 v, int w, int s) { return wrap(static_cast<u128>(sext(v, w) >> s), w - s); }

}  // namespace traj
