// SPDX-License-Identifier: Apache-2.0
// Test-only helpers of the forward-difference compiler tests: a format
// builder, and the per-register needs computed independently of the compiler
// (exact GMP arithmetic by plain loops, not the compiler's limb code).
#pragma once
#include <gmpxx.h>

#include <algorithm>
#include <cstdint>
#include <string>

#include "fd/fd_compiler.hpp"

namespace fd_test {

using traj::fd::Format;
using traj::fd::RegisterNeeds;

inline Format fmt(int axes, int deg, int w, int c, int g, int frac) { return {axes, deg, w, c, g, frac}; }

// C(k, i) = k (k-1) ... (k-i+1) / i!, numerator and denominator as products.
inline mpz_class binom_product(uint64_t k, int i) {
  if (static_cast<uint64_t>(i) > k) return 0;
  mpz_class num = 1, den = 1;
  for (int t = 0; t < i; ++t) {
    num *= mpz_class(std::to_string(k - static_cast<uint64_t>(t)));
    den *= t + 1;
  }
  return num / den;  // exact
}

inline int bit_length(mpz_class v) {  // v >= 0, by repeated halving
  int n = 0;
  while (v > 0) {
    v >>= 1;
    ++n;
  }
  return n;
}

// Least integer f >= 0 with x <= tol 2^f (x >= 0), tol the exact rational of
// the double: x q <= p 2^f with tol = p/q.
inline int least_f(const mpz_class& x, double tol) {
  if (x == 0) return 0;
  mpq_class t;
  mpq_set_d(t.get_mpq_t(), tol);
  const mpz_class p = t.get_num(), q = t.get_den();
  const mpz_class lhs = x * q;
  int f = std::max(0, bit_length(lhs) - bit_length(p) - 1);
  while (lhs > (p << f)) ++f;
  while (f > 0 && lhs <= (p << (f - 1))) --f;
  return f;
}

inline RegisterNeeds reference_needs(int deg, uint64_t k, double tol) {
  RegisterNeeds r;
  r.alone.assign(deg + 1, 0);
  r.share.assign(deg + 1, 0);
  mpz_class sum = 0, best = -1;
  for (int i = 1; i <= deg; ++i) {
    const mpz_class c = binom_product(k, i);
    sum += c;
    r.alone[i] = least_f(c, tol);      // 1/2 C 2^-f <= tol/2
    r.share[i] = least_f(c * deg, tol);  // 1/2 C 2^-f <= tol/(2N)
    if (c >= best) {
      best = c;
      r.binding = i;
    }
  }
  r.common = least_f(sum, tol);
  return r;
}

}  // namespace fd_test
