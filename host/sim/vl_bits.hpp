// SPDX-License-Identifier: Apache-2.0
// Bits [lo, lo+n) (n <= 128) of a Verilator port: an integral type for ports
// up to 64 bits, a VlWide (array of 32-bit words) above.
#pragma once
#include <type_traits>

#include "traj_common.hpp"

namespace traj {

template <class T>
u128 vl_bits(const T& v, int lo, int n) {
  if constexpr (std::is_integral_v<T>) {
    return bits(u128(static_cast<unsigned long long>(v)), lo, n);
  } else {
    // The 32-bit words that hold the field, at most five, then one shift.
    const int first = lo / 32, last = (lo + n - 1) / 32;
    u128 r = 0;
    for (int w = last; w > first; --w) r = (r << 32) | v[w];
    const unsigned sh = static_cast<unsigned>(lo % 32);
    r = (r << (32 - sh)) | (v[first] >> sh);  // 32 - sh in 1..32: defined for u128
    return n == 128 ? r : r & ((u128(1) << n) - 1);
  }
}

}  // namespace traj
