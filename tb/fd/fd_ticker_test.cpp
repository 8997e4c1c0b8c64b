// SPDX-License-Identifier: Apache-2.0
// fd::FdTicker (the engine's recurrence on 128-bit ring values) against the
// compiler's closed form r0(k) = sum r_i C(k, i), reduced to Width bits
// (Compiler::sample_at, in GMP), at every tick: random registers of every
// degree and of widths 16..128, the difference registers wider than Width
// (they wrap in the engine and in the ticker), negative values, and the end
// state after K ticks.
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "fd/fd_compiler.hpp"
#include "fd/fd_ticker.hpp"

namespace {

using traj::fd::Compiled;
using traj::fd::Compiler;
using traj::fd::FdTicker;
using traj::fd::Format;

// A random signed integer of up to `bits` bits.
mpz_class random_signed(gmp_randclass& r, int bits) {
  mpz_class v = r.get_z_bits(bits);
  if (r.get_z_bits(1) == 1) v = -v;
  return v;
}

void check_format(int width, int guard, int degree, unsigned seed) {
  Format f;
  f.axes = 2;
  f.degree = degree;
  f.width = width;
  f.chunk_width = 16;
  f.guard_bits = guard;
  f.frac_bits = 4;
  const Compiler comp(f);
  gmp_randclass r(gmp_randinit_default);
  r.seed(seed);
  std::mt19937_64 rng(seed);
  FdTicker t(width, guard);
  for (int seg = 0; seg < 6; ++seg) {
    Compiled c;
    c.ticks = static_cast<uint32_t>(std::uniform_int_distribution<int>(1, 700)(rng));
    c.regs.assign(2, std::vector<mpz_class>(static_cast<size_t>(degree) + 1));
    for (auto& axis : c.regs)
      for (size_t i = 0; i < axis.size(); ++i) axis[i] = random_signed(r, i == 0 ? width - 1 : width + 8);
    t.load(c.regs);
    for (uint32_t k = 0; k < c.ticks; ++k)
      for (int a = 0; a < 2; ++a)
        ASSERT_EQ(mpz_class(static_cast<long>(t.sample_and_step(a))), comp.sample_at(c, a, k))
            << "width " << width << " degree " << degree << " segment " << seg << " tick " << k << " axis " << a;
    for (int a = 0; a < 2; ++a) {
      const mpz_class end = Compiler::state_at(c, a, c.ticks);  // exact (width 0: no reduction)
      EXPECT_TRUE(t.holds(a, end)) << "width " << width << " degree " << degree << " axis " << a;
      EXPECT_FALSE(t.holds(a, end + 1)) << "width " << width << " degree " << degree << " axis " << a;
    }
  }
}

TEST(FdTicker, MatchesTheClosedFormAtEveryTick) {
  unsigned seed = 1;
  for (const auto& wg : std::vector<std::pair<int, int>>{{16, 4}, {64, 32}, {96, 48}, {112, 60}, {128, 64}, {80, 16}})
    for (int degree = 1; degree <= 7; ++degree) check_format(wg.first, wg.second, degree, seed++);
}

TEST(FdTicker, RefusesWidthsBeyondItsRing) {
  EXPECT_THROW(FdTicker(129, 32), std::invalid_argument);
  EXPECT_THROW(FdTicker(64, 64), std::invalid_argument);
}

TEST(FdTicker, RefusesASampleBeyond64Bits) {
  FdTicker t(128, 48);  // 80-bit samples: values within 64 bits pass, others are refused
  t.load({{mpz_class(-7) << 48, mpz_class(1) << 48}});
  EXPECT_EQ(t.sample_and_step(0), -7);
  EXPECT_EQ(t.sample_and_step(0), -6);
  t.load({{mpz_class(1) << 112}});
  EXPECT_THROW(t.sample_and_step(0), std::range_error);
}

}  // namespace
