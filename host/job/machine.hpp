// SPDX-License-Identifier: Apache-2.0
// The machine a job is planned for: the servo tick period, the units, and the
// engine that samples the segments. This is the one owner of the tick period:
// the planner, the compiler and the stream header take it from here, and it
// is validated once, in validate().
#pragma once
#include <cstdint>
#include <string>

#include "fd/fd_compiler.hpp"
#include "geometry/bspline.hpp"
#include "stream/segment_stream.hpp"

namespace traj::job {

struct Machine {
  double period = 1e-3;      // servo tick period h, s
  int degree = 5;            // segment degree: 5 (quintic, C2 joins) or 3 (cubic, C1)
  std::string units = "mm";  // units of the path and of the output LSB

  // plan::PlanError naming the field if the period is not positive and
  // finite or the tool carries no engine of this degree.
  void validate() const;
  // The engine format of the build the tool carries for `degree`:
  //   quintic: Axes 3, Degree 5, Width 96, Chunk 16, Guard 48, F 32 (1 LSB = 2^-32 units)
  //   cubic:   Axes 3, Degree 3, Width 64, Chunk 16, Guard 32, F 16
  fd::Format format() const;
  double lsb() const;  // one output LSB, units
  // The deviation the fit may use out of the path tolerance `tol`: what is
  // left after the output rounding (1/2 LSB) and the register error bound
  // (format().tol_lsb LSB). plan::PlanError if nothing is left.
  double fit_budget(double tol) const;
  // The longest segment (ticks) the compiler accepts in this format.
  uint32_t longest_segment() const;
  stream::Header header() const;
  // The largest |coordinate| the output holds: 2^(out_width-1-frac_bits) units
  // (32768 mm for the quintic engine).
  double output_range() const;
  // Refuses, before any planning, a curve that reaches outside the output
  // range: plan::PlanError("<where>: axis A leaves the output range: |x|
  // reaches X units, the format holds |x| < R (...)"), the compiler's message
  // for a segment. The curve lies in the hull of its control points, so only
  // a curve with a control point outside is evaluated (at its span ends and
  // midpoints); one that stays inside although a control point does not is
  // left to the compiler's exact check.
  void check_range(const geo::BSpline& c, const std::string& where) const;
};

}  // namespace traj::job
