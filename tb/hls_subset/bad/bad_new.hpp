// SPDX-License-Identifier: Apache-2.0
// A model outside the hls subset: heap allocation. Must be refused.
#pragma once
#include <cstdint>
inline int64_t* bad_alloc() { return new int64_t[4]; }
