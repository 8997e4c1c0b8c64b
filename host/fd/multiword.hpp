// SPDX-License-Identifier: Apache-2.0
// trajcore host: multi-word integers for the forward-difference compiler's
// fast exact paths (fd_grid*.cpp, fd_exact.cpp, fd_needs.cpp).
//
// Two kinds of value, both arrays of 64-bit limbs, least significant first:
//   - signed: n limbs of two's complement, arithmetic modulo 2^(64 n); the
//     callers bound the exact values in advance so that they fit, and the ring
//     operations (add, subtract, multiply by a non-negative constant, shift)
//     then give them exactly. A 128-bit value is the case n = 2 (u128).
//   - unsigned magnitudes: an n-limb array read as a non-negative integer
//     (leading zero limbs allowed), and Big, a magnitude that grows (the
//     binomials C(K, i), i <= 7, K < 2^64: below 2^448, 7 limbs).
// and their conversions to and from GMP's mpz (its limbs are 64-bit here).
// Everything is inline: the grid paths call these per term and register, with
// n a compile-time constant at the call.
#pragma once
#include <gmp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace traj::fd::mw {

static_assert(GMP_NUMB_BITS == 64 && sizeof(mp_limb_t) == 8, "64-bit GMP limbs expected");
using u128 = unsigned __int128;
using i128 = __int128;

// ---- bit lengths and bits of unsigned magnitudes ----

inline int bitlen_u64(uint64_t v) { return v ? 64 - __builtin_clzll(v) : 0; }
// Bit length of an n-limb magnitude (leading zero limbs allowed).
inline int bitlen_limbs(const uint64_t* x, int n) {
  while (n > 0 && x[n - 1] == 0) --n;
  return n ? 64 * (n - 1) + bitlen_u64(x[n - 1]) : 0;
}
// Bits [pos, pos + 64) of an n-limb magnitude (pos >= 0).
inline uint64_t bits64_at(const uint64_t* x, int n, long pos) {
  const long q = pos >> 6;
  const unsigned r = static_cast<unsigned>(pos & 63);
  const uint64_t lo = q < n ? x[q] : 0;
  if (!r) return lo;
  const uint64_t hi = q + 1 < n ? x[q + 1] : 0;
  return (lo >> r) | (hi << (64 - r));
}
// The same for pos of any sign (bits below 0 are zero).
inline uint64_t get64(const uint64_t* x, int n, long pos) {
  if (pos >= 0) return bits64_at(x, n, pos);
  if (pos <= -64) return 0;
  return x[0] << (-pos);
}
// Whether any of bits [0, pos) of x is set.
inline bool any_bits_below(const uint64_t* x, int n, long pos) {
  const long q = pos >> 6;
  for (long l = 0; l < q && l < n; ++l)
    if (x[l]) return true;
  const unsigned r = static_cast<unsigned>(pos & 63);
  return r && q < n && (x[q] & ((uint64_t(1) << r) - 1));
}
// Sign of x - m 2^s for an n-limb magnitude x and 1 <= m < 2^64, exactly.
inline int cmp_m2e(const uint64_t* x, int n, uint64_t m, long s) {
  const long bx = bitlen_limbs(x, n), bm = bitlen_u64(m);
  if (bx != bm + s) return bx > bm + s ? 1 : -1;
  if (s >= 0) {  // same bit length: compare the top bm bits, then the rest
    const uint64_t top = bits64_at(x, n, s) & (bm == 64 ? ~uint64_t(0) : (uint64_t(1) << bm) - 1);
    if (top != m) return top > m ? 1 : -1;
    return any_bits_below(x, n, s) ? 1 : 0;
  }
  const uint64_t xs = x[0] << (-s);  // bx = bm + s < 64 bits, shifted to bm bits
  return xs > m ? 1 : xs < m ? -1 : 0;
}
// Least integer p with x <= m 2^p (x >= 1, m >= 1): with p0 = bitlen(x) -
// bitlen(m), m 2^(p0-1) < 2^(bitlen(x)-1) <= x and x < 2^bitlen(x) <= m 2^(p0+1),
// so p is p0 or p0 + 1, decided by one exact comparison.
inline long least_pow2_exponent(const uint64_t* x, int n, uint64_t m) {
  const long p0 = static_cast<long>(bitlen_limbs(x, n)) - bitlen_u64(m);
  return cmp_m2e(x, n, m, p0) <= 0 ? p0 : p0 + 1;
}
// x = floor(x / d) for an n-limb magnitude, d < 2^32; returns the remainder.
// Two 64-by-32-bit steps per limb (the running remainder is below d, so every
// partial dividend fits in 64 bits).
inline uint64_t div_small(uint64_t* x, int n, uint64_t d) {
  uint64_t r = 0;
  for (int l = n - 1; l >= 0; --l) {
    const uint64_t hi = (r << 32) | (x[l] >> 32);
    const uint64_t qh = hi / d;
    r = hi - qh * d;
    const uint64_t lo = (r << 32) | (x[l] & 0xffffffffu);
    const uint64_t ql = lo / d;
    r = lo - ql * d;
    x[l] = (qh << 32) | ql;
  }
  return r;
}
// |x| 2^p of an n-limb magnitude as a double, truncated to 53 bits like
// mpz_get_d / mpq_get_d; false if the result would not be a normal double.
inline bool trunc_double(const uint64_t* x, int n, long p, double& out) {
  const int bx = bitlen_limbs(x, n);
  if (bx == 0) {
    out = 0;
    return true;
  }
  uint64_t mant = bx <= 64 ? x[0] : bits64_at(x, n, bx - 64);
  const int bm = bx <= 64 ? bx : 64;
  p += bx - bm;
  if (bm > 53) {
    mant >>= bm - 53;
    p += bm - 53;
  }
  const long binade = p + std::min(bm, 53) - 1;
  if (binade < -1022 || binade > 1023) return false;
  const uint64_t bits = (static_cast<uint64_t>(binade + 1023) << 52) |
                        ((mant << (53 - std::min(bm, 53))) & ((uint64_t(1) << 52) - 1));
  std::memcpy(&out, &bits, sizeof out);
  return true;
}

