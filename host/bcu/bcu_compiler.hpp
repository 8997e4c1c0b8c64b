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
// It does not depend on d: the generator itself adds no error.
#pragma once
#include <Eigen/Dense>
#include <cstdint>
#include <gmpxx.h>
#include <vector>

namespace traj::bcu {

struct Format {
  int axes = 3;          // 1..8
  int chunk_width = 32;  // stream word width, 8..64
  int ctrl_width = 40;   // control value width (two's complement)
  int guard_bits = 9;    // control bits below the output LSB
  int out_width = 32;    // sample width, >= ctrl_width - guard_bits + (guard_bits > 0)
  int max_depth = 12;    // largest d
  int frac_bits = 16;    // F: output LSB = 2^-F input units
  // stream words per value: the datapath digits, ceil((ctrl_width + 3*max_depth)/chunk_width)
  int words_per_value() const { return (ctrl_width + 3 * max_depth + chunk_width - 1) / chunk_width; }
  void validate() const;  // throws std::invalid_argument
};

// Control values: one row per axis, columns b0..b3.
using Controls = Eigen::Matrix<double, Eigen::Dynamic, 4>;

struct Segment {
  int depth = 0;                             // d, K = 2^d
  std::vector<std::vector<mpz_class>> ctrl;  // [axis][i], LSB 2^-(F+G)
  std::vector<uint64_t> words;               // stream words, chunk_width bits each
  std::vector<std::vector<int64_t>> samples; // [j][axis], j = 0..K (j = K: end value)
  double bound = 0.0;                        // error bound vs the double curve
};

// Compile one segment. Throws std::invalid_argument naming the axis and the
// control value for NaN/Inf or out-of-range values, and for d out of range.
Segment compile_segment(const Controls& b, int depth, const Format& f);

// Exact sample j (0..K) of axis a from integer control values (GMP).
int64_t predict_sample(const std::vector<mpz_class>& c, int depth, int j, int guard_bits);

// Exact rational value sum_i B_i(j/2^d) c_i (in control LSBs).
mpq_class exact_value(const std::vector<mpz_class>& c, int depth, int64_t j);

// Double-precision de Casteljau of a cubic at t.
double de_casteljau(const double b[4], double t);

// The bound stated above for control values with max |b| = max_abs.
double error_bound(const Format& f, double max_abs);

// Stream words of an already compiled set of integer control values.
std::vector<uint64_t> stream_words(const std::vector<std::vector<mpz_class>>& c, int depth,
                                   const Format& f);

}  // namespace traj::bcu
