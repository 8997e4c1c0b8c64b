// SPDX-License-Identifier: Apache-2.0
// Streaming (bounded look-ahead window) planner: the emitted segments, run
// through the hls engine model, keep every guarantee of the whole-path planner
// and chain exactly across windows.
#include <gtest/gtest.h>

#include <cmath>

#include "fd_drive.hpp"
#include "output_check.hpp"
#include "input/raster.hpp"
#include "job/streaming.hpp"
#include "traj_fd_engine.hpp"

using namespace traj;
using namespace traj::plan;
using namespace traj::input;
using namespace traj::job;


TEST(Streaming, RasterKeepsGuaranteesAndChainsExactly) {
  const size_t pieces = 24;
  JobConfig cfg;
  cfg.limits.feed = 40;
  RasterSource src(pieces, 6.0, 1.0);
  std::vector<fd::Compiled> comp;
  StreamOptions so;
  so.window = 6;
  so.commit = 3;
  const StreamStats st = run_streaming(src, cfg, so, [&](const fd::Compiled& c, const TimeSegment&) { comp.push_back(c); });
  EXPECT_EQ(st.curves, pieces);
  EXPECT_GE(st.windows, pieces / so.commit);
  // run the emitted stream through the hls model of the engine
  using Eng = FdEngine<3, 5, 96, 16, 48>;
  fd::Compiler compiler(Machine{}.format());
  Eng e;
  std::vector<std::array<double, 3>> x;
  const double lsb = std::ldexp(1.0, -32);
  traj::test::run_segments(e, compiler, comp, Eng::kWords + Eng::kChunks + 2,
                           [&](size_t s, uint64_t k, const Eng::Out& o) {
                             std::array<double, 3> v{};
                             for (int a = 0; a < 3; ++a) {
                               v[a] = static_cast<double>(sext(o.sample[a], Eng::kOutWidth)) * lsb;
                               // the model equals the host's exact prediction
                               ASSERT_EQ(traj::test::to_mpz_signed(o.sample[a], Eng::kOutWidth),
                                         compiler.sample_at(comp[s], a, k));
                             }
                             x.push_back(v);
                           });
  EXPECT_EQ(static_cast<long long>(x.size()), st.ticks);
  // the whole path, for distances
  Path whole;
  RasterSource again(pieces, 6.0, 1.0);
  geo::BSpline b;
  std::string w;
  while (again.next(b, w)) whole.add(b, w);
  double dev = 0;
  size_t hint = 0;
  for (size_t k = 0; k < x.size(); ++k) dev = std::max(dev, traj::test::distance_to_path(whole, x[k].data(), hint));
  EXPECT_LE(dev, cfg.limits.tol);
  // every limit at the samples, within the quantisation allowance (q: the
  // largest stated sample error of the emitted segments)
  double q = 0;
  for (const auto& c : comp) q = std::max(q, (0.5 + c.bound_lsb) * lsb);
  const traj::test::OutputVerdict ov = traj::test::check_output_limits(x, 2, cfg.limits, cfg.machine.period, q, true);
  EXPECT_LE(ov.worst, 1 + 1e-9) << ov.what << " at tick " << ov.tick;
  // starts at the path start, ends at the path end
  const Eigen::VectorXd p0 = whole.curve(0).point(whole.curve(0).u_begin());
  const Eigen::VectorXd p1 = whole.curve(whole.size() - 1).point(whole.curve(whole.size() - 1).u_end());
  for (int a = 0; a < 2; ++a) {
    EXPECT_NEAR(x.front()[a], p0[a], 1e-9);
    EXPECT_NEAR(x.back()[a], p1[a], 1e-9);
  }
  // a bounded window plans about as fast as the whole path: it sees less, but
  // the planner is greedy (stations, local speed caps from tick checks), so
  // either may be a little faster
  JobConfig whole_cfg = cfg;
  const JobResult wr = run_job(whole, whole_cfg);
  std::printf("  streaming: %zu windows, %lld ticks (%.3f s); whole path %.3f s; deviation %.3g\n", st.windows,
              st.ticks, st.motion_time, wr.plan.duration(), dev);
  EXPECT_GE(st.motion_time, wr.plan.duration() * 0.99);
  EXPECT_LE(st.motion_time, wr.plan.duration() * 1.10);
}

