// SPDX-License-Identifier: Apache-2.0
// Planner tests. References: exact polynomial identities, dense brute-force
// sampling, numerical integration of the S-curve pieces, the published
// butterfly length, and the Verilated core (RTL) for the output checks.
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

#include "rest_to_rest.hpp"
#include "test_seed.hpp"
#include "cusp_cubic.hpp"
#include "input/path_json.hpp"
#include "report/report.hpp"
#include "planner/profile.hpp"
#include "planner/segments.hpp"
#include "output_check.hpp"
#include "sim/sim.hpp"

using namespace traj;
using namespace traj::plan;
using namespace traj::input;
using namespace traj::job;
using namespace traj::report;
using traj::test::rest_to_rest_time;

#ifndef TRAJ_ASSETS
#error "TRAJ_ASSETS must name host/assets"
#endif

// Every other case with a shortest jerk phase tau (PlanOptions::jerk_phase_ticks), a third of them
// with changes small enough to need a lower jerk (dv < J tau^2).
TEST(Profile, ChangeDistanceMatchesIntegratedPieces) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> U(0, 1);
  for (int rep = 0; rep < 1500; ++rep) {
    const double A = 10 + 1000 * U(rng), J = 100 + 1e5 * U(rng), v0 = 100 * U(rng);
    const double tau = rep % 2 ? 0 : 1e-4 + 4e-3 * U(rng);
    const double v1 = rep % 3 ? 100 * U(rng) : std::max(0.0, v0 + (2 * U(rng) - 1) * J * tau * tau);
    std::vector<Piece> p;
    const double t_end = append_change(p, 0, 0, v0, v1, A, J, tau);
    // continuity of s, v, a between pieces; limits respected; end state
    double s = 0, v = v0, a = 0;
    for (const auto& q : p) {
      ASSERT_NEAR(q.s0, s, 1e-9 * (1 + s));
      ASSERT_NEAR(q.v0, v, 1e-9 * (1 + v));
      ASSERT_NEAR(q.a0, a, 1e-9 * A);
      ASSERT_LE(std::fabs(q.j), J * (1 + 1e-12));
      ASSERT_LE(std::max(std::fabs(q.a(0)), std::fabs(q.a(q.T))), A * (1 + 1e-9));
      if (q.j != 0) {
        ASSERT_GE(q.T, tau * (1 - 1e-9)) << "a jerk phase shorter than tau, rep " << rep;
      }
      s = q.s(q.T);
      v = q.v(q.T);
      a = q.a(q.T);
    }
    EXPECT_NEAR(v, v1, 1e-9 * (1 + v1));
    EXPECT_NEAR(a, 0, 1e-6 * A);
    EXPECT_NEAR(s, change_distance(v0, v1, A, J, tau), 1e-9 * (1 + s));
    EXPECT_NEAR(t_end, change_time(std::fabs(v1 - v0), A, J, tau), 1e-12 * (1 + t_end));
    // reachable is the inverse of change_distance, and never beyond it
    for (const double dv : {50.0, 0.3 * J * tau * tau}) {
      if (dv <= 0) continue;
      const double L = change_distance(v0, v0 + dv, A, J, tau);
      const double r = reachable(v0, L, A, J, 1e9, tau);
      EXPECT_NEAR(r, v0 + dv, 1e-6 * (1 + v0)) << "rep " << rep << " dv " << dv;
      EXPECT_LE(change_distance(v0, r, A, J, tau), L);
    }
  }
}

// Blocks with their own tangential acceleration: the profile, integrated
// piece by piece, keeps |a| <= A_i inside block i, reaches every station at
// its planned speed (<= vmax) and is continuous.
TEST(Profile, PerBlockAccelerationHoldsInEveryBlock) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  for (int rep = 0; rep < 200; ++rep) {
    const int n = 2 + rep % 9;
    std::vector<Station> st(n);
    std::vector<double> cap(n - 1), A(n - 1);
    double s = 0;
    for (int i = 0; i < n; ++i) {
      st[i].s = s;
      st[i].vmax = (i == 0 || i == n - 1) ? 0 : 60 * U(rng);
      s += 0.05 + 20 * U(rng) * U(rng);
    }
    for (int i = 0; i + 1 < n; ++i) {
      cap[i] = 5 + 60 * U(rng);
      A[i] = 10 + 2000 * U(rng) * U(rng);  // from 10 to 2010: blocks differ by up to 200x
    }
    const double J = 1000 + 50000 * U(rng);
    const double tau = rep % 2 ? 0 : 2e-3 * U(rng);  // a shortest jerk phase in every other case
    const std::vector<Piece> p = plan_blocks(st, cap, A, J, tau);
    ASSERT_FALSE(p.empty());
    double se = 0, v = 0, a = 0;
    size_t blk = 0;
    for (const auto& q : p) {
      ASSERT_NEAR(q.s0, se, 1e-9 * (1 + se));
      ASSERT_NEAR(q.v0, v, 1e-9 * (1 + v));
      ASSERT_NEAR(q.a0, a, 1e-6 * (1 + std::fabs(a)));
      // the block this piece lies in (by its midpoint)
      const double sm = q.s(q.T / 2);
      while (blk + 2 < static_cast<size_t>(n) && sm > st[blk + 1].s) ++blk;
      for (int k = 0; k <= 8; ++k) {
        const double tau = q.T * k / 8;
        ASSERT_LE(std::fabs(q.a(tau)), A[blk] * (1 + 1e-9)) << "rep " << rep << " block " << blk;
        ASSERT_GE(q.v(tau), -1e-9);
      }
      ASSERT_LE(std::fabs(q.j), J * (1 + 1e-12));
      if (q.j != 0) {
        ASSERT_GE(q.T, tau * (1 - 1e-9)) << "rep " << rep;
      }
      se = q.s(q.T);
      v = q.v(q.T);
      a = q.a(q.T);
    }
    EXPECT_NEAR(se, st.back().s, 1e-9 * (1 + se));
    for (const auto& x : st) EXPECT_LE(x.v, x.vmax + 1e-12);
  }
}

TEST(Segments, HermiteReproducesPolynomialsAndMaxIsExact) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int rep = 0; rep < 200; ++rep) {
    double c[6];
    for (double& x : c) x = U(rng);
    const double T = 0.5 + U(rng) * 0.4;
    auto P = [&](double t, int d) {
      double e[6];
      for (int j = 0; j < 6; ++j) e[j] = c[j];
      for (int r = 0; r < d; ++r)
        for (int j = 0; j < 6; ++j) e[j] = j + 1 < 6 ? e[j + 1] * (j + 1) : 0;
      double v = 0;
      for (int j = 5; j >= 0; --j) v = v * t + e[j];
      return v;
    };
    // max |p| over [0,T] vs dense sampling (sampling can only under-estimate)
    const double m = max_abs_poly(c, 5, T);
    double dense = 0;
    for (int i = 0; i <= 200000; ++i) dense = std::max(dense, std::fabs(P(T * i / 200000, 0)));
    EXPECT_GE(m, dense * (1 - 1e-12));
    EXPECT_LE(m, dense * (1 + 1e-6) + 1e-12);
  }
}

