// SPDX-License-Identifier: Apache-2.0
// Test groups 2, 4 and 5 (hls model against the host), plus the compiler's
// refusals. References: the host's exact closed-form prediction (GMP) for the
// bit-exact checks, and the double-coefficient polynomial evaluated in
// binary128 (113-bit significand) for the error-bound checks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <tuple>

#include "fd/fd_compiler.hpp"
#include "fd_test_util.hpp"
#include "fd_drive.hpp"
#include "traj_fd_engine.hpp"

using traj::u128;
using traj::fd::Compiled;
using traj::fd::CompileError;
using traj::fd::Compiler;
using traj::fd::Format;
using traj::fd::PolySegment;

namespace {

using f128 = __float128;

f128 horner128(const std::vector<double>& c, f128 t) {
  f128 v = 0;
  for (size_t j = c.size(); j-- > 0;) v = v * t + f128(c[j]);
  return v;
}
double to_d(f128 v) { return static_cast<double>(v); }
f128 mpz_to_f128(const mpz_class& z) {
  // exact enough: split into 64-bit limbs
  mpz_class a = abs(z);
  f128 r = 0, w = 1;
  while (a != 0) {
    mpz_class lo = a & mpz_class("18446744073709551615");
    r += f128(static_cast<double>(mpz_class(lo >> 32).get_ui())) * 4294967296.0Q * w +
         f128(static_cast<double>(mpz_class(lo & 0xffffffffUL).get_ui())) * w;
    a >>= 64;
    w *= 18446744073709551616.0Q;
  }
  return z < 0 ? -r : r;
}

// A random polynomial x(t) on [0, T] with |x| well inside `range` units and
// x(0) = x0; coefficients scaled so that each term is O(range/4) at t = T.
std::vector<double> random_poly(std::mt19937_64& rng, int deg, double T, double x0, double range) {
  std::uniform_real_distribution<double> U(-1, 1);
  std::vector<double> c(deg + 1);
  c[0] = x0;
  double Tj = 1;
  for (int j = 1; j <= deg; ++j) {
    Tj *= T;
    c[j] = U(rng) * range / (4.0 * deg) / Tj;
  }
  return c;
}

template <int D, int W, int C, int G>
struct Cfg {
  static constexpr int kDeg = D, kW = W, kC = C, kG = G;
};

using fd_test::fmt;

// ---------------------------------------------------------------------------
// Group 2: hls model == host prediction, bit for bit, random chained segments.
// ---------------------------------------------------------------------------
template <class Cf>
void check_model_vs_prediction(uint64_t seed) {
  constexpr int A = 2;
  using Eng = traj::FdEngine<A, Cf::kDeg, Cf::kW, Cf::kC, Cf::kG>;
  const Format f = fmt(A, Cf::kDeg, Cf::kW, Cf::kC, Cf::kG, 4);
  Compiler comp(f);
  std::mt19937_64 rng(seed);
  const double h = 1e-3;
  const uint64_t kmax = std::min<uint64_t>(Compiler::longest_segment(Cf::kDeg, Cf::kG, f.tol_lsb), 300);
  ASSERT_GE(kmax, 1u);
  std::uniform_int_distribution<uint64_t> Kd(1, kmax);
  const double range = std::ldexp(1.0, f.out_width() - 2 - f.frac_bits);  // units
  std::vector<Compiled> segs;
  std::vector<double> x0(A, 0.0);
  for (int s = 0; s < 8; ++s) {
    PolySegment seg;
    seg.h = h;
    seg.ticks = Kd(rng);
    const double T = seg.ticks * h;
    for (int a = 0; a < A; ++a) {
      seg.coef.push_back(random_poly(rng, Cf::kDeg, T, x0[a], range / 2));
    }
    const std::vector<mpz_class>* start = segs.empty() ? nullptr : &segs.back().end;
    segs.push_back(comp.compile(seg, start));
    for (int a = 0; a < A; ++a) {
      // next segment starts where this target ends (continuous path)
      const auto& c = seg.coef[a];
      x0[a] = to_d(horner128(c, f128(T)));
    }
  }
  Eng e;
  size_t n = 0;
  traj::test::run_segments(e, comp, segs, Eng::kWords + Eng::kChunks + 2,
                           [&](size_t s, uint64_t k, const typename Eng::Out& o) {
                             for (int a = 0; a < A; ++a) {
                               const mpz_class got = traj::test::to_mpz_signed(o.sample[a], Eng::kOutWidth);
                               ASSERT_EQ(got, comp.sample_at(segs[s], a, k))
                                   << "seed " << seed << " segment " << s << " tick " << k << " axis " << a;
                             }
                             ++n;
                           });
  size_t total = 0;
  for (auto& s : segs) total += s.ticks;
  EXPECT_EQ(n, total);
}

template <class... Cs>
void all_model_vs_prediction(uint64_t seed) {
  (check_model_vs_prediction<Cs>(seed), ...);
}

#define FD_CONFIGS_FOR_DEGREE(D) \
  Cfg<D, 48, 16, 20>, Cfg<D, 64, 16, 32>, Cfg<D, 96, 32, 56>, Cfg<D, 128, 64, 80>

}  // namespace