namespace {

// A chain of cubic Béziers joined G1 with random length ratios (the
// curvature jumps at every join, so the per-axis acceleration steps there),
// and a tangent break (a corner) every `corner_every` curves.
class G1ChainSource : public CurveSource {
 public:
  G1ChainSource(size_t n, uint64_t seed, size_t corner_every) : n_(n), rng_(seed), corner_every_(corner_every) {
    p_ << 0, 0;
    t_ << 1, 0;
  }
  bool next(geo::BSpline& out, std::string& where) override {
    if (i_ >= n_) return false;
    std::uniform_real_distribution<double> U(0, 1);
    if (i_ > 0 && corner_every_ && i_ % corner_every_ == 0) {
      const double th = 0.3 + 1.2 * U(rng_);  // the corner's turn, rad
      t_ = Eigen::Rotation2Dd(U(rng_) < 0.5 ? th : -th) * t_;
    }
    const double len = 2 + 6 * U(rng_);
    Eigen::Vector2d d = Eigen::Rotation2Dd(1.4 * (U(rng_) - 0.5)) * t_;
    Eigen::MatrixXd c(4, 2);
    const Eigen::Vector2d p1 = p_ + (0.2 + 0.3 * U(rng_)) * len * t_;
    const Eigen::Vector2d p3 = p_ + len * d;
    const Eigen::Vector2d t3 = Eigen::Rotation2Dd(1.0 * (U(rng_) - 0.5)) * d;
    const Eigen::Vector2d p2 = p3 - (0.2 + 0.3 * U(rng_)) * len * t3;
    c.row(0) = p_.transpose();
    c.row(1) = p1.transpose();
    c.row(2) = p2.transpose();
    c.row(3) = p3.transpose();
    out = geo::make_bezier(c);
    where = "G1 chain piece " + std::to_string(i_);
    p_ = p3;
    t_ = t3.normalized();
    ++i_;
    return true;
  }

 private:
  size_t n_, i_ = 0;
  std::mt19937_64 rng_;
  size_t corner_every_;
  Eigen::Vector2d p_, t_;
};

}  // namespace

