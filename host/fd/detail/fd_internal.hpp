// SPDX-License-Identifier: Apache-2.0
// trajcore host: what the forward-difference compiler's source files share
// (not part of the public API, fd_compiler.hpp).
//
// compile() runs the checks before any arithmetic and the budget check, then
// tries the fixed-point grid path (fd_grid.cpp), which settles nearly every
// segment without GMP, and hands what it cannot settle to the exact integer
// path (fd_exact.cpp), which hands refusals and borderline range decisions to
// the exact rational reference (fd_reference.cpp). Both fast paths rest on the
// following.
//
// Every input is a double, so every quantity is a dyadic rational: h = m_h 2^e_h,
// c_j 2^(G+F) = m_j 2^(e_j+G+F), and the exact forward differences of the
// unblended target are
//     Delta^i q(0) = sum_{j>=i} c_j 2^(G+F) h^j surj(j,i),  surj(j,i) = i! S(j,i),
// integers over one common power of two 2^-z. The linear blend of the carried
// error e0 (c_1 -= e0/T, T = K h) adds -e0/K to Delta^1 only; it is folded in
// by one exact integer division by K. Rounding floor(x + 1/2) is then a shift
// (and, for r[1], a floor division by K): the registers equal the mpq
// reference's bit for bit, since they are the same rationals rounded the same
// way. In compile_exact() the sums run on fixed-size two's complement limb
// arrays (at most 16 limbs, size bounded in advance per axis; mpz otherwise),
// the rest on mpz scratch variables held per thread (no allocation once warm).
//
// The range check is first tried in long double (range_ok, fd_range.cpp): the
// Bernstein coefficients of the blended target are computed with an a-priori
// error bound (2^-48 times the sum of the magnitudes of their terms, against
// an actual worst case below 2^-51: every input is exact or carries one
// rounding of relative size 2^-52 (double conversions of r0, e0) or 2^-64
// (long double operations, at most ~30 per coefficient)). The segment is
// accepted on this path only if
//     (max_i (|b_i| + 2^-48 sum_j |term_ij|) + |e0| + 2 Q(K) + 2) (1 + 2^-40)
//         < 2^(W-1) (1 - 2^-40),
// which implies that the reference's own long double computation accepts too
// (its roundings are relative 2^-52 at worst). The cruder bound
// sum_j |a_j| >= max_i |b_i| with the same margins is tried first. Anything
// else (a refusal, or a path within that margin of the limit) goes to
// compile_reference(), which then decides and words the message. The same
// holds for a discontinuous start and for a carried error too small for a
// normal double.
#pragma once
#include <gmpxx.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fd/fd_compiler.hpp"
#include "fd/multiword.hpp"

