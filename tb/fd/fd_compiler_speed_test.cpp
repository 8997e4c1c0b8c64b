// SPDX-License-Identifier: Apache-2.0
// The compiler's fast exact path (integer dyadic arithmetic, long double range
// pre-check, cached budget) against the straightforward exact mpq form kept
// here as the reference (the compiler as it was before the fast path): on many
// random chained segments, every degree 1..7, widths 48/64/96/128, ties,
// near-refusal cases (range limit, continuity limit, K budget) and bad input,
// the registers, end states, error bounds, words and predictions must be
// identical, and a refusal must be a refusal with the same message (up to the
// suggestion the compiler appends after "; ").
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <sstream>

#include "fd/fd_compiler.hpp"
#include "fd_test_util.hpp"

using traj::fd::Compiled;
using traj::fd::CompileError;
using traj::fd::Compiler;
using traj::fd::Format;
using traj::fd::PolySegment;
using traj::fd::RegisterNeeds;
using fd_test::fmt;

namespace ref {

// ---- reference: exact rationals throughout (the original implementation) ----
std::string fmt_double(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}
mpq_class exact(double v) {
  mpq_class q;
  mpq_set_d(q.get_mpq_t(), v);
  return q;
}
mpz_class round_nearest(const mpq_class& q) {
  mpq_class t = q + mpq_class(1, 2);
  mpz_class r;
  mpz_fdiv_q(r.get_mpz_t(), t.get_num_mpz_t(), t.get_den_mpz_t());
  return r;
}
mpz_class pow2(int e) {
  mpz_class r = 1;
  r <<= e;
  return r;
}
mpz_class binom(uint64_t k, int i) {
  mpz_class r;
  mpz_bin_uiui(r.get_mpz_t(), k, static_cast<unsigned long>(i));
  return r;
}
double to_lsb(const mpq_class& reg_units, int guard_bits) {
  mpq_class q = reg_units / mpq_class(pow2(guard_bits));
  return std::fabs(q.get_d());
}
long double max_abs_on(const std::vector<mpq_class>& c, const mpq_class& T) {
  const int n = static_cast<int>(c.size()) - 1;
  std::vector<mpq_class> a(c.size());
  mpq_class Tj = 1;
  for (int j = 0; j <= n; ++j) {
    a[j] = c[j] * Tj;
    Tj *= T;
  }
  long double m = 0;
  for (int i = 0; i <= n; ++i) {
    mpq_class b = 0;
    for (int j = 0; j <= i; ++j) b += a[j] * mpq_class(binom(i, j)) / mpq_class(binom(n, j));
    m = std::max(m, std::fabs(static_cast<long double>(b.get_d())));
  }
  return m;
}
mpz_class quant_bound_x2(int degree, uint64_t k) {
  mpz_class s = 0;
  for (int i = 1; i <= degree; ++i) s += binom(k, i);
  return s;
}
double quant_bound_lsb(const Format& f, uint64_t k) {
  return to_lsb(mpq_class(quant_bound_x2(f.degree, k), 2), f.guard_bits);
}
bool fits(int degree, uint64_t k, int guard_bits, double tol_lsb) {
  return mpq_class(quant_bound_x2(degree, k)) <= exact(tol_lsb) * mpq_class(pow2(guard_bits));
}
uint64_t longest_segment(int degree, int guard_bits, double tol_lsb) {
  if (!fits(degree, 1, guard_bits, tol_lsb)) return 0;
  uint64_t lo = 1, hi = 2;
  while (hi < (uint64_t(1) << 62) && fits(degree, hi, guard_bits, tol_lsb)) {
    lo = hi;
    hi *= 2;
  }
  while (hi - lo > 1) {
    uint64_t mid = lo + (hi - lo) / 2;
    (fits(degree, mid, guard_bits, tol_lsb) ? lo : hi) = mid;
  }
  return lo;
}
int guard_bits_needed(int degree, uint64_t k, double tol_lsb) {
  for (int g = 0; g < 400; ++g)
    if (fits(degree, k, g, tol_lsb)) return g;
  return 400;
}
mpz_class state_at(const Compiled& c, int axis, uint64_t k) {
  const auto& r = c.regs[axis];
  mpz_class s = 0;
  for (size_t i = 0; i < r.size(); ++i) s += r[i] * binom(k, static_cast<int>(i));
  return s;
}

Compiled compile(const Format& f_, const PolySegment& seg, const std::vector<mpz_class>* start,
                 const std::string& where) {
  const int N = f_.degree;
  const int A = f_.axes;
  auto fail = [&](const std::string& what) { throw CompileError(where + ": " + what); };
  if (static_cast<int>(seg.coef.size()) != A)
    fail("has " + std::to_string(seg.coef.size()) + " axes, the engine has " + std::to_string(A));
  if (!(seg.h > 0) || !std::isfinite(seg.h)) fail("tick period " + fmt_double(seg.h) + " s must be positive and finite");
  if (seg.ticks < 1) fail("tick count K=0: a segment needs at least one tick");
  if (seg.ticks > f_.max_ticks)
    fail("K=" + std::to_string(seg.ticks) + " ticks exceeds max_ticks=" + std::to_string(f_.max_ticks) +
         "; split the segment");
  for (int a = 0; a < A; ++a) {
    if (static_cast<int>(seg.coef[a].size()) > N + 1)
      fail("axis " + std::to_string(a) + " has degree " + std::to_string(seg.coef[a].size() - 1) +
           ", the engine is built for degree " + std::to_string(N));
    for (size_t j = 0; j < seg.coef[a].size(); ++j)
      if (!std::isfinite(seg.coef[a][j]))
        fail("axis " + std::to_string(a) + " coefficient c" + std::to_string(j) + " = " +
             fmt_double(seg.coef[a][j]) + " is not finite");
  }
  if (start && static_cast<int>(start->size()) != A) fail("start state has the wrong number of axes");
  const uint64_t K = seg.ticks;
  const int G = f_.guard_bits;
  if (!fits(N, K, G, f_.tol_lsb)) {
    const uint64_t kmax = longest_segment(N, G, f_.tol_lsb);
    const int gneed = guard_bits_needed(N, K, f_.tol_lsb);
    fail("K=" + std::to_string(K) + " ticks at degree " + std::to_string(N) + " has quantisation bound " +
         fmt_double(quant_bound_lsb(f_, K)) + " LSB > tol/2 = " + fmt_double(f_.tol_lsb / 2) +
         " LSB with guard_bits=" + std::to_string(G) + "; split into segments of at most K=" +
         std::to_string(kmax) + " ticks, or use guard_bits >= " + std::to_string(gneed) +
         " (width >= " + std::to_string(f_.out_width() + gneed) + ")");
  }
  const mpq_class h = exact(seg.h);
  const mpq_class T = h * mpq_class(mpz_class(std::to_string(K)));
  mpq_class scale = mpq_class(pow2(G));
  if (f_.frac_bits >= 0) scale *= mpq_class(pow2(f_.frac_bits));
  else scale /= mpq_class(pow2(-f_.frac_bits));
  const mpq_class bias(pow2(G), 2);
  const mpq_class half_tol_reg = exact(f_.tol_lsb / 2) * mpq_class(pow2(G));
  const mpq_class limit = mpq_class(pow2(f_.width - 1));
  Compiled out;
  out.ticks = static_cast<uint32_t>(K);
  out.regs.assign(A, std::vector<mpz_class>(N + 1));
  out.end.resize(A);
  double carried = 0;
  for (int a = 0; a < A; ++a) {
    std::vector<mpq_class> c(N + 1, 0);
    for (size_t j = 0; j < seg.coef[a].size(); ++j) c[j] = exact(seg.coef[a][j]) * scale;
    c[0] += bias;
    mpz_class r0 = start ? (*start)[a] : round_nearest(c[0]);
    mpq_class e0 = mpq_class(r0) - c[0];
    if (abs(e0) > half_tol_reg && start)
      fail("axis " + std::to_string(a) + " starts " + fmt_double(to_lsb(e0, G)) +
           " LSB away from the previous segment's end (more than tol/2 = " + fmt_double(f_.tol_lsb / 2) +
           " LSB): the path is not continuous here");
    carried = std::max(carried, to_lsb(e0, G));
    c[0] += e0;
    c[1] -= e0 / T;
    const long double qmax = max_abs_on(c, T);
    const long double margin = std::fabs(static_cast<long double>(e0.get_d())) +
                               static_cast<long double>(quant_bound_x2(N, K).get_d()) + 2;
    if (qmax + margin >= static_cast<long double>(limit.get_d()))
      fail("axis " + std::to_string(a) + " leaves the output range: |x| may reach " +
           fmt_double(static_cast<double>(qmax / static_cast<long double>(scale.get_d()))) +
           " units, the format holds |x| < " + fmt_double(std::ldexp(1.0, f_.out_width() - 1 - f_.frac_bits)) +
           " (out_width=" + std::to_string(f_.out_width()) + ", frac_bits=" + std::to_string(f_.frac_bits) + ")");
    std::vector<mpq_class> y(N + 1);
    for (int m = 0; m <= N; ++m) {
      const mpq_class t = h * m;
      mpq_class v = 0;
      for (int j = N; j >= 0; --j) v = v * t + c[j];
      y[m] = v;
    }
    out.regs[a][0] = r0;
    for (int i = 1; i <= N; ++i) {
      for (int m = 0; m + i <= N; ++m) y[m] = y[m + 1] - y[m];
      out.regs[a][i] = round_nearest(y[0]);
    }
    out.end[a] = state_at(out, a, K);
  }
  out.carried_lsb = carried;
  out.bound_lsb = carried + quant_bound_lsb(f_, K);
  return out;
}

std::vector<uint64_t> words(const Format& f_, const Compiled& c) {
  const int C = f_.chunk_width;
  std::vector<uint64_t> w;
  const uint64_t cmask = C == 64 ? ~uint64_t(0) : ((uint64_t(1) << C) - 1);
  if (C < 32) {
    for (int s = 0; s < 32; s += C) w.push_back((uint64_t(c.ticks) >> s) & cmask);
  } else {
    w.push_back(c.ticks);
  }
  const mpz_class mod = pow2(f_.width);
  for (const auto& axis : c.regs)
    for (const auto& r : axis) {
      mpz_class v = r % mod;
      if (v < 0) v += mod;
      for (int s = 0; s < f_.width; s += C) {
        const mpz_class chunk = (v >> s) & (pow2(C) - 1);
        uint64_t lo = mpz_class(chunk & mpz_class(0xffffffffUL)).get_ui();
        uint64_t hi = mpz_class(chunk >> 32).get_ui();
        w.push_back(lo | (hi << 32));
      }
    }
  return w;
}

}  // namespace ref

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

