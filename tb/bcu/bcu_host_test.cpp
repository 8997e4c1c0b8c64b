// SPDX-License-Identifier: Apache-2.0
// host/bcu: segment compiler (errors, exact prediction == hls, bound vs double
// at every sample) and the [BCU] C1 spline (eq. 9-16) sampled by the hls
// generator (1, 3, 5 and 8 axes; d up to MaxDepth 12). The generator is driven
// through its public interface only (it is being reworked for throughput;
// timing constants come from its header).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "test_seed.hpp"
#include "bcu/bcu_compiler.hpp"
#include "bcu/bezier_spline.hpp"
#include "traj_bcu_gen.hpp"

namespace bcu = traj::bcu;

namespace {
constexpr int kAx = 3, kChunk = 32, kCtrl = 40, kGuard = 9, kOut = 32, kMaxD = 12, kFrac = 16;
using Gen = traj::BcuGen<kAx, kChunk, kCtrl, kGuard, kOut, kMaxD>;

bcu::Format fmt() { return {kAx, kChunk, kCtrl, kGuard, kOut, kMaxD, kFrac}; }

// Play segments back to back through the hls generator, driven through its
// public interface only (tready, sample_valid, underrun, tick_err, sample;
// kMinTickSpacing from the header): the first tick a minimum tick spacing
// after the first segment has entered, then a new tick as soon as the previous
// one is answered (one tick outstanding, so never a tick_err), and one more
// tick after the last segment, answered by an underrun with the end value.
// Returns every answer's sample; fails the test on tick_err or an early underrun.
template <class G>
std::vector<std::vector<int64_t>> play_gen(const std::vector<bcu::Segment>& segs) {
  G gen;
  std::vector<uint64_t> words;
  size_t want = 0, first_len = 0;
  for (const auto& s : segs) {
    words.insert(words.end(), s.words.begin(), s.words.end());
    if (!first_len) first_len = words.size();
    want += size_t(1) << s.depth;
  }
  want += 1;  // the final end value, on an underrun tick
  std::vector<std::vector<int64_t>> out;
  size_t wi = 0, issued = 0;
  uint64_t start = ~0ull;
  for (uint64_t cyc = 0; out.size() < want; ++cyc) {
    if (cyc > uint64_t(want + 8) * G::kMinTickSpacing * 4 + 100000) {
      ADD_FAILURE() << "generator stalled after " << out.size() << " of " << want << " samples";
      break;
    }
    if (gen.tick_err()) {
      ADD_FAILURE() << "tick_err at cycle " << cyc;
      break;
    }
    if (gen.sample_valid() || gen.underrun()) {
      if (gen.underrun() && out.size() + 1 < want) {
        ADD_FAILURE() << "underrun at sample " << out.size();
        break;
      }
      std::vector<int64_t> v;
      for (int a = 0; a < G::kAxes; ++a) v.push_back(gen.sample(a));
      out.push_back(v);
    }
    typename G::In in;
    in.tvalid = wi < words.size();
    in.tdata = in.tvalid ? words[wi] : 0;
    if (start == ~0ull && wi >= first_len) start = cyc + G::kMinTickSpacing;
    in.tick = cyc >= start && issued == out.size() && issued < want;
    if (in.tick) ++issued;
    if (in.tvalid && gen.tready()) ++wi;
    gen.clock(in);
  }
  return out;
}

std::vector<std::vector<int64_t>> play(const std::vector<bcu::Segment>& segs) { return play_gen<Gen>(segs); }

uint64_t seed() { return traj::test::test_seed(20240611ull); }

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
// [BCU], eq. 9-16.
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

TEST(BcuPaperSpline, Eq10InterpolatesAndEq13MatchesEq9) {
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

TEST(BcuPaperSpline, Eq11PrintedFormIsOffByThree) {
  std::mt19937_64 rng(seed() + 2);
  const auto p = random_points(rng, 6, 3);
  const double lam = 0.25, mu = 0.4;
  const auto segs = bcu::c1_spline(p, lam, mu);
  for (int i = 1; i <= 5; ++i) {
    const auto& s = segs[i - 1];
    // Numerical end derivatives by CENTRAL differences (x(t+h) - x(t-h)) / 2h:
    // the segment is a polynomial, so de Casteljau evaluates it just outside
    // [0, 1] too. Truncation error h^2/6 |x'''| with x''' = 6 (b3 - 3 b2 + 3 b1 - b0),
    // |b| < 300: <= 8 h^2 max|b| = 2.4e-5 at h = 1e-4; rounding about
    // 2 eps max|x| / h < 1e-9. Tolerance 3e-5 per axis.
    const double h = 1e-4, tol = 3e-5 * std::sqrt(3.0);
    const Eigen::VectorXd d0 = (bcu::eval_segment(s, h) - bcu::eval_segment(s, -h)) / (2 * h);
    const Eigen::VectorXd d1 = (bcu::eval_segment(s, 1 + h) - bcu::eval_segment(s, 1 - h)) / (2 * h);
    const Eigen::VectorXd printed0 = lam * (p.row(i + 1) - p.row(i - 1)).transpose();
    const Eigen::VectorXd printed1 = mu * (p.row(i + 2) - p.row(i)).transpose();
    // corrected: 3 lambda (P_{i+1}-P_{i-1}), 3 mu (P_{i+2}-P_i)
    EXPECT_LE((d0 - 3 * printed0).norm(), tol);
    EXPECT_LE((d1 - 3 * printed1).norm(), tol);
    // the printed eq. 11 fails: it is off by the factor 3
    EXPECT_GT((d0 - printed0).norm(), 0.5 * printed0.norm());
    EXPECT_GT((d1 - printed1).norm(), 0.5 * printed1.norm());
    EXPECT_LE((bcu::eval_derivative(s, 0) - 3 * printed0).norm(), 1e-9 * (1 + d0.norm()));
    EXPECT_LE((bcu::eval_derivative(s, 1) - 3 * printed1).norm(), 1e-9 * (1 + d1.norm()));
  }
}

TEST(BcuPaperSpline, C1IffLambdaEqualsMuElseG1) {
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

// The spline through the hls generator, over axis counts and depths: a C1
// spline (lambda = mu = 1/6) through 7 random points, compiled to segments of
// K = 2^D, played back to back: every sample equals the host prediction and is
// within the bound of the double de Casteljau curve; chaining is exact (next
// A == this D); the samples at the joints are the points, within the bound.
template <int Axes, int D>
struct SplineCfg {
  static constexpr int kAxes = Axes, kDepth = D;
  using G = traj::BcuGen<Axes, kChunk, kCtrl, kGuard, kOut, kMaxD>;
};
template <class C>
class SplineThroughGenerator : public ::testing::Test {};
using SplineCfgs = ::testing::Types<SplineCfg<1, 12>, SplineCfg<3, 8>, SplineCfg<5, 10>, SplineCfg<8, 12>>;
TYPED_TEST_SUITE(SplineThroughGenerator, SplineCfgs);

TYPED_TEST(SplineThroughGenerator, SampledWithinBound) {
  constexpr int A = TypeParam::kAxes, D = TypeParam::kDepth, K = 1 << D;
  std::mt19937_64 rng(seed() + 4 + A * 100 + D);
  const auto p = random_points(rng, 7, A);
  const auto spl = bcu::c1_spline(p, 1.0 / 6.0);
  bcu::Format f = fmt();
  f.axes = A;
  std::vector<bcu::Segment> segs;
  for (const auto& s : spl) segs.push_back(bcu::compile_segment(s.transpose(), D, f));
  // chaining is exact: next A == this D (same double -> same integer)
  for (size_t s = 0; s + 1 < segs.size(); ++s)
    for (int a = 0; a < A; ++a) EXPECT_EQ(segs[s].ctrl[a][3], segs[s + 1].ctrl[a][0]);
  const auto got = play_gen<typename TypeParam::G>(segs);
  ASSERT_EQ(got.size(), segs.size() * K + 1);
  size_t k = 0;
  for (size_t s = 0; s < segs.size(); ++s) {
    const int jmax = (s + 1 == segs.size()) ? K : K - 1;
    for (int j = 0; j <= jmax; ++j, ++k) {
      const Eigen::VectorXd ref = bcu::eval_segment(spl[s], double(j) / K);
      for (int a = 0; a < A; ++a) {
        ASSERT_EQ(got[k][a], segs[s].samples[j][a]) << "segment " << s << " j " << j << " axis " << a;
        ASSERT_LE(std::fabs(std::ldexp(double(got[k][a]), -kFrac) - ref(a)), segs[s].bound)
            << "segment " << s << " j " << j << " axis " << a;
      }
    }
  }
  // the samples at the joints are the points P_1..P_7, within the bound
  for (int i = 1; i <= 7; ++i)
    for (int a = 0; a < A; ++a)
      EXPECT_LE(std::fabs(std::ldexp(double(got[(i - 1) * K][a]), -kFrac) - p(i, a)), segs[0].bound)
          << "point " << i << " axis " << a;
}

TEST(BcuPaperSpline, ClearErrors) {
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(5, 2);
  expect_message([&] { bcu::c1_spline(p.topRows(3), 0.2); }, "at least 4 points");
  p(3, 1) = std::nan("");
  expect_message([&] { bcu::c1_spline(p, 0.2); }, "point P_3 axis 1 is NaN");
  p(3, 1) = 0;
  expect_message([&] { bcu::c1_spline(p, 0.0); }, "lambda = 0 out of range");
  expect_message([&] { bcu::c1_spline(p, 0.2, 1.5); }, "mu = 1.5 out of range");
}
