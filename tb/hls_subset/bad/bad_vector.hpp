// SPDX-License-Identifier: Apache-2.0
// A model outside the hls subset: a dynamic container. Must be refused.
#pragma once
#include <cstdint>
#include <vector>
template <int N> struct BadTaps { std::vector<uint32_t> taps; };
