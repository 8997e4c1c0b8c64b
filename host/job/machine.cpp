#include "job/machine.hpp"

#include <algorithm>
#include <cmath>

#include "planner/planner.hpp"
#include "util/format.hpp"
#include "util/tick_period.hpp"

namespace traj::job {

using plan::PlanError;
using util::fmt;

void Machine::validate() const {
  if (const std::string m = util::tick_period_problem(period); !m.empty()) throw PlanError(m);
  (void)format();
}

fd::Format Machine::format() const {
  fd::Format f;
  f.axes = 3;
  f.chunk_width = 16;
  if (degree == 5) {
    f.degree = 5;
    f.width = 96;
    f.guard_bits = 48;
    f.frac_bits = 32;
  } else if (degree == 3) {
    f.degree = 3;
    f.width = 64;
    f.guard_bits = 32;
    f.frac_bits = 16;
  } else {
    throw PlanError("segment degree " + std::to_string(degree) + ": the tool carries engines for degree 3 and 5");
  }
  return f;
}

double Machine::lsb() const { return std::ldexp(1.0, -format().frac_bits); }

double Machine::fit_budget(double tol) const {
  const fd::Format f = format();
  const double quant = (0.5 + f.tol_lsb) * lsb();
  const double budget = tol - quant;
  if (!(budget > 0))
    throw PlanError("path tolerance " + fmt("%g", tol) + " " + units + " is below the output quantisation (" +
                    fmt("%g", quant) + " " + units + ": 1/2 LSB + the register bound at 2^-" +
                    std::to_string(f.frac_bits) + ")");
  return budget;
}

uint32_t Machine::longest_segment() const {
  const fd::Format f = format();
  return static_cast<uint32_t>(
      std::min<uint64_t>(fd::Compiler::longest_segment(f.degree, f.guard_bits, f.tol_lsb), f.max_ticks));
}

stream::Header Machine::header() const { return stream::Header::from(format(), period, units); }

}  // namespace traj::job