TEST(FdModel, MatchesHostPredictionAllDegreesAndWidths) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    all_model_vs_prediction<FD_CONFIGS_FOR_DEGREE(1), FD_CONFIGS_FOR_DEGREE(2), FD_CONFIGS_FOR_DEGREE(3),
                            FD_CONFIGS_FOR_DEGREE(4)>(seed);
    all_model_vs_prediction<FD_CONFIGS_FOR_DEGREE(5), FD_CONFIGS_FOR_DEGREE(6), FD_CONFIGS_FOR_DEGREE(7)>(seed);
  }
}

// Group 2 with wraps: a scaled Chebyshev T7 over K = 5 ticks at degree 7 and
// W = 48. The compiler's range check (Bernstein bound 85.8 for T7 on [-1, 1])
// keeps r[0] inside the register, but the differences of T7 over so few ticks
// are hundreds of times larger (Delta^7 = amp 64 7! (2/K)^7 = 529 amp), so
// r[1..7] wrap modulo 2^48, already when loaded and again while ticking.
// Checked: that wraps happen (exact unwrapped register values from the closed
// form, outside [-2^47, 2^47)), that every model register equals its exact
// value modulo 2^48 after every tick, and that every sample equals the host's
// prediction bit for bit.
TEST(FdModel, IntermediateRegistersWrapAndMatchPrediction) {
  constexpr int A = 2, D = 7, W = 48, C = 16, G = 16;
  using Eng = traj::FdEngine<A, D, W, C, G>;
  const Format f = fmt(A, D, W, C, G, 4);
  Compiler comp(f);
  const uint64_t K = 5;
  const double h = 1e-3, T = static_cast<double>(K) * h;
  const double range = std::ldexp(1.0, f.out_width() - 1 - f.frac_bits);  // |x| < range units
  // x(t) = sign amp T7(2t/T - 1), T7(u) = 64u^7 - 112u^5 + 56u^3 - 7u, as a power series in t.
  auto cheb7 = [&](double amp) {
    const long double a[8] = {0, -7, 0, 56, 0, -112, 0, 64};
    const long double al = 2.0L / T, be = -1;
    std::vector<double> c(8);
    for (int m = 0; m <= 7; ++m) {
      long double v = 0;
      for (int k = m; k <= 7; ++k) {
        long double binom = 1;
        for (int t = 1; t <= m; ++t) binom = binom * (k - m + t) / t;
        v += a[k] * binom * std::pow(al, m) * std::pow(be, k - m);
      }
      c[m] = static_cast<double>(amp * v);
    }
    return c;
  };
  const double amp = 0.45 * range / 85.8;
  PolySegment seg;
  seg.h = h;
  seg.ticks = K;
  seg.coef = {cheb7(amp), cheb7(-0.7 * amp)};
  const Compiled c = comp.compile(seg, nullptr, "T7");

  // Exact unwrapped registers at tick k: r_i(k) = sum_j r_(i+j) C(k, j).
  const mpz_class half = mpz_class(1) << (W - 1), mod = mpz_class(1) << W;
  auto exact_reg = [&](int a, int i, uint64_t k) {
    mpz_class v = 0;
    for (int j = 0; i + j <= D; ++j) v += c.regs[a][i + j] * traj::fd::binom(k, j);
    return v;
  };
  auto wrap_signed = [&](mpz_class v) {  // v mod 2^W in [-2^(W-1), 2^(W-1))
    v %= mod;
    if (v < 0) v += mod;
    if (v >= half) v -= mod;
    return v;
  };

  Eng e;
  typename Eng::In in;
  for (uint64_t w : comp.words(c)) {
    in.tvalid = true;
    in.tdata = w;
    while (!e.outputs().tready) e.clock(typename Eng::In{});
    e.clock(in);
  }
  in.tvalid = false;
  int wraps = 0, max_excess_bits = 0, samples = 0;
  for (uint64_t k = 0; k <= K; ++k) {
    for (int a = 0; a < A; ++a)
      for (int i = 0; i <= D; ++i) {
        const mpz_class x = exact_reg(a, i, k);
        const bool wrapped = x < -half || x >= half;
        if (i == 0) {
          ASSERT_FALSE(wrapped) << "r[0] must stay in range; tick " << k << " axis " << a;
        }
        if (wrapped) {
          ++wraps;
          max_excess_bits = std::max(max_excess_bits, static_cast<int>(mpz_sizeinbase(x.get_mpz_t(), 2)) - (W - 1));
        }
        ASSERT_EQ(traj::test::to_mpz_signed(e.reg(a, i), W), wrap_signed(x))
            << "tick " << k << " axis " << a << " r[" << i << "]";
      }
    if (k == K) break;
    in.tick = true;
    e.clock(in);
    in.tick = false;
    for (int cyc = 0; cyc < Eng::kChunks + 2; ++cyc) {
      const auto o = e.outputs();
      if (o.sample_valid) {
        ++samples;
        for (int a = 0; a < A; ++a)
          ASSERT_EQ(traj::test::to_mpz_signed(o.sample[a], Eng::kOutWidth), comp.sample_at(c, a, k))
              << "tick " << k << " axis " << a;
      }
      e.clock(in);
    }
  }
  EXPECT_EQ(samples, static_cast<int>(K));
  EXPECT_GT(wraps, 0) << "no register wrapped: the case no longer tests wrapping";
  std::printf("  T7 over K=%llu ticks: %d register values outside the 48-bit range (up to 2^%d times it), "
              "samples == prediction\n",
              static_cast<unsigned long long>(K), wraps, max_excess_bits);
}