// ---- signed n-limb two's complement, modulo 2^(64 n) ----

inline bool is_neg(const uint64_t* x, int n) { return static_cast<int64_t>(x[n - 1]) < 0; }
inline bool is_zero(const uint64_t* x, int n) {
  uint64_t o = 0;
  for (int l = 0; l < n; ++l) o |= x[l];
  return o == 0;
}
inline void neg(uint64_t* x, int n) {  // x = -x
  uint64_t c = 1;
  for (int l = 0; l < n; ++l) {
    x[l] = ~x[l] + c;
    c = c && x[l] == 0;
  }
}
inline void abs_to(const uint64_t* x, uint64_t* m, int n) {  // m = |x|
  for (int l = 0; l < n; ++l) m[l] = x[l];
  if (is_neg(x, n)) neg(m, n);
}
inline void add(uint64_t* x, const uint64_t* y, int n) {  // x += y
  u128 c = 0;
  for (int l = 0; l < n; ++l) {
    c += static_cast<u128>(x[l]) + y[l];
    x[l] = static_cast<uint64_t>(c);
    c >>= 64;
  }
}
inline void sub(uint64_t* x, const uint64_t* y, int n) {  // x -= y
  uint64_t borrow = 0;
  for (int l = 0; l < n; ++l) {
    const uint64_t t = x[l] - y[l];
    const uint64_t b1 = x[l] < y[l];
    x[l] = t - borrow;
    borrow = b1 | (t < borrow);
  }
}
inline void add_u64_at(uint64_t* x, uint64_t v, int at, int n) {  // x += v 2^(64 at)
  uint64_t c = v;
  for (int l = at; l < n; ++l) {
    x[l] += c;
    c = x[l] < c;
  }
}
inline void sub_u64(uint64_t* x, uint64_t v, int n) {  // x -= v
  uint64_t b = v;
  for (int l = 0; l < n; ++l) {
    const uint64_t t = x[l];
    x[l] = t - b;
    b = t < b;
  }
}
// out = x m (m >= 0; out may be x); returns the carry out of the top limb,
// so that it also multiplies an unsigned magnitude.
inline uint64_t mul1(uint64_t* out, const uint64_t* x, uint64_t m, int n) {
  u128 c = 0;
  for (int l = 0; l < n; ++l) {
    c += static_cast<u128>(x[l]) * m;
    out[l] = static_cast<uint64_t>(c);
    c >>= 64;
  }
  return static_cast<uint64_t>(c);
}
inline void shl(uint64_t* x, unsigned long s, int n) {  // x <<= s
  const long q = static_cast<long>(s / 64);
  const unsigned r = static_cast<unsigned>(s % 64);
  for (long l = n - 1; l >= 0; --l) {
    const uint64_t hi = l - q >= 0 ? x[l - q] : 0;
    const uint64_t lo = l - q - 1 >= 0 ? x[l - q - 1] : 0;
    x[l] = r ? (hi << r) | (lo >> (64 - r)) : hi;
  }
}
inline void sar(uint64_t* x, unsigned long s, int n) {  // x = floor(x / 2^s)
  const uint64_t fill = is_neg(x, n) ? ~uint64_t(0) : 0;
  const unsigned long q = s / 64;
  const unsigned r = static_cast<unsigned>(s % 64);
  for (unsigned long l = 0; l < static_cast<unsigned long>(n); ++l) {
    const uint64_t lo = l + q < static_cast<unsigned long>(n) ? x[l + q] : fill;
    const uint64_t hi = l + q + 1 < static_cast<unsigned long>(n) ? x[l + q + 1] : fill;
    x[l] = r ? (lo >> r) | (hi << (64 - r)) : lo;
  }
}
// Signed value as long double (relative error below 2^-61), n <= 16.
inline long double to_long_double(const uint64_t* x, int n) {
  uint64_t m[16];
  abs_to(x, m, n);
  long double v = 0;
  for (int l = n - 1; l >= 0; --l) v = v * 0x1p64L + static_cast<long double>(m[l]);
  return is_neg(x, n) ? -v : v;
}

