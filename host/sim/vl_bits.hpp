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
    u128 r = 0;
    for (int b = 0; b < n; ++b) {
      const int bit = lo + b;
      if ((v[bit / 32] >> (bit % 32)) & 1u) r |= u128(1) << b;
    }
    return r;
  }
}

}  // namespace traj