// ---------------------------------------------------------------------------
// Group 4: the error bound holds at every tick for the longest segment the
// compiler accepts, at each degree and width.
// ---------------------------------------------------------------------------
namespace {

struct BoundResult {
  uint64_t K;
  double bound, worst_reg, worst_out;
};

template <class Cf>
BoundResult check_bound_longest(uint64_t seed) {
  constexpr int A = 1;
  using Eng = traj::FdEngine<A, Cf::kDeg, Cf::kW, Cf::kC, Cf::kG>;
  Format f = fmt(A, Cf::kDeg, Cf::kW, Cf::kC, Cf::kG, 8);
  Compiler comp(f);
  const uint64_t K = std::min<uint64_t>(Compiler::longest_segment(Cf::kDeg, Cf::kG, f.tol_lsb), f.max_ticks);
  // one more tick must be refused (unless capped by max_ticks)
  std::mt19937_64 rng(seed);
  const double h = 1e-4;
  const double T = K * h;
  const double range = std::ldexp(1.0, f.out_width() - 2 - f.frac_bits);
  PolySegment seg;
  seg.h = h;
  seg.ticks = K;
  seg.coef.push_back(random_poly(rng, Cf::kDeg, T, range * 0.3, range / 2));
  const Compiled c = comp.compile(seg);
  Eng e;
  // load
  auto words = comp.words(c);
  typename Eng::In in;
  for (size_t i = 0; i < words.size();) {
    in.tvalid = true;
    in.tdata = words[i];
    if (e.outputs().tready) ++i;
    e.clock(in);
  }
  in.tvalid = false;
  const f128 sreg = f128(std::ldexp(1.0, f.frac_bits + f.guard_bits));
  const f128 bias = f128(std::ldexp(1.0, f.guard_bits - 1));
  const f128 sout = f128(std::ldexp(1.0, f.frac_bits));
  const f128 lsb_reg = f128(std::ldexp(1.0, f.guard_bits));
  BoundResult r{K, c.bound_lsb, 0, 0};
  // binary128 evaluation error: < 2^-100 of the largest term sum, far below 1e-6 LSB here.
  const double eval_slack = 1e-6;
  uint64_t k = 0;
  while (k < K) {
    // r0 before the k-th tick's update equals the k-th sample's state
    const mpz_class r0 = traj::test::to_mpz_signed(e.reg(0, 0), Cf::kW);
    const f128 exact = horner128(seg.coef[0], f128(double(k)) * f128(h)) * sreg + bias;
    const double err_reg = std::fabs(to_d((mpz_to_f128(r0) - exact) / lsb_reg));
    r.worst_reg = std::max(r.worst_reg, err_reg);
    if (err_reg > c.bound_lsb + eval_slack) {
      ADD_FAILURE() << "deg " << Cf::kDeg << " W " << Cf::kW << " tick " << k << ": register error " << err_reg
                    << " LSB > bound " << c.bound_lsb;
      return r;
    }
    in.tick = true;
    e.clock(in);
    in.tick = false;
    // wait for the sample, then for the update to finish
    for (int cyc = 0; cyc < Eng::kChunks + 2; ++cyc) {
      auto o = e.outputs();
      if (o.sample_valid) {
        const f128 x = horner128(seg.coef[0], f128(double(k)) * f128(h)) * sout;
        const double err_out = std::fabs(to_d(f128(double(traj::sext(o.sample[0], Eng::kOutWidth))) - x));
        r.worst_out = std::max(r.worst_out, err_out);
        if (err_out > 0.5 + c.bound_lsb + eval_slack) {
          ADD_FAILURE() << "deg " << Cf::kDeg << " W " << Cf::kW << " tick " << k << ": output error " << err_out
                        << " LSB > 0.5 + bound " << c.bound_lsb;
          return r;
        }
      }
      e.clock(in);
    }
    ++k;
  }
  return r;
}

template <class... Cs>
void all_bounds(uint64_t seed) {
  (
      [&] {
        const auto r = check_bound_longest<Cs>(seed);
        std::printf("  degree %d width %3d guard %2d: K=%8llu bound %.4f LSB, worst register error %.4f LSB, "
                    "worst output error %.4f LSB\n",
                    Cs::kDeg, Cs::kW, Cs::kG, static_cast<unsigned long long>(r.K), r.bound, r.worst_reg,
                    r.worst_out);
      }(),
      ...);
}

}  // namespace