// ---- unsigned magnitudes that grow: Big ----

struct Big {
  uint64_t v[8] = {};
  int n = 0;  // limbs in use; v[n-1] != 0 unless n == 0
};
inline void big_set(Big& x, uint64_t v) {
  x.v[0] = v;
  x.n = v ? 1 : 0;
}
inline void big_mul_small(Big& x, uint64_t m) {  // x *= m
  const uint64_t c = mul1(x.v, x.v, m, x.n);
  if (c) x.v[x.n++] = c;
  if (m == 0) x.n = 0;
}
inline void big_add(Big& x, const Big& y) {  // x += y
  const int n = std::max(x.n, y.n);
  u128 c = 0;
  for (int l = 0; l < n; ++l) {
    c += static_cast<u128>(l < x.n ? x.v[l] : 0) + (l < y.n ? y.v[l] : 0);
    x.v[l] = static_cast<uint64_t>(c);
    c >>= 64;
  }
  x.n = n;
  if (c) x.v[x.n++] = static_cast<uint64_t>(c);
}
inline int big_cmp(const Big& x, const Big& y) {
  if (x.n != y.n) return x.n < y.n ? -1 : 1;
  for (int l = x.n - 1; l >= 0; --l)
    if (x.v[l] != y.v[l]) return x.v[l] < y.v[l] ? -1 : 1;
  return 0;
}

// ---- conversions to and from mpz ----

