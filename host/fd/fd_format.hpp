// SPDX-License-Identifier: Apache-2.0
// trajcore host: the forward-difference engine's number format (fd::Format),
// shared by the compiler (fd_compiler.hpp, which explains the format and its
// error analysis) and the segment stream's header.
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>

namespace traj::fd {

class CompileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Format {
  int axes = 3;            // 1..8
  int degree = 3;          // engine degree N, 1..7
  int width = 64;          // register width W, multiple of chunk_width, <= 128
  int chunk_width = 16;    // 16, 32 or 64
  int guard_bits = 32;     // G, register bits below the output LSB, 1..width-2
                           // (the RTL also builds GuardBits = 0; the compiler refuses
                           // it, see Format::validate).
  int frac_bits = 16;      // F, output LSB = 2^-F position units
  double tol_lsb = 0.5;    // register error budget per sample, output LSB
  uint32_t max_ticks = 1u << 20;  // longest segment accepted

  int out_width() const { return width - guard_bits; }
  // Throws CompileError naming the field if the format is not buildable.
  // guard_bits = 0 is refused although the RTL builds it: every register is
  // then rounded to a whole output LSB, so the bound needs |e0| <= 1/2 <= tol/2
  // and 1/2 sum C(K,i) <= tol/2, i.e. tol >= 1 and sum C(K,i) <= tol: K = 1 at
  // tol = 1 (every tick its own segment, nothing left to sample), and no
  // segment at all at the default tol = 0.5. It would also need a second
  // rounding convention (no +1/2 bias, since the engine's floor shifts nothing).
  // GuardBits = 0 remains for difference tables that are exact integers,
  // written by other means than this compiler.
  void validate() const;
};

}  // namespace traj::fd