TEST(FdBound, HoldsAtEveryTickForLongestAcceptedSegment) {
  // out_width 32 (guard = width - 32) for widths 48/64/96/128.
  all_bounds<Cfg<1, 48, 16, 16>, Cfg<1, 64, 16, 32>, Cfg<1, 96, 32, 64>, Cfg<1, 128, 64, 96>>(11);
  all_bounds<Cfg<2, 48, 16, 16>, Cfg<2, 64, 16, 32>, Cfg<2, 96, 32, 64>, Cfg<2, 128, 64, 96>>(12);
  all_bounds<Cfg<3, 48, 16, 16>, Cfg<3, 64, 16, 32>, Cfg<3, 96, 32, 64>, Cfg<3, 128, 64, 96>>(13);
  all_bounds<Cfg<4, 48, 16, 16>, Cfg<4, 64, 16, 32>, Cfg<4, 96, 32, 64>, Cfg<4, 128, 64, 96>>(14);
  all_bounds<Cfg<5, 48, 16, 16>, Cfg<5, 64, 16, 32>, Cfg<5, 96, 32, 64>, Cfg<5, 128, 64, 96>>(15);
  all_bounds<Cfg<6, 48, 16, 16>, Cfg<6, 64, 16, 32>, Cfg<6, 96, 32, 64>, Cfg<6, 128, 64, 96>>(16);
  all_bounds<Cfg<7, 48, 16, 16>, Cfg<7, 64, 16, 32>, Cfg<7, 96, 32, 64>, Cfg<7, 128, 64, 96>>(17);
}