struct Outcome {
  bool ok = false;
  std::string msg;
  Compiled c;
};

struct Stats {
  long accepted = 0, refused = 0;
};

// Compiles with both, checks they agree in every respect; returns the outcome.
Outcome check_same(const Compiler& comp, const PolySegment& seg, const std::vector<mpz_class>* start,
                   const std::string& ctx, Stats* st = nullptr) {
  Outcome fast, slow;
  try {
    fast.c = comp.compile(seg, start, "seg");
    fast.ok = true;
  } catch (const CompileError& e) {
    fast.msg = e.what();
  }
  try {
    slow.c = ref::compile(comp.format(), seg, start, "seg");
    slow.ok = true;
  } catch (const CompileError& e) {
    slow.msg = e.what();
  }
  EXPECT_EQ(fast.ok, slow.ok) << ctx << "\n fast: " << fast.msg << "\n ref: " << slow.msg;
  if (fast.ok != slow.ok) return slow;
  if (!fast.ok) {
    // The reference words what and where; the compiler appends what would fit
    // after "; " (tested in fd_model_test.cpp), so the heads must agree.
    auto head = [](const std::string& m) { return m.substr(0, m.find("; ")); };
    EXPECT_EQ(head(fast.msg), head(slow.msg)) << ctx << "\n fast: " << fast.msg << "\n ref: " << slow.msg;
    if (st) ++st->refused;
    return slow;
  }
  if (st) ++st->accepted;
  const Compiled &a = fast.c, &b = slow.c;
  EXPECT_EQ(a.ticks, b.ticks) << ctx;
  EXPECT_TRUE(same_bits(a.carried_lsb, b.carried_lsb)) << ctx << " " << a.carried_lsb << " vs " << b.carried_lsb;
  EXPECT_TRUE(same_bits(a.bound_lsb, b.bound_lsb)) << ctx << " " << a.bound_lsb << " vs " << b.bound_lsb;
  EXPECT_EQ(a.regs.size(), b.regs.size()) << ctx;
  EXPECT_EQ(a.end.size(), b.end.size()) << ctx;
  for (size_t ax = 0; ax < std::min(a.regs.size(), b.regs.size()); ++ax) {
    EXPECT_EQ(a.regs[ax].size(), b.regs[ax].size()) << ctx;
    // The compiler gives r[1..N] as the engine holds them, Width-bit two's complement (the reference
    // keeps the exact differences; r[0] is range-checked and never wraps).
    const int W = comp.format().width;
    const mpz_class mod = mpz_class(1) << W, half = mpz_class(1) << (W - 1);
    for (size_t i = 0; i < std::min(a.regs[ax].size(), b.regs[ax].size()); ++i) {
      mpz_class want = b.regs[ax][i] % mod;  // truncating division: |want| < mod
      if (want < -half) want += mod;
      if (want >= half) want -= mod;
      EXPECT_EQ(a.regs[ax][i], want) << ctx << " axis " << ax << " r[" << i << "]";
    }
    if (ax < a.end.size() && ax < b.end.size()) {
      EXPECT_EQ(a.end[ax], b.end[ax]) << ctx << " axis " << ax << " end";
    }
  }
  EXPECT_EQ(comp.words(a), ref::words(comp.format(), b)) << ctx;
  const RegisterNeeds want = fd_test::reference_needs(comp.format().degree, seg.ticks, comp.format().tol_lsb);
  EXPECT_EQ(a.needs.alone, want.alone) << ctx;
  EXPECT_EQ(a.needs.share, want.share) << ctx;
  EXPECT_EQ(a.needs.binding, want.binding) << ctx;
  EXPECT_EQ(a.needs.common, want.common) << ctx;
  return fast;
}

