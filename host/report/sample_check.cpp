// SPDX-License-Identifier: Apache-2.0
#include "report/sample_check.hpp"

#include <algorithm>
#include <cmath>

#include "planner/sampled.hpp"

namespace traj::report {

namespace {
// Samples are at most 63 bits: their differences up to the third (coefficient
// sums 2, 4, 8) fit 128 bits exactly and are converted once.
using Wide = __int128;
double units(Wide v, double lsb) { return static_cast<double>(v) * lsb; }
}  // namespace

SampleCheck::SampleCheck(int axes, double lsb, double h) : axes_(axes), lsb_(lsb), h_(h) {}

void SampleCheck::add(const Sample& s) {
  for (int i = 0; i < 3; ++i) last_[i] = last_[i + 1];
  last_[3] = s;
  ++n_;
  const auto& x0 = last_[0];
  const auto& x1 = last_[1];
  const auto& x2 = last_[2];
  const auto& x3 = last_[3];
  double v2 = 0, a2 = 0, j2 = 0;
  for (int a = 0; a < axes_; ++a) {
    if (n_ >= 2) {
      const double dv = units(Wide(x3[a]) - x2[a], lsb_) / h_;
      pk_.v_axis[a] = std::max(pk_.v_axis[a], std::fabs(dv));
      v2 += dv * dv;
    }
    if (n_ >= 3) {
      const double da = units(Wide(x3[a]) - 2 * Wide(x2[a]) + x1[a], lsb_) / (h_ * h_);
      pk_.a_axis[a] = std::max(pk_.a_axis[a], std::fabs(da));
      a2 += da * da;
    }
    if (n_ >= 4) {
      const double dj = units(Wide(x3[a]) - 3 * Wide(x2[a]) + 3 * Wide(x1[a]) - x0[a], lsb_) / (h_ * h_ * h_);
      pk_.j_axis[a] = std::max(pk_.j_axis[a], std::fabs(dj));
      j2 += dj * dj;
    }
  }
  pk_.feed = std::max(pk_.feed, std::sqrt(v2));
  path_a_ = std::max(path_a_, std::sqrt(a2));
  path_j_ = std::max(path_j_, std::sqrt(j2));
  if (n_ >= 4) window(3);
}

void SampleCheck::finish() {
  if (n_ >= 3) window(2);
}

void SampleCheck::window(int m) {
  // the window starts m samples before the newest
  const Sample& first = last_[3 - m];
  double p[4][plan::kMaxAxes] = {};
  for (int i = 1; i <= m; ++i)
    for (int a = 0; a < axes_; ++a) p[i][a] = units(Wide(last_[3 - m + i][a]) - first[a], lsb_);
  // 16 LSB: below it a chord's direction is rounding, the machine at rest
  const plan::SampledWindow w = plan::sampled_window(p[0], p[1], p[2], m == 3 ? p[3] : nullptr, axes_, h_, 16 * lsb_);
  pk_.a_tan = std::max(pk_.a_tan, w.at);
  pk_.a_cen = std::max(pk_.a_cen, w.an);
  pk_.j_tan = std::max(pk_.j_tan, w.jt);
  pk_.j_cen = std::max(pk_.j_cen, w.jn);
}

Worst worst_of_samples(const plan::Peaks& out, const job::Allowance& al, const plan::Limits& l, int axes,
                       bool jerk_claimed) {
  Worst w;
  const auto chk = [&](double v, double allow, double lim, const std::string& what) {
    const double q = (v - allow) / lim;
    if (q > w.ratio) {
      w.ratio = q;
      w.what = what;
    }
  };
  for (int a = 0; a < axes; ++a) {
    const std::string ax = l.axis(a);
    chk(out.v_axis[a], al.v, l.v_axis[a], "v_axis." + ax);
    chk(out.a_axis[a], al.a, l.a_axis[a], "a_axis." + ax);
    if (jerk_claimed) chk(out.j_axis[a], al.j, l.j_axis[a], "j_axis." + ax);
  }
  const double sd = std::sqrt(static_cast<double>(axes));
  chk(out.feed, sd * al.v, l.feed, "feed");
  chk(out.a_tan, sd * al.a, l.a_tan, "a_tan");
  chk(out.a_cen, sd * al.a, l.a_cen, "a_cen");
  if (jerk_claimed) {
    chk(out.j_tan, sd * al.j, l.j_tan, "j_tan");
    chk(out.j_cen, sd * al.j, l.j_cen, "j_cen");
  }
  return w;
}

}  // namespace traj::report
