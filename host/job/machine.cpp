// SPDX-License-Identifier: Apache-2.0
#include "job/machine.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/curve.hpp"
#include "planner/planner.hpp"
#include "util/format.hpp"
#include "util/tick_period.hpp"

namespace traj::job {

using plan::PlanError;
using util::fmt;

void Machine::validate() const {
  if (const std::string m = util::tick_period_problem(period); !m.empty()) throw PlanError(m);
  if (!(feed_accuracy >= 0 && feed_accuracy <= 0.1))
    throw PlanError("feed accuracy " + fmt("%g", feed_accuracy) + ": give 0 (the default fit) or a bound in (0, 0.1]");
  (void)format();
}

Allowance sample_allowance(double q, double offset, double h) {
  return {(2 * q + offset) / h, 4 * q / (h * h), 8 * q / (h * h * h)};
}

AllowanceShare allowance_share(const Allowance& al, const plan::Limits& l, int axes, int degree) {
  AllowanceShare w;
  auto take = [&](double allowance, double limit, const std::string& name) {
    if (allowance / limit > w.share) w = {allowance / limit, name};
  };
  const double sd = std::sqrt(static_cast<double>(axes));
  const bool jerk = degree != 3;
  for (int a = 0; a < axes && a < plan::kMaxAxes; ++a) {
    const std::string ax = l.axis(a);
    take(al.v, l.v_axis[a], "v_" + ax);
    take(al.a, l.a_axis[a], "a_" + ax);
    if (jerk) take(al.j, l.j_axis[a], "j_" + ax);
  }
  take(sd * al.v, l.feed, "feed");
  take(sd * al.a, l.a_tan, "a_tan");
  take(sd * al.a, l.a_cen, "a_cen");
  if (jerk) {
    take(sd * al.j, l.j_tan, "j_tan");
    take(sd * al.j, l.j_cen, "j_cen");
  }
  return w;
}

std::vector<fd::Format> Machine::carried_formats(int degree, int axes) {
  if (axes < 1 || axes > plan::kMaxAxes)
    throw PlanError(std::to_string(axes) + " axes: the tool carries engines of 1 to " + std::to_string(plan::kMaxAxes));
  // {axes, degree, width, chunk_width, guard_bits, frac_bits}
  if (axes > 3) {
    if (degree == 5) return {{8, 5, 96, 16, 48, 32}, {8, 5, 128, 16, 67, 44}};
    throw PlanError("segment degree " + std::to_string(degree) + " with " + std::to_string(axes) +
                    " axes: the tool carries 8-axis engines of degree 5 only (--degree 5)");
  }
  if (degree == 5) return {{3, 5, 96, 16, 48, 32}, {3, 5, 128, 16, 67, 44}};
  if (degree == 3) return {{3, 3, 64, 16, 32, 16}, {3, 3, 96, 16, 48, 32}};
  throw PlanError("segment degree " + std::to_string(degree) + ": the tool carries engines for degree 3 and 5");
}

fd::Format Machine::format() const {
  const std::vector<fd::Format> f = carried_formats(degree, axes);
  if (build < 0 || build >= static_cast<int>(f.size()))
    throw PlanError("engine build " + std::to_string(build) + " of degree " + std::to_string(degree) +
                    ": the tool carries " + std::to_string(f.size()));
  return f[build];
}

namespace {

AllowanceShare share_of(const fd::Format& f, int axes, double period, const plan::Limits& l) {
  const double lsb = std::ldexp(1.0, -f.frac_bits);
  return allowance_share(sample_allowance(Machine::sample_error_lsb(f) * lsb, Machine::joint_lsb(f) * lsb, period), l,
                         std::min(axes, f.axes), f.degree);
}

}  // namespace

void Machine::choose_format(const plan::Limits& l) {
  l.validate();
  validate();
  const std::vector<fd::Format> fs = carried_formats(degree, axes);
  if (engine_width != 0) {
    std::string widths;
    for (build = 0; build < static_cast<int>(fs.size()); ++build) {
      if (fs[build].width == engine_width) return;
      widths += (widths.empty() ? "" : ", ") + std::to_string(fs[build].width);
    }
    build = 0;
    throw PlanError("engine width " + std::to_string(engine_width) + ": the tool carries degree-" +
                    std::to_string(degree) + " engines of width " + widths);
  }
  for (build = 0; build + 1 < static_cast<int>(fs.size()); ++build)
    if (share_of(fs[build], axes, period, l).share <= kAllowanceShare) return;
}

double Machine::output_range() const {
  const fd::Format f = format();
  return std::ldexp(1.0, f.out_width() - 1 - f.frac_bits);
}

void Machine::check_range(const geo::BSpline& c, const std::string& where) const {
  if (c.ctrl.cols() > axes)
    throw PlanError(where + ": " + std::to_string(c.ctrl.cols()) + " axes, more than the machine's " +
                    std::to_string(axes) + " (name them with --axes, e.g. XYZA for 4)");
  const double range = output_range();
  if (!(c.ctrl.size() > 0) || c.ctrl.cwiseAbs().maxCoeff() < range) return;
  const geo::Curve curve(c, where);
  std::vector<double> us;
  for (const auto& sp : curve.spans()) us.insert(us.end(), {sp.u0, 0.5 * (sp.u0 + sp.u1)});
  us.push_back(curve.u_end());
  int axis = -1;
  double worst = 0, at = 0;
  for (double u : us) {
    const Eigen::VectorXd x = curve.point(u);
    for (int a = 0; a < x.size(); ++a)
      if (!(std::fabs(x[a]) < range) && !(std::fabs(x[a]) <= worst)) {
        axis = a;
        worst = std::fabs(x[a]);
        at = u;
      }
  }
  if (axis < 0) return;
  const fd::Format f = format();
  throw PlanError(where + ": axis " + std::to_string(axis) + " leaves the output range: |x| reaches " +
                  fmt("%.6g", worst) + " " + units + " (at u = " + fmt("%.6g", at) + "), the format holds |x| < " +
                  fmt("%.6g", range) + " (out_width=" + std::to_string(f.out_width()) +
                  ", frac_bits=" + std::to_string(f.frac_bits) + "); move the origin or split the path");
}

double Machine::lsb() const { return std::ldexp(1.0, -format().frac_bits); }

double Machine::fit_budget(double tol) const {
  const fd::Format f = format();
  const double quant = (sample_error_lsb(f) + joint_lsb(f)) * lsb();
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

int Machine::fit_ticks() const {
  // 1e-9: a period that divides kFitPeriod (1e-3 / 2e-5) gives the whole quotient
  return static_cast<int>(std::max(1.0, std::floor(kFitPeriod / period * (1 + 1e-9))));
}

stream::Header Machine::header() const { return stream::Header::from(format(), period, units); }

}  // namespace traj::job