// A random polynomial on [0, T] from x0 with terms of size ~ range/(4 deg) at T;
// with some probability exactly dyadic ("nice") coefficients, zeros, or fewer
// coefficients.
std::vector<double> random_poly(std::mt19937_64& rng, int deg, double T, double x0, double range) {
  std::uniform_real_distribution<double> U(-1, 1);
  std::uniform_int_distribution<int> pick(0, 9);
  std::vector<double> c(deg + 1);
  c[0] = x0;
  double Tj = 1;
  const bool nice = pick(rng) == 0;
  for (int j = 1; j <= deg; ++j) {
    Tj *= T;
    double v = U(rng) * range / (4.0 * deg) / Tj;
    if (nice) {
      int e;
      std::frexp(v, &e);
      v = std::ldexp(std::round(std::ldexp(v, 6 - e)), e - 6);  // 6-bit mantissa
    }
    const int p = pick(rng);
    if (p == 1) v = 0;
    if (p == 2 && j > 1) v = -0.0;
    c[j] = v;
  }
  if (pick(rng) == 3) c.resize(1 + std::uniform_int_distribution<int>(0, deg)(rng));
  return c;
}

double pick_h(std::mt19937_64& rng) {
  switch (std::uniform_int_distribution<int>(0, 5)(rng)) {
    case 0: return 1e-3;
    case 1: return std::ldexp(1.0, -std::uniform_int_distribution<int>(4, 16)(rng));
    case 2: return 1.0 / 3.0e3;
    case 3: return 2.5e-4;
    default: return std::uniform_real_distribution<double>(1e-5, 1e-2)(rng);
  }
}

double horner_q(const std::vector<double>& c, double t) {
  __float128 v = 0;
  for (size_t j = c.size(); j-- > 0;) v = v * __float128(t) + __float128(c[j]);
  return static_cast<double>(v);
}

struct WG {
  int w, c, g;
};

