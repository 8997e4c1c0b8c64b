// SPDX-License-Identifier: Apache-2.0
// A model outside the hls subset: heap allocation through the C library. Must be refused.
#pragma once
#include <cstdint>
#include <cstdlib>
inline void* bad_buffer(std::size_t n) { return std::malloc(n); }
