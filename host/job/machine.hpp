// SPDX-License-Identifier: Apache-2.0
// The machine a job is planned for: the servo tick period, the units, and the
// engine that samples the segments. This is the one owner of the tick period:
// the planner, the compiler and the stream header take it from here, and it
// is validated once, in validate().
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "fd/fd_compiler.hpp"
#include "geometry/bspline.hpp"
#include "stream/segment_stream.hpp"

namespace traj::plan {
struct Limits;
}

namespace traj::job {

// The quantisation allowance on the differences of samples that are each
// within q units of a smooth trajectory, at tick period h: the first, second
// and third differences over h, h^2, h^3 move by at most 2q/h, 4q/h^2, 8q/h^3
// (coefficient sums 2, 4, 8). Per axis; sqrt(axes) x for path quantities
// (vector norms).
struct Allowance {
  double v = 0, a = 0, j = 0;
};
// q: the samples' error about a smooth trajectory; offset: a linear
// deviation on top (exact joints, Machine::joint_lsb), which moves first
// differences only.
Allowance sample_allowance(double q, double offset, double h);

// The largest allowance of a format, as a share of the limit it is compared
// with (every per-axis v, a, j and the path's feed, a_tan, a_cen, j_tan,
// j_cen; no jerk for cubic segments, which do not limit it), with q the
// samples' error (Machine::sample_error_lsb and joint_lsb).
struct AllowanceShare {
  double share = 0;
  std::string limit;  // the limit it is largest against, e.g. "j_tan"
};
AllowanceShare allowance_share(const Allowance& al, const plan::Limits& l, int axes, int degree);

struct Machine {
  double period = 1e-3;      // servo tick period h, s
  int degree = 5;            // segment degree: 5 (quintic, C2 joins) or 3 (cubic, C1)
  // Bound on |chord between consecutive samples / planned arc - 1| at every
  // tick (--feed-accuracy); 0: the default fit (each tick within 0.25 % of
  // its travel, about +-2e-3).
  double feed_accuracy = 0;
  std::string units = "mm";  // units of the path and of the output LSB
  int axes = 3;              // axes of the path (3 or fewer: the 3-axis engines; 4..8: the 8-axis ones)
  // Which of the degree's carried engine builds (carried_formats): 0 the
  // narrowest; set by choose_format.
  int build = 0;
  // Register width the engine must have (--engine-width; 96: the board's
  // build, rtl/traj_board.sv), 0: chosen by choose_format.
  int engine_width = 0;

  // The output format should be fine enough that the quantisation allowance
  // on sample differences is at most this share of every limit; where no
  // carried format is, the report states the guarantee in its exact form
  // (host/report/README.md).
  static constexpr double kAllowanceShare = 0.01;

  // plan::PlanError naming the field if the period is not positive and
  // finite or the tool carries no engine of this degree.
  void validate() const;
  // The engine formats of the builds the tool carries for `degree`
  // (host/sim/CMakeLists.txt, TRAJ_SIM_BUILDS), narrowest first:
  //   quintic: Axes 3, Width 96, Chunk 16, Guard 48, F 32 (1 LSB = 2^-32 units, |x| < 32768)
  //            Axes 3, Width 128, Chunk 16, Guard 67, F 44 (2^-44 units, |x| < 65536: fine ticks;
  //            67 guard bits: segments of up to about 24 000 ticks, which
  //            the fit's long polynomials at 1 us need)
  //   cubic:   Axes 3, Width 64, Chunk 16, Guard 32, F 16 (|x| < 32768)
  //            Axes 3, Width 96, Chunk 16, Guard 48, F 32
  //   4 to 8 axes: the quintic formats with Axes 8 (a path's further axes
  //            idle, at 0)
  // PlanError if the tool carries no engine of this degree for so many axes.
  static std::vector<fd::Format> carried_formats(int degree, int axes = 3);
  // The fit keeps absolute coordinates in double precision, so consecutive
  // fitted polynomials meet only to a few ulp of their terms (the end of a
  // long segment sums terms several times its travel). The segment compiler
  // joins each segment exactly to where the previous polynomial ends
  // (SegmentCompiler) by a linear blend of the mismatch, at most kJointUnits
  // (2^-34 units: a few ulp of the largest coordinate the 96-bit format
  // holds; a larger one is a jump and refused), which moves positions and
  // first differences only (fd::Compiled::offset_lsb). At 2^-44 units that is
  // 1024 LSB; at 2^-32, 1/4 LSB, which the compiler's own start tolerance
  // (tol/2, which the register error carried from a segment of the longest
  // length may fill nearly alone) did not leave room for: on LibreCAD's
  // architectural library drawing Complete-Lib-V.dxf (segments of up to
  // 1 761 ticks) a segment started 0.2504 LSB from its polynomial, the
  // previous segment's register error plus a joint of a few thousandths,
  // and the compile stopped.
  static constexpr double kJointUnits = 0x1p-34;
  static double joint_lsb(const fd::Format& f) { return std::ldexp(kJointUnits, f.frac_bits); }
  // The samples' error about the fitted polynomials, output LSB: 1/2
  // (rounding) + tol_lsb (registers); joint_lsb on top for positions and
  // first differences.
  static double sample_error_lsb(const fd::Format& f) { return 0.5 + f.tol_lsb; }
  // The format of the chosen build.
  fd::Format format() const;
  // Sets `build` to the narrowest carried format whose allowance share
  // (allowance_share with q = sample_error_lsb, offset joint_lsb) is at most
  // kAllowanceShare, else to the finest; with engine_width set, to the
  // carried format of that width (PlanError if none). Validates the limits
  // and the machine first.
  void choose_format(const plan::Limits& l);
  double lsb() const;  // one output LSB, units
  // The deviation the fit may use out of the path tolerance `tol`: what is
  // left after the samples' error and the joints (sample_error_lsb +
  // joint_lsb).
  // plan::PlanError if nothing is left.
  double fit_budget(double tol) const;
  // The longest segment (ticks) the compiler accepts in this format.
  uint32_t longest_segment() const;
  // The fit's tick: the planner samples the plan, checks it and fits the
  // segments on a grid of fit_ticks() engine ticks (kFitPeriod or a little
  // less, at least one tick), so that its work and memory follow the
  // motion's duration, not the tick rate. Where it is more than one engine
  // tick the segments it accepts are checked for every engine tick by
  // per-segment bounds (planner/fine_check.hpp), and each is cut into pieces
  // the compiler takes (job::engine_pieces).
  static constexpr double kFitPeriod = 1e-3;
  int fit_ticks() const;
  double fit_period() const { return fit_ticks() * period; }
  stream::Header header() const;
  // The largest |coordinate| the output holds: 2^(out_width-1-frac_bits) units
  // (32768 mm for the quintic engine).
  double output_range() const;
  // Refuses, before any planning, a curve of more axes than the machine's
  // (`axes`, --axes), and one that reaches outside the output range: plan::PlanError("<where>: axis A leaves the output range: |x|
  // reaches X units, the format holds |x| < R (...)"), the compiler's message
  // for a segment. The curve lies in the hull of its control points, so only
  // a curve with a control point outside is evaluated (at its span ends and
  // midpoints); one that stays inside although a control point does not is
  // left to the compiler's exact check.
  void check_range(const geo::BSpline& c, const std::string& where) const;
};

}  // namespace traj::job
