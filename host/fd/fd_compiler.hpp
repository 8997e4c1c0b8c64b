// SPDX-License-Identifier: Apache-2.0
// trajcore host: forward-difference segment compiler.
//
// Turns a per-axis polynomial in time into the engine's fixed-point difference
// registers, with exact rational arithmetic (GMP) for every rounding, an exact
// prediction of every output sample, and a proven error bound.
//
// Number format (all axes):
//   output sample  : OutWidth = Width - GuardBits bits, two's complement,
//                    1 LSB = 2^-FracBits position units
//   register r[i]  : Width bits, 1 LSB = 2^-GuardBits output LSB (one common LSB
//                    for every register, so the run-time path never shifts and
//                    the prediction is a closed form)
//   r[0] holds (x * 2^FracBits + 1/2) * 2^GuardBits: the engine's floor
//   (r[0] >> GuardBits) is then round-to-nearest of the position.
//
// Error analysis. Let the ideal register values be the exact forward
// differences D_i of the target q (see below) and r_i = D_i + e_i with
// |e_i| <= 1/2 (round to nearest) for i >= 1. Since r0(k) = sum_i r_i C(k,i)
// exactly (wrapping arithmetic is exact modulo 2^Width and r0 is range-checked),
// the register error at tick k is
//     E_k = e0 (1 - k/K) + sum_{i=1..N} e_i C(k,i),
//     |E_k| <= |e0| + Q(K),   Q(K) = 1/2 sum_{i=1..N} C(K,i)   (register LSB)
// where e0 is the start error carried in from the previous segment. The
// target is q(t) = x(t) 2^(F+G) + 2^(G-1) + e0 (1 - t/T): the carried error is
// blended out linearly, so the end state is within Q(K) of the exact end and
// chained segments never accumulate error. The compiler accepts a segment
// only if Q(K) <= tol/2 * 2^G and |e0| <= tol/2 * 2^G; every register error is
// then <= tol output LSB and every output sample is within 1/2 + tol LSB of the
// exact polynomial (the 1/2 is the output rounding).
//
// Per-register fraction bits, and why the registers share one LSB.
// Give register i >= 1 its own f_i fraction bits below the output LSB. Rounded
// to nearest, |e_i| <= 1/2 2^-f_i output LSB, and its contribution e_i C(k,i)
// is at most 1/2 C(K,i) 2^-f_i over the segment (C(k,i) grows with k). For
// every compiled segment the compiler reports (RegisterNeeds, below):
//   alone[i]  least f >= 0 with 1/2 C(K,i) 2^-f <= tol/2: register i given the
//             whole budget. A lower bound for ANY format: all the other terms
//             can have the same sign, so no register can do with fewer bits.
//   share[i]  least f >= 0 with 1/2 C(K,i) 2^-f <= tol/(2N): the budget split
//             equally among the N registers (the share rule). If every register
//             meets its share, the bound Q <= tol/2 holds. Equal shares are also
//             the split that minimises the total bits sum f_i (minimising
//             sum f_i subject to sum C_i 2^-f_i = tol gives C_i 2^-f_i equal).
//   binding   the register with the largest C(K,i) (the highest i on ties).
//             C(K,i+1)/C(K,i) = (K-i)/(i+1) >= 1 iff K >= 2i+1, so r[N] binds
//             for every K >= 2N-1, where alone[i], share[i] never decrease
//             with i.
//   common    least G >= 0 with 1/2 sum_i C(K,i) 2^-G <= tol/2: the one common
//             LSB that compile() requires (guard_bits >= common).
// Exactness forces the common LSB. In fixed point, r[i] <- r[i] + r[i+1] is
// exact in r[i]'s format only if f_i >= f_(i+1) (otherwise the low bits of
// r[i+1] are dropped every tick: a fresh rounding error per tick that
// accumulates like r[i+1]'s own, and a shifter in the real-time path). So
// f_0 >= f_1 >= ... >= f_N, while the needs grow with i: together
// f_i >= max_(j >= i) need_j, i.e. r[0] and r[1] (which carry every register's
// contribution) need the maximum over all registers, and for K >= 2N-1 every
// register is pushed up to r[N]'s need. One common LSB set by r[N] therefore
// costs nothing (only in segments shorter than 2N-1 ticks could registers
// above the binding one be coarser), and it keeps the run-time path free of
// shifts. Numerically max_i alone[i] <= common <= max_i share[i] (since
// C(K,i) <= sum_j C(K,j) <= N max_j C(K,j)), i.e. for K >= 2N-1
// alone[N] <= common <= share[N]: the common LSB is r[N]'s need under any
// split of the budget that gives r[N] between 1/N and all of it. Example (cubic, K = 4096, tol = 0.5): alone 13/24/35, share
// 15/26/36, common 35. The rule of thumb 12/23/34 is ceil(log2 C(4096,i)),
// i.e. the "alone" rule with 1/2 output LSB per register (tol = 1), a total
// of up to N/2 LSB rather than a share of tol/2.
#pragma once
#include <gmpxx.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "fd/fd_format.hpp"
#include "traj_common.hpp"