void random_chain(int deg, WG wg, int frac, uint64_t seed, int nseg, Stats& st) {
  const int axes = 1 + static_cast<int>(seed % 3);
  const Format f = fmt(axes, deg, wg.w, wg.c, wg.g, frac);
  const Compiler comp(f);
  std::mt19937_64 rng(seed);
  const uint64_t kfit = std::min<uint64_t>(ref::longest_segment(deg, wg.g, f.tol_lsb), f.max_ticks);
  ASSERT_EQ(kfit, std::min<uint64_t>(Compiler::longest_segment(deg, wg.g, f.tol_lsb), f.max_ticks));
  const double full = std::ldexp(1.0, f.out_width() - 1 - f.frac_bits);  // |x| limit, units
  std::uniform_real_distribution<double> U01(0, 1);
  std::vector<double> x0(axes, 0.0);
  bool have_prev = false;
  Compiled prev;
  for (int s = 0; s < nseg; ++s) {
    PolySegment seg;
    seg.h = pick_h(rng);
    const int kp = std::uniform_int_distribution<int>(0, 19)(rng);
    if (kfit == 0) seg.ticks = 1 + kp;
    else if (kp == 0) seg.ticks = kfit + 1 + std::uniform_int_distribution<int>(0, 3)(rng);  // budget refusal
    else if (kp == 1) seg.ticks = kfit;
    else seg.ticks = std::uniform_int_distribution<uint64_t>(1, std::min<uint64_t>(kfit, 3000))(rng);
    const double T = seg.h * static_cast<double>(seg.ticks);
    // range factor: mostly inside, sometimes at or beyond the limit
    const int rp = std::uniform_int_distribution<int>(0, 9)(rng);
    const double rho = rp == 0 ? 1e-9 : rp == 1 ? 3.5 : rp == 2 ? 8.0 : 0.05 + 0.9 * U01(rng);
    for (int a = 0; a < axes; ++a) {
      double xs = have_prev ? x0[a] : (U01(rng) - 0.5) * full;
      if (std::fabs(xs) > 0.6 * full) xs *= 0.5;
      seg.coef.push_back(random_poly(rng, deg, T, xs, full * rho));
    }
    const Outcome o = check_same(comp, seg, have_prev ? &prev.end : nullptr,
                                 "deg " + std::to_string(deg) + " W " + std::to_string(wg.w) + " G " +
                                     std::to_string(wg.g) + " F " + std::to_string(frac) + " seed " +
                                     std::to_string(seed) + " seg " + std::to_string(s),
                                 &st);
    if (::testing::Test::HasFailure()) return;
    if (o.ok) {
      // predictions at a few ticks
      for (uint64_t k : {uint64_t(0), uint64_t(1), seg.ticks / 2, seg.ticks - 1, seg.ticks}) {
        const int a = static_cast<int>(k % axes);
        ASSERT_EQ(Compiler::state_at(o.c, a, k), ref::state_at(o.c, a, k));
        mpz_class q;
        mpz_fdiv_q_2exp(q.get_mpz_t(), ref::state_at(o.c, a, k).get_mpz_t(), f.guard_bits);
        ASSERT_EQ(comp.sample_at(o.c, a, k), q);
      }
      prev = o.c;
      have_prev = std::uniform_int_distribution<int>(0, 7)(rng) != 0;
      for (int a = 0; a < axes; ++a) {
        x0[a] = horner_q(seg.coef[a], T);
        // sometimes a start slightly off the end (continuity limit)
        if (std::uniform_int_distribution<int>(0, 9)(rng) == 0)
          x0[a] += std::ldexp((U01(rng) - 0.5) * 1.2, -f.frac_bits);
      }
    } else {
      have_prev = false;
    }
  }
}

}  // namespace

TEST(FdCompilerFast, RandomChainsAllDegreesAndWidths) {
  const WG wgs[] = {{48, 16, 16}, {48, 16, 20}, {64, 16, 32}, {64, 32, 40}, {96, 16, 48},
                    {96, 32, 56}, {128, 64, 80}, {128, 32, 64}, {128, 16, 100}};
  const int fracs[] = {0, 4, 12, 16, 32, -6};
  Stats st;
  uint64_t seed = 1;
  const auto t0 = std::chrono::steady_clock::now();
  for (int deg = 1; deg <= 7; ++deg)
    for (const WG& wg : wgs)
      for (int frac : fracs) {
        if (wg.w - wg.g - 1 - frac < 2) continue;
        random_chain(deg, wg, frac, seed++, 60, st);
        if (HasFailure()) return;
      }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("  %ld accepted, %ld refused segments identical (%.1f s)\n", st.accepted, st.refused, s);
  EXPECT_GT(st.accepted, 10000);
  EXPECT_GT(st.refused, 500);
}

// Scale a polynomial towards the range limit: bisect the reference's
// accept/refuse boundary, then check both sides of it very closely.
TEST(FdCompilerFast, RangeLimitBoundary) {
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> U(-1, 1);
  long checked = 0;
  for (int deg = 1; deg <= 7; ++deg)
    for (WG wg : {WG{48, 16, 16}, WG{64, 16, 32}, WG{96, 16, 48}, WG{128, 32, 80}}) {
      const Format f = fmt(2, deg, wg.w, wg.c, wg.g, 8);
      const Compiler comp(f);
      const uint64_t kfit = std::min<uint64_t>(Compiler::longest_segment(deg, wg.g, f.tol_lsb), 500);
      for (int rep = 0; rep < 6; ++rep) {
        PolySegment base;
        base.h = pick_h(rng);
        base.ticks = std::uniform_int_distribution<uint64_t>(1, kfit)(rng);
        const double T = base.h * static_cast<double>(base.ticks);
        for (int a = 0; a < 2; ++a) {
          std::vector<double> c(deg + 1);
          double Tj = 1;
          for (int j = 0; j <= deg; ++j, Tj *= T) c[j] = U(rng) / Tj;
          base.coef.push_back(c);
        }
        auto scaled = [&](double s) {
          PolySegment p = base;
          for (auto& c : p.coef)
            for (auto& v : c) v *= s;
          return p;
        };
        auto accepts = [&](double s) {
          try {
            ref::compile(f, scaled(s), nullptr, "seg");
            return true;
          } catch (const CompileError&) {
            return false;
          }
        };
        double lo = 0, hi = std::ldexp(1.0, f.out_width() - f.frac_bits + 4);
        if (!accepts(lo) || accepts(hi)) continue;
        for (int it = 0; it < 200 && std::nextafter(lo, hi) < hi; ++it) {
          const double mid = lo + (hi - lo) / 2;
          (accepts(mid) ? lo : hi) = mid;
        }
        double s = lo;
        for (int k = 0; k < 8; ++k) s = std::nextafter(s, 0.0);
        for (int k = 0; k < 24; ++k, s = std::nextafter(s, 1e300)) {
          check_same(comp, scaled(s), nullptr, "range boundary deg " + std::to_string(deg));
          ++checked;
        }
        for (double r : {1 - 1e-6, 1 - 1e-9, 1 - 1e-12, 1 + 1e-12, 1 + 1e-9, 1 + 1e-6}) {
          check_same(comp, scaled(lo * r), nullptr, "range boundary deg " + std::to_string(deg));
          ++checked;
        }
        if (HasFailure()) return;
      }
    }
  EXPECT_GT(checked, 2000);
}