// Group 4, adversarial: the same cells with a polynomial built so that every
// difference register rounds by almost exactly +1/2 LSB. Its exact forward
// differences are set to D_i = n_i + 1/2 + 2^-10 (random integers n_i, in
// register LSB; the coefficients solved from D_i = 2^(F+G) sum_(j>=i) c_j h^j
// i! S(j,i) from i = N down, each rounded to double with the rounding carried
// into the next), with h = 2^-13 and a dyadic start (e0 = 0). Round to nearest
// then gives e_i = 1/2 - 2^-10 (checked from an exact difference table), and
// the error E_k = sum_i e_i C(k,i) reaches (1 - 2^-9) Q(K) at the end state.
// The exact target is stepped in integers (everything is dyadic), so the error
// at every tick is exact. Each cell must stay within the bound and come within
// 0.8 of it: a bound 0.8x as large would be violated, so the check has teeth.
namespace {

struct AdvResult {
  uint64_t K;
  double e_min, e_max;
  double worst_ratio;          // max |E_k| / bound over k = 0..K (K: the end state, the next start)
  double worst_ratio_samples;  // the same over the K emitted samples, k < K
  double worst_out;            // output error, LSB
};

long long stirling2(int j, int i) {  // S(j, i), j, i <= 7
  if (j == 0 && i == 0) return 1;
  if (j == 0 || i == 0) return 0;
  return i * stirling2(j - 1, i) + stirling2(j - 1, i - 1);
}

mpq_class exact_q(double v) {
  mpq_class q;
  mpq_set_d(q.get_mpq_t(), v);
  return q;
}

template <class Cf>
AdvResult check_bound_adversarial(uint64_t seed) {
  constexpr int A = 1, N = Cf::kDeg, G = Cf::kG;
  using Eng = traj::FdEngine<A, N, Cf::kW, Cf::kC, G>;
  const Format f = fmt(A, N, Cf::kW, Cf::kC, G, 8);
  Compiler comp(f);
  const uint64_t K = std::min<uint64_t>(Compiler::longest_segment(N, G, f.tol_lsb), f.max_ticks);
  const double h = std::ldexp(1.0, -13);
  const mpq_class hq = exact_q(h);
  const mpq_class S(mpz_class(1) << (f.frac_bits + G));
  const mpq_class eps(1, 1024);
  std::mt19937_64 rng(seed);
  const long long nmax = 1LL << (f.out_width() - 4);
  std::uniform_int_distribution<long long> U(-nmax, nmax);
  std::vector<double> c(N + 1);
  std::vector<mpq_class> cq(N + 1);
  c[0] = std::ldexp(1.0, f.out_width() - 3 - f.frac_bits);  // a quarter of the range, exact in registers
  cq[0] = exact_q(c[0]);
  mpz_class fact = 1;
  for (int i = N; i >= 1; --i) {
    fact = 1;
    for (int t = 2; t <= i; ++t) fact *= t;
    mpq_class hi = 1;
    for (int t = 0; t < i; ++t) hi *= hq;
    mpq_class rest = 0;  // what the higher coefficients (already rounded) put into D_i
    for (int j = i + 1; j <= N; ++j) {
      mpq_class hj = 1;
      for (int t = 0; t < j; ++t) hj *= hq;
      rest += cq[j] * hj * mpq_class(fact) * mpq_class(static_cast<long>(stirling2(j, i)));
    }
    const mpq_class target = mpq_class(static_cast<long>(U(rng))) + mpq_class(1, 2) + eps;
    const mpq_class ci = (target - S * rest) / (S * hi * mpq_class(fact));
    c[i] = ci.get_d();
    cq[i] = exact_q(c[i]);
  }
  PolySegment seg;
  seg.h = h;
  seg.ticks = K;
  seg.coef.push_back(c);
  const Compiled cc = comp.compile(seg);
  EXPECT_EQ(cc.carried_lsb, 0.0);

  // Exact differences of q(t) = 2^(F+G) x(t) + 2^(G-1) from q(m h), m = 0..N.
  const mpq_class bias(mpz_class(1) << (G - 1));
  std::vector<mpq_class> y(N + 1), Dq(N + 1);
  for (int m = 0; m <= N; ++m) {
    mpq_class v = 0;
    const mpq_class t = hq * m;
    for (int j = N; j >= 0; --j) v = v * t + cq[j];
    y[m] = v * S + bias;
  }
  Dq[0] = y[0];
  for (int i = 1; i <= N; ++i) {
    for (int m = 0; m + i <= N; ++m) y[m] = y[m + 1] - y[m];
    Dq[i] = y[0];
  }
  AdvResult r{K, 1, 0, 0, 0, 0};
  for (int i = 1; i <= N; ++i) {
    const double ei = mpq_class(mpq_class(cc.regs[0][i]) - Dq[i]).get_d();
    r.e_min = std::min(r.e_min, ei);
    r.e_max = std::max(r.e_max, ei);
  }
  EXPECT_GT(r.e_min, 0.5 - 1.0 / 512) << "deg " << N << " W " << Cf::kW << ": rounding errors not all near +1/2";
  EXPECT_LE(r.e_max, 0.5);
  EXPECT_EQ(mpq_class(cc.regs[0][0]), Dq[0]);  // e0 = 0

  // Integers: Q_i = D_i 2^Z (all D_i are dyadic), stepped exactly.
  unsigned long Z = 0;
  for (int i = 0; i <= N; ++i) {
    Dq[i].canonicalize();
    const mpz_class& den = Dq[i].get_den();
    EXPECT_EQ(mpz_popcount(den.get_mpz_t()), 1u);
    Z = std::max<unsigned long>(Z, mpz_sizeinbase(den.get_mpz_t(), 2) - 1);
  }
  std::vector<mpz_class> Q(N + 1);
  for (int i = 0; i <= N; ++i) {
    mpq_class v = Dq[i] * mpq_class(mpz_class(1) << Z);
    v.canonicalize();
    Q[i] = v.get_num();
  }
  // The limit is the compiler's stated bound (bound_lsb, output LSB) in the
  // same scaled integer units, floored (the errors are integers there); it
  // must agree with Q(K) = 1/2 sum C(K,i) computed here.
  mpq_class stated = exact_q(cc.bound_lsb) * mpq_class(mpz_class(1) << (G + Z));
  const mpz_class bound_reg = stated.get_num() / stated.get_den();  // floor (stated >= 0)
  const mpz_class half_out = mpz_class(1) << (G - 1 + Z);             // 1/2 output LSB, scaled
  stated += mpq_class(half_out);
  const mpz_class bound_out = stated.get_num() / stated.get_den();
  mpz_class qk2 = 0;  // 2 Q(K) = sum C(K, i), register LSB
  for (int i = 1; i <= N; ++i) qk2 += traj::fd::binom(K, i);
  EXPECT_NEAR(cc.bound_lsb, std::ldexp(qk2.get_d(), -(G + 1)), 1e-12 * cc.bound_lsb);

  Eng e;
  typename Eng::In in;
  for (uint64_t w : comp.words(cc)) {
    in.tvalid = true;
    in.tdata = w;
    while (!e.outputs().tready) e.clock(typename Eng::In{});
    e.clock(in);
  }
  in.tvalid = false;
  mpz_class err;
  for (uint64_t k = 0; k <= K; ++k) {
    // register error at tick k (r0 before the k-th update; k = K: the end state)
    err = (traj::test::to_mpz_signed(e.reg(0, 0), Cf::kW) << Z) - Q[0];
    if (mpz_cmpabs(err.get_mpz_t(), bound_reg.get_mpz_t()) > 0) {
      ADD_FAILURE() << "deg " << N << " W " << Cf::kW << " tick " << k << ": register error "
                    << mpq_class(mpq_class(err) / mpq_class(bound_reg)).get_d() << " x the stated bound "
                    << cc.bound_lsb << " LSB";
      return r;
    }
    const double ratio = std::fabs(mpq_class(mpq_class(err) / mpq_class(bound_reg)).get_d());
    r.worst_ratio = std::max(r.worst_ratio, ratio);
    if (k == K) break;
    r.worst_ratio_samples = std::max(r.worst_ratio_samples, ratio);
    in.tick = true;
    e.clock(in);
    in.tick = false;
    for (int cyc = 0; cyc < Eng::kChunks + 2; ++cyc) {
      const auto o = e.outputs();
      if (o.sample_valid) {
        // sample - x(kh) 2^F, scaled by 2^(G+Z): sample 2^(G+Z) - (Q_0 - 2^(G-1+Z))
        const mpz_class oe =
            (traj::test::to_mpz_signed(o.sample[0], Eng::kOutWidth) << (G + Z)) - Q[0] + half_out;
        if (mpz_cmpabs(oe.get_mpz_t(), bound_out.get_mpz_t()) > 0) {
          ADD_FAILURE() << "deg " << N << " W " << Cf::kW << " tick " << k << ": output error above 1/2 + bound";
          return r;
        }
        r.worst_out = std::max(
            r.worst_out, std::fabs(mpq_class(mpq_class(oe) / mpq_class(mpz_class(1) << (G + Z))).get_d()));
      }
      e.clock(in);
    }
    for (int i = 0; i < N; ++i) Q[i] += Q[i + 1];
  }
  EXPECT_GT(r.worst_ratio, 0.8) << "deg " << N << " W " << Cf::kW << ": the adversarial case does not reach the bound";
  return r;
}

template <class... Cs>
void all_adversarial(uint64_t seed) {
  (
      [&] {
        const auto r = check_bound_adversarial<Cs>(seed);
        std::printf("  degree %d width %3d guard %2d: K=%8llu e_i in [%.5f, %.5f] LSB, register error up to "
                    "%.4f x bound (end state), %.4f x over the samples; output error up to %.4f LSB\n",
                    Cs::kDeg, Cs::kW, Cs::kG, static_cast<unsigned long long>(r.K), r.e_min, r.e_max, r.worst_ratio,
                    r.worst_ratio_samples, r.worst_out);
      }(),
      ...);
}

}  // namespace