namespace {

struct RunOut {
  JobResult job;
  traj::sim::SimResult sim;
  Report rep;
};

RunOut run_through_core(const Path& p, const JobConfig& cfg) {
  RunOut o;
  o.job = run_job(p, cfg);
  o.sim = traj::sim::simulate(o.job.header, records_of(o.job));
  o.rep = make_report(p, cfg, o.job, o.sim.samples);
  return o;
}

void expect_guarantees(const Path& p, const JobConfig& cfg, const RunOut& o, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_EQ(o.sim.mismatches, 0u) << "RTL != hls";
  EXPECT_FALSE(o.sim.tick_err);
  EXPECT_EQ(o.sim.underruns, 0u);
  EXPECT_EQ(o.sim.samples.v.size(), o.job.ticks.size());
  EXPECT_LE(o.rep.worst_plan, 1 + 1e-9) << o.rep.worst_plan_what << "\n" << report_text(cfg, o.rep, o.job);
  EXPECT_LE(o.rep.worst_fit, 1 + 1e-9) << o.rep.worst_fit_what;
  EXPECT_LE(o.rep.worst_out, 1 + 1e-9) << o.rep.worst_out_what;
  // the fit takes chords up to 1e-9 above the feed (the rounding of a chord
  // planned at exactly the feed, planner/segments.cpp), as worst_out above
  EXPECT_LE(o.rep.out_path_v, cfg.limits.feed * (1 + 1e-9) + o.rep.allow_path_v);
  EXPECT_LE(o.rep.max_deviation, cfg.limits.tol);
  // the same limits and the deviation, checked apart from the report
  // (output_check.hpp) on the samples the Verilated core emitted
  {
    const double lsb = std::ldexp(1.0, -o.job.header.frac_bits);
    std::vector<std::array<double, 3>> x(o.sim.samples.v.size());
    for (size_t k = 0; k < x.size(); ++k)
      for (int a = 0; a < 3; ++a) x[k][a] = static_cast<double>(o.sim.samples.v[k][a]) * lsb;
    const test::OutputVerdict ov =
        test::check_output_limits(x, p.dim(), cfg.limits, cfg.machine.period, o.rep.quant, o.job.header.degree == 5);
    EXPECT_LE(ov.worst, 1 + 1e-9) << ov.what << " at tick " << ov.tick;
    double dev = 0;
    for (size_t k = 0; k < x.size(); ++k)
      dev = std::max(dev, test::distance_to_curve_near(p.curve(o.job.ticks[k].curve), x[k].data(), o.job.ticks[k].u));
    EXPECT_LE(dev, cfg.limits.tol);
    std::printf("  %s: independent check: worst %.4f (%s), deviation %.3g\n", what.c_str(), ov.worst, ov.what.c_str(),
                dev);
  }
  // first and last samples: the curve's ends
  const double lsb = std::ldexp(1.0, -o.job.header.frac_bits);
  const Eigen::VectorXd a = p.curve(0).point(p.curve(0).u_begin());
  const Eigen::VectorXd b = p.curve(p.size() - 1).point(p.curve(p.size() - 1).u_end());
  for (int k = 0; k < p.dim(); ++k) {
    EXPECT_NEAR(o.sim.samples.v.front()[k] * lsb, a[k], o.rep.quant);
    EXPECT_NEAR(o.sim.samples.v.back()[k] * lsb, b[k], o.rep.quant);
  }
}

}  // namespace

TEST(PlannerCore, ButterflyThroughVerilatedCore) {
  const Path p = load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json");
  EXPECT_NEAR(p.length(), 382.86031, 5e-6);  // published arc length
  JobConfig cfg;
  cfg.limits.feed = 50;
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "butterfly 50 mm/s");
  // feed accuracy at the output: deviations <= 0.25% of each tick's travel give
  // chords within 0.5% of the planned arc (plus the chord-vs-arc difference)
  EXPECT_LE(std::max(std::fabs(o.rep.feed_fluct_max), std::fabs(o.rep.feed_fluct_min)), 0.006);
  std::printf("  butterfly: %.3f s, %zu segments, deviation %.3g mm, worst plan/fit/out %.4f/%.4f/%.4f\n",
              o.rep.motion_time, o.rep.segments, o.rep.max_deviation, o.rep.worst_plan, o.rep.worst_fit,
              o.rep.worst_out);
}

// The engine format is the narrowest carried one whose quantisation
// allowance on sample differences is at most 1 % of every limit; the shares
// here are worked by hand from 2q/h, 4q/h^2, 8q/h^3 with q = 1 LSB (1/2 LSB
// of rounding + tol_lsb 1/2) and sqrt(3) for the path quantities.
TEST(PlannerInput, FormatChosenSoTheAllowanceIsAtMostOnePercent) {
  JobConfig cfg;  // the main job's limits: j_tan 2e4, a_tan 1000
  cfg.machine.period = 1e-3;
  cfg.machine.degree = 5;
  cfg.machine.choose_format(cfg.limits);
  // quintic, 2^-32 mm: j_tan share sqrt(3) 8 2^-32 / 1e-9 / 2e4 = 1.6e-4 %
  EXPECT_EQ(cfg.machine.format().width, 96);
  EXPECT_EQ(cfg.machine.format().frac_bits, 32);
  cfg.machine.degree = 3;
  cfg.machine.choose_format(cfg.limits);
  // cubic, 2^-16 mm: a_tan share sqrt(3) 4 2^-16 / 1e-6 / 1000 = 10.6 % > 1 %; at 2^-32: 1.6e-4 %
  EXPECT_EQ(cfg.machine.format().width, 96);
  EXPECT_EQ(cfg.machine.format().frac_bits, 32);
  const double q16 = std::ldexp(1.0, -16);
  const AllowanceShare s16 = allowance_share(sample_allowance(q16, 0, 1e-3), cfg.limits, 3, 3);
  EXPECT_NEAR(s16.share, std::sqrt(3.0) * 4 * q16 / 1e-6 / 1000, 1e-12);
  EXPECT_EQ(s16.limit, "a_tan");
  // a long tick: the narrowest cubic engine is fine enough (a_tan: sqrt(3) 4 2^-16 / 0.1^2 / 1000 = 1e-5)
  cfg.machine.period = 0.1;
  cfg.machine.choose_format(cfg.limits);
  EXPECT_EQ(cfg.machine.format().width, 64);
  // bad limits are refused before a format is chosen
  cfg.limits.j_tan = std::nan("");
  EXPECT_THROW(cfg.machine.choose_format(cfg.limits), PlanError);
}