// x = (negate ? -z : z) in n limbs (exact if |z| < 2^(64 n - 1); modulo
// 2^(64 n) otherwise).
inline void from_mpz(uint64_t* x, mpz_srcptr z, bool negate, int n) {
  const int zn = std::abs(z->_mp_size);
  const mp_limb_t* p = z->_mp_d;
  for (int l = 0; l < n; ++l) x[l] = l < zn ? p[l] : 0;
  if ((z->_mp_size < 0) != negate && z->_mp_size != 0) neg(x, n);
}
// Low 128 bits of an mpz in two's complement.
inline u128 low128(mpz_srcptr z) {
  uint64_t x[2];
  from_mpz(x, z, false, 2);
  return (static_cast<u128>(x[1]) << 64) | x[0];
}

// The mpz setters write the limbs straight into the mpz: in place if there is
// room (a reused result); a fresh mpz (GMP >= 6.2: mpz_init allocates
// nothing, _mp_alloc = 0) gets exactly the limbs it needs from GMP's own
// allocation function (fetched once per result by the caller, so a program
// that sets its own keeps it), which is what mpz_limbs_write would do through
// _mpz_realloc, minus the round trip; GMP frees them with mpz_clear.
using GmpAlloc = void* (*)(size_t);
inline GmpAlloc gmp_alloc_func() {
  void* (*fa)(size_t);
  mp_get_memory_functions(&fa, nullptr, nullptr);
  return fa;
}
inline mp_limb_t* mpz_room(mpz_ptr z, int k, GmpAlloc alloc) {  // k >= 1
  if (z->_mp_alloc >= k) return z->_mp_d;
  if (z->_mp_alloc == 0) {
    mp_limb_t* p = static_cast<mp_limb_t*>(alloc(static_cast<size_t>(k) * sizeof(mp_limb_t)));
    z->_mp_d = p;
    z->_mp_alloc = k;
    return p;
  }
  return mpz_limbs_write(z, k);
}
// z = sign * the k-limb magnitude m (m[k-1] != 0 or k = 0).
inline void mpz_set_mag(mpz_ptr z, const uint64_t* m, int k, bool negative, GmpAlloc alloc) {
  if (k > 0) {
    mp_limb_t* p = mpz_room(z, k, alloc);
    for (int l = 0; l < k; ++l) p[l] = m[l];
  }
  z->_mp_size = negative ? -k : k;
}
// z = the signed n-limb two's complement value x (n <= 16).
inline void mpz_set_limbs(mpz_ptr z, const uint64_t* x, int n, GmpAlloc alloc) {
  uint64_t m[16];
  const bool negative = is_neg(x, n);
  const uint64_t flip = negative ? ~uint64_t(0) : 0;
  uint64_t c = negative ? 1 : 0;
  for (int l = 0; l < n; ++l) {  // m = negative ? ~x + 1 : x
    m[l] = (x[l] ^ flip) + c;
    c = c & (m[l] == 0);
  }
  int k = n;
  while (k > 0 && m[k - 1] == 0) --k;
  mpz_set_mag(z, m, k, negative, alloc);
}
// z = v, a signed 128-bit value.
inline void mpz_set_s128(mpz_ptr z, u128 v, GmpAlloc alloc) {
  const uint64_t x[2] = {static_cast<uint64_t>(v), static_cast<uint64_t>(v >> 64)};
  mpz_set_limbs(z, x, 2, alloc);
}
// |v| 2^p as long double, v an integer (rounded to 53 bits; exact exponent).
inline long double mpz_ldexp_abs(mpz_srcptr v, long p) {
  if (mpz_sgn(v) == 0) return 0;
  long ex;
  const double d = mpz_get_d_2exp(&ex, v);
  return std::ldexp(std::fabs(static_cast<long double>(d)), static_cast<int>(ex + p));
}
inline long double mpz_ldexp(mpz_srcptr v, long p) {
  const long double a = mpz_ldexp_abs(v, p);
  return mpz_sgn(v) < 0 ? -a : a;
}

}  // namespace traj::fd::mw
