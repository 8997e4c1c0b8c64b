// SPDX-License-Identifier: Apache-2.0
#include "fd/fd_format.hpp"

#include <cmath>

#include "fd/detail/fd_internal.hpp"
#include "util/format.hpp"

namespace traj::fd {

std::string detail::fmt_double(double v) { return util::num(v); }

void Format::validate() const {
  auto bad = [](const std::string& what) { throw CompileError("format: " + what); };
  if (axes < 1 || axes > 8) bad("axes=" + std::to_string(axes) + " out of range 1..8");
  if (degree < 1 || degree > 7) bad("degree=" + std::to_string(degree) + " out of range 1..7");
  if (chunk_width != 16 && chunk_width != 32 && chunk_width != 64)
    bad("chunk_width=" + std::to_string(chunk_width) + " must be 16, 32 or 64");
  if (width < chunk_width || width > 128 || width % chunk_width != 0)
    bad("width=" + std::to_string(width) + " must be a multiple of chunk_width=" +
        std::to_string(chunk_width) + ", at most 128");
  if (guard_bits == 0)
    bad("guard_bits=0 is not supported by the compiler (the RTL builds it): with no bit below the output LSB "
        "every register rounding is a whole 1/2 output LSB, so the error bound admits no segment at tol < 1 "
        "and only K=1 at tol=1; use guard_bits >= 1 (Compiler::guard_bits_needed gives the count for K ticks)");
  if (guard_bits < 1 || guard_bits > width - 2)
    bad("guard_bits=" + std::to_string(guard_bits) + " out of range 1..width-2");
  if (frac_bits < -64 || frac_bits > 64)
    bad("frac_bits=" + std::to_string(frac_bits) + " out of range -64..64");
  if (!(tol_lsb > 0) || !std::isfinite(tol_lsb))
    bad("tol_lsb=" + detail::fmt_double(tol_lsb) + " must be positive and finite");
  if (max_ticks < 1) bad("max_ticks must be at least 1");
}

}  // namespace traj::fd