TEST(FdBound, AdversarialRoundingReachesTheBound) {
  all_adversarial<Cfg<1, 48, 16, 16>, Cfg<1, 64, 16, 32>, Cfg<1, 96, 32, 64>, Cfg<1, 128, 64, 96>>(21);
  all_adversarial<Cfg<2, 48, 16, 16>, Cfg<2, 64, 16, 32>, Cfg<2, 96, 32, 64>, Cfg<2, 128, 64, 96>>(22);
  all_adversarial<Cfg<3, 48, 16, 16>, Cfg<3, 64, 16, 32>, Cfg<3, 96, 32, 64>, Cfg<3, 128, 64, 96>>(23);
  all_adversarial<Cfg<4, 48, 16, 16>, Cfg<4, 64, 16, 32>, Cfg<4, 96, 32, 64>, Cfg<4, 128, 64, 96>>(24);
  all_adversarial<Cfg<5, 48, 16, 16>, Cfg<5, 64, 16, 32>, Cfg<5, 96, 32, 64>, Cfg<5, 128, 64, 96>>(25);
  all_adversarial<Cfg<6, 48, 16, 16>, Cfg<6, 64, 16, 32>, Cfg<6, 96, 32, 64>, Cfg<6, 128, 64, 96>>(26);
  all_adversarial<Cfg<7, 48, 16, 16>, Cfg<7, 64, 16, 32>, Cfg<7, 96, 32, 64>, Cfg<7, 128, 64, 96>>(27);
}