namespace {

// Every core sample against the fitted polynomials evaluated in 256-bit GMP
// floats (independent of the report's long double evaluation): the largest
// distance and the stated bound (1/2 LSB + the segment's register bound +
// its exact-joint offset).
std::pair<double, double> samples_to_polynomials(const RunOut& o, const JobConfig& cfg, int dim) {
  const double lsb = std::ldexp(1.0, -o.job.header.frac_bits);
  double worst = 0, bound = 0;
  size_t k = 0;
  for (size_t i = 0; i < o.job.segments.size(); ++i) {
    const TimeSegment& sg = o.job.segments[i];
    bound = std::max(bound, (0.5 + o.job.compiled[i].bound_lsb + o.job.compiled[i].offset_lsb) * lsb);
    for (uint32_t t = 0; t < sg.K; ++t, ++k)
      for (int a = 0; a < dim; ++a) {
        mpf_class tau(0, 256), x(0, 256), c(0, 256);
        tau = cfg.machine.period;
        tau *= t;
        for (int j = sg.degree; j >= 0; --j) {
          c = sg.coef[a][j];
          x = x * tau + c;
        }
        mpf_class sample(0, 256);
        sample = static_cast<double>(o.sim.samples.v[k][a]);
        sample *= lsb;
        const mpf_class e = abs(sample - x);
        worst = std::max(worst, e.get_d());
      }
  }
  EXPECT_EQ(k, o.sim.samples.v.size());
  return {worst, bound};
}

}  // namespace

// At 20 us ticks the allowance on the third differences is 8 q / h^3: at
// 2^-32 mm 2.3e5 mm/s^3, above the jerk limits. The tool then takes the
// 128-bit quintic engine at 2^-44 mm, whose joints are made exact
// (Machine::exact_joints; a linear blend, so the third differences see
// q = 1/2 + 1/2 LSB): 8 2^-44 / (2e-5)^3 sqrt(3) = 98 mm/s^3, 0.49 % of
// j_tan 2e4. Every limit then holds on the
// core's sample differences (expect_guarantees checks them apart from the
// report), and every sample is within the bound of the fitted polynomials.
TEST(PlannerCore, FineTicksMeetTheOnePercentAllowance) {
  const Path p = load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json");
  JobConfig cfg;
  cfg.machine.period = 20e-6;
  cfg.machine.choose_format(cfg.limits);
  EXPECT_EQ(cfg.machine.format().width, 128);
  EXPECT_EQ(cfg.machine.format().frac_bits, 44);
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "butterfly at 20 us");
  EXPECT_FALSE(o.rep.exact_form);
  EXPECT_LE(o.rep.allow_share, 0.01);
  EXPECT_LE(o.rep.allow_share, std::sqrt(3.0) * 8 * 1.0 * std::ldexp(1.0, -44) / 8e-15 / cfg.limits.j_tan * 1.000001);
  const auto [worst, bound] = samples_to_polynomials(o, cfg, p.dim());
  EXPECT_LE(worst, bound);
  std::printf("  20 us: allowance %.3g of %s, samples to polynomials %.3g mm (bound %.3g)\n", o.rep.allow_share,
              o.rep.allow_share_what.c_str(), worst, bound);
}

// At 2 us no carried format reaches 1 % (the 2^-44 mm engine's jerk
// allowance is 1.8e5 mm/s^3), so the report states the guarantee in its
// exact form: every core sample within the bound of the fitted polynomials
// (checked here again in 256-bit floats), and the polynomials within the
// limits.
TEST(PlannerCore, VeryFineTicksGiveTheExactFormGuarantee) {
  Path p;
  Eigen::VectorXd a(2), b(2);
  a << 3, 1;
  b << 9, 5;
  p.add(geo::make_line(a, b), "line");
  JobConfig cfg;
  cfg.machine.period = 2e-6;
  cfg.machine.choose_format(cfg.limits);
  EXPECT_EQ(cfg.machine.format().frac_bits, 44);
  const RunOut o = run_through_core(p, cfg);
  EXPECT_EQ(o.sim.mismatches, 0u);
  EXPECT_TRUE(o.rep.exact_form);
  EXPECT_GT(o.rep.allow_share, 0.01);
  EXPECT_LE(o.rep.worst_fit, 1 + 1e-9) << o.rep.worst_fit_what;
  EXPECT_LE(o.rep.max_deviation, cfg.limits.tol);
  EXPECT_LE(o.rep.sample_to_fit, o.rep.sample_bound);
  const std::string text = report_text(cfg, o.rep, o.job);
  EXPECT_NE(text.find("guarantee (exact form)"), std::string::npos) << text;
  EXPECT_NE(text.find("not checked: exact form"), std::string::npos) << text;
  const auto [worst, bound] = samples_to_polynomials(o, cfg, p.dim());
  EXPECT_LE(worst, bound);
  EXPECT_GT(worst, 0.25 * bound);  // the bound is not slack by orders of magnitude
  std::printf("  2 us: allowance %.3g of %s, samples to polynomials %.3g mm (bound %.3g)\n", o.rep.allow_share,
              o.rep.allow_share_what.c_str(), worst, bound);
}

// At 1 us the sampled tangential and normal checks divide third differences
// by h^3 = 1e-18 s^3: on absolute coordinates near 125 mm the doubles' rounding
// alone (8 eps |x| / h^3, about 1e5 mm/s^3) is above the jerk limits. The fit
// and the report take positions relative to each segment's start (its
// travel), so an arc far from the origin fits with no cap and its fitted
// polynomials' tangential and normal jerks read within the limits.
TEST(PlannerCore, MicrosecondTicksFitWithoutRoundingNoise) {
  Path p;
  p.add(geo::make_arc(Eigen::Vector2d(120, 80), 5, 0, 0.5 * M_PI), "quarter arc far from the origin");
  JobConfig cfg;
  cfg.machine.period = 1e-6;
  cfg.machine.choose_format(cfg.limits);
  const RunOut o = run_through_core(p, cfg);
  EXPECT_EQ(o.job.repairs, 0);
  EXPECT_EQ(o.job.rounds, 1);
  EXPECT_EQ(o.sim.mismatches, 0u);
  EXPECT_TRUE(o.rep.exact_form);
  EXPECT_LE(o.rep.worst_fit, 1 + 1e-9) << o.rep.worst_fit_what;
  EXPECT_GT(o.rep.fit_peaks.j_tan, 0.1 * cfg.limits.j_tan);  // measured, not zero
  EXPECT_LE(o.rep.max_deviation, cfg.limits.tol);
  EXPECT_LE(o.rep.sample_to_fit, o.rep.sample_bound);
  std::printf("  1 us: %zu segments, fit j_tan %.4g, j_cen %.4g (limits %g, %g)\n", o.job.segments.size(),
              o.rep.fit_peaks.j_tan, o.rep.fit_peaks.j_cen, cfg.limits.j_tan, cfg.limits.j_cen);
}