// A start exactly at, just inside and just outside tol/2 of the target.
TEST(FdCompilerFast, ContinuityLimitAndTies) {
  std::mt19937_64 rng(99);
  for (int deg = 1; deg <= 7; ++deg)
    for (WG wg : {WG{48, 16, 16}, WG{64, 16, 32}, WG{96, 16, 48}, WG{128, 64, 80}})
      for (double tol : {0.5, 0.1, 1.0, 1e-3}) {
        Format f = fmt(3, deg, wg.w, wg.c, wg.g, 10);
        f.tol_lsb = tol;
        const Compiler comp(f);
        const uint64_t kfit = std::min<uint64_t>(Compiler::longest_segment(deg, wg.g, tol), 200);
        if (kfit == 0) continue;
        for (int rep = 0; rep < 10; ++rep) {
          PolySegment seg;
          // dyadic h and coefficients: many exact half-LSB ties in the registers
          seg.h = std::ldexp(1.0, -std::uniform_int_distribution<int>(2, 12)(rng));
          seg.ticks = std::uniform_int_distribution<uint64_t>(1, kfit)(rng);
          for (int a = 0; a < 3; ++a) {
            std::vector<double> c(deg + 1);
            c[0] = std::ldexp(static_cast<double>(std::uniform_int_distribution<int>(-1000, 1000)(rng)), -13);
            for (int j = 1; j <= deg; ++j)
              c[j] = std::ldexp(static_cast<double>(std::uniform_int_distribution<int>(-7, 7)(rng)),
                                -std::uniform_int_distribution<int>(4, 20)(rng));
            seg.coef.push_back(c);
          }
          check_same(comp, seg, nullptr, "ties");
          // c0 in register units: (x 2^F + 1/2) 2^G; starts around c0 +- tol/2 2^G
          const mpq_class half_tol = ref::exact(tol / 2) * mpq_class(ref::pow2(wg.g));
          for (int d : {-2, -1, 0, 1, 2}) {
            std::vector<mpz_class> start(3);
            for (int a = 0; a < 3; ++a) {
              mpq_class c0 = ref::exact(seg.coef[a][0]) * mpq_class(ref::pow2(wg.g + 10)) + mpq_class(ref::pow2(wg.g), 2);
              const mpq_class edge = a == 1 ? mpq_class(c0 - half_tol) : mpq_class(c0 + half_tol);
              mpz_class e;
              mpz_fdiv_q(e.get_mpz_t(), edge.get_num_mpz_t(), edge.get_den_mpz_t());
              start[a] = e + d;
            }
            check_same(comp, seg, &start, "continuity d=" + std::to_string(d));
          }
          if (HasFailure()) return;
        }
      }
}

// Odd inputs: tiny, subnormal and huge coefficients, extreme tick periods,
// negative frac_bits, bad input of every kind.
TEST(FdCompilerFast, EdgeCasesAndBadInput) {
  for (int deg : {1, 3, 5, 7}) {
    const Format f = fmt(2, deg, 64, 16, 32, 8);
    const Compiler comp(f);
    auto seg_of = [&](std::vector<double> c0, std::vector<double> c1, double h, uint64_t K) {
      return PolySegment{{c0, c1}, h, K};
    };
    const std::vector<PolySegment> segs = {
        seg_of({1.0, 2.0}, {0.0}, 1e-3, 100),
        seg_of({}, {}, 1e-3, 5),
        seg_of({1.0, 5e-324, 1e-310}, {-0.0, -1e-300}, 1e-3, 10),
        seg_of({1e-300, 1e-200}, {3.0, 0, 0, 1e-250}, 1e-3, 10),
        seg_of({1e300}, {0.0}, 1e-3, 10),
        seg_of({1.0, 1e300}, {0.0}, 1e-3, 10),
        seg_of({1.0, 1.0}, {2.0, 1.0}, 5e-324, 10),
        seg_of({1.0, 1e-6}, {2.0, 1e-6}, 1e300, 1),
        seg_of({1.0, 1.0}, {2.0, 1.0}, 0.0, 10),
        seg_of({1.0, 1.0}, {2.0, 1.0}, -1e-3, 10),
        seg_of({1.0, 1.0}, {2.0, 1.0}, NAN, 10),
        seg_of({1.0, 1.0}, {2.0, 1.0}, INFINITY, 10),
        seg_of({1.0, NAN}, {2.0, 1.0}, 1e-3, 10),
        seg_of({1.0, 1.0}, {2.0, -INFINITY}, 1e-3, 10),
        seg_of({1.0, 1.0}, {2.0, 1.0}, 1e-3, 0),
        seg_of({1.0, 1.0}, {2.0, 1.0}, 1e-3, 100000),
        seg_of({1.0, 1.0}, {2.0, 1.0}, 1e-3, uint64_t(1) << 21),
        seg_of({1, 2, 3, 4, 5, 6, 7, 8, 9}, {2.0}, 1e-3, 10),
        PolySegment{{{1.0}}, 1e-3, 10},
    };
    int n = 0;
    for (const auto& s : segs) check_same(comp, s, nullptr, "edge " + std::to_string(n++) + " deg " + std::to_string(deg));
    // starts: wrong axis count, tiny and huge offsets
    const PolySegment s = seg_of({1.0, 2.0}, {-3.0}, 1e-3, 50);
    std::vector<mpz_class> one(1);
    check_same(comp, s, &one, "start axes");
    const mpz_class c0 = (mpz_class(1) << 40) + (mpz_class(1) << 31);  // (1*2^8 + 1/2) 2^32
    for (mpz_class off : {mpz_class(0), mpz_class(1), mpz_class(-1), mpz_class(mpz_class(1) << 30),
                          mpz_class(mpz_class(1) << 31), mpz_class((mpz_class(1) << 30) + 1),
                          mpz_class(mpz_class(1) << 200)})
      for (int sign : {1, -1}) {
        std::vector<mpz_class> st = {c0 + sign * off, (mpz_class(-3) << 40) + (mpz_class(1) << 31)};
        check_same(comp, s, &st, "start offset");
      }
  }
  // negative frac_bits, large guard, all chunk widths
  for (int frac : {-64, -20, 0, 40}) {
    const Format f = fmt(1, 4, 128, 64, 60, frac);
    const Compiler comp(f);
    PolySegment s{{{std::ldexp(1.0, 20 - frac), 3.0, -1.5, 1e-3, 7.0}}, 1e-4, 1000};
    check_same(comp, s, nullptr, "frac " + std::to_string(frac));
  }
}

