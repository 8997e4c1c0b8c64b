// SPDX-License-Identifier: Apache-2.0
// A model outside the hls subset: a double. Must be refused.
#pragma once
#include <cstdint>
inline int64_t bad_half(int64_t x) { double d = static_cast<double>(x); return static_cast<int64_t>(d); }