TEST(PlannerCore, RandomSplinesThroughVerilatedCore) {
  std::mt19937_64 rng(traj::test::test_seed(99));
  std::uniform_real_distribution<double> U(-1, 1);
  for (int rep = 0; rep < 6; ++rep) {
    geo::BSpline sp;
    sp.degree = 2 + rep % 4;
    const int dim = 2 + rep % 2, n = sp.degree + 3 + rep;
    sp.ctrl.resize(n, dim);
    for (int i = 0; i < n; ++i)
      for (int a = 0; a < dim; ++a) sp.ctrl(i, a) = 20 * U(rng) + 5 * i;
    sp.knots.resize(n + sp.degree + 1);
    for (int i = 0; i <= sp.degree; ++i) {
      sp.knots[i] = 0;
      sp.knots[n + i] = 1;
    }
    for (int i = sp.degree + 1; i < n; ++i) sp.knots[i] = double(i - sp.degree) / (n - sp.degree);
    if (rep % 3 == 2) {
      sp.weights.resize(n);
      for (int i = 0; i < n; ++i) sp.weights[i] = 1 + 0.5 * (U(rng) + 1);
    }
    Path p;
    p.add(sp, "random spline " + std::to_string(rep));
    JobConfig cfg;
    cfg.limits.feed = 30 + 40 * (U(rng) + 1);
    cfg.machine.degree = rep % 3 == 1 ? 3 : 5;
    cfg.limits.tol = cfg.machine.degree == 3 ? 2e-3 : 1e-3;
    const RunOut o = run_through_core(p, cfg);
    expect_guarantees(p, cfg, o, "random spline " + std::to_string(rep) + " degree " + std::to_string(sp.degree) +
                                     " dim " + std::to_string(dim) + " segments of degree " + std::to_string(cfg.machine.degree));
  }
}

TEST(PlannerCore, CornerStopsAndLimitsHold) {
  Path p;
  Eigen::VectorXd a(2), b(2), c(2);
  a << 0, 0;
  b << 10, 0;
  c << 10, 10;
  p.add(geo::make_line(a, b), "line 1");
  p.add(geo::make_line(b, c), "line 2");
  JobConfig cfg;
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "right-angle corner");
  // the feed is zero where the lines meet
  double v_corner = 1e9;
  for (const auto& t : o.job.ticks)
    if (std::fabs(t.s - 10) < 1e-3) v_corner = std::min(v_corner, t.v);
  const double v_near = [&] {
    double m = 1e9;
    for (const auto& t : o.job.ticks) m = std::min(m, std::fabs(t.s - 10) < 0.02 ? t.v : 1e9);
    return m;
  }();
  EXPECT_LT(v_near, 0.5) << "feed near the corner";
  (void)v_corner;
}

// Straight moves between stops (corners) switch the jerk only on ticks and
// use the jerk at axis_j_share of the limits (PlanOptions::align_straight_moves),
// also under a speed cap over the whole move (a lower feed):
// every moving piece starts on a tick, each move takes at least the
// continuous least time at those limits and at most 5 ticks more, the path is
// faster than with the moves left as planned, and every limit holds on the
// Verilated core's samples. At 1 ms (the fit tick is the engine's) and at
// 0.5 ms (fit ticks of two engine ticks, corners rest two engine ticks).
TEST(PlannerCore, StraightMovesBetweenStopsSwitchJerkOnTicks) {
  Path p;
  std::vector<Eigen::VectorXd> pts(5, Eigen::VectorXd(2));
  pts[0] << 0, 0;
  pts[1] << 30, 0;   // long: reaches the feed
  pts[2] << 30, 0.4;  // short: does not
  pts[3] << 12, 14;   // diagonal: both axes
  pts[4] << 12, 2;
  for (size_t i = 0; i + 1 < pts.size(); ++i) p.add(geo::make_line(pts[i], pts[i + 1]), "line " + std::to_string(i));
  for (double period : {1e-3, 5e-4}) {
    SCOPED_TRACE("period " + std::to_string(period));
    JobConfig cfg;
    cfg.machine.period = period;
    // the last move at a lower feed (a speed cap over the whole move, as a G-code F gives)
    const double s_last = p.offset(p.size() - 1), v_last = 20;
    cfg.plan.caps = {{s_last, p.length(), v_last}};
    // exact stops at the corners (as G61 or a G-code exact stop gives; where
    // the fit tick is coarser than the engine's, corners are stops anyway)
    for (size_t i = 1; i < p.size(); ++i) cfg.plan.caps.push_back({p.offset(i) - 1e-9, p.offset(i) + 1e-9, 0.0});
    const RunOut o = run_through_core(p, cfg);
    expect_guarantees(p, cfg, o, "straight moves between stops");
    const PlanOptions po = cfg.plan_options();
    const double h = po.period;  // the fit tick
    const Limits& L = cfg.limits;
    double jmax = 0;
    for (const Piece& q : o.job.plan.pieces) {
      if (q.v0 == 0 && q.a0 == 0 && q.j == 0) continue;  // at rest (a corner's rest, a rest up to the next tick)
      const double ph = q.t0 / h;
      EXPECT_NEAR(ph, std::round(ph), 1e-6) << "a jerk switch between ticks at t = " << q.t0;
      jmax = std::max(jmax, std::fabs(q.j));
    }
    // each move: from its first moving piece to its stop
    double t_move0 = -1;
    size_t move = 0;
    for (size_t k = 0; k < o.job.plan.pieces.size(); ++k) {
      const Piece& q = o.job.plan.pieces[k];
      const bool rest = q.v0 == 0 && q.a0 == 0 && q.j == 0;
      if (!rest && t_move0 < 0) t_move0 = q.t0;
      const bool ends = k + 1 == o.job.plan.pieces.size() ||
                        (o.job.plan.pieces[k + 1].v0 == 0 && o.job.plan.pieces[k + 1].a0 == 0);
      if (rest || !ends) continue;
      ASSERT_LT(move, pts.size() - 1);
      const Eigen::VectorXd u = (pts[move + 1] - pts[move]).normalized();
      double V = std::min(L.feed * po.feed_share, move + 2 == pts.size() ? v_last : 1e300);
      double A = po.tan_a_share * L.a_tan, J = po.axis_j_share * L.j_tan;
      for (int a = 0; a < 2; ++a)
        if (u[a] != 0) {
          V = std::min(V, po.axis_v_share * L.v_axis[a] / std::fabs(u[a]));
          A = std::min(A, po.axis_a_share * L.a_axis[a] / std::fabs(u[a]));
          J = std::min(J, po.axis_j_share * L.j_axis[a] / std::fabs(u[a]));
        }
      const double len = (pts[move + 1] - pts[move]).norm();
      const double t = q.t0 + q.T - t_move0, t_min = rest_to_rest_time(len, V, A, J);
      EXPECT_GE(t, t_min * (1 - 1e-9)) << "move " << move;
      EXPECT_LE(t, t_min + 5 * h) << "move " << move;
      ++move;
      t_move0 = -1;
    }
    EXPECT_EQ(move, pts.size() - 1);
    EXPECT_GT(jmax, 1.2 * po.tan_j_share * L.j_tan) << "the moves keep the lower jerk";
    PlanOptions off = po;
    off.align_straight_moves = false;
    EXPECT_LT(o.job.plan.duration(), plan_path(p, L, off).duration());
    std::printf("  period %g: %.4f s (%.4f s as planned), peak jerk %.0f\n", period, o.job.plan.duration(),
                plan_path(p, L, off).duration(), jmax);
  }
}

