// SPDX-License-Identifier: Apache-2.0
// job::SegmentCompiler's exact joints (at every format: the 96-bit engine at
// 2^-32 units and the fine ticks' 128-bit engine at 2^-44) against an
// independent construction in exact
// rationals: the target written out as the polynomial plus the joint's
// linear blend, delta (1 - t/T) with delta = the previous polynomial's end
// (mpq) minus this one's start, compiled by the compiler's exact-target path
// (fd::Compiler::compile_target, mpq throughout). Every register and end
// state must be equal, and the stated parts must bound the exact ones: the
// carried error |r0 - previous polynomial's end| <= carried_lsb and
// |delta| <= offset_lsb.
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "geometry/bspline.hpp"
#include "input/path_json.hpp"
#include "job/job.hpp"

namespace {

using namespace traj;

mpq_class exact(double v) {
  mpq_class q;
  mpq_set_d(q.get_mpq_t(), v);
  return q;
}

// The previous polynomial at its end, exactly.
mpq_class end_of(const plan::TimeSegment& s, int axis, const mpq_class& h) {
  const mpq_class T = h * mpq_class(static_cast<unsigned long>(s.K));
  mpq_class v = 0;
  for (int j = s.degree; j >= 0; --j) v = v * T + exact(s.coef[axis][j]);
  return v;
}

// The tool's engine at this tick period: 2^-32 units at 1 ms, 2^-44 at 20 us.
job::Machine machine_at(double period, int frac_bits) {
  job::JobConfig cfg;
  cfg.machine.period = period;
  cfg.machine.choose_format(cfg.limits);
  EXPECT_EQ(cfg.machine.format().frac_bits, frac_bits);
  return cfg.machine;
}

struct Segments {
  std::vector<plan::TimeSegment> segments;
  std::vector<fd::Compiled> compiled;
};

// Returns the largest |delta| seen, output LSB.
double check_joints(const job::Machine& m, const Segments& r) {
  const fd::Format f = m.format();
  const fd::Compiler ref(f);
  const mpq_class h = exact(m.period);
  const mpq_class lsb_units = mpq_class(mpz_class(1) << f.frac_bits);
  const mpq_class scale = lsb_units * mpq_class(mpz_class(1) << f.guard_bits);
  double worst_joint = 0;
  for (size_t i = 1; i < r.segments.size(); ++i) {
    const plan::TimeSegment& prev = r.segments[i - 1];
    const plan::TimeSegment& seg = r.segments[i];
    const fd::Compiled& got = r.compiled[i];
    fd::ExactTarget t;
    t.ticks = seg.K;
    t.q.assign(static_cast<size_t>(f.axes), std::vector<mpq_class>(static_cast<size_t>(f.degree) + 1, 0));
    for (int a = 0; a < f.axes; ++a) {
      const mpq_class end = end_of(prev, a, h);
      const mpq_class delta = end - exact(seg.coef[a][0]);
      const double delta_lsb = std::fabs(mpq_class(delta * lsb_units).get_d());
      worst_joint = std::max(worst_joint, delta_lsb);
      EXPECT_LE(delta_lsb, got.offset_lsb) << "segment " << i << " axis " << a;
      // the carried error: the start (the previous segment's exact end) from the previous polynomial's end
      const mpq_class e0 = mpq_class(r.compiled[i - 1].end[a]) - end * scale - mpq_class(mpz_class(1) << f.guard_bits, 2);
      EXPECT_LE(std::fabs(mpq_class(e0 / mpq_class(mpz_class(1) << f.guard_bits)).get_d()), got.carried_lsb)
          << "segment " << i << " axis " << a;
      mpq_class hj = 1;
      auto& q = t.q[static_cast<size_t>(a)];
      for (int j = 0; j <= f.degree; ++j, hj *= h) q[j] = exact(seg.coef[a][j]) * scale * hj;
      q[0] += delta * scale + mpq_class(mpz_class(1) << f.guard_bits, 2);
      q[1] -= delta * scale / mpq_class(static_cast<unsigned long>(seg.K));
    }
    const fd::Compiled want = ref.compile_target(t, &r.compiled[i - 1].end, "segment " + std::to_string(i));
    EXPECT_EQ(got.regs, want.regs) << "segment " << i;
    EXPECT_EQ(got.end, want.end) << "segment " << i;
    if (got.regs != want.regs || got.end != want.end) break;
  }
  std::printf("  %zu joints at 2^-%d units: the largest %.3g LSB\n", r.segments.size() - 1, f.frac_bits, worst_joint);
  return worst_joint;
}

// A planned job's segments (the butterfly at 20 us and at 1 ms ticks):
// joints of a few hundredths of an LSB at 2^-44, as the fit's doubles leave
// them.
void expect_job_joints_exact(double period, int frac_bits) {
  job::JobConfig cfg;
  cfg.machine = machine_at(period, frac_bits);
  const job::JobResult r =
      job::run_job(input::load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json"), cfg);
  ASSERT_GT(r.segments.size(), 20u);
  EXPECT_GT(check_joints(cfg.machine, {r.segments, r.compiled}), 0.0);
}
TEST(SegmentCompiler, ExactJointsOfAJobMatchTheExactTarget) { expect_job_joints_exact(20e-6, 44); }
TEST(SegmentCompiler, ExactJointsOfAJobMatchTheExactTargetAtTheBoardFormat) { expect_job_joints_exact(1e-3, 32); }

// Quintic segments whose starts are set off from the previous polynomial's
// end by up to 0.88 of Machine::joint_lsb (900 LSB at 2^-44, 0.22 LSB at
// 2^-32, where with the carried register error that is beyond the
// compiler's own start tolerance, tol/2): the blend takes them, bit for bit
// as the exact target does; past the bound (1.07 of it) the segment is
// refused as a jump.
void expect_joints_taken_and_jumps_refused(const job::Machine& m) {
  const double lsb = std::ldexp(1.0, -m.format().frac_bits);
  const double bound = job::Machine::joint_lsb(m.format());
  job::SegmentCompiler sc(m);
  Segments r;
  double x[3] = {12.5, -40.25, 3.0};
  for (int i = 0; i < 12; ++i) {
    plan::TimeSegment s;
    s.K = static_cast<uint32_t>(50 + 37 * i);
    s.degree = 5;
    const double T = s.K * m.period;
    for (int a = 0; a < 3; ++a) {
      s.coef[a][0] = x[a] + (i == 0 ? 0 : (i % 3 - 1) * (0.293 * bound) * (i % 4) * lsb);
      s.coef[a][1] = 10.0 + a - 0.5 * i;
      s.coef[a][2] = 200.0 * (a - 1);
      s.coef[a][3] = -1000.0 * (i % 5 - 2);
      x[a] = s.coef[a][0] + T * (s.coef[a][1] + T * (s.coef[a][2] + T * s.coef[a][3]));
    }
    r.compiled.push_back(sc.compile(s, static_cast<size_t>(i)));
    r.segments.push_back(s);
  }
  EXPECT_GT(check_joints(m, r), 0.8 * bound);
  plan::TimeSegment jump = r.segments.back();
  jump.coef[0][0] = x[0] + 1.07 * bound * lsb;
  try {
    sc.compile(jump, 12);
    ADD_FAILURE() << "a jump of 1.07 times the joint bound was compiled";
  } catch (const plan::PlanError& e) {
    EXPECT_NE(std::string(e.what()).find("segment 12: starts"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not continuous"), std::string::npos) << e.what();
  }
}
TEST(SegmentCompiler, LargeJointsMatchTheExactTargetAndJumpsAreRefused) {
  expect_joints_taken_and_jumps_refused(machine_at(20e-6, 44));
}
TEST(SegmentCompiler, JointsAtTheBoardFormatMatchTheExactTargetAndJumpsAreRefused) {
  expect_joints_taken_and_jumps_refused(machine_at(1e-3, 32));
}

}  // namespace