namespace traj::fd::detail {

using mw::i128;
using mw::u128;

// ---- exact rational helpers (fd_reference.cpp, fd_format.cpp) ----

// A double for messages, 6 significant digits.
std::string fmt_double(double v);
// Exact rational of a finite double.
mpq_class exact(double v);
// floor(q + 1/2)
mpz_class round_nearest(const mpq_class& q);
mpz_class pow2(int e);
// |reg_units| / 2^guard_bits as a double (output LSB).
double to_lsb(const mpq_class& reg_units, int guard_bits);
// Q(K) <= tol/2 * 2^G  <=>  sum C(K,i) <= tol * 2^G, exactly.
bool fits(int degree, uint64_t k, int guard_bits, double tol_lsb);

// ---- the paths of compile() ----

// The refusals before any arithmetic (shape, h, K, degree, finite
// coefficients, start state), shared by compile() and the reference.
void check_segment(const Format& f, const PolySegment& seg, const std::vector<mpz_class>* start,
                   const std::string& where);
// The straightforward exact form (mpq throughout). The fast paths fall back
// to it for every refusal and every case they cannot settle, so messages and
// borderline decisions are this function's by construction.
// start_tol_lsb < 0: tol/2 (Compiler::compile's start slack adds to it).
Compiled compile_reference(const Format& f, const PolySegment& seg, const std::vector<mpz_class>* start,
                           const std::string& where, double start_tol_lsb = -1);
// The grid path for a segment that passed the checks before any arithmetic
// and the budget check: true with `out` filled, or false (nothing decided).
// scale_ld = 2^(G+F), limit_ld = 2^(W-1) (1 - 2^-40), exact in long double.
// start_tol_lsb: the largest |e0| taken at a given start (Compiler::compile).
bool compile_grid(const Format& f, long double scale_ld, long double limit_ld, const PolySegment& seg,
                  const std::vector<mpz_class>* start, double start_tol_lsb, Compiled& out);
// The exact integer path: exact dyadic sums on limb arrays sized per axis,
// mpz otherwise; what it cannot decide goes to compile_reference().
// scale_ld = 2^(G+F), limit_ld = 2^(W-1) (1 - 2^-40) as compile_grid().
Compiled compile_exact(const Format& f, long double scale_ld, long double limit_ld, const PolySegment& seg,
                       const std::vector<mpz_class>* start, double start_tol_lsb, const std::string& where);

// ---- shared by the fast paths ----

// v = m 2^e with m odd (or m = 0, e = 0). Exact for every finite double.
struct Dyadic {  // trivial (arrays of it are not zeroed unless asked)
  int64_t m;
  int e;
};
inline Dyadic dyadic(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  const int ef = static_cast<int>((bits >> 52) & 0x7ff);
  uint64_t m = bits & ((uint64_t(1) << 52) - 1);
  Dyadic d{0, 0};
  if (ef == 0 && m == 0) return d;  // +-0
  int e = ef == 0 ? -1074 : ef - 1075;  // subnormal : normal
  if (ef != 0) m |= uint64_t(1) << 52;
  const int tz = __builtin_ctzll(m);
  d.m = static_cast<int64_t>(m >> tz);
  if (bits >> 63) d.m = -d.m;
  d.e = e + tz;
  return d;
}

// surj(j, i) = i! S(j, i) = Delta^i m^j at m = 0, j, i <= 7 (zero for i > j).
struct SurjConst {
  uint64_t v[8][8];
};
constexpr SurjConst make_surj() {
  SurjConst t{};
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i <= j; ++i) {
      int64_t sum = 0, cik = 1;  // sum_k (-1)^(i-k) C(i,k) k^j
      for (int k = 0; k <= i; ++k) {
        int64_t kj = 1;
        for (int e = 0; e < j; ++e) kj *= k;
        sum += ((i - k) % 2 ? -1 : 1) * cik * kj;
        cik = cik * (i - k) / (k + 1);
      }
      t.v[j][i] = static_cast<uint64_t>(sum);
    }
  return t;
}
constexpr SurjConst kSurj = make_surj();
static_assert(kSurj.v[5][5] == 120 && kSurj.v[7][4] == 8400 && kSurj.v[3][2] == 6, "surj(j,i) = i! S(j,i)");

// The long double range check (see above) for one axis' blended target with
// r0 = r0_ld, e0 = e0_ld (register units), q2_d = 2 Q(K) truncated to a
// double: true if it accepts; false leaves the decision (and a refusal's
// words) to the exact paths (fd_range.cpp).
bool range_ok(int N, const std::vector<double>& cf, long double scale_ld, long double T_ld, long double r0_ld,
              long double e0_ld, double q2_d, long double limit_ld);

// Register needs (fd_needs.cpp) in fixed arrays, i = 1..N.
struct NeedsArr {
  int alone[8] = {}, share[8] = {};
  int binding = 1, common = 0;
};
void set_needs(RegisterNeeds& nd, int N, const NeedsArr& a);
// Per (degree, K, tol): C(K, i) modulo 2^128, 2 Q(K) = sum C(K, i) as a
// double truncated like mpz_get_d, and the register needs; cached per thread.
struct KData {
  uint64_t K = 0, tol = 0;
  int N = 0;  // 0: empty
  double q2_d = 0;
  u128 binlo[8] = {};
  NeedsArr needs;
};
const KData& k_data(int N, uint64_t K, double tol_lsb);

// mpz scratch variables held per thread (fd_exact.cpp): no allocation once warm.
struct Scratch {
  mpz_t hp[8], u[8], bin[8], x, c0, r0, e, t, half, q2, sb, sw;
  Scratch();
  ~Scratch();
};
Scratch& scratch();

}  // namespace traj::fd::detail