// The public helpers keep their exact values.
TEST(FdCompilerFast, HelpersUnchanged) {
  for (int deg = 1; deg <= 7; ++deg)
    for (int g : {0, 16, 32, 48, 80}) {
      EXPECT_EQ(Compiler::longest_segment(deg, g, 0.5), ref::longest_segment(deg, g, 0.5));
      for (uint64_t k : {uint64_t(1), uint64_t(7), uint64_t(1000), uint64_t(1) << 32}) {
        EXPECT_EQ(Compiler::quant_bound_x2(deg, k), ref::quant_bound_x2(deg, k));
        EXPECT_EQ(Compiler::guard_bits_needed(deg, k, 0.5), ref::guard_bits_needed(deg, k, 0.5));
      }
    }
  for (uint64_t k : {uint64_t(0), uint64_t(3), uint64_t(1) << 40})
    for (int i = 0; i <= 8; ++i) EXPECT_EQ(traj::fd::binom(k, i), ref::binom(k, i));
}

// ---------------------------------------------------------------------------
// The fixed-point grid path (the common case) and its hand-over to the exact
// integer path.

namespace {
traj::fd::PathCounts counts_since(const traj::fd::PathCounts& b) {
  const traj::fd::PathCounts& a = traj::fd::path_counts();
  return {a.grid2 - b.grid2, a.grid3 - b.grid3, a.grid4 - b.grid4, a.exact - b.exact, a.reference - b.reference};
}
void print_counts(const char* what, const traj::fd::PathCounts& c) {
  std::printf("  %s: grid2 %llu, grid3 %llu, grid4 %llu, exact %llu, reference %llu\n", what,
              static_cast<unsigned long long>(c.grid2), static_cast<unsigned long long>(c.grid3), static_cast<unsigned long long>(c.grid4),
              static_cast<unsigned long long>(c.exact), static_cast<unsigned long long>(c.reference));
}
}  // namespace

// Every buildable width 48..128 (chunk 16) at two guard-bit counts, every
// degree, several frac_bits, chained random segments (mixed tick periods,
// starts at and just off the previous end, ranges up to and beyond the
// limit): identical to the reference, and the grid path (3 limbs, and 4 at the
// widest formats) settles nearly every accepted segment.
TEST(FdCompilerFast, GridPathAllWidthsChained) {
  const WG wgs[] = {{48, 16, 8},  {48, 16, 30},  {64, 16, 16},  {64, 16, 48},  {80, 16, 24},   {80, 16, 60},
                    {96, 16, 48}, {96, 16, 70},  {112, 16, 40}, {112, 16, 90}, {128, 16, 64}, {128, 16, 110}};
  const int fracs[] = {0, 16, 32, -8};
  Stats st;
  uint64_t seed = 5000;
  const traj::fd::PathCounts before = traj::fd::path_counts();
  for (int deg = 1; deg <= 7; ++deg)
    for (const WG& wg : wgs)
      for (int frac : fracs) {
        if (wg.w - wg.g - 1 - frac < 2) continue;
        random_chain(deg, wg, frac, seed++, 40, st);
        if (HasFailure()) return;
      }
  const traj::fd::PathCounts c = counts_since(before);
  std::printf("  %ld accepted, %ld refused segments identical\n", st.accepted, st.refused);
  print_counts("paths", c);
  EXPECT_GT(st.accepted, 8000);
  EXPECT_GE(static_cast<double>(c.grid2 + c.grid3 + c.grid4), 0.9 * static_cast<double>(st.accepted));
  EXPECT_GT(c.grid2, 1000u);
  EXPECT_GT(c.grid3, 1000u);
  EXPECT_GT(c.grid4, 100u);
  EXPECT_GT(c.exact, 0u);
}

// The planner's main format and tick (3 axes, quintic, W 96, G 48, F 32,
// h = 1 ms, K = 20..400, chained): every segment on the grid path, nearly all
// on 2 limbs.
TEST(FdCompilerFast, GridPathMainJobFormat) {
  const Format f = fmt(3, 5, 96, 16, 48, 32);
  const Compiler comp(f);
  std::mt19937_64 rng(4242);
  std::uniform_int_distribution<uint64_t> Kd(20, 400);
  std::uniform_real_distribution<double> U(-1, 1);
  std::vector<double> x0(3, 0.0);
  Compiled prev;
  Stats st;
  const traj::fd::PathCounts before = traj::fd::path_counts();
  for (int s = 0; s < 3000; ++s) {
    PolySegment seg;
    seg.h = 1e-3;
    seg.ticks = Kd(rng);
    const double T = seg.h * static_cast<double>(seg.ticks);
    for (int a = 0; a < 3; ++a) {
      std::vector<double> c(6);
      c[0] = x0[a];
      double Tj = 1;
      for (int j = 1; j <= 5; ++j) {
        Tj *= T;
        c[j] = U(rng) * 1000.0 / 20.0 / Tj;
      }
      c[1] -= x0[a] / T * 0.5;
      x0[a] = horner_q(c, T);
      seg.coef.push_back(c);
    }
    const Outcome o = check_same(comp, seg, s ? &prev.end : nullptr, "main job seg " + std::to_string(s), &st);
    ASSERT_TRUE(o.ok) << o.msg;
    if (HasFailure()) return;
    prev = o.c;
  }
  const traj::fd::PathCounts c = counts_since(before);
  print_counts("paths", c);
  EXPECT_EQ(c.grid2 + c.grid3, 3000u);
  EXPECT_GT(c.grid2, 2900u);
}

