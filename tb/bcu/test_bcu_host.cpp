// host/bcu: segment compiler (errors, exact prediction == hls, bound vs double
// at every sample) and the seed-000 C1 spline (eq. 9-16) sampled by the hls
// generator.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "bcu/bcu_compiler.hpp"
#include "bcu/bezier_spline.hpp"
#include "bcu_driver.hpp"
#include "traj_bcu_gen.hpp"

namespace bcu = traj::bcu;

namespace {
constexpr int kAx = 3, kChunk = 32, kCtrl = 40, kGuard = 9, kOut = 32, kMaxD = 12, kFrac = 16;
using Gen = traj::BcuGen<kAx, kChunk, kCtrl, kGuard, kOut, kMaxD>;

bcu::Format fmt() {
  bcu::Format f;
  f.axes = kAx;
  f.chunk_width = kChunk;
  f.ctrl_width = kCtrl;
  f.guard_bits = kGuard;
  f.out_width = kOut;
  f.max_depth = kMaxD;
  f.frac_bits = kFrac;
  return f;
}

// Play segments back to back through the hls generator (tick when ready).
std::vector<std::vector<int64_t>> play(const std::vector<bcu::Segment>& segs) {
  bcu::test::Driver<Gen> drv;
  size_t want = 0;
  for (const auto& s : segs) {
    drv.words.insert(drv.words.end(), s.words.begin(), s.words.end());
    want += size_t(1) << s.depth;
  }
  want += 1;  // the final end value, on an underrun tick
  while (drv.events.size() < want) {
    const auto& r = drv.gen.regs();
    const bool tick = !r.tick_q && (drv.gen.state() == Gen::S_READY ||
                                    (drv.gen.state() == Gen::S_IDLE && drv.wi == drv.words.size()));
    drv.step(tick);
  }
  std::vector<std::vector<int64_t>> out;
  for (const auto& e : drv.events) out.push_back(e.sample);
  return out;
}

uint64_t seed() {
  const char* s = std::getenv("TRAJ_BCU_SEED");
  const uint64_t v = s ? std::strtoull(s, nullptr, 0) : 20240611ull;
  std::printf("TRAJ_BCU_SEED=%llu\n", static_cast<unsigned long long>(v));
  return v;
}

void expect_message(const std::function<void()>& f, const std::string& part) {
  try {
    f();
    ADD_FAILURE() << "no exception, expected one mentioning '" << part << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(BcuCompiler, ClearErrors) {
  const bcu::Format f = fmt();
  bcu::Controls b = bcu::Controls::Zero(3, 4);
  b(1, 2) = std::numeric_limits<double>::quiet_NaN();
  expect_message([&] { bcu::compile_segment(b, 4, f); }, "axis 1 control value b2 is NaN");
  b(1, 2) = std::numeric_limits<double>::infinity();
  expect_message([&] { bcu::compile_segment(b, 4, f); }, "axis 1 control value b2 is infinite");
  b(1, 2) = 0;
  b(2, 3) = 1e9;  // needs |x| < 2^(39-25) = 16384
  expect_message([&] { bcu::compile_segment(b, 4, f); }, "axis 2 control value b3 = 1e+09 out of range");
  b(2, 3) = 0;
  expect_message([&] { bcu::compile_segment(b, 13, f); }, "depth d = 13 out of range 0..12");
  expect_message([&] { bcu::compile_segment(b, -1, f); }, "depth d = -1 out of range");
  bcu::Format g = f;
  g.ctrl_width = 100;
  expect_message([&] { bcu::compile_segment(b, 1, g); }, "Format.ctrl_width = 100");
  expect_message([&] { bcu::compile_segment(bcu::Controls::Zero(2, 4), 1, f); }, "2 axes");
}

TEST(BcuCompiler, PredictionIsHlsAndWithinBound) {
  std::mt19937_64 rng(seed());
  std::uniform_real_distribution<double> U(-16000.0, 16000.0);
  const bcu::Format f = fmt();
  std::vector<bcu::Segment> segs;
  std::vector<bcu::Controls> ctrl;
  for (int d : {12, 0, 3, 9, 1, 12}) {
    bcu::Controls b(3, 4);
    for (int a = 0; a < 3; ++a)
      for (int i = 0; i < 4; ++i) b(a, i) = U(rng);
    if (!ctrl.empty())
      for (int a = 0; a < 3; ++a) b(a, 0) = ctrl.back()(a, 3);  // chained
    ctrl.push_back(b);
    segs.push_back(bcu::compile_segment(b, d, f));
  }
  const auto got = play(segs);
  size_t k = 0;
  double worst = 0;
  for (size_t s = 0; s < segs.size(); ++s) {
    const int K = 1 << segs[s].depth;
    const int jmax = (s + 1 == segs.size()) ? K : K - 1;  // last segment: end value too
    for (int j = 0; j <= jmax; ++j, ++k) {
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(got[k][a], segs[s].samples[j][a]) << "segment " << s << " j " << j;
        const double b[4] = {ctrl[s](a, 0), ctrl[s](a, 1), ctrl[s](a, 2), ctrl[s](a, 3)};
        const double ref = bcu::de_casteljau(b, double(j) / K);
        const double err = std::fabs(std::ldexp(double(got[k][a]), -kFrac) - ref);
        ASSERT_LE(err, segs[s].bound) << "segment " << s << " j " << j << " axis " << a;
        worst = std::max(worst, err / std::ldexp(1.0, -kFrac));
      }
    }
  }
  EXPECT_EQ(k, got.size());
  std::printf("max error %.4f output LSB (bound %.4f)\n", worst,
              segs[0].bound / std::ldexp(1.0, -kFrac));
}

// ---------------------------------------------------------------------------
// Seed 000, eq. 9-16.
// ---------------------------------------------------------------------------
namespace {
Eigen::MatrixXd random_points(std::mt19937_64& rng, int n, int axes) {
  std::uniform_real_distribution<double> U(-100.0, 100.0);
  Eigen::MatrixXd p(n + 2, axes);
  for (int r = 0; r < n + 2; ++r)
    for (int c = 0; c < axes; ++c) p(r, c) = U(rng);
  return p;
}
}  // namespace

TEST(Seed000Spline, Eq10InterpolatesAndEq13MatchesEq9) {
  std::mt19937_64 rng(seed() + 1);
  for (int axes : {1, 2, 3, 5}) {
    const auto p = random_points(rng, 8, axes);
    const double lam = 0.2, mu = 0.35;
    const auto segs = bcu::c1_spline(p, lam, mu);
    ASSERT_EQ(segs.size(), 7u);  // N = 8 points -> N-1 segments
    for (int i = 1; i <= 7; ++i) {
      const auto& s = segs[i - 1];
      EXPECT_LE((bcu::eval_segment(s, 0.0) - p.row(i).transpose()).norm(), 1e-12);
      EXPECT_LE((bcu::eval_segment(s, 1.0) - p.row(i + 1).transpose()).norm(), 1e-12);
      for (double t = 0; t <= 1.0; t += 1.0 / 64)
        EXPECT_LE((bcu::eval_eq13(p, i, lam, mu, t) - bcu::eval_segment(s, t)).norm(), 1e-11);
    }
  }
}

TEST(Seed000Spline, Eq11PrintedFormIsOffByThree) {
  std::mt19937_64 rng(seed() + 2);
  const auto p = random_points(rng, 6, 3);
  const double lam = 0.25, mu = 0.4;
  const auto segs = bcu::c1_spline(p, lam, mu);
  for (int i = 1; i <= 5; ++i) {
    const auto& s = segs[i - 1];
    // numerical derivative (central differences on the double curve)
    const double h = 1e-6;
    const Eigen::VectorXd d0 = (bcu::eval_segment(s, h) - bcu::eval_segment(s, 0)) / h;
    const Eigen::VectorXd d1 = (bcu::eval_segment(s, 1) - bcu::eval_segment(s, 1 - h)) / h;
    const Eigen::VectorXd printed0 = lam * (p.row(i + 1) - p.row(i - 1)).transpose();
    const Eigen::VectorXd printed1 = mu * (p.row(i + 2) - p.row(i)).transpose();
    // corrected: 3 lambda (P_{i+1}-P_{i-1}), 3 mu (P_{i+2}-P_i)
    EXPECT_LE((d0 - 3 * printed0).norm(), 1e-3 * (1 + d0.norm()));
    EXPECT_LE((d1 - 3 * printed1).norm(), 1e-3 * (1 + d1.norm()));
    EXPECT_GT((d0 - printed0).norm(), 0.5 * printed0.norm());  // printed eq. 11 fails
    EXPECT_LE((bcu::eval_derivative(s, 0) - 3 * printed0).norm(), 1e-9 * (1 + d0.norm()));
  }
}

TEST(Seed000Spline, C1IffLambdaEqualsMuElseG1) {
  std::mt19937_64 rng(seed() + 3);
  const auto p = random_points(rng, 10, 3);
  const auto c1 = bcu::c1_spline(p, 0.3);
  for (size_t i = 0; i + 1 < c1.size(); ++i) {
    const Eigen::VectorXd a = bcu::eval_derivative(c1[i], 1), b = bcu::eval_derivative(c1[i + 1], 0);
    EXPECT_LE((a - b).norm(), 1e-9 * (1 + a.norm())) << "joint " << i;
  }
  const auto g1 = bcu::c1_spline(p, 0.3, 0.15);
  for (size_t i = 0; i + 1 < g1.size(); ++i) {
    const Eigen::VectorXd a = bcu::eval_derivative(g1[i], 1), b = bcu::eval_derivative(g1[i + 1], 0);
    EXPECT_GT((a - b).norm(), 1e-3 * a.norm());               // not C1
    EXPECT_LE((a.normalized() - b.normalized()).norm(), 1e-9);  // G1: same direction
    EXPECT_NEAR(a.norm() / b.norm(), 0.15 / 0.3, 1e-9);
  }
}

TEST(Seed000Spline, SampledByGeneratorWithinBound) {
  std::mt19937_64 rng(seed() + 4);
  const auto p = random_points(rng, 7, 3);
  const auto spl = bcu::c1_spline(p, 1.0 / 6.0);
  const bcu::Format f = fmt();
  std::vector<bcu::Segment> segs;
  for (const auto& s : spl) segs.push_back(bcu::compile_segment(s.transpose(), 8, f));
  // chaining is exact: next A == this D (same double -> same integer)
  for (size_t s = 0; s + 1 < segs.size(); ++s)
    for (int a = 0; a < 3; ++a) EXPECT_EQ(segs[s].ctrl[a][3], segs[s + 1].ctrl[a][0]);
  const auto got = play(segs);
  size_t k = 0;
  for (size_t s = 0; s < segs.size(); ++s) {
    const int jmax = (s + 1 == segs.size()) ? 256 : 255;
    for (int j = 0; j <= jmax; ++j, ++k) {
      const Eigen::VectorXd ref = bcu::eval_segment(spl[s], j / 256.0);
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(got[k][a], segs[s].samples[j][a]);
        ASSERT_LE(std::fabs(std::ldexp(double(got[k][a]), -kFrac) - ref(a)), segs[s].bound)
            << "segment " << s << " j " << j << " axis " << a;
      }
    }
  }
  // passes through every interior point exactly to within the bound
  for (int i = 1; i <= 6; ++i)
    for (int a = 0; a < 3; ++a)
      EXPECT_LE(std::fabs(std::ldexp(double(got[(i - 1) * 256][a]), -kFrac) - p(i, a)), segs[0].bound);
}

TEST(Seed000Spline, ClearErrors) {
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(5, 2);
  expect_message([&] { bcu::c1_spline(p.topRows(3), 0.2); }, "at least 4 points");
  p(3, 1) = std::nan("");
  expect_message([&] { bcu::c1_spline(p, 0.2); }, "point P_3 axis 1 is NaN");
  p(3, 1) = 0;
  expect_message([&] { bcu::c1_spline(p, 0.0); }, "lambda = 0 out of range");
  expect_message([&] { bcu::c1_spline(p, 0.2, 1.5); }, "mu = 1.5 out of range");
}
