// SPDX-License-Identifier: Apache-2.0
// Test group 1: the forward-difference recurrence in double reproduces Horner
// evaluation, degrees 0..7; [FD]'s printed recurrence does not.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fd/fd_double.hpp"

using traj::fd::fd_init;
using traj::fd::fd_step;
using traj::fd::fd_step_printed;
using traj::fd::horner;

namespace {

// Dyadic coefficients and a power-of-two step: every Horner sample, every
// difference and every register sum is exactly representable in double
// (integers far below 2^53 after scaling), so the recurrence must reproduce
// Horner bit for bit; any algebraic slip shows as an inequality.
std::vector<double> dyadic_poly(std::mt19937_64& rng, int deg) {
  std::uniform_int_distribution<int> d(-64, 64);
  std::vector<double> c(deg + 1);
  for (auto& x : c) x = std::ldexp(d(rng), -3);
  return c;
}

}  // namespace

TEST(FdRecurrence, ReproducesHornerExactlyDegrees0To7) {
  std::mt19937_64 rng(20261122);
  for (int deg = 0; deg <= 7; ++deg) {
    for (int rep = 0; rep < 20; ++rep) {
      const auto c = dyadic_poly(rng, deg);
      const double h = 0.125, t0 = -2.0;  // t in [-2, 2): |p| < 2^30, exact
      auto r = fd_init(c, t0, h, deg);
      for (int k = 0; k < 32; ++k) {
        ASSERT_EQ(r[0], horner(c, t0 + k * h)) << "degree " << deg << " tick " << k;
        fd_step(r);
      }
    }
  }
}

TEST(FdRecurrence, FdPaperPrintedRecurrenceFails) {
  // The printed update keeps r_0 constant and outputs r_N: for any degree >= 1
  // with a non-zero derivative it departs from p; demonstrate on p(t) = t.
  std::vector<double> c = {0.0, 1.0, 0.0, 0.0};
  auto r = fd_init(c, 0.0, 1.0, 3);  // r = (0, 1, 0, 0)
  int mismatches = 0;
  for (int k = 0; k < 8; ++k) {
    if (r[3] != horner(c, k)) ++mismatches;
    fd_step_printed(r);
  }
  EXPECT_GT(mismatches, 0);
}

TEST(FdRecurrence, RandomRealCoefficientsWithinRoundingBound) {
  // Non-dyadic data: the double recurrence accumulates rounding. Bound: each
  // register sum adds at most u |r_i| (u = 2^-53) and register i's error
  // reaches the output weighted by C(k, i); with |r_i| <= M for all registers
  // over the run, |err_k| <= (N+1) u M sum_i C(k, i) * (1 + small) plus the
  // initial differencing error, which is bounded the same way by 2^N u P with
  // P = max |p|. We check 4x that (a generous but computed factor, not an epsilon).
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  const double u = std::ldexp(1.0, -53);
  for (int deg = 0; deg <= 7; ++deg) {
    std::vector<double> c(deg + 1);
    for (auto& x : c) x = U(rng);
    const double h = 1.0 / 1000, t0 = 0.1;
    const int K = 1000;
    auto r = fd_init(c, t0, h, deg);
    double M = 0, P = 0;
    for (int k = 0; k <= K; ++k) P = std::max(P, std::fabs(horner(c, t0 + k * h)));
    for (int k = 0; k <= K; ++k) {
      for (double x : r) M = std::max(M, std::fabs(x));
      double sumC = 0, Cki = 1;
      for (int i = 0; i <= deg; ++i) {
        sumC += Cki;
        Cki = Cki * (k - i) / (i + 1);
      }
      const double bound = 4 * ((deg + 1) * u * M * sumC + std::ldexp(1.0, deg) * u * P * sumC);
      ASSERT_LE(std::fabs(r[0] - horner(c, t0 + k * h)), bound) << "degree " << deg << " tick " << k;
      fd_step(r);
    }
  }
}