// A fast machine quoted with one acceleration and one jerk (as
// bench_toolpaths' set (i)): feed 100 mm/s, 3000 mm/s^2 and 60 000 mm/s^3
// for every axis and along and across the path, 0.5 ms ticks.
namespace {
JobConfig fast_machine() {
  JobConfig cfg;
  Limits& L = cfg.limits;
  L.feed = 100;
  for (int a = 0; a < kMaxAxes; ++a) L.v_axis[a] = 100, L.a_axis[a] = 3000, L.j_axis[a] = 60000;
  L.a_tan = L.a_cen = 3000;
  L.j_tan = L.j_cen = 60000;
  cfg.machine.period = 5e-4;
  return cfg;
}
}  // namespace

// Curved moves between stops (PlanOptions::align_curved_moves): a raster
// row over a wavy surface, a wide bend, a tight S-bend, and a line, a bend
// and a line joined with continuous curvature, in 3-D, each between exact
// stops, at limits with one acceleration and one jerk for every axis and
// the path (as bench_toolpaths' set (i)). The row, the bend and the chain
// are re-timed on the tick grid (every moving piece on a tick) with a jerk
// above the profile's J_t; where the exact trajectory would break a
// per-axis or centripetal limit, the re-timing lowers its jerk, acceleration
// or speed, or leaves the move as planned. The path is faster than with the
// curved moves not re-timed as a whole (only their blocks between
// stations, PlanOptions::align_blocks), and every limit holds on the Verilated
// core's samples (checked apart from the planner, output_check.hpp).
TEST(PlannerCore, CurvedMovesBetweenStopsSwitchJerkOnTicks) {
  auto spline = [](const std::vector<std::array<double, 3>>& c) {
    geo::BSpline sp;
    sp.degree = 3;
    const int n = static_cast<int>(c.size());
    sp.ctrl.resize(n, 3);
    for (int i = 0; i < n; ++i) sp.ctrl.row(i) << c[i][0], c[i][1], c[i][2];
    sp.knots.resize(n + 4);
    for (int i = 0; i < n + 4; ++i) sp.knots[i] = std::clamp(i - 3, 0, n - 3);  // clamped, uniform
    return sp;
  };
  std::vector<std::array<double, 3>> row, bend, sbend;
  for (int k = 0; k <= 20; ++k) row.push_back({1.5 * k, 0, std::sin(1.5 * k / 6)});
  for (int k = 0; k <= 8; ++k) {
    const double a = 0.5 * k / 8;  // a quarter-ish turn of radius 30 about (30, 30)
    bend.push_back({30 + 30 * std::sin(a), 30 - 30 * std::cos(a), row.back()[2]});
  }
  for (int k = 0; k <= 8; ++k)  // an S of amplitude 1.5 over 6 mm
    sbend.push_back({bend.back()[0] + 0.75 * k, bend.back()[1] + 1.5 * std::sin(k * 3.14159265358979 / 4), bend.back()[2]});
  // the chain: the bend's first and last three control points in line with
  // the lines, so that its curvature is zero where it meets them
  const std::array<double, 3> c0 = sbend.back();
  auto at = [&](double dx, double dy) { return std::array<double, 3>{c0[0] + dx, c0[1] + dy, c0[2]}; };
  const std::vector<std::array<double, 3>> chain_bend = {at(4, 0),  at(6, 0),         at(8, 0),
                                                         at(10, 0), at(11.732, 1), at(13.464, 2)};
  Path p;
  p.add(spline(row), "raster row");
  p.add(spline(bend), "wide bend");
  p.add(spline(sbend), "tight S-bend");
  auto vec = [](const std::array<double, 3>& a) { return Eigen::Vector3d(a[0], a[1], a[2]); };
  p.add(geo::make_line(vec(c0), vec(at(4, 0))), "chain: line in");
  p.add(spline(chain_bend), "chain: bend");
  p.add(geo::make_line(vec(at(13.464, 2)), vec(at(17.794, 4.5))), "chain: line out");
  JobConfig cfg = fast_machine();
  const Limits& L = cfg.limits;
  for (size_t i = 1; i < 4; ++i) cfg.plan.caps.push_back({p.offset(i) - 1e-9, p.offset(i) + 1e-9, 0.0});
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "curved moves between stops");
  const PlanOptions po = cfg.plan_options();
  const double h = po.period;
  // the largest jerk of the pieces on each curve, and whether every moving piece there starts on a tick
  std::vector<double> jmax(p.size(), 0);
  std::vector<bool> on_ticks(p.size(), true);
  for (const Piece& q : o.job.plan.pieces) {
    if (q.v0 == 0 && q.a0 == 0 && q.j == 0) continue;
    const size_t ci = p.curve_at(q.s0 + 1e-6);
    jmax[ci] = std::max(jmax[ci], std::fabs(q.j));
    const double ph = q.t0 / h;
    if (std::fabs(ph - std::round(ph)) > 1e-6) on_ticks[ci] = false;
  }
  for (size_t ci = 0; ci < p.size(); ++ci)
    std::printf("  %s: peak jerk %.0f (J_t %.0f), jerk switches %s\n", p.entry(ci).where.c_str(), jmax[ci],
                o.job.plan.J_t, on_ticks[ci] ? "on ticks" : "anywhere");
  for (size_t ci : {0, 1, 3, 4, 5}) EXPECT_TRUE(on_ticks[ci]) << p.entry(ci).where;
  // (the chain's bend is passed at its cruise: no piece starts on it)
  for (size_t ci : {0, 1, 3}) EXPECT_GT(jmax[ci], 1.2 * o.job.plan.J_t) << p.entry(ci).where;
  PlanOptions off = po;
  off.align_curved_moves = false;
  const double t_off = plan_path(p, L, off).duration();
  std::printf("  %.4f s (%.4f s with the curved moves not re-timed as a whole)\n", o.job.plan.duration(), t_off);
  EXPECT_LT(o.job.plan.duration(), t_off);
}