// Windows of several sizes on G1 chains with curvature jumps and corners: the
// emitted stream, through the hls engine, chains exactly, stays within the
// tolerance of the path and within every limit at the samples (the window
// junctions included), and ends at the path's end.
TEST(Streaming, G1ChainsKeepGuaranteesAtEveryWindowSize) {
  // (window, seed): seeds 1, 2 have a corner every 11th curve, where the
  // commit moves to the nearest smooth junction (windows from 3 curves work);
  // seed 3 is a polyline (every junction a corner): the commit cuts the curve
  // after the corner (windows from 8 curves; see host/job/README.md for smaller ones)
  const std::pair<size_t, uint64_t> cases[] = {{3, 1}, {3, 2}, {4, 1}, {4, 2}, {8, 1}, {8, 2}, {16, 1},
                                               {16, 2}, {8, 3}, {16, 3}, {64, 3}};
  for (const auto& [window, seed] : cases) {
    {
      // seed 3: every junction a corner (a polyline of Beziers); else every 11th
      const size_t corner_every = seed == 3 ? 1 : 11;
      SCOPED_TRACE("window " + std::to_string(window) + " seed " + std::to_string(seed));
      const size_t pieces = 30;
      JobConfig cfg;
      cfg.limits.feed = 60;
      G1ChainSource src(pieces, seed, corner_every);
      std::vector<fd::Compiled> comp;
      StreamOptions so;
      so.window = window;
      so.commit = std::max<size_t>(1, window / 2);
      const StreamStats st =
          run_streaming(src, cfg, so, [&](const fd::Compiled& c, const TimeSegment&) { comp.push_back(c); });
      using Eng = FdEngine<3, 5, 96, 16, 48>;
      fd::Compiler compiler(Machine{}.format());
      Eng e;
      std::vector<std::array<double, 3>> x;
      const double lsb = std::ldexp(1.0, -32);
      traj::test::run_segments(e, compiler, comp, Eng::kWords + Eng::kChunks + 2,
                               [&](size_t s, uint64_t k, const Eng::Out& o) {
                                 std::array<double, 3> v{};
                                 for (int a = 0; a < 3; ++a) {
                                   v[a] = static_cast<double>(sext(o.sample[a], Eng::kOutWidth)) * lsb;
                                   ASSERT_EQ(traj::test::to_mpz_signed(o.sample[a], Eng::kOutWidth),
                                             compiler.sample_at(comp[s], a, k));
                                 }
                                 x.push_back(v);
                               });
      ASSERT_EQ(static_cast<long long>(x.size()), st.ticks);
      Path whole;
      G1ChainSource again(pieces, seed, corner_every);
      geo::BSpline b;
      std::string w;
      while (again.next(b, w)) whole.add(b, w);
      double dev = 0;
      size_t hint = 0;
      for (size_t k = 0; k < x.size(); ++k) dev = std::max(dev, traj::test::distance_to_path(whole, x[k].data(), hint));
      EXPECT_LE(dev, cfg.limits.tol);
      double q = 0;
      for (const auto& c : comp) q = std::max(q, (0.5 + c.bound_lsb) * lsb);
      const traj::test::OutputVerdict ov = traj::test::check_output_limits(x, 2, cfg.limits, cfg.machine.period, q, true);
      EXPECT_LE(ov.worst, 1 + 1e-9) << ov.what << " at tick " << ov.tick;
      const Eigen::VectorXd p1 = whole.curve(whole.size() - 1).point(whole.curve(whole.size() - 1).u_end());
      for (int a = 0; a < 2; ++a) EXPECT_NEAR(x.back()[a], p1[a], 1e-9);
      std::printf("  G1 chain, window %zu, seed %llu: %zu windows, %.3f s, deviation %.3g, worst %.4f (%s)\n", window,
                  static_cast<unsigned long long>(seed), st.windows, st.motion_time, dev, ov.worst, ov.what.c_str());
    }
  }
}

// Tick times far into a stream: a window starting at tick 2^40 (35 years at
// 1 ms) samples exactly what the same window starting at tick 0 samples, when
// its start is given as an integer tick origin plus a sub-tick offset (what
// run_streaming passes). As one double time, k h - T0, each tick's plan time
// would be rounded by up to 1e-7 s there (the tick grid itself is lost).
TEST(Streaming, TickTimesKeepFullPrecisionFarIntoTheStream) {
  Path p;
  Eigen::VectorXd a(2), b(2);
  a << 0, 0;
  b << 5, 3;
  p.add(geo::make_line(a, b), "line");
  JobConfig cfg;
  cfg.limits.feed = 50;
  const Plan plan = plan_path(p, cfg.limits, cfg.plan_options());
  const double h = cfg.machine.period, off = 0.37 * h;
  const long long n = static_cast<long long>(plan.duration() / h);
  ASSERT_GT(n, 50);
  const long long far = 1LL << 40;
  std::vector<TickSample> near_ts, far_ts;
  append_ticks_range(p, plan, h, off, 1, n, near_ts, 0);
  append_ticks_range(p, plan, h, off, far + 1, far + n, far_ts, far);
  ASSERT_EQ(near_ts.size(), far_ts.size());
  for (size_t k = 0; k < near_ts.size(); ++k) {
    ASSERT_EQ(near_ts[k].s, far_ts[k].s) << "tick " << k;
    ASSERT_EQ(near_ts[k].v, far_ts[k].v) << "tick " << k;
    for (int ax = 0; ax < 2; ++ax) ASSERT_EQ(near_ts[k].x[ax], far_ts[k].x[ax]) << "tick " << k;
  }
  // the plan times on the near side are exact multiples of h less the offset:
  // the sampled speed follows the profile to rounding
  for (size_t k = 0; k < near_ts.size(); ++k)
    EXPECT_NEAR(near_ts[k].s, state_at(plan, static_cast<double>(k + 1) * h - off).s, 1e-12);
}
