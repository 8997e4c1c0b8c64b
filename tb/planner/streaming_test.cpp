// Streaming (bounded look-ahead window) planner: the emitted segments, run
// through the hls engine model, keep every guarantee of the whole-path planner
// and chain exactly across windows.
#include <gtest/gtest.h>

#include <cmath>

#include "fd_drive.hpp"
#include "planner/raster.hpp"
#include "planner/streaming.hpp"
#include "traj_fd_engine.hpp"

using namespace traj;
using namespace traj::plan;

namespace {

// Distance from x to the nearest point of the path (coarse scan + Newton per curve).
double distance_to_path(const Path& p, const double* x) {
  double best = 1e300;
  for (size_t ci = 0; ci < p.size(); ++ci) {
    const geo::Curve& c = p.curve(ci);
    const int d = c.dim();
    double bu = c.u_begin(), bd = 1e300;
    for (int i = 0; i <= 64; ++i) {
      const double u = c.u_begin() + (c.u_end() - c.u_begin()) * i / 64;
      const Eigen::VectorXd q = c.point(u);
      double e2 = 0;
      for (int a = 0; a < d; ++a) e2 += (q[a] - x[a]) * (q[a] - x[a]);
      if (e2 < bd) {
        bd = e2;
        bu = u;
      }
    }
    double u = bu, buf[9];
    for (int it = 0; it < 20; ++it) {
      c.eval(u, 2, buf);
      double f = 0, fp = 0;
      for (int a = 0; a < d; ++a) {
        const double e = buf[a] - x[a];
        f += e * buf[d + a];
        fp += buf[d + a] * buf[d + a] + e * buf[2 * d + a];
      }
      if (fp <= 0) break;
      u = std::clamp(u - f / fp, c.u_begin(), c.u_end());
    }
    c.eval(u, 0, buf);
    double e2 = 0;
    for (int a = 0; a < d; ++a) e2 += (buf[a] - x[a]) * (buf[a] - x[a]);
    best = std::min(best, std::sqrt(e2));
  }
  return best;
}

}  // namespace

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
  fd::Compiler compiler(engine_format(5));
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
  for (size_t k = 0; k < x.size(); k += 3) dev = std::max(dev, distance_to_path(whole, x[k].data()));
  EXPECT_LE(dev, cfg.limits.tol);
  // sampled per-axis derivatives within limits + quantisation allowance
  const double h = cfg.plan.period, q = 1 * lsb;
  for (size_t k = 0; k + 3 < x.size(); ++k)
    for (int a = 0; a < 2; ++a) {
      const double v = std::fabs(x[k + 1][a] - x[k][a]) / h;
      const double acc = std::fabs(x[k + 2][a] - 2 * x[k + 1][a] + x[k][a]) / (h * h);
      const double j = std::fabs(x[k + 3][a] - 3 * x[k + 2][a] + 3 * x[k + 1][a] - x[k][a]) / (h * h * h);
      ASSERT_LE(v, cfg.limits.v_axis[a] + 2 * q / h) << "tick " << k;
      ASSERT_LE(acc, cfg.limits.a_axis[a] + 4 * q / (h * h)) << "tick " << k;
      ASSERT_LE(j, cfg.limits.j_axis[a] + 8 * q / (h * h * h)) << "tick " << k;
    }
  // starts at the path start, ends at the path end
  const Eigen::VectorXd p0 = whole.curve(0).point(whole.curve(0).u_begin());
  const Eigen::VectorXd p1 = whole.curve(whole.size() - 1).point(whole.curve(whole.size() - 1).u_end());
  for (int a = 0; a < 2; ++a) {
    EXPECT_NEAR(x.front()[a], p0[a], 1e-9);
    EXPECT_NEAR(x.back()[a], p1[a], 1e-9);
  }
  // a bounded window plans no faster than the whole path (it sees less), and not much slower here
  JobConfig whole_cfg = cfg;
  const JobResult wr = run_job(whole, whole_cfg);
  std::printf("  streaming: %zu windows, %lld ticks (%.3f s); whole path %.3f s; deviation %.3g\n", st.windows,
              st.ticks, st.motion_time, wr.plan.duration(), dev);
  EXPECT_GE(st.motion_time, wr.plan.duration() * (1 - 1e-6));
  EXPECT_LE(st.motion_time, wr.plan.duration() * 1.10);
}
