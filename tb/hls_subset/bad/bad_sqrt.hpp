// SPDX-License-Identifier: Apache-2.0
// A model outside the hls subset: floating arithmetic with neither a float
// keyword nor a floating literal. Must be refused.
#pragma once
#include <cmath>
#include <cstdint>
inline int64_t bad_root(int64_t x) { return static_cast<int64_t>(std::sqrt(x)); }