TEST(FdBound, LongestSegmentIsTight) {
  // K_max from the compiler: K_max accepted, K_max + 1 refused with a message
  // that says what would fit. Independent check of the bound arithmetic: the
  // refusal happens exactly where 1/2 sum C(K,i) crosses tol/2 * 2^G, computed
  // here in long double.
  for (int deg = 1; deg <= 7; ++deg) {
    const int G = 32;
    Format f = fmt(1, deg, 64, 16, G, 0);
    f.max_ticks = 0xffffffffu;
    Compiler comp(f);
    const uint64_t K = Compiler::longest_segment(deg, G, f.tol_lsb);
    auto sumC = [&](uint64_t k) {
      long double s = 0, c = 1;
      for (int i = 1; i <= deg; ++i) {
        c = c * (long double)(k - i + 1) / i;
        s += c;
      }
      return s;
    };
    const long double lim = 0.5L * std::ldexp(1.0L, G);
    EXPECT_LE(sumC(K), lim) << deg;
    EXPECT_GT(sumC(K + 1), lim) << deg;
    PolySegment seg{{{1.0}}, 1e-3, K};
    if (K <= f.max_ticks) {
      EXPECT_NO_THROW(comp.compile(seg));
    }
    seg.ticks = K + 1;
    try {
      comp.compile(seg);
      ADD_FAILURE() << "K_max+1 accepted at degree " << deg;
    } catch (const CompileError& e) {
      EXPECT_NE(std::string(e.what()).find("at most K=" + std::to_string(K)), std::string::npos) << e.what();
    }
  }
}

// ---------------------------------------------------------------------------
// Group 5: 100,000 chained segments never drift.
// ---------------------------------------------------------------------------
TEST(FdChain, HundredThousandSegmentsNoDrift) {
  constexpr int A = 1, D = 3, W = 64, C = 16, G = 32;
  using Eng = traj::FdEngine<A, D, W, C, G>;
  Format f = fmt(A, D, W, C, G, 12);
  Compiler comp(f);
  std::mt19937_64 rng(424242);
  std::uniform_int_distribution<uint64_t> Kd(1, 64);
  const double h = 1e-3;
  double x0 = 100.0;
  Compiled prev;
  bool have_prev = false;
  Eng e;
  typename Eng::In in;
  uint64_t samples = 0;
  std::vector<double> last_coef;
  uint64_t last_K = 0;
  double worst_end = 0;
  for (int s = 0; s < 100000; ++s) {
    PolySegment seg;
    seg.h = h;
    seg.ticks = Kd(rng);
    const double T = seg.ticks * h;
    seg.coef.push_back(random_poly(rng, D, T, x0, 50.0));
    const Compiled c = comp.compile(seg, have_prev ? &prev.end : nullptr, "segment " + std::to_string(s));
    // stream it into the model, tick through it
    for (uint64_t w : comp.words(c)) {
      in.tvalid = true;
      in.tdata = w;
      while (!e.outputs().tready) e.clock(typename Eng::In{});
      e.clock(in);
    }
    in.tvalid = false;
    for (uint64_t k = 0; k < c.ticks; ++k) {
      in.tick = true;
      e.clock(in);
      in.tick = false;
      for (int cyc = 0; cyc < Eng::kChunks + 1; ++cyc) {
        if (e.outputs().sample_valid) {
          ++samples;
          ASSERT_EQ(traj::test::to_mpz_signed(e.outputs().sample[0], Eng::kOutWidth), comp.sample_at(c, 0, k))
              << "segment " << s << " tick " << k;
        }
        e.clock(in);
      }
    }
    // every segment's end is within its own Q(K) of the exact end
    const f128 exact_end = horner128(seg.coef[0], f128(T)) * f128(std::ldexp(1.0, f.frac_bits + G)) +
                           f128(std::ldexp(1.0, G - 1));
    const double end_err = std::fabs(to_d((mpz_to_f128(c.end[0]) - exact_end) / f128(std::ldexp(1.0, G))));
    worst_end = std::max(worst_end, end_err / comp.quant_bound_lsb(c.ticks));
    ASSERT_LE(end_err, comp.quant_bound_lsb(c.ticks) + 1e-9) << "segment " << s;
    prev = c;
    have_prev = true;
    x0 = to_d(horner128(seg.coef[0], f128(T)));
    last_coef = seg.coef[0];
    last_K = c.ticks;
  }
  // final state in the model == host prediction, and within one segment's bound
  EXPECT_EQ(traj::test::to_mpz_signed(e.reg(0, 0), W), prev.end[0]);
  const double final_err =
      std::fabs(to_d((mpz_to_f128(prev.end[0]) -
                      (f128(x0) * f128(std::ldexp(1.0, f.frac_bits + G)) + f128(std::ldexp(1.0, G - 1)))) /
                     f128(std::ldexp(1.0, G))));
  std::printf("  %llu samples; final position error %.3g LSB, one segment's bound %.3g LSB; "
              "worst end error / own bound %.3f\n",
              static_cast<unsigned long long>(samples), final_err, comp.quant_bound_lsb(last_K), worst_end);
  EXPECT_LE(final_err, comp.quant_bound_lsb(last_K) + 1e-6);
}