// A curved move between stops whose cruise bound is low in a few places
// only: a lobe of a pocket outline (r = 15 (1 + 0.15 sin 3φ + 0.07 cos(5φ +
// 0.4)) for φ from 2.6 to 4.7 rad, one cubic B-spline whose 41 control
// points lie on it), at limits with one acceleration and one jerk for
// every axis and the path (as bench_toolpaths' set (i)). With one cruise
// speed the whole lobe would run at the bound of its tightest spot; the
// profile's blocks re-timed on their own (PlanOptions::align_blocks) keep
// the profile's speed bound, which holds the whole jerk sums with every
// term's absolute value; with speed levels (PlanOptions::align_level_moves)
// the lobe runs near the feed and dips at its tight spots only: faster by
// 10 ms at least, every moving piece on a tick, and every limit held on the
// Verilated core's samples (checked apart from the planner,
// output_check.hpp).
TEST(PlannerCore, CurvedMoveBetweenStopsDipsAtItsTightSpots) {
  geo::BSpline sp;
  sp.degree = 3;
  const int n = 41;
  sp.ctrl.resize(n, 2);
  for (int i = 0; i < n; ++i) {
    const double phi = 2.6 + 2.1 * i / (n - 1);
    const double r = 15 * (1 + 0.15 * std::sin(3 * phi) + 0.07 * std::cos(5 * phi + 0.4));
    sp.ctrl.row(i) << r * std::cos(phi), r * std::sin(phi);
  }
  sp.knots.resize(n + 4);
  for (int i = 0; i < n + 4; ++i) sp.knots[i] = std::clamp(i - 3, 0, n - 3);
  Path p;
  p.add(sp, "lobe");
  JobConfig cfg = fast_machine();
  const Limits& L = cfg.limits;
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "a lobe");
  const PlanOptions po = cfg.plan_options();
  PlanOptions no_levels = po;
  no_levels.align_level_moves = false;
  const Plan without = plan_path(p, L, no_levels);
  auto speeds = [](const Plan& pl, double& lo, double& hi) {
    lo = 1e300, hi = 0;
    for (const Piece& q : pl.pieces)
      if (q.a0 == 0 && q.v0 > 0) lo = std::min(lo, q.v0), hi = std::max(hi, q.v0);
  };
  double lo = 0, hi = 0, lo0 = 0, hi0 = 0;
  speeds(o.job.plan, lo, hi);
  speeds(without, lo0, hi0);
  for (const Piece& q : o.job.plan.pieces) {
    if (q.v0 == 0 && q.a0 == 0 && q.j == 0) continue;
    const double ph = q.t0 / po.period;
    EXPECT_NEAR(ph, std::round(ph), 1e-6) << "a jerk switch between ticks at t = " << q.t0;
  }
  std::printf("  %.4f s, cruising at %.2f to %.2f mm/s; without levels %.4f s (%.2f to %.2f)\n",
              o.job.plan.duration(), lo, hi, without.duration(), lo0, hi0);
  EXPECT_LT(o.job.plan.duration(), without.duration() - 0.01);
  EXPECT_GT(hi, 0.95 * L.feed);
  EXPECT_LT(lo, 0.9 * hi);
}

// Blocks between stations, on the tick grid (PlanOptions::align_blocks): a
// path that does not stop between its ends (a line, a tangent arc of R 2 mm
// turning 90°, a line, a tangent arc turning back, a line) at limits with
// one acceleration and one jerk for every axis and the path (as
// bench_toolpaths' set (i)). Its profile's blocks between stations (the
// arcs' speed bounds) are re-timed on the tick grid with the jerk at up to
// 0.95 of the limits instead of J_t = 0.6, each after a cruise of less than
// a tick at its station's speed: faster than the profile as planned, a
// jerk above 1.2 J_t, every other piece starting on a tick, and every limit
// held on the Verilated core's samples (checked apart from the planner,
// output_check.hpp).
TEST(PlannerCore, BlocksBetweenStationsSwitchJerkOnTicks) {
  Path p;
  Eigen::VectorXd a(2), b(2), c(2), d(2), e(2), f(2);
  a << 0, 0;
  b << 15, 0;
  c << 17, 2;
  d << 17, 12;
  e << 19, 14;
  f << 34, 14;
  p.add(geo::make_line(a, b), "line 1");
  p.add(geo::make_arc(Eigen::Vector2d(15, 2), 2, -M_PI / 2, 0), "arc 1");
  p.add(geo::make_line(c, d), "line 2");
  p.add(geo::make_arc(Eigen::Vector2d(19, 12), 2, M_PI, M_PI / 2), "arc 2");
  p.add(geo::make_line(e, f), "line 3");
  JobConfig cfg = fast_machine();
  const Limits& L = cfg.limits;
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "lines and tangent arcs");
  const PlanOptions po = cfg.plan_options();
  PlanOptions off = po;
  off.align_blocks = false;
  const Plan planned = plan_path(p, L, off);
  double jmax = 0;
  size_t off_tick = 0;
  for (const Piece& q : o.job.plan.pieces) {
    jmax = std::max(jmax, std::fabs(q.j));
    const double ph = q.t0 / po.period;
    if (std::fabs(ph - std::round(ph)) > 1e-6) ++off_tick;  // the cruises that put a block on a tick
  }
  std::printf("  %.4f s (%.4f s with the blocks as planned), peak jerk %.0f (J_t %.0f), %zu of %zu pieces off the ticks\n",
              o.job.plan.duration(), planned.duration(), jmax, o.job.plan.J_t, off_tick, o.job.plan.pieces.size());
  EXPECT_LT(o.job.plan.duration(), planned.duration() - 0.01);
  EXPECT_GT(jmax, 1.2 * o.job.plan.J_t);
  EXPECT_LE(off_tick, o.job.plan.stations.size());
}

// A raster U-turn: a 0.5 mm half circle between two passes (curvature jumps
// at both ends). With the whole tangential acceleration reserved for the
// coupling terms 3 K v a_t, and a fifth of the axis jerk (half of j_cen) given
// to them a priori, the jerk limits would hold the arc to
// v <= 0.2 j_axis / (3 kappa A_t) (1.75 mm/s here); with the local tangential
// acceleration (planner.hpp) the arc runs several times faster, and every
// limit still holds on the Verilated core's samples.
TEST(PlannerCore, TightUTurnRunsFastAndLimitsHold) {
  Path p;
  Eigen::VectorXd a(2), b(2), c(2), d(2);
  a << 0, 0;
  b << 20, 0;
  c << 20, 1;
  d << 0, 1;
  p.add(geo::make_line(a, b), "pass 1");
  p.add(geo::make_arc(Eigen::Vector2d(20, 0.5), 0.5, -M_PI / 2, M_PI / 2), "u-turn");
  p.add(geo::make_line(c, d), "pass 2");
  JobConfig cfg;
  cfg.limits.feed = 50;
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "0.5 mm u-turn");
  const Plan& plan = o.job.plan;
  // |K_a| reaches kappa on the arc (where the tangent is along the other axis)
  const double kappa = 2;
  double v_reserved = 0.5 * cfg.limits.j_cen / (3 * kappa * plan.A_t);
  for (int ax = 0; ax < 2; ++ax)
    v_reserved = std::min(v_reserved, 0.2 * cfg.limits.j_axis[ax] / (3 * kappa * plan.A_t));
  double v_arc = 0;
  for (const auto& t : o.job.ticks)
    if (t.curve == 1) v_arc = std::max(v_arc, t.v);
  std::printf("  u-turn: peak speed on the arc %.3f mm/s (bound with A_t reserved: %.3f), motion %.3f s\n", v_arc,
              v_reserved, o.rep.motion_time);
  EXPECT_GT(v_arc, 4 * v_reserved);
}