// Roundings on the edge of the grid's truncation error, built exactly: with a
// dyadic tick h = 2^-10, x(0) = 2^(B-81) (so that c0 = x(0) 2^80 + 2^47 and
// r0 have B = 124 - g bits and the 2-limb grid takes g fraction bits), the
// terms u_j = c_j 2^sigma h^j are chosen in grid units (2^-g register LSB) so
// that X_1 - qd + 2^(g-1) (qd = floor(e0/K) of the carried error) ends in a
// given g-bit pattern L0, plus up to two terms (u_3, u_4) of +-2^-20 grid
// units below the grid (err_1 = 1 or 2). The 2-limb grid must settle exactly
// the cases its bound
// allows (L0 >= err + [rd > 0], L0 + err <= 2^g), leave the others to the
// finer grid or the exact path, and every result must equal the reference's
// (including the exact case L0 = 0 with rd > 0, which rounds down).
TEST(FdCompilerFast, GridRoundingBoundaries) {
  const Format f = fmt(1, 4, 96, 16, 48, 32);  // sigma = 80
  const Compiler comp(f);
  const uint64_t K = 3;
  long settled = 0, handed = 0;
  for (int g : {64, 52, 40, 33}) {
    const int B = 124 - g;
    const double x0 = std::ldexp(1.0, B - 81);
    const mpz_class c0 = (mpz_class(1) << (B - 1)) + (mpz_class(1) << 47);
    const mpz_class two_g = mpz_class(1) << g;
    auto c_of = [g](const mpq_class& u, int j) {  // c_j = u 2^-g 2^-80 / 2^(-10 j)
      mpq_class c = u;
      mpz_mul_2exp(c.get_den_mpz_t(), c.get_den_mpz_t(), g + 80 - 10 * j);
      c.canonicalize();
      const double dv = c.get_d();
      EXPECT_EQ(ref::exact(dv), c);  // exact
      return dv;
    };
    for (int delta : {0, 1, -1, 2, 3, -3}) {  // 0: no start (r0 from c0)
      const bool with_start = delta != 0;
      const mpz_class e0g = mpz_class(delta) * two_g;
      mpz_class qd, rd;
      mpz_fdiv_qr_ui(qd.get_mpz_t(), rd.get_mpz_t(), e0g.get_mpz_t(), K);
      const bool below = rd != 0;
      const uint64_t top = g == 64 ? ~uint64_t(0) : (uint64_t(1) << g) - 1;
      for (uint64_t L0 : {uint64_t(0), uint64_t(1), uint64_t(2), uint64_t(3), uint64_t(1) << (g - 1), top, top - 1})
        for (const std::pair<int, int>& tiny : {std::pair<int, int>{0, 0}, {1, 0}, {-1, 0}, {1, 1}, {-1, -1}, {1, -1}})
          for (int kint : {7, -6}) {
            // X_1 = kint 2^g + T, T = L0 - 2^(g-1) + qd (mod 2^g), split so that
            // both parts are exact doubles
            mpz_class T = mpz_class(std::to_string(L0)) - (mpz_class(1) << (g - 1)) + qd;
            mpz_fdiv_r_2exp(T.get_mpz_t(), T.get_mpz_t(), g);
            const mpz_class X1 = mpz_class(kint) * two_g + T;
            mpz_class u2;
            mpz_fdiv_r_2exp(u2.get_mpz_t(), X1.get_mpz_t(), g - 24);
            const mpz_class u1 = X1 - u2;
            const mpq_class u3(tiny.first, 1 << 20), u4(tiny.second, 1 << 20);
            PolySegment seg{{{x0, c_of(mpq_class(u1), 1), c_of(mpq_class(u2), 2), c_of(u3, 3), c_of(u4, 4)}},
                            std::ldexp(1.0, -10), K};
            ASSERT_EQ(ref::exact(x0) * mpq_class(mpz_class(1) << 80) + mpq_class(mpz_class(1) << 47), mpq_class(c0));
            std::vector<mpz_class> start{c0 + delta};
            const traj::fd::PathCounts before = traj::fd::path_counts();
            const std::string ctx = "g " + std::to_string(g) + " delta " + std::to_string(delta) + " L0 " +
                                    std::to_string(L0) + " tiny " + std::to_string(tiny.first) + "," +
                                    std::to_string(tiny.second) + " kint " + std::to_string(kint);
            const Outcome o = check_same(comp, seg, with_start ? &start : nullptr, ctx);
            ASSERT_TRUE(o.ok) << ctx << ": " << o.msg;
            const traj::fd::PathCounts c = counts_since(before);
            const unsigned __int128 err = (tiny.first != 0) + (tiny.second != 0), bl = with_start && below ? 1 : 0;
            const bool decided = err == 0 || (L0 >= err + bl && L0 + err <= (static_cast<unsigned __int128>(1) << g));
            EXPECT_EQ(c.grid2, decided ? 1u : 0u) << ctx;
            EXPECT_EQ(c.grid2 + c.grid3 + c.exact, 1u) << ctx;
            (decided ? settled : handed) += 1;
            if (HasFailure()) return;
          }
    }
  }
  std::printf("  %ld settled on the 2-limb grid, %ld left to the finer grid or the exact path\n", settled, handed);
  EXPECT_GT(handed, 100);
}

// The 2-limb grid on random chained segments of every degree 1..7 at several
// widths (mixed tick periods: dyadic ones, where every term lies on the grid,
// and 1 ms, whose m_h^j exceed 128 bits from j = 3 on, so the truncated powers
// weigh 2 grid units): identical to the reference, and for every degree the
// 2-limb grid settles a good share of the accepted segments (the rest: values
// of full-range size at the wide formats, too large for 2 limbs).
TEST(FdCompilerFast, Grid2RandomAllDegrees) {
  const WG wgs[] = {{48, 16, 12}, {64, 16, 32}, {96, 16, 48}, {96, 32, 40}, {128, 32, 64}};
  const int fracs[] = {0, 16, 32};
  uint64_t seed = 90000;
  for (int deg = 1; deg <= 7; ++deg) {
    Stats st;
    const traj::fd::PathCounts before = traj::fd::path_counts();
    for (const WG& wg : wgs)
      for (int frac : fracs) {
        if (wg.w - wg.g - 1 - frac < 2) continue;
        random_chain(deg, wg, frac, seed++, 50, st);
        if (HasFailure()) return;
      }
    const traj::fd::PathCounts c = counts_since(before);
    std::printf("  degree %d: %ld accepted, %ld refused;", deg, st.accepted, st.refused);
    print_counts("paths", c);
    EXPECT_GT(st.accepted, 400) << "degree " << deg;
    EXPECT_GE(static_cast<double>(c.grid2), 0.3 * static_cast<double>(st.accepted)) << "degree " << deg;
    EXPECT_GT(c.grid2, 100u) << "degree " << deg;
  }
}