// ---------------------------------------------------------------------------
// The compiler refuses bad segments with a message naming what and where.
// ---------------------------------------------------------------------------
TEST(FdCompiler, RefusesBadInput) {
  Format f = fmt(2, 3, 64, 16, 32, 8);
  Compiler comp(f);
  auto msg = [&](PolySegment s, const std::vector<mpz_class>* start = nullptr) -> std::string {
    try {
      comp.compile(s, start, "seg 7");
    } catch (const CompileError& e) {
      return e.what();
    }
    return "";
  };
  PolySegment ok{{{1.0, 2.0}, {0.0}}, 1e-3, 100};
  EXPECT_EQ(msg(ok), "");
  auto s = ok;
  s.coef[1] = {0.0, NAN};
  EXPECT_NE(msg(s).find("seg 7: axis 1 coefficient c1"), std::string::npos) << msg(s);
  s = ok;
  s.coef[0][0] = INFINITY;
  EXPECT_NE(msg(s).find("not finite"), std::string::npos);
  s = ok;
  s.h = 0;
  EXPECT_NE(msg(s).find("tick period"), std::string::npos);
  s = ok;
  s.h = NAN;
  EXPECT_NE(msg(s).find("tick period"), std::string::npos);
  s = ok;
  s.ticks = 0;
  EXPECT_NE(msg(s).find("K=0"), std::string::npos);
  s = ok;
  s.ticks = 100000;
  EXPECT_NE(msg(s).find("split into segments of at most K="), std::string::npos) << msg(s);
  s = ok;
  s.coef.pop_back();
  EXPECT_NE(msg(s).find("axes"), std::string::npos);
  s = ok;
  s.coef[0] = {1, 2, 3, 4, 5};
  EXPECT_NE(msg(s).find("degree"), std::string::npos);
  s = ok;
  s.coef[0] = {1e6};  // 2^(32-1-8) = 8.4e6 units: 1e6 fits
  EXPECT_EQ(msg(s), "");
  s.coef[0] = {1e7};
  EXPECT_NE(msg(s).find("output range"), std::string::npos) << msg(s);
  // a start state that is not where the path is: refused, not a jump
  const Compiled c = comp.compile(ok);
  std::vector<mpz_class> start = c.end;
  start[0] += mpz_class(1) << 40;
  EXPECT_NE(msg(ok, &start).find("not continuous"), std::string::npos);
  // formats
  Format bad = f;
  bad.width = 70;
  EXPECT_THROW(Compiler{bad}, CompileError);
  bad = f;
  bad.degree = 8;
  EXPECT_THROW(Compiler{bad}, CompileError);
  bad = f;
  bad.tol_lsb = NAN;
  EXPECT_THROW(Compiler{bad}, CompileError);
}
