// SPDX-License-Identifier: Apache-2.0
// The forward-difference compiler's public entry points (fd_compiler.hpp).
// The paths behind compile() are in fd_grid*.cpp, fd_exact.cpp and
// fd_reference.cpp (see detail/fd_internal.hpp); the budget functions in
// fd_reference.cpp, register_needs in fd_needs.cpp.
#include "fd/fd_compiler.hpp"

#include <cmath>
#include <stdexcept>

#include "fd/detail/fd_internal.hpp"

namespace traj::fd {

using namespace detail;

PathCounts& path_counts() {
  thread_local PathCounts c;
  return c;
}

mpz_class binom(uint64_t k, int i) {
  mpz_class r;
  mpz_bin_uiui(r.get_mpz_t(), k, static_cast<unsigned long>(i));
  return r;
}

Compiler::Compiler(Format f) : f_(f) {
  f_.validate();
  scale_ld_ = std::ldexp(1.0L, f_.guard_bits + f_.frac_bits);
  limit_ld_ = std::ldexp(1.0L, f_.width - 1) * (1 - std::ldexp(1.0L, -40));
  // Q(K) is increasing in K, so the budget check is K <= kfit_ for every
  // K <= max_ticks; found with the exact fits() test.
  if (fits(f_.degree, f_.max_ticks, f_.guard_bits, f_.tol_lsb)) {
    kfit_ = f_.max_ticks;
  } else if (fits(f_.degree, 1, f_.guard_bits, f_.tol_lsb)) {
    uint64_t lo = 1, hi = f_.max_ticks;  // fits(lo), !fits(hi)
    while (hi - lo > 1) {
      const uint64_t mid = lo + (hi - lo) / 2;
      (fits(f_.degree, mid, f_.guard_bits, f_.tol_lsb) ? lo : hi) = mid;
    }
    kfit_ = lo;
  } else {
    kfit_ = 0;
  }
}

void Compiler::compile(const PolySegment& seg, const std::vector<mpz_class>* start, const std::string& where,
                       Compiled& out, double start_slack_lsb) const {
  // The refusals before any arithmetic, in the reference's order and words.
  check_segment(f_, seg, start, where);
  if (!(start_slack_lsb >= 0) || !std::isfinite(start_slack_lsb))
    throw std::invalid_argument("Compiler::compile: the start slack must be finite and >= 0");
  const double start_tol = f_.tol_lsb / 2 + start_slack_lsb;
  if (seg.ticks > kfit_) {
    out = compile_reference(f_, seg, start, where, start_tol);  // words the refusal
    return;
  }
  // compile_grid() reads `start` before it writes `out` (r[0] of an axis
  // before its end), so start may be &out.end.
  if (!compile_grid(f_, scale_ld_, limit_ld_, seg, start, start_tol, out))
    out = compile_exact(f_, scale_ld_, limit_ld_, seg, start, start_tol, where);
  wrap_differences(out);
}

// r[1..N] as the engine holds them: two's complement in Width bits. The
// engine's adders wrap modulo 2^Width, so r0(k) = sum_i r_i C(k,i) modulo
// 2^Width is the same for the exact and the wrapped values, and r0(k) itself
// is range-checked: only a difference register that needs more than Width
// bits (one-tick quintics: r[4], r[5]) changes. `end` stays the exact r0(K).
void Compiler::wrap_differences(Compiled& c) const {
  for (auto& axis : c.regs)
    for (size_t i = 1; i < axis.size(); ++i) wrap_to_width(axis[i], f_.width);
}

void wrap_to_width(mpz_class& v, int width) {
  mpz_ptr p = v.get_mpz_t();
  const auto w = static_cast<mp_bitcnt_t>(width);
  if (mpz_sizeinbase(p, 2) < w) return;  // |v| < 2^(W-1): already a W-bit two's complement value
  mpz_fdiv_r_2exp(p, p, w);              // 0 <= v < 2^W
  if (mpz_tstbit(p, w - 1)) {            // top bit set: the negative value
    mpz_class m;
    mpz_setbit(m.get_mpz_t(), w);
    mpz_sub(p, p, m.get_mpz_t());
  }
}

Compiled Compiler::compile(const PolySegment& seg, const std::vector<mpz_class>* start,
                           const std::string& where) const {
  Compiled out;
  compile(seg, start, where, out);
  return out;
}

mpz_class Compiler::state_at(const Compiled& c, int axis, uint64_t k, int width) {
  const auto& r = c.regs[axis];
  mpz_class s = 0;
  if (r.empty()) return s;
  mpz_ptr sp = s.get_mpz_t();
  mpz_set(sp, r[0].get_mpz_t());
  mpz_ptr b = scratch().sb;  // C(k, i), built incrementally
  mpz_set_ui(b, 1);
  for (size_t i = 1; i < r.size() && i <= k; ++i) {
    mpz_mul_ui(b, b, k - i + 1);
    mpz_divexact_ui(b, b, static_cast<unsigned long>(i));
    mpz_addmul(sp, r[i].get_mpz_t(), b);
  }
  if (width > 0) wrap_to_width(s, width);
  return s;
}

mpz_class Compiler::sample_at(const Compiled& c, int axis, uint64_t k) const {
  mpz_class s = state_at(c, axis, k, f_.width);
  mpz_fdiv_q_2exp(s.get_mpz_t(), s.get_mpz_t(), f_.guard_bits);
  return s;
}

std::vector<uint64_t> Compiler::words(const Compiled& c) const {
  static_assert(GMP_NUMB_BITS == 64, "words() reads 64-bit GMP limbs");
  const int C = f_.chunk_width;
  std::vector<uint64_t> w;
  size_t nregs = 0;
  for (const auto& axis : c.regs) nregs += axis.size();
  w.reserve(2 + nregs * static_cast<size_t>(f_.width / C));
  const uint64_t cmask = C == 64 ? ~uint64_t(0) : ((uint64_t(1) << C) - 1);
  if (C < 32) {
    for (int s = 0; s < 32; s += C) w.push_back((uint64_t(c.ticks) >> s) & cmask);
  } else {
    w.push_back(c.ticks);
  }
  mpz_ptr v = scratch().sw;
  for (const auto& axis : c.regs) {
    for (const auto& r : axis) {
      mpz_fdiv_r_2exp(v, r.get_mpz_t(), static_cast<mp_bitcnt_t>(f_.width));  // two's complement, W bits
      // C divides 64, so a chunk never straddles two limbs.
      for (int s = 0; s < f_.width; s += C)
        w.push_back((static_cast<uint64_t>(mpz_getlimbn(v, s / 64)) >> (s % 64)) & cmask);
    }
  }
  return w;
}

}  // namespace traj::fd