// The 2-limb grid's size limit: with W 128, G 48, F 32 (sigma = 80) and
// x(0) = 2^11 the start state has 92 bits, the grid g = 124 - 92 = 32
// fraction bits (the least it takes); one bit more and the segment goes to
// the 3-limb grid. Random quintic terms at h = 1 ms, chained and unchained,
// on both sides of the limit: identical to the reference on every one.
TEST(FdCompilerFast, Grid2SizeLimit) {
  const Format f = fmt(3, 5, 128, 32, 48, 32);
  const Compiler comp(f);
  std::mt19937_64 rng(31337);
  std::uniform_real_distribution<double> U(-1, 1);
  struct Side {
    double x0;
    bool grid2;
  };
  const Side sides[] = {{std::ldexp(1.0, 11) - std::ldexp(1.0, -30), true},
                        {std::ldexp(1.0, 11), true},
                        {std::ldexp(1.0, 12) - std::ldexp(1.0, -30), true},
                        {std::ldexp(1.0, 12), false},
                        {-std::ldexp(1.0, 12), false}};
  long n2 = 0, n3 = 0;
  for (const Side& sd : sides)
    for (int rep = 0; rep < 40; ++rep) {
      PolySegment seg;
      seg.h = 1e-3;
      seg.ticks = std::uniform_int_distribution<uint64_t>(20, 400)(rng);
      const double T = seg.h * static_cast<double>(seg.ticks);
      for (int a = 0; a < 3; ++a) {
        std::vector<double> c(6);
        c[0] = a == 0 ? sd.x0 : U(rng);
        double Tj = 1;
        for (int j = 1; j <= 5; ++j) {
          Tj *= T;
          c[j] = U(rng) * 1e-3 / Tj;  // the end stays within the same bit length
        }
        seg.coef.push_back(c);
      }
      const bool chained = rep % 2 == 1;
      std::vector<mpz_class> start;
      if (chained) {
        for (int a = 0; a < 3; ++a) start.push_back(comp.position_to_state(seg.coef[a][0]) + (rep % 4 == 1 ? 1 : -1));
      }
      const traj::fd::PathCounts before = traj::fd::path_counts();
      const std::string ctx = "x0 " + std::to_string(sd.x0) + " rep " + std::to_string(rep);
      const Outcome o = check_same(comp, seg, chained ? &start : nullptr, ctx);
      ASSERT_TRUE(o.ok) << ctx << ": " << o.msg;
      const traj::fd::PathCounts c = counts_since(before);
      EXPECT_EQ(c.grid2, sd.grid2 ? 1u : 0u) << ctx;
      EXPECT_EQ(c.grid3, sd.grid2 ? 0u : 1u) << ctx;
      n2 += static_cast<long>(c.grid2);
      n3 += static_cast<long>(c.grid3);
      if (HasFailure()) return;
    }
  std::printf("  %ld on the 2-limb grid, %ld on the 3-limb grid\n", n2, n3);
}

// compile() into one reused Compiled (the allocation-free form) gives what a
// fresh compile() gives, also with the start taken from that same object's
// end, across refusals.
TEST(FdCompilerFast, CompileIntoReusedResult) {
  for (const WG wg : {WG{64, 16, 32}, WG{96, 16, 48}, WG{128, 32, 64}})
    for (int deg : {1, 3, 5, 7}) {
      const Format f = fmt(3, deg, wg.w, wg.c, wg.g, 16);
      const Compiler comp(f);
      std::mt19937_64 rng(deg * 1000 + wg.w);
      const uint64_t kfit = std::min<uint64_t>(Compiler::longest_segment(deg, wg.g, f.tol_lsb), 400);
      const double full = std::ldexp(1.0, f.out_width() - 1 - f.frac_bits);
      Compiled work, fresh;
      bool have = false;
      std::vector<double> x0(3, 0.0);
      for (int s = 0; s < 300; ++s) {
        PolySegment seg;
        seg.h = pick_h(rng);
        seg.ticks = std::uniform_int_distribution<uint64_t>(1, kfit + (s % 37 == 0 ? 5 : 0))(rng);
        const double T = seg.h * static_cast<double>(seg.ticks);
        for (int a = 0; a < 3; ++a) seg.coef.push_back(random_poly(rng, deg, T, have ? x0[a] : 0.0, full * 0.3));
        const std::vector<mpz_class> start = work.end;
        bool ok_fresh = true, ok_work = true;
        try {
          fresh = comp.compile(seg, have ? &start : nullptr, "seg");
        } catch (const CompileError&) {
          ok_fresh = false;
        }
        try {
          comp.compile(seg, have ? &work.end : nullptr, "seg", work);
        } catch (const CompileError&) {
          ok_work = false;
        }
        ASSERT_EQ(ok_fresh, ok_work) << "seg " << s;
        if (!ok_work) {
          have = false;
          work = Compiled();
          continue;
        }
        ASSERT_EQ(work.ticks, fresh.ticks);
        ASSERT_EQ(work.regs, fresh.regs) << "seg " << s;
        ASSERT_EQ(work.end, fresh.end) << "seg " << s;
        ASSERT_TRUE(same_bits(work.carried_lsb, fresh.carried_lsb));
        ASSERT_TRUE(same_bits(work.bound_lsb, fresh.bound_lsb));
        ASSERT_EQ(work.needs.alone, fresh.needs.alone);
        ASSERT_EQ(work.needs.share, fresh.needs.share);
        ASSERT_EQ(work.needs.binding, fresh.needs.binding);
        ASSERT_EQ(work.needs.common, fresh.needs.common);
        have = true;
        for (int a = 0; a < 3; ++a) x0[a] = horner_q(seg.coef[a], T);
      }
    }
}
