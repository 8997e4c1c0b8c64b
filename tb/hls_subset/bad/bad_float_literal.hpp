// SPDX-License-Identifier: Apache-2.0
// A model outside the hls subset: a floating literal in a template that is
// never instantiated (so no code is emitted for it). Must be refused.
#pragma once
#include <cstdint>
template <int N> int64_t bad_scale(int64_t x) { return static_cast<int64_t>(x * 1e3); }