namespace traj::fd {

// Per axis, coefficients c[j] of t^j (t in seconds from the segment start).
// Fewer than degree+1 coefficients are padded with zeros.
struct PolySegment {
  std::vector<std::vector<double>> coef;
  double h = 1e-3;        // tick period, seconds
  uint64_t ticks = 0;     // K
};

// Per-register fraction-bit needs of a K-tick segment (see the header
// comment). Index i = 1..degree; index 0 (the position, which carries the
// start error, not a rounding of its own) is 0.
struct RegisterNeeds {
  std::vector<int> alone;  // register i with the whole budget tol/2 (a lower bound)
  std::vector<int> share;  // register i within an equal share tol/(2N) (sufficient)
  int binding = 0;         // the register with the largest C(K,i): r[N] when K >= 2N-1
  int common = 0;          // least common guard bits: sum C(K,i) <= tol 2^G
};

// A target given exactly (a polynomial already in the engine's units, e.g.
// one recovered from another stream's registers): per axis q(m) in the tick
// index m, 0 <= m <= K, in register units with r0's rounding bias included
// (q = x 2^(G+F) + 2^(G-1) for a position x), coefficients of m^j.
struct ExactTarget {
  std::vector<std::vector<mpq_class>> q;
  uint64_t ticks = 0;  // K
};

struct Compiled {
  uint32_t ticks = 0;
  std::vector<std::vector<mpz_class>> regs;  // [axis][i], signed exact values
  std::vector<mpz_class> end;                // r0 after K ticks: the next start
  double carried_lsb = 0;                    // |e0| in output LSB
  double bound_lsb = 0;                      // |e0| + Q(K), output LSB (register error bound)
  // |delta| of a linear blend delta (1 - t/T) the caller put into the target
  // (job::SegmentCompiler's exact joints), output LSB: it moves positions by
  // up to |delta| and first differences by |delta| / K, no higher difference.
  double offset_lsb = 0;
  RegisterNeeds needs;                       // per-register fraction bits for these K ticks
};

class Compiler {
 public:
  explicit Compiler(Format f);
  const Format& format() const { return f_; }

  // Exact state r0 for a position, as the compiler rounds it.
  mpz_class position_to_state(double x) const;

  // Compile one segment. `start` (per axis) is the exact r0 the engine holds at
  // the segment start (the previous segment's `end`); null means start from
  // the polynomial's own value (first segment after a preset).
  // `where` names the segment in error messages.
  Compiled compile(const PolySegment& seg, const std::vector<mpz_class>* start = nullptr,
                   const std::string& where = "segment") const;
  // The same into `out`, reusing its storage: a caller that compiles segment
  // after segment into one Compiled (its registers and vectors already sized)
  // allocates nothing on the common path. `start` may point to out.end. On a
  // CompileError `out` is unspecified.
  // start_slack_lsb: a start up to tol/2 + start_slack_lsb output LSB from
  // the polynomial's value is taken (its difference blended out linearly, as
  // always); carried_lsb and bound_lsb then count all of it. A caller that
  // knows the start's distance from the end of the previous polynomial (its
  // register error) and the two polynomials' mismatch (a joint) apart states
  // them itself (job::SegmentCompiler).
  void compile(const PolySegment& seg, const std::vector<mpz_class>* start, const std::string& where,
               Compiled& out, double start_slack_lsb = 0) const;

  // The same for an exact target (the reference's exact rational path: no
  // double anywhere), with the same checks, rounding and bound.
  Compiled compile_target(const ExactTarget& seg, const std::vector<mpz_class>* start = nullptr,
                          const std::string& where = "segment") const;

  // The engine's stream words for a compiled segment (header, then registers).
  std::vector<uint64_t> words(const Compiled& c) const;

  // Exact prediction: r0 at tick k (0 <= k <= K) and the output sample there.
  // The registers r[1..N] of a compiled segment are Width-bit two's complement
  // values (they may have wrapped, see wrap_differences): with `width` > 0 the
  // state is reduced to Width bits as the engine holds it (the exact r0 for
  // any segment the compiler accepted); 0 gives the plain sum.
  static mpz_class state_at(const Compiled& c, int axis, uint64_t k, int width = 0);
  mpz_class sample_at(const Compiled& c, int axis, uint64_t k) const;

  // Q(K) of the error analysis in register LSB (exact) and in output LSB.
  static mpz_class quant_bound_x2(int degree, uint64_t k);  // 2 Q(K) = sum C(K,i)
  double quant_bound_lsb(uint64_t k) const;
  // Longest K with Q(K) <= tol/2 (not capped by max_ticks); 0 if none.
  static uint64_t longest_segment(int degree, int guard_bits, double tol_lsb);
  // Guard bits needed for K ticks at this degree and tolerance.
  static int guard_bits_needed(int degree, uint64_t k, double tol_lsb);
  // Per-register needs for K >= 1 ticks (exact integer arithmetic; tol_lsb > 0).
  static RegisterNeeds register_needs(int degree, uint64_t k, double tol_lsb);

 private:
  void wrap_differences(Compiled& c) const;
  Format f_;
  // Longest K <= max_ticks with Q(K) <= tol/2 (0 if none), computed once: the
  // budget check of compile() is then K <= kfit_ (Q(K) is increasing in K).
  uint64_t kfit_ = 0;
  // Constants of compile()'s fast path: 2^(G+F) and the range limit
  // 2^(W-1) (1 - 2^-40), exact powers of two (and their product) in long double.
  long double scale_ld_ = 0;
  long double limit_ld_ = 0;
};

// Diagnostics (tests, benchmarks): how compile() settled segments on this
// thread. grid2/grid3/grid4: the fixed-point grid path on 2 limbs (the common
// case), or on 3 or 4 (wider values, or a rounding the 2-limb grid left open);
// exact: the exact integer path (a rounding the grids could not settle, or
// values too large for them); reference: the exact rational form (refusals,
// and what the fast paths leave to it).
struct PathCounts {
  uint64_t grid2 = 0, grid3 = 0, grid4 = 0, exact = 0, reference = 0;
};
PathCounts& path_counts();

// v reduced to a `width`-bit two's complement value: -2^(W-1) <= v < 2^(W-1).
void wrap_to_width(mpz_class& v, int width);

// Binomial C(k, i) exactly.
mpz_class binom(uint64_t k, int i);

}  // namespace traj::fd
