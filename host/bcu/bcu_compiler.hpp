// SPDX-License-Identifier: Apache-2.0
// traj::bcu: host compiler for the BCU generator (rtl/traj_bcu_gen.sv,
// hls/traj_bcu_gen.hpp).
//
// A segment is a time-parameterised cubic Bezier per axis on K = 2^d ticks:
//   x_a(t) = sum_i C(3,i) (1-t)^(3-i) t^i b_{a,i},  t = j/K, j = 0..K.
// Control values are compiled to integers with LSB 2^-(F+G) (F fraction bits of
// the output, G guard bits), rounded to nearest (ties away from zero):
//   c_{a,i} = round(b_{a,i} * 2^(F+G)),  |c - b*2^(F+G)| <= 1/2.
// The generator outputs, exactly (it is bit-exact, see hls/traj_bcu_gen.hpp),
//   s_j = floor( (N_j + 2^(3d+G-1)) / 2^(3d+G) ),
//   N_j = sum_i C(3,i) (K-j)^(3-i) j^i c_i          (integer, GMP),
// i.e. the fixed-point polynomial at t = j/K rounded once, half up.
//
// Error bound (every sample, every axis, any d), in units of the input:
//   |s_j 2^-F - x(t_j)| <= 2^-(F+1)        output rounding (half an LSB)
//                        + 2^-(F+G+1)      control rounding (Bernstein weights
//                                          are >= 0 and sum to 1)
//                        + 8 eps max|b|    the double reference itself
// It does not depend on d: the generator itself adds no error. Per sample it
// is tighter (Segment::exact_bound_lsb): with B0 = (1-t)^3 and offset the
// exact start offset c_0 2^-G - b_0 2^F (output LSB),
//   |s_j - x(t_j) 2^F| <= 1/2 + B0 |offset| + (1 - B0) 2^-(G+1)   (exact x)
// since s_j is within 1/2 of P(t_j) = sum_i B_i c_i 2^-G and
// P - x 2^F = B0 offset + sum_{i>=1} B_i (c_i 2^-G - b_i 2^F). A chained
// segment (bcu/chain.hpp) starts from the previous segment's exact end
// instead of round(b0 2^(F+G)); its offset is then larger (FD -> BCU: up to
// the FD end error + 2^-G) and fades out with (1-t)^3.
#pragma once
#include <Eigen/Dense>
#include <cstdint>
#include <gmpxx.h>
#include <vector>

#include "bcu/bcu_format.hpp"

namespace traj::bcu {


// Control values: one row per axis, columns b0..b3.
using Controls = Eigen::Matrix<double, Eigen::Dynamic, 4>;

struct Segment {
  int depth = 0;                             // d, K = 2^d
  std::vector<std::vector<mpz_class>> ctrl;  // [axis][i], LSB 2^-(F+G)
  std::vector<uint64_t> words;               // stream words, chunk_width bits each
  std::vector<std::vector<int64_t>> samples; // [j][axis], j = 0..K (j = K: end value)
  double bound = 0.0;                        // uniform error bound vs the double curve (input units):
                                             // the max over axes and j of bound_lsb(a, j) * 2^-F
  // Start offset of every axis, exact, in output LSB:
  //   offset[a] = c_{a,0} / 2^G - b_{a,0} 2^F.
  // For a segment compiled from its own b0 it is the control rounding,
  // |offset| <= 2^-(G+1). For a segment chained onto the previous segment's
  // exact end (traj::bcu::compile_segment_after, bcu/chain.hpp) it is
  // whatever the hand-off needs; it enters the bound with weight (1-t)^3.
  std::vector<mpq_class> offset;
  // End offset of every axis, exact, in output LSB: c_{a,3} / 2^G - b_{a,3} 2^F
  // (|end_offset| <= 2^-(G+1): D is always rounded from b3).
  std::vector<mpq_class> end_offset;
  int guard_bits = 0, frac_bits = 0;         // of the format it was compiled for
  double ref_lsb = 0.0;                      // 8 eps max|b| 2^F: the double reference's own error

  // Error bound of sample j (0..K) of axis a against the EXACT Bezier of the
  // given (double) control values, in output LSB (B0 = (1-t)^3, t = j/2^d):
  //   1/2 + B0 |offset[a]| + (1 - B0) 2^-(G+1)
  // (output rounding; the start offset; the rounding of b1..b3, whose
  // Bernstein weights sum to 1 - B0).
  double exact_bound_lsb(int a, int j) const;
  // The same against the double-precision de Casteljau curve: + ref_lsb.
  double bound_lsb(int a, int j) const { return exact_bound_lsb(a, j) + ref_lsb; }
};

// Compile one segment. Throws std::invalid_argument naming the axis and the
// control value for NaN/Inf or out-of-range values, and for d out of range.
Segment compile_segment(const Controls& b, int depth, const Format& f);

// Compile one segment whose A control values are given exactly (one integer
// per axis, LSB 2^-(F+G)) instead of being rounded from b0: the start of a
// chained segment (bcu/chain.hpp computes it from the previous segment's
// exact end). b0 is still used for the offset and the bound. Throws
// std::invalid_argument as compile_segment, and if a start value does not fit
// ctrl_width.
Segment compile_segment(const Controls& b, int depth, const Format& f,
                        const std::vector<mpz_class>& start);

// Exact sample j (0..K) of axis a from integer control values (GMP).
int64_t predict_sample(const std::vector<mpz_class>& c, int depth, int j, int guard_bits);

// Double-precision de Casteljau of a cubic at t.
double de_casteljau(const double b[4], double t);

// The bound stated above for control values with max |b| = max_abs.
double error_bound(const Format& f, double max_abs);

// Stream words of an already compiled set of integer control values.
std::vector<uint64_t> stream_words(const std::vector<std::vector<mpz_class>>& c, int depth,
                                   const Format& f);

}  // namespace traj::bcu
