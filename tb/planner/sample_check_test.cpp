// SPDX-License-Identifier: Apache-2.0
// report::SampleCheck, which measures the core's samples one at a time (run's report and
// `sim --check`), against a whole-vector reference written from the definitions in
// planner/sampled.hpp, in long double: every window of every difference, the last window of two
// steps included, and the worst ratio against the limits after the allowance.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "report/sample_check.hpp"

namespace {

using traj::report::Sample;
using LD = long double;

struct Ref {
  LD v[8] = {}, a[8] = {}, j[8] = {}, feed = 0, at = 0, an = 0, jt = 0, jn = 0;
};

LD norm(const std::vector<LD>& x) {
  LD s = 0;
  for (LD e : x) s += e * e;
  return std::sqrt(s);
}

// |c - (c.u) u| for a unit vector u
LD normal_part(const std::vector<LD>& c, const std::vector<LD>& dir) {
  const LD n = norm(dir);
  LD dot = 0;
  for (size_t i = 0; i < c.size(); ++i) dot += c[i] * dir[i] / n;
  std::vector<LD> r(c.size());
  for (size_t i = 0; i < c.size(); ++i) r[i] = c[i] - dot * dir[i] / n;
  return norm(r);
}

Ref reference(const std::vector<Sample>& s, int d, LD lsb, LD h, LD min_chord) {
  Ref r;
  const size_t n = s.size();
  auto x = [&](size_t k, int a) { return static_cast<LD>(s[k][a]) * lsb; };
  auto diff = [&](size_t k0, size_t k1) {
    std::vector<LD> v(d);
    for (int a = 0; a < d; ++a) v[a] = x(k1, a) - x(k0, a);
    return v;
  };
  for (size_t k = 0; k + 1 < n; ++k) {
    std::vector<LD> dv(d);
    for (int a = 0; a < d; ++a) {
      dv[a] = (x(k + 1, a) - x(k, a)) / h;
      r.v[a] = std::max(r.v[a], std::fabs(dv[a]));
      if (k + 2 < n) r.a[a] = std::max(r.a[a], std::fabs((x(k + 2, a) - 2 * x(k + 1, a) + x(k, a)) / (h * h)));
      if (k + 3 < n)
        r.j[a] = std::max(r.j[a],
                          std::fabs((x(k + 3, a) - 3 * x(k + 2, a) + 3 * x(k + 1, a) - x(k, a)) / (h * h * h)));
    }
    r.feed = std::max(r.feed, norm(dv));
  }
  // windows k..k+3 (k..k+2 for the last one)
  for (size_t k = 0; k + 2 < n; ++k) {
    const LD s0 = norm(diff(k, k + 1)) / h, s1 = norm(diff(k + 1, k + 2)) / h;
    r.at = std::max(r.at, std::fabs(s1 - s0) / h);
    std::vector<LD> acc(d);
    for (int a = 0; a < d; ++a) acc[a] = (x(k + 2, a) - 2 * x(k + 1, a) + x(k, a)) / (h * h);
    if (norm(diff(k, k + 2)) > 2 * min_chord) r.an = std::max(r.an, normal_part(acc, diff(k, k + 2)));
    if (k + 3 >= n) continue;
    const LD s2 = norm(diff(k + 2, k + 3)) / h;
    r.jt = std::max(r.jt, std::fabs(s2 - 2 * s1 + s0) / (h * h));
    std::vector<LD> jerk(d);
    for (int a = 0; a < d; ++a) jerk[a] = (x(k + 3, a) - 3 * x(k + 2, a) + 3 * x(k + 1, a) - x(k, a)) / (h * h * h);
    if (norm(diff(k + 1, k + 2)) > min_chord) r.jn = std::max(r.jn, normal_part(jerk, diff(k + 1, k + 2)));
  }
  return r;
}

// Relative to the size of the differences the figure is made of (a normal part that is 0 in
// exact arithmetic is rounding of the order of 1e-16 of them in either).
void expect_close(double got, LD want, LD scale, const char* what) {
  EXPECT_NEAR(got, static_cast<double>(want), 1e-9 * std::max<LD>(1, scale)) << what;
}

void check_against_reference(const std::vector<Sample>& s, int d, double lsb, double h) {
  traj::report::SampleCheck c(d, lsb, h);
  for (const Sample& v : s) c.add(v);
  c.finish();
  const Ref r = reference(s, d, lsb, h, 16 * static_cast<LD>(lsb));
  const auto& p = c.peaks();
  LD sa = 0, sj = 0;
  for (int a = 0; a < d; ++a) {
    expect_close(p.v_axis[a], r.v[a], r.v[a], "v");
    expect_close(p.a_axis[a], r.a[a], r.a[a], "a");
    expect_close(p.j_axis[a], r.j[a], r.j[a], "j");
    sa = std::max(sa, r.a[a]);
    sj = std::max(sj, r.j[a]);
  }
  expect_close(p.feed, r.feed, r.feed, "feed");
  expect_close(p.a_tan, r.at, d * sa, "a_tan");
  expect_close(p.a_cen, r.an, d * sa, "a_cen");
  expect_close(p.j_tan, r.jt, d * sj, "j_tan");
  expect_close(p.j_cen, r.jn, d * sj, "j_cen");
  EXPECT_EQ(c.count(), static_cast<long long>(s.size()));
}

}  // namespace

