// SPDX-License-Identifier: Apache-2.0
// What the compiler reports: per-register fraction-bit needs (against an
// independent exact computation: binomials as explicit products, tol as the
// exact rational of the double, an integer log2 by bit length and a final
// adjustment), and refusal messages that say what would fit (the suggested
// format is then compiled to show that it does).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <regex>
#include <string>

#include "fd/fd_compiler.hpp"
#include "fd_test_util.hpp"

using traj::fd::CompileError;
using traj::fd::Compiler;
using traj::fd::Format;
using traj::fd::PolySegment;
using traj::fd::RegisterNeeds;
using fd_test::binom_product;
using fd_test::fmt;
using fd_test::reference_needs;

namespace {

std::string refusal(const Compiler& comp, const PolySegment& s, const std::string& where = "seg 7") {
  try {
    comp.compile(s, nullptr, where);
  } catch (const CompileError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// ---------------------------------------------------------------------------
// Per-register needs
// ---------------------------------------------------------------------------
TEST(FdRegisterNeeds, MatchIndependentExactComputation) {
  const uint64_t ks[] = {1, 2, 3, 4, 5, 6, 7, 12, 13, 16, 58, 74, 100, 255, 476, 2344, 4096, 65535, 100000,
                         uint64_t(1) << 20, 4294967295ull, uint64_t(1) << 40};
  const double tols[] = {0.5, 0.25, 1.0, 0.1, 1e-3, 3.0, 0.3};
  long n = 0;
  for (int deg = 1; deg <= 7; ++deg)
    for (uint64_t k : ks)
      for (double tol : tols) {
        const RegisterNeeds got = Compiler::register_needs(deg, k, tol);
        const RegisterNeeds want = reference_needs(deg, k, tol);
        const std::string ctx = "deg " + std::to_string(deg) + " K " + std::to_string(k) + " tol " + std::to_string(tol);
        ASSERT_EQ(got.alone, want.alone) << ctx;
        ASSERT_EQ(got.share, want.share) << ctx;
        ASSERT_EQ(got.binding, want.binding) << ctx;
        ASSERT_EQ(got.common, want.common) << ctx;
        // The compiler's own guard-bit count is the common need.
        if (k <= 100000) {
          ASSERT_EQ(got.common, Compiler::guard_bits_needed(deg, k, tol)) << ctx;
        }
        // Sandwich: max alone <= common <= max share.
        const int max_alone = *std::max_element(got.alone.begin(), got.alone.end());
        const int max_share = *std::max_element(got.share.begin(), got.share.end());
        ASSERT_LE(max_alone, got.common) << ctx;
        ASSERT_LE(got.common, max_share) << ctx;
        ASSERT_LE(max_share - max_alone, static_cast<int>(std::ceil(std::log2(deg)))) << ctx;
        // For K >= 2N-1 the needs never decrease with i and r[N] binds.
        if (k >= static_cast<uint64_t>(2 * deg - 1)) {
          ASSERT_EQ(got.binding, deg) << ctx;
          for (int i = 2; i <= deg; ++i) {
            ASSERT_GE(got.alone[i], got.alone[i - 1]) << ctx;
            ASSERT_GE(got.share[i], got.share[i - 1]) << ctx;
          }
          ASSERT_EQ(max_alone, got.alone[deg]) << ctx;
        }
        ++n;
      }
  EXPECT_EQ(n, 7L * 22 * 7);
}

// The same on random K of every size up to 2^64 - 1 and random tolerances
// from 2^-1000 to 2^1000 (every branch of the exact power-of-two comparison),
// and on tolerances that put C(K,i), N C(K,i) or their sum exactly on a power
// of two times tol (the boundary of each least f).
TEST(FdRegisterNeeds, MatchIndependentOnRandomKAndTolAndExactBoundaries) {
  std::mt19937_64 rng(2024);
  std::uniform_int_distribution<int> deg_d(1, 7), bits_d(0, 64), exp_d(-1000, 1000), s_d(-40, 40);
  std::uniform_real_distribution<double> mant_d(0.5, 1.0);
  long n = 0;
  for (int rep = 0; rep < 6000; ++rep) {
    const int deg = deg_d(rng);
    const int kb = bits_d(rng);
    uint64_t k = kb == 0 ? 1 : (rng() >> (64 - kb)) | (uint64_t(1) << (kb - 1));
    if (rep % 7 == 0) k = static_cast<uint64_t>(std::uniform_int_distribution<int>(1, 20)(rng));
    double tol = std::ldexp(mant_d(rng), rep % 3 == 0 ? exp_d(rng) : s_d(rng));
    if (rep % 4 == 1 && k < (uint64_t(1) << 17)) {
      // tol = X 2^-s for X = C(K,i), N C(K,i) or the sum: exact (X < 2^53 here)
      const int i = std::uniform_int_distribution<int>(1, deg)(rng);
      mpz_class x = binom_product(k, i);
      if (rep % 3 == 1) x *= deg;
      if (rep % 3 == 2) {
        x = 0;
        for (int t = 1; t <= deg; ++t) x += binom_product(k, t);
      }
      if (x == 0 || mpz_sizeinbase(x.get_mpz_t(), 2) > 53) continue;
      tol = std::ldexp(x.get_d(), s_d(rng));
      if (rep % 5 == 0) tol = std::nextafter(tol, rep % 2 ? 0.0 : 1e300);
    }
    const RegisterNeeds got = Compiler::register_needs(deg, k, tol);
    const RegisterNeeds want = reference_needs(deg, k, tol);
    const std::string ctx = "deg " + std::to_string(deg) + " K " + std::to_string(k) + " tol " + std::to_string(tol);
    ASSERT_EQ(got.alone, want.alone) << ctx;
    ASSERT_EQ(got.share, want.share) << ctx;
    ASSERT_EQ(got.binding, want.binding) << ctx;
    ASSERT_EQ(got.common, want.common) << ctx;
    ++n;
  }
  EXPECT_GT(n, 5000);
}

// The rule-of-thumb figures, by hand: log2 C(4096, i) = 12, 22.9996, 33.414
// (and 43.413, 53.090 for i = 4, 5).
TEST(FdRegisterNeeds, RuleOfThumbCubicAndQuinticOver4096Ticks) {
  // 1/2 output LSB per register (tol = 1): ceil(log2 C(4096, i)), the notes' 12/23/34.
  RegisterNeeds n = Compiler::register_needs(3, 4096, 1.0);
  EXPECT_EQ(n.alone, (std::vector<int>{0, 12, 23, 34}));
  // The compiler's budget tol/2 = 0.25 LSB: one bit more alone, log2(6) more
  // with equal shares; the common LSB is r[3]'s alone need.
  n = Compiler::register_needs(3, 4096, 0.5);
  EXPECT_EQ(n.alone, (std::vector<int>{0, 13, 24, 35}));
  EXPECT_EQ(n.share, (std::vector<int>{0, 15, 26, 36}));  // 6 C(4096,3) = 68669153280 <= 2^36
  EXPECT_EQ(n.common, 35);
  EXPECT_EQ(n.binding, 3);
  // Quintic: the notes' "about 53" in register 5 is log2 C(4096,5) = 53.09, so 54 bits.
  n = Compiler::register_needs(5, 4096, 1.0);
  EXPECT_EQ(n.alone, (std::vector<int>{0, 12, 23, 34, 44, 54}));
  EXPECT_EQ(n.binding, 5);
  // A segment shorter than 2N-1 ticks: the middle binds (C(5,2) = C(5,3) = 10, highest index on ties).
  n = Compiler::register_needs(7, 5, 0.5);
  EXPECT_EQ(n.binding, 3);
  EXPECT_EQ(n.alone, (std::vector<int>{0, 4, 5, 5, 4, 1, 0, 0}));
}

// compile() reports the needs of every compiled segment (fast path and the
// exact reference path), and accepts a segment exactly when guard_bits >= common.
TEST(FdRegisterNeeds, ReportedByCompileAndDecideAcceptance) {
  for (int deg = 1; deg <= 7; ++deg)
    for (int g : {16, 32, 48}) {
      Format f = fmt(1, deg, 128, 32, g, 0);
      f.max_ticks = 0xffffffffu;
      const Compiler comp(f);
      const uint64_t kmax = Compiler::longest_segment(deg, g, f.tol_lsb);
      for (uint64_t k : {uint64_t(1), uint64_t(2 * deg - 1), kmax / 2, kmax, kmax + 1}) {
        if (k < 1 || k > f.max_ticks) continue;
        const RegisterNeeds want = reference_needs(deg, k, f.tol_lsb);
        const PolySegment seg{{{1.0, 0.5}}, 1e-3, k};
        const std::string msg = refusal(comp, seg);
        EXPECT_EQ(msg.empty(), want.common <= g) << "deg " << deg << " G " << g << " K " << k << ": " << msg;
        if (msg.empty()) {
          const auto c = comp.compile(seg);
          EXPECT_EQ(c.needs.alone, want.alone);
          EXPECT_EQ(c.needs.share, want.share);
          EXPECT_EQ(c.needs.binding, want.binding);
          EXPECT_EQ(c.needs.common, want.common);
        } else {
          const std::string note = "r[" + std::to_string(want.binding) + "] binds: alone it needs " +
                                   std::to_string(want.alone[want.binding]) + " guard bits";
          EXPECT_NE(msg.find(note), std::string::npos) << msg;
        }
      }
    }
}

// ---------------------------------------------------------------------------
// Refusals say what would fit
// ---------------------------------------------------------------------------

// host/fd/README.md's example, word for word.
TEST(FdRefusal, TooLongExactMessage) {
  const Compiler comp(fmt(2, 3, 64, 16, 32, 8));
  const PolySegment s{{{1.0, 2.0}, {0.0}}, 1e-3, 100000};
  EXPECT_EQ(refusal(comp, s),
            "seg 7: K=100000 ticks at degree 3 has quantisation bound 19402.6 LSB > tol/2 = 0.25 LSB with "
            "guard_bits=32; split into segments of at most K=2344 ticks, or use guard_bits >= 49 (width >= 96: "
            "32 output + 49 guard bits, rounded up to a multiple of chunk_width=16); r[3] binds: alone it needs 49 "
            "guard bits (r[1] 18, r[2] 34)");
}

// The suggested width is buildable (a multiple of chunk_width, <= 128), the
// smallest such that keeps out_width, and the suggested formats accept it.
TEST(FdRefusal, TooLongSuggestsBuildableWidth) {
  struct Case {
    int deg, w, c, g;
    uint64_t k;
  };
  const std::regex re(R"(guard_bits >= (\d+) \(width >= (\d+): (\d+) output \+ (\d+) guard bits)");
  int checked = 0;
  for (const Case& cs : {Case{3, 64, 16, 32, 100000}, Case{3, 64, 32, 32, 100000}, Case{3, 64, 64, 32, 100000},
                         Case{5, 48, 16, 16, 5000}, Case{2, 48, 16, 20, 70000}, Case{7, 96, 32, 64, 20000},
                         Case{4, 64, 16, 40, 3000}}) {
    Format f = fmt(1, cs.deg, cs.w, cs.c, cs.g, 4);
    f.max_ticks = 0xffffffffu;
    const Compiler comp(f);
    const PolySegment s{{{1.0, 0.25}}, 1e-3, cs.k};
    const std::string msg = refusal(comp, s);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(msg, m, re)) << msg;
    const int gneed = std::stoi(m[1]), wsug = std::stoi(m[2]);
    const int ow = f.out_width();
    EXPECT_EQ(gneed, reference_needs(cs.deg, cs.k, f.tol_lsb).common) << msg;
    EXPECT_EQ(std::stoi(m[3]), ow);
    EXPECT_EQ(wsug % cs.c, 0) << msg;
    EXPECT_GE(wsug, ow + gneed) << msg;
    EXPECT_LT(wsug - cs.c, ow + gneed) << msg;
    EXPECT_LE(wsug, 128) << msg;
    // Both readings of the suggestion compile the segment: same out_width
    // (guard = width - out_width), or exactly gneed guard bits at that width.
    for (int g2 : {wsug - ow, gneed}) {
      Format f2 = f;
      f2.width = wsug;
      f2.guard_bits = g2;
      EXPECT_NO_THROW(Compiler(f2).compile(s)) << msg << " at width " << wsug << " guard " << g2;
    }
    // And one guard bit fewer does not.
    Format f3 = f;
    f3.width = 128;
    f3.chunk_width = 64;
    f3.guard_bits = gneed - 1;
    EXPECT_THROW(Compiler(f3).compile(s), CompileError);
    ++checked;
  }
  EXPECT_EQ(checked, 7);
  // No buildable width keeps the output: the suggestion says so.
  {
    Format f = fmt(1, 7, 128, 64, 96, 0);
    f.max_ticks = 0xffffffffu;
    const PolySegment s{{{1.0}}, 1e-3, 100000};  // needs 105 guard bits: 32 + 105 > 128
    const std::string msg = refusal(Compiler(f), s);
    EXPECT_NE(msg.find("guard_bits >= 105 (at width=128 that leaves out_width <= 23, fewer than 32)"),
              std::string::npos)
        << msg;
    const PolySegment s2{{{1.0}}, 1e-3, 4000000000ull};  // needs 212 > 126
    const std::string msg2 = refusal(Compiler(f), s2);
    EXPECT_NE(msg2.find("(no buildable width: width <= 128 holds at most 126 guard bits)"), std::string::npos)
        << msg2;
  }
}

// Out of range: the message names segment and axis and says which frac_bits
// or which width would hold the path; both suggestions compile.
TEST(FdRefusal, OutOfRangeSaysWhatFits) {
  const std::regex re_f(R"(it fits with frac_bits <= (-?\d+) \(\|x\| < ([0-9.e+]+)\))");
  const std::regex re_w(R"(width >= (\d+) \(out_width=(\d+) at guard_bits=(\d+)\))");
  struct Case {
    double x;
    int axis, w, c, g, frac;
  };
  for (const Case& cs : {Case{1e7, 0, 64, 16, 32, 8}, Case{1e9, 1, 64, 16, 32, 8}, Case{1e12, 0, 64, 16, 32, 8},
                         Case{-3e6, 1, 48, 16, 16, 10},
                         Case{5e3, 0, 64, 32, 40, 12}, Case{2.5e4, 1, 96, 32, 64, 20}}) {
    const Format f = fmt(2, 3, cs.w, cs.c, cs.g, cs.frac);
    const Compiler comp(f);
    PolySegment s{{{1.0, 0.5}, {-2.0, 0.25}}, 1e-3, 20};
    s.coef[cs.axis] = {cs.x, 0.01 * cs.x, -0.02 * cs.x};
    const std::string msg = refusal(comp, s, "seg 12");
    const std::string head = "seg 12: axis " + std::to_string(cs.axis) + " leaves the output range";
    ASSERT_EQ(msg.rfind(head, 0), 0u) << msg;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(msg, m, re_f)) << msg;
    const int fsug = std::stoi(m[1]);
    EXPECT_LT(fsug, cs.frac);
    Format ff = f;
    ff.frac_bits = fsug;
    EXPECT_NO_THROW(Compiler(ff).compile(s)) << msg;
    // The largest such frac_bits (here nothing is near the limit's margin).
    ff.frac_bits = fsug + 1;
    EXPECT_THROW(Compiler(ff).compile(s), CompileError) << msg;
    ASSERT_TRUE(std::regex_search(msg, m, re_w)) << msg;
    const int wsug = std::stoi(m[1]);
    EXPECT_EQ(wsug % cs.c, 0);
    EXPECT_EQ(std::stoi(m[2]), wsug - cs.g);
    Format fw = f;
    fw.width = wsug;
    EXPECT_NO_THROW(Compiler(fw).compile(s)) << msg;
    if (wsug - cs.c > cs.w) {
      fw.width = wsug - cs.c;
      EXPECT_THROW(Compiler(fw).compile(s), CompileError) << msg;
    }
  }
  // Nothing holds it: said so.
  const Compiler comp(fmt(1, 3, 64, 16, 32, 8));
  const std::string msg = refusal(comp, PolySegment{{{1e300}}, 1e-3, 10});
  EXPECT_NE(msg.find("no frac_bits >= -64 and no width <= 128 holds it"), std::string::npos) << msg;
}

// guard_bits = 0 (which the RTL builds) is refused with the reason, and the
// reason holds: with G = 0 the bound admits no segment at tol = 0.5 and only
// K = 1 at tol = 1, at every degree.
TEST(FdRefusal, GuardBitsZeroRefusedWithReason) {
  Format f = fmt(3, 3, 64, 16, 0, 16);
  try {
    Compiler c(f);
    ADD_FAILURE() << "guard_bits=0 accepted";
  } catch (const CompileError& e) {
    EXPECT_NE(std::string(e.what()).find("format: guard_bits=0 is not supported by the compiler"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("use guard_bits >= 1"), std::string::npos) << e.what();
  }
  for (int deg = 1; deg <= 7; ++deg) {
    EXPECT_EQ(Compiler::longest_segment(deg, 0, 0.5), 0u) << deg;
    EXPECT_EQ(Compiler::longest_segment(deg, 0, 1.0), 1u) << deg;
    EXPECT_GE(Compiler::guard_bits_needed(deg, 2, 1.0), 1) << deg;
  }
  f.guard_bits = 1;
  EXPECT_NO_THROW(Compiler{f});
  f.guard_bits = -1;
  EXPECT_THROW(Compiler{f}, CompileError);
}