// A line ending where a cubic starts backwards (a turn of 179.8 degrees) and
// turns forward again at a cusp 2e-5 mm later: simple-icons' furrynetwork.svg
// (a Bezier handle pointing 5 um back). The cubic is tb/geometry/cusp_cubic.hpp's
// with the cusp at u = 0.002: the cusp lies inside
// the first of the 32 intervals at which PathCurve::cusp_s samples the span's
// speed, and the arc length missed twice the way back, so the samples jumped
// 4e-5 mm at the curve's end and no repair could fit them ("the limits cannot
// be met"); with the cusp found, the block between the two stops had no inner
// grid point, so no speed bound, and was skipped (the samples jumped 2e-5 mm).
// Now both are stops at the closed-form arc lengths, the block between them
// is run, and every limit holds on the Verilated core's samples.
TEST(PlannerCore, ReversalIntoACuspJustInsideACurveStopsAtBoth) {
  const geotest::CuspCubic cc{10, 20, 0.002};
  const Eigen::MatrixXd P = cc.bezier();
  const Eigen::Vector2d c0 = P.row(0).transpose();
  Path p;
  p.add(geo::make_line(Eigen::Vector2d(c0 - Eigen::Vector2d(10, 0)), c0), "line");
  p.add(geo::make_bezier(P), "cubic");
  const double back = cc.back();
  ASSERT_EQ(p.entry(1).cusp_s().size(), 1u);
  EXPECT_NEAR(p.entry(1).cusp_s()[0], back, 1e-12);
  EXPECT_NEAR(p.length(), 10 + cc.s(1), 1e-12);
  JobConfig cfg;
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "reversal into a cusp");
  int stops = 0;
  for (const Station& st : o.job.plan.stations)
    if ((std::fabs(st.s - 10) < 1e-12 || std::fabs(st.s - 10 - back) < 1e-12) && st.v == 0) ++stops;
  EXPECT_EQ(stops, 2) << "a stop at the reversal and at the cusp";
}

// A cubic that starts with its first handle retracted to within 1e-12 mm of
// its end point, in line with the line before it: the tangent is continuous,
// but the curvature grows as 1/u towards the start (without bound), so the
// only way through is a stop (PathCurve::cusp_at_start). As a tangent join
// the speed bound there came from a curvature of order 1e10 and the profile
// crawled through at a speed no repair could fit (simple-icons' ferrari.svg,
// whose near-retracted handles gave 5e28 times a limit).
Path line_into_retracted_handle(double line_length) {
  Path p;
  Eigen::MatrixXd P(4, 2);
  P << 0, 0, 1e-12, 0, 3, 0.5, 6, 2;
  p.add(geo::make_line(Eigen::Vector2d(-line_length, 0), Eigen::Vector2d(0, 0)), "line");
  p.add(geo::make_bezier(P), "cubic");
  return p;
}

TEST(PlannerCore, RetractedHandleAtAJunctionIsAStop) {
  const Path p = line_into_retracted_handle(10);
  EXPECT_TRUE(p.entry(1).cusp_at_start());
  EXPECT_FALSE(p.entry(1).cusp_at_end());
  EXPECT_FALSE(p.entry(0).cusp_at_end());
  JobConfig cfg;
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "retracted handle at a junction");
  bool stop = false;
  for (const Station& st : o.job.plan.stations) stop = stop || (std::fabs(st.s - 10) < 1e-12 && st.v == 0);
  EXPECT_TRUE(stop);
}

// The same junction 20 m along a path, where an arc length is known to a few
// 1e-12 mm only: a tick a few microseconds before or after the stop rounds
// onto the junction, and is sampled there with the plan's small speed (2e-7
// mm/s 6 us before a stop at 12 000 mm/s^3). Its frame was taken 1e-9 of the
// span inside the cubic, where the curvature (as 1/u) is of order 1e9 mm^-1:
// such a tick read 29 times the jerk limit on LinuxCNC's LatheMacro.svg, and
// no speed cap could lower a speed already below the repairs' floor. Every
// sample within 30 us of the stop, on both sides, keeps every limit.
TEST(PlannerCore, TicksWithinRoundingOfARetractedHandleKeepTheLimits) {
  const Path p = line_into_retracted_handle(20000);
  ASSERT_TRUE(p.entry(1).cusp_at_start());
  JobConfig cfg;
  const Limits L = cfg.limits;
  const Plan plan = plan_path(p, L, cfg.plan_options());
  double t_stop = -1;
  for (const Piece& q : plan.pieces)
    if (q.t0 > 0 && q.v0 == 0 && std::fabs(q.s0 - p.offset(1)) < 1e-9) t_stop = q.t0;
  ASSERT_GT(t_stop, 0) << "a stop at the junction";
  double worst = 0, worst_dt = 0;
  int on_junction = 0;
  SampleHints hints;
  for (int k = -30; k <= 30; ++k) {
    const double tp = t_stop + k * 1e-6;
    const TickSample ts = sample_plan(p, plan, tp, tp, hints);
    on_junction += ts.s == p.offset(1);
    const double q = tick_ratio(ts, L, p.dim());
    if (q > worst) worst = q, worst_dt = k * 1e-6;
  }
  std::printf("  %d of 61 samples within 30 us of the stop round onto the junction; worst ratio %.3g (%.0f us)\n",
              on_junction, worst, worst_dt * 1e6);
  EXPECT_GT(on_junction, 0) << "the case this test is about";
  EXPECT_LE(worst, 1.0);
}

// A local minimum of the speed bound (a bump of one cubic B-spline, v_lim 47.5 mm/s at feed 50,
// 1.33 mm before a corner stop): the profile cannot reach it (braking for the stop passes there at
// about 28 mm/s), so it is no station. As one (acceleration 0 there) it split the braking into two
// speed changes with a plateau between them (0.931 s of motion against 0.914 s). Every limit still
// holds on the core.
TEST(PlannerCore, SpeedBoundMinimumTheProfileCannotReachIsNoStation) {
  geo::BSpline sp;
  sp.degree = 3;
  sp.ctrl.resize(8, 2);
  sp.ctrl << -20, 0, -12, 0, -4, 0, 0, 0, 0.5, 0.015, 1, 0, 1.5, 0, 2, 0;
  sp.knots.resize(12);
  sp.knots << 0, 0, 0, 0, 0.2, 0.4, 0.6, 0.8, 1, 1, 1, 1;
  Path p;
  p.add(sp, "bump");
  Eigen::VectorXd d(2), e(2);
  d << 2, 0;
  e << 2, 10;
  p.add(geo::make_line(d, e), "line out");  // a 90 degree corner: a stop
  JobConfig cfg;
  cfg.limits.feed = 50;
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "bump before a corner");
  const Plan& plan = o.job.plan;
  int inside = 0;
  for (const auto& st : plan.stations) inside += st.s > 1e-9 && st.s < p.offset(1) - 1e-9;
  double v_bump = 0;
  for (const auto& t : o.job.ticks)
    if (t.curve == 0 && t.s > 15 && t.s < 21) v_bump = std::max(v_bump, t.v);
  std::printf("  bump before a corner: %d stations inside the curve, peak %.2f mm/s near the bump, motion %.3f s\n",
              inside, v_bump, o.rep.motion_time);
  EXPECT_EQ(inside, 0);
}