// A random walk of 1..8 axes, 2^-32 units, 1 ms: every figure as the reference has it.
TEST(SampleCheck, MatchesTheWholeVectorReference) {
  std::mt19937_64 rng(7);
  for (int d = 1; d <= 8; ++d)
    for (size_t n : {1u, 2u, 3u, 4u, 5u, 200u}) {
      std::vector<Sample> s(n, Sample{});
      std::uniform_int_distribution<long long> step(-(1ll << 30), 1ll << 30);
      Sample x{};
      for (size_t k = 0; k < n; ++k) {
        for (int a = 0; a < d; ++a) x[a] += step(rng);
        s[k] = x;
      }
      SCOPED_TRACE("axes " + std::to_string(d) + ", samples " + std::to_string(n));
      check_against_reference(s, d, std::ldexp(1.0, -32), 1e-3);
    }
}

// A straight run that turns at its very end: the largest centripetal
// acceleration is in the last window, of two steps only (taken by finish()).
TEST(SampleCheck, TheLastWindowCounts) {
  std::vector<Sample> s;
  for (long long k = 0; k < 10; ++k) s.push_back(Sample{k << 32, 0});
  s.push_back(Sample{9ll << 32, 1ll << 32});  // a right angle at the last sample
  check_against_reference(s, 2, std::ldexp(1.0, -32), 1e-3);
  traj::report::SampleCheck c(2, std::ldexp(1.0, -32), 1e-3);
  for (const Sample& v : s) c.add(v);
  const double before = c.peaks().a_cen;
  c.finish();
  EXPECT_GT(c.peaks().a_cen, before);
}

// Samples near the ends of 63 bits: the differences are exact (no overflow).
TEST(SampleCheck, DifferencesOfLargeSamplesAreExact) {
  const long long big = (1ll << 62) - 5;
  std::vector<Sample> s = {Sample{big}, Sample{-big}, Sample{big}, Sample{-big}};
  traj::report::SampleCheck c(1, 1.0, 1.0);
  for (const Sample& v : s) c.add(v);
  c.finish();
  EXPECT_EQ(c.peaks().j_axis[0], 8.0 * static_cast<double>(big));  // |x3 - 3 x2 + 3 x1 - x0| = 8 big
}

// The worst ratio: (peak - allowance) / limit, the per-axis allowance sqrt(axes) x for path figures,
// jerk only when claimed.
TEST(SampleCheck, WorstAfterTheAllowance) {
  traj::plan::Peaks pk;
  traj::plan::Limits l;
  pk.v_axis[0] = 10;
  pk.feed = 20;
  pk.j_tan = 3 * l.j_tan;
  traj::job::Allowance al;
  al.v = 1;
  al.j = l.j_tan;  // sqrt(4) x: the jerk check then sees 3 - 2 = 1 limit
  l.v_axis[0] = 9;
  l.feed = 18;
  auto w = traj::report::worst_of_samples(pk, al, l, 4, true);
  EXPECT_NEAR(w.ratio, 1.0, 1e-12);
  EXPECT_TRUE(w.what == "v_axis.x" || w.what == "feed" || w.what == "j_tan") << w.what;
  l.v_axis[0] = 8;  // (10 - 1) / 8
  w = traj::report::worst_of_samples(pk, al, l, 4, true);
  EXPECT_EQ(w.what, "v_axis.x");
  EXPECT_NEAR(w.ratio, 9.0 / 8, 1e-12);
  pk.j_tan = 100 * l.j_tan;
  w = traj::report::worst_of_samples(pk, al, l, 4, false);  // cubic: no jerk claim
  EXPECT_EQ(w.what, "v_axis.x");
}