// A tight arc (R 1 mm) and then a wider one (R 5 mm, a quarter) into a stop,
// at the limits of a fast machine (feed 100, 3000 mm/s^2, 60 000 mm/s^3). On
// the wide arc the jerk sums leave little tangential acceleration at the
// speed bound, and the block from the tight arc to the stop took that for
// all of its ramp (about 350 mm/s^2), although it runs far below the bound.
// With A taken at the speeds the block can run at (raise_accels) it brakes
// about twice as hard; every limit still holds on the core.
TEST(PlannerCore, BrakingForAStopTakesTheAccelerationOfItsOwnSpeeds) {
  Path p;
  Eigen::VectorXd a(2);
  a << -30, -1;
  Eigen::VectorXd b(2);
  b << 0, -1;
  p.add(geo::make_line(a, b), "line in");
  p.add(geo::make_arc(Eigen::Vector2d(0, 0), 1, -M_PI / 2, 0), "tight arc");
  p.add(geo::make_arc(Eigen::Vector2d(-4, 0), 5, 0, M_PI / 2), "wide arc");
  JobConfig cfg = fast_machine();
  const Limits& L = cfg.limits;
  // the profile as planned: the re-timing on the tick grid (step 5) takes
  // the braking block anew, whatever acceleration the profile gave it
  cfg.plan.align_straight_moves = false;
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "two arcs into a stop");
  PlanOptions off = cfg.plan_options();
  off.accel_at_profile_speed = false;
  const double t_off = plan_path(p, L, off).duration(), t_on = o.job.plan.duration();
  // the largest deceleration on the wide arc, planned
  auto peak_braking = [&](const Plan& plan) {
    double a_min = 0;
    for (const auto& q : plan.pieces)
      if (q.s0 > p.offset(2)) a_min = std::min({a_min, q.a(0), q.a(q.T)});
    return -a_min;
  };
  const double brake_on = peak_braking(o.job.plan), brake_off = peak_braking(plan_path(p, L, off));
  std::printf("  two arcs into a stop: %.4f s (A at v_lim: %.4f s), braking on the wide arc %.0f mm/s^2 (%.0f)\n", t_on,
              t_off, brake_on, brake_off);
  EXPECT_GT(brake_on, 1.5 * brake_off);
  EXPECT_LT(t_on, t_off - 0.01);
}

// A hairpin (one quadratic B-spline): nearly straight legs into a tip of
// high curvature, no junction between them. The local tangential acceleration
// is small only near the tip; a block from the start to the tip would take
// that smallest value for its whole ramp (about 1/20 of A_t here). Stations
// where the local acceleration has changed 4x split the ramp, so the legs
// accelerate and brake at up to A_t; every limit still holds on the core.
TEST(PlannerCore, HairpinRampsAtFullAccelerationAwayFromTheTip) {
  geo::BSpline sp;
  sp.degree = 2;
  sp.ctrl.resize(4, 2);
  sp.ctrl << 0, 0, 20, 0, 20, 0.4, 0, 0.4;
  sp.knots.resize(7);
  sp.knots << 0, 0, 0, 0.5, 1, 1, 1;
  Path p;
  p.add(sp, "hairpin");
  JobConfig cfg;
  cfg.limits.feed = 50;
  const RunOut o = run_through_core(p, cfg);
  expect_guarantees(p, cfg, o, "hairpin");
  double a_peak = 0;
  for (const auto& q : o.job.plan.pieces) a_peak = std::max({a_peak, std::fabs(q.a(0)), std::fabs(q.a(q.T))});
  std::printf("  hairpin: motion %.3f s, planned tangential acceleration peak %.1f of A_t %.1f\n", o.rep.motion_time,
              a_peak, o.job.plan.A_t);
  // the ramp between the tip and the feed reaches half of A_t, or what the
  // jerk-limited change needs (sqrt(dv J_t): it never holds its
  // acceleration), not the tip's local acceleration
  double v_min = cfg.limits.feed;
  for (const auto& t : o.job.ticks)
    if (t.t > 0.3 && t.t < o.rep.motion_time - 0.3) v_min = std::min(v_min, t.v);
  const double a_need = std::sqrt((cfg.limits.feed - v_min) * o.job.plan.J_t);
  std::printf("  hairpin: slowest %.2f mm/s at the tip; a jerk-limited change to the feed peaks at %.1f\n", v_min, a_need);
  EXPECT_GT(a_peak, std::min(0.5 * o.job.plan.A_t, 0.9 * a_need));
}

TEST(PlannerInput, BadInputGetsOneClearError) {
  const Path p = load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json");
  auto msg = [&](auto mutate) -> std::string {
    JobConfig cfg;
    mutate(cfg);
    try {
      run_job(p, cfg);
    } catch (const PlanError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(msg([](JobConfig& c) { c.limits.feed = 0; }).find("feed"), std::string::npos);
  EXPECT_NE(msg([](JobConfig& c) { c.limits.feed = NAN; }).find("feed"), std::string::npos);
  EXPECT_NE(msg([](JobConfig& c) { c.limits.a_axis[1] = -5; }).find("a_axis.y"), std::string::npos);
  EXPECT_NE(msg([](JobConfig& c) { c.limits.j_tan = INFINITY; }).find("j_tan"), std::string::npos);
  EXPECT_NE(msg([](JobConfig& c) { c.limits.tol = 0; }).find("tol"), std::string::npos);
  EXPECT_NE(msg([](JobConfig& c) { c.machine.period = 0; }).find("tick period"), std::string::npos);
  EXPECT_NE(msg([](JobConfig& c) { c.machine.period = NAN; }).find("tick period"), std::string::npos);
  // zero-length curve
  Eigen::VectorXd a(2);
  a << 1, 1;
  Path z;
  try {
    z.add(geo::make_line(a, a), "zero");
    ADD_FAILURE() << "zero-length curve accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("zero"), std::string::npos) << e.what();
  }
  // unreadable and malformed files
  EXPECT_THROW(load_path("/nonexistent/path.json"), PlanError);
  const std::string bad = ::testing::TempDir() + "/bad_path.json";
  std::ofstream(bad) << "{\"curves\": [ {\"degree\": 3, ";
  try {
    load_path(bad);
    ADD_FAILURE();
  } catch (const PlanError& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos);
  }
}

// The planner's own guard (whatever the output format): a line of 1e12 units
// would need 4e12 grid points 0.25 apart; it is refused naming the curve,
// before any point is built (a fraction of a second, not 17 GB).
TEST(PlannerCore, GridBeyondItsBoundRefusedNamingTheCurve) {
  Eigen::VectorXd a(2), b(2);
  a << 0, 0;
  b << 1e12, 0;
  Path p;
  p.add(geo::make_line(a, b), "far line");
  JobConfig cfg;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    (void)traj::plan::plan_path(p, cfg.limits, cfg.plan_options());
    ADD_FAILURE() << "a grid of 4e12 points accepted";
  } catch (const PlanError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("far line: the arc-length grid would pass"), std::string::npos) << m;
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
}
