// SPDX-License-Identifier: Apache-2.0
// Exact chaining across segment kinds through the host library
// (traj::bcu::MixedChain, bcu/chain.hpp) and the core model (hls/traj_core.hpp):
//   * FdToBcuHandOffExactRationals: every FD -> BCU hand-off, for several
//     (Gf, Gb) pairs, checked step by step in exact rationals (GMP): the first
//     BCU sample is the FD end sample; the start offset delta is exactly
//     Delta + eps_E - phi (Gb > 0; + 1/2 for Gb = 0) with |eps_E| <= Q(K) and
//     0 <= phi <= 2^-Gb - 2^-Gf, so |delta| <= Q(K) + 2^-Gb + |Delta|; every
//     sample's exact error P/2^Gb - x 2^F is exactly B0 delta + sum_{i>=1} B_i rho_i
//     with |rho_i| <= 2^-(Gb+1), and |s - x 2^F| <= 1/2 + B0 |delta| + (1 - B0) 2^-(Gb+1);
//   * BcuToFdHandOffExactRationals: the first FD sample is the BCU end value,
//     and the FD compiler's carried error is within 2^-(Gb+1) + |Delta| (+ 2^-Gf);
//   * AlternatingKindsManySwitchesNoDrift: a G0 path of 400 random cubic
//     pieces, kinds mostly alternating (hundreds of switches, every pair of
//     neighbouring kinds, K = 1 pieces of both kinds), through the core model:
//     every sample == the host's exact prediction, seg_done with every K-th,
//     every tick answered exactly Core::answer_clocks later (2, or the
//     time-multiplexed FD engine's pass + 2),
//     the first sample of every piece == the previous piece's end sample, every
//     sample within its stated bound of the double-precision path, and the
//     error of the last pieces no larger than that of the first (no drift);
//   * LongerPiecesAtMinTickSpacing: the same with longer pieces (d up to 7,
//     FD K up to 150). All core runs tick exactly Core::kMinTickSpacing
//     clocks apart (read from the hls header, the core's contract): every tick
//     answered on time, none lost or late at a switch;
//   * LongFdBezierIsSplitAndChainsExactly: MixedChain::add_fd_bezier splits a
//     6000-tick Bezier into FD segments the format accepts, exact joints;
//   * Refusals: a jump, incompatible formats, a missing previous segment.
// The core model is driven through its public interface only (tready,
// sample_valid, underrun, seg_done, tick_err, sample).
// Seed: env TRAJ_SEED (default 20240613), printed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <gmpxx.h>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "test_seed.hpp"
#include "bcu/chain.hpp"
#include "fd/fd_compiler.hpp"
#include "traj_core.hpp"

namespace bcu = traj::bcu;
namespace fd = traj::fd;

namespace {
#ifndef C_FDTM
#define C_FDTM 0
#endif
using Core = traj::Core<C_AXES, C_DEGREE, C_WIDTH, C_CHUNK, C_GUARD, C_CTRL, C_BGUARD, C_DEPTH, C_FDTM != 0>;
constexpr int kF = 16;
constexpr double kH = 1e-3;
const double kEps = std::numeric_limits<double>::epsilon() / 2;  // unit roundoff

uint64_t test_seed() { return traj::test::test_seed(20240613ull); }

fd::Format fd_format(int width = C_WIDTH, int guard = C_GUARD) {
  return {C_AXES, C_DEGREE, width, C_CHUNK, guard, kF};
}
bcu::Format bcu_format(int ctrl = C_CTRL, int guard = C_BGUARD, int out = Core::kOutWidth) {
  return {C_AXES, C_CHUNK, ctrl, guard, out, C_DEPTH, kF};
}

mpq_class exact(double x) {
  mpq_class q;
  mpq_set_d(q.get_mpq_t(), x);
  return q;
}
mpq_class p2(int e) {
  mpz_class one = 1;
  return e >= 0 ? mpq_class(one << e) : mpq_class(one, one << -e);
}
// Bernstein basis B_i(t), t = j/2^d, exact.
mpq_class bern(int i, int64_t j, int d) {
  const mpq_class t(mpz_class(j), mpz_class(1) << d), u = 1 - t;
  static const int C[4] = {1, 3, 3, 1};
  mpq_class r = C[i];
  for (int k = 0; k < 3 - i; ++k) r *= u;
  for (int k = 0; k < i; ++k) r *= t;
  return r;
}
// Exact value at t (seconds from the segment start) of an FD target polynomial.
mpq_class poly_at(const std::vector<double>& c, const mpq_class& t) {
  mpq_class v = 0;
  for (size_t j = c.size(); j-- > 0;) v = v * t + exact(c[j]);
  return v;
}

// A random cubic Bezier (axes x 4) starting at `start`.
bcu::Controls random_piece(std::mt19937_64& rng, const std::vector<double>& start, double step = 6.0) {
  std::uniform_real_distribution<double> st(-step, step);
  bcu::Controls b(C_AXES, 4);
  for (int a = 0; a < C_AXES; ++a) {
    b(a, 0) = start[a];
    for (int k = 1; k < 4; ++k) b(a, k) = b(a, k - 1) + st(rng);
  }
  return b;
}

}  // namespace

// ---------------------------------------------------------------------------
// FD -> BCU, step by step in exact rationals.
// ---------------------------------------------------------------------------
TEST(MixedChain, FdToBcuHandOffExactRationals) {
  std::mt19937_64 rng(test_seed());
  struct Combo {
    int fw, fg, bc, bg;
  };
  // (FD width, FD guard, BCU ctrl width, BCU guard): Gf > Gb, Gf = Gb, Gb = 0, Gb > Gf
  const Combo combos[] = {{64, 32, 40, 9}, {64, 32, 40, 1}, {64, 32, 40, 0}, {48, 9, 40, 9}, {48, 9, 44, 14}};
  int handoffs = 0;
  double worst_delta = 0;
  for (const Combo& cb : combos) {
    const fd::Format ff = fd_format(cb.fw, cb.fg);
    const bcu::Format bf = bcu_format(cb.bc, cb.bg, 40);
    const fd::Compiler fdc(ff);
    const int Gf = cb.fg, Gb = cb.bg;
    for (int rep = 0; rep < 8; ++rep) {
      std::uniform_real_distribution<double> pos(-40, 40);
      std::vector<double> s0(C_AXES);
      for (auto& x : s0) x = pos(rng);
      const bcu::Controls bfd = random_piece(rng, s0);
      const uint64_t Kf = 1 + rng() % std::min<uint64_t>(200, fd::Compiler::longest_segment(3, Gf, ff.tol_lsb));
      const fd::PolySegment ps = bcu::fd_poly_of_bezier(bfd, Kf, kH);
      const fd::Compiled c = fdc.compile(ps);
      const bcu::EndState end = bcu::end_of(c, ff);
      std::vector<double> s1(C_AXES);
      for (int a = 0; a < C_AXES; ++a) s1[a] = bfd(a, 3);
      const bcu::Controls bb = random_piece(rng, s1);
      const int d = static_cast<int>(rng() % 8);
      const bcu::Segment s = bcu::compile_segment_after(end, bb, d, bf, "hand-off");
      ++handoffs;
      const mpq_class T = exact(kH) * mpq_class(mpz_class(std::to_string(Kf)));
      const mpq_class Q(fd::Compiler::quant_bound_x2(ff.degree, Kf), mpz_class(1) << (Gf + 1));  // output LSB
      EXPECT_EQ(mpq_class(end.err_lsb), mpq_class(Q.get_d()));
      for (int a = 0; a < C_AXES; ++a) {
        const mpz_class& E = c.end[a];
        // 1. the first BCU sample IS the FD end sample
        mpz_class fd_end;
        mpz_fdiv_q_2exp(fd_end.get_mpz_t(), E.get_mpz_t(), Gf);
        ASSERT_EQ(s.samples[0][a], fd_end.get_si()) << "Gf " << Gf << " Gb " << Gb << " axis " << a;
        ASSERT_EQ(end.sample(a), fd_end.get_si());
        ASSERT_EQ(fdc.sample_at(c, a, Kf), fd_end);
        // 2. delta = Delta + eps_E - phi (+ 1/2 when Gb = 0), exactly
        const mpq_class xT = poly_at(ps.coef[a], T);                    // the FD polynomial at its end
        const mpq_class Delta = (xT - exact(bb(a, 0))) * p2(kF);        // the pieces' own joint mismatch
        const mpq_class qT = xT * p2(kF + Gf) + p2(Gf - 1);              // FD target at t = T (e0 blended out)
        const mpq_class epsE = (mpq_class(E) - qT) * p2(-Gf);            // FD end error, output LSB
        mpz_class fl;                                                    // floor(E 2^(Gb-Gf))
        if (Gb >= Gf) fl = E << (Gb - Gf);
        else mpz_fdiv_q_2exp(fl.get_mpz_t(), E.get_mpz_t(), Gf - Gb);
        const mpq_class phi = mpq_class(E) * p2(-Gf) - mpq_class(fl) * p2(-Gb);
        const mpq_class delta = mpq_class(s.ctrl[a][0]) * p2(-Gb) - exact(bb(a, 0)) * p2(kF);
        ASSERT_EQ(delta, s.offset[a]);
        ASSERT_EQ(delta, Delta + epsE - phi + (Gb == 0 ? mpq_class(1, 2) : mpq_class(0)));
        ASSERT_LE(abs(epsE), Q);
        ASSERT_GE(phi, 0);
        if (Gb >= Gf) ASSERT_EQ(phi, 0);
        else ASSERT_LE(phi, p2(-Gb) - p2(-Gf));
        // the stated bound on the offset
        ASSERT_LE(abs(delta), Q + p2(-Gb) + abs(Delta)) << "Gf " << Gf << " Gb " << Gb;
        worst_delta = std::max(worst_delta, std::fabs(delta.get_d()));
        // 3. every sample: exact error decomposition and the bound
        mpq_class rho[4];
        for (int i = 1; i < 4; ++i) {
          rho[i] = mpq_class(s.ctrl[a][i]) * p2(-Gb) - exact(bb(a, i)) * p2(kF);
          ASSERT_LE(abs(rho[i]), p2(-(Gb + 1)));
        }
        const int K = 1 << d;
        for (int j = 0; j <= K; ++j) {
          mpq_class P = 0, X = 0, B[4];
          for (int i = 0; i < 4; ++i) {
            B[i] = bern(i, j, d);
            P += B[i] * mpq_class(s.ctrl[a][i]);
            X += B[i] * exact(bb(a, i));
          }
          P *= p2(-Gb);
          X *= p2(kF);
          ASSERT_EQ(P - X, B[0] * delta + B[1] * rho[1] + B[2] * rho[2] + B[3] * rho[3]);
          const mpq_class err = abs(mpq_class(s.samples[j][a]) - X);
          ASSERT_LE(abs(mpq_class(s.samples[j][a]) - P), mpq_class(1, 2));  // one rounding, half up
          const mpq_class bound = mpq_class(1, 2) + B[0] * abs(delta) + (1 - B[0]) * p2(-(Gb + 1));
          ASSERT_LE(err, bound) << "j " << j << " axis " << a;
          // the library's double form of the bound is not below the exact one
          ASSERT_GE(mpq_class(s.exact_bound_lsb(a, j)) * (1 + mpq_class(1, 1 << 20)), bound);
        }
      }
    }
  }
  std::printf("  %d FD -> BCU hand-offs, worst |delta| %.6f LSB\n", handoffs, worst_delta);
}

// ---------------------------------------------------------------------------
// BCU -> FD, exact rationals.
// ---------------------------------------------------------------------------
TEST(MixedChain, BcuToFdHandOffExactRationals) {
  std::mt19937_64 rng(test_seed() + 1);
  struct Combo {
    int fw, fg, bc, bg;
  };
  const Combo combos[] = {{64, 32, 40, 9}, {64, 32, 40, 1}, {48, 9, 40, 9}, {48, 9, 44, 14}};
  for (const Combo& cb : combos) {
    const fd::Format ff = fd_format(cb.fw, cb.fg);
    const bcu::Format bf = bcu_format(cb.bc, cb.bg, 40);
    const fd::Compiler fdc(ff);
    const int Gf = cb.fg, Gb = cb.bg;
    for (int rep = 0; rep < 12; ++rep) {
      std::uniform_real_distribution<double> pos(-40, 40);
      std::vector<double> s0(C_AXES);
      for (auto& x : s0) x = pos(rng);
      const bcu::Controls bb = random_piece(rng, s0);
      const int d = static_cast<int>(rng() % 9);
      const bcu::Segment s = bcu::compile_segment(bb, d, bf);
      const bcu::EndState end = bcu::end_of(s);
      std::vector<double> s1(C_AXES);
      for (int a = 0; a < C_AXES; ++a) s1[a] = bb(a, 3);
      const bcu::Controls bfd = random_piece(rng, s1);
      const uint64_t Kf = 1 + rng() % std::min<uint64_t>(200, fd::Compiler::longest_segment(3, Gf, ff.tol_lsb));
      const fd::PolySegment ps = bcu::fd_poly_of_bezier(bfd, Kf, kH);
      const std::vector<mpz_class> r0 = bcu::fd_start(end, ff);
      const fd::Compiled c = fdc.compile(ps, &r0, "after BCU");
      for (int a = 0; a < C_AXES; ++a) {
        // the first FD sample IS the BCU end value round(D)
        ASSERT_EQ(fdc.sample_at(c, a, 0).get_si(), s.samples[1 << d][a]) << "Gf " << Gf << " Gb " << Gb;
        ASSERT_EQ(end.sample(a), s.samples[1 << d][a]);
        // carried error e0 = r0 - q(0), output LSB: within 2^-(Gb+1) + |Delta| (+ 2^-Gf if Gb > Gf)
        const mpq_class x0 = exact(ps.coef[a][0]);
        const mpq_class e0 = (mpq_class(r0[a]) - (x0 * p2(kF + Gf) + p2(Gf - 1))) * p2(-Gf);
        const mpq_class Delta = (exact(bb(a, 3)) - x0) * p2(kF);
        const mpq_class lim = p2(-(Gb + 1)) + abs(Delta) + (Gb > Gf ? p2(-Gf) : mpq_class(0));
        ASSERT_LE(abs(e0), lim);
        ASSERT_LE(std::fabs(e0.get_d()), c.carried_lsb + 1e-300);
      }
      // here x_fd(0) = b0 exactly (Delta = 0): the carried error is the BCU's own end rounding
      ASSERT_LE(c.carried_lsb, std::ldexp(1.0, -(Gb + 1)) + (Gb > Gf ? std::ldexp(1.0, -Gf) : 0.0));
    }
  }
}

// ---------------------------------------------------------------------------
// Through the core model.
// ---------------------------------------------------------------------------
namespace {

struct Path {
  std::vector<bcu::Controls> b;  // per piece: the Bezier the piece samples (whole curve)
  std::vector<uint64_t> k0, kc;  // FD pieces of a split curve: first tick, ticks of the whole curve
  size_t switches = 0;
};

// n pieces, kinds mostly alternating (runs of the same kind now and then), K = 1 of both kinds.
Path build(std::mt19937_64& rng, bcu::MixedChain& ch, int n, int max_d, uint64_t max_kf) {
  Path p;
  std::uniform_real_distribution<double> pos(-40, 40);
  std::vector<double> start(C_AXES);
  for (auto& x : start) x = pos(rng);
  bool kind = rng() & 1;
  for (int i = 0; i < n; ++i) {
    if (rng() % 5 != 0) kind = !kind;  // switch 4 times in 5
    const bcu::Controls b = random_piece(rng, start, 4.0);
    for (int a = 0; a < C_AXES; ++a) start[a] = b(a, 3);
    const std::string where = "piece " + std::to_string(i);
    if (kind) {
      const int d = (i % 37 == 5) ? 0 : static_cast<int>(rng() % (max_d + 1));
      ch.add_bcu(b, d, where);
      p.b.push_back(b);
      p.k0.push_back(0);
      p.kc.push_back(uint64_t(1) << d);
    } else {
      const uint64_t K = (i % 41 == 7) ? 1 : 1 + rng() % max_kf;
      ch.add_fd(bcu::fd_poly_of_bezier(b, K, kH), where);
      p.b.push_back(b);
      p.k0.push_back(0);
      p.kc.push_back(K);
    }
  }
  const auto& pc = ch.pieces();
  for (size_t i = 1; i < pc.size(); ++i) p.switches += pc[i].kind != pc[i - 1].kind;
  return p;
}

struct Played {
  std::vector<std::vector<int64_t>> samples;
  std::vector<bool> done;
  std::vector<uint64_t> latency;  // answer cycle - tick cycle
  bool tick_err = false, underrun = false;
};

// Ticks exactly `spacing` clocks apart (the core's contract: at least
// Core::kMinTickSpacing, which covers a BCU segment switch and an FD reload;
// faster ticks may reach an engine before its next segment is in flight).
Played play(const bcu::MixedChain& ch, int spacing) {
  std::vector<std::pair<uint64_t, bool>> words;
  size_t total = 0, first_len = 0;
  for (const auto& pc : ch.pieces()) {
    for (uint64_t w : pc.words) words.push_back({w, pc.kind == bcu::Kind::kBcu});
    if (!first_len) first_len = words.size();
    total += pc.ticks;
  }
  Core core;
  Played out;
  size_t wi = 0;
  uint64_t cyc = 0, start = ~0ull, next = ~0ull, last_tick = 0;
  int outstanding = 0;
  while (out.samples.size() < total) {
    if (cyc > 2000000000ull) break;
    if (core.sample_valid() || core.underrun()) {
      --outstanding;
      if (core.underrun()) out.underrun = true;
      std::vector<int64_t> v;
      for (int a = 0; a < C_AXES; ++a) v.push_back(core.sample(a));
      out.samples.push_back(v);
      out.done.push_back(core.seg_done());
      out.latency.push_back(cyc - last_tick);
    }
    out.tick_err |= core.tick_err();
    Core::In in;
    in.tvalid = wi < words.size();
    in.tdata = in.tvalid ? words[wi].first : 0;
    in.tuser = in.tvalid ? words[wi].second : false;
    // first tick a minimum spacing after the first segment has entered (it is
    // then loaded and ready whatever its kind), then every `spacing`
    if (start == ~0ull && wi >= first_len) start = next = cyc + Core::kMinTickSpacing;
    bool tick = false;
    if (cyc >= start && out.samples.size() + outstanding < total) {
      if (cyc == next) {
        tick = true;
        next += spacing;
      }
    }
    if (tick) {
      ++outstanding;
      last_tick = cyc;
    }
    in.tick = tick;
    const bool acc = core.tready(in) && in.tvalid;
    core.clock(in);
    if (acc) ++wi;
    ++cyc;
  }
  return out;
}

// Checks every sample; returns the worst error (output LSB) per piece.
std::vector<double> check(const bcu::MixedChain& ch, const Path& p, const Played& got, bool strict_latency) {
  const auto& pcs = ch.pieces();
  std::vector<double> worst(pcs.size(), 0.0);
  EXPECT_FALSE(got.tick_err);
  EXPECT_FALSE(got.underrun);
  const double lsb = std::ldexp(1.0, -kF);
  size_t n = 0;
  for (size_t i = 0; i < pcs.size(); ++i) {
    const auto& pc = pcs[i];
    if (i > 0) {
      const auto& pr = pcs[i - 1];
      EXPECT_EQ(pc.samples[0], pr.samples[pr.ticks]) << "piece " << i << " first sample != previous end sample";
    }
    const double maxb = p.b[i].cwiseAbs().maxCoeff();
    // FD: 1/2 + register bound + 256 eps max|b| 2^F for the double power basis
    // (each coefficient a sum of terms bounded by 8 max|b|, a few roundings
    // each, and the double de Casteljau reference's 8 eps max|b|); BCU: its
    // own bound_lsb (with the reference's 8 eps max|b| 2^F).
    const double fd_ref = 256 * kEps * maxb / lsb;
    for (uint64_t k = 0; k < pc.ticks; ++k, ++n) {
      if (n >= got.samples.size()) {
        ADD_FAILURE() << "too few samples";
        return worst;
      }
      EXPECT_EQ(got.samples[n], pc.samples[k]) << "piece " << i << " k " << k;
      EXPECT_EQ(got.done[n], k + 1 == pc.ticks) << "piece " << i << " k " << k;
      if (strict_latency) {
        EXPECT_EQ(got.latency[n], unsigned(Core::answer_clocks(pc.kind == bcu::Kind::kBcu, k + 1 == pc.ticks)))
            << "piece " << i << " k " << k;
      }
      const double u = double(p.k0[i] + k) / double(p.kc[i]);
      for (int a = 0; a < C_AXES; ++a) {
        const double bb[4] = {p.b[i](a, 0), p.b[i](a, 1), p.b[i](a, 2), p.b[i](a, 3)};
        const double err = std::fabs(double(pc.samples[k][a]) - bcu::de_casteljau(bb, u) / lsb);
        const double bound = pc.kind == bcu::Kind::kBcu ? pc.bcu.bound_lsb(a, static_cast<int>(k))
                                                        : pc.bound_lsb(a, k) + fd_ref;
        EXPECT_LE(err, bound) << "piece " << i << " k " << k << " axis " << a;
        worst[i] = std::max(worst[i], err);
      }
    }
    // No drift: the end sample (the next piece's first) is within the piece's
    // OWN end bound, whatever was carried in: FD 1/2 + Q(K) (the carried start
    // error is blended out to 0 at k = K), BCU 1/2 + 2^-(Gb+1) (D is rounded
    // from b3; the start offset has weight 0 at t = 1), + the double terms.
    for (int a = 0; a < C_AXES; ++a) {
      const double bb[4] = {p.b[i](a, 0), p.b[i](a, 1), p.b[i](a, 2), p.b[i](a, 3)};
      const double u = double(p.k0[i] + pc.ticks) / double(p.kc[i]);
      const double err = std::fabs(double(pc.samples[pc.ticks][a]) - bcu::de_casteljau(bb, u) / lsb);
      const double bound = pc.kind == bcu::Kind::kBcu
                               ? 0.5 + std::ldexp(1.0, -(C_BGUARD + 1)) + pc.bcu.ref_lsb
                               : 0.5 + ch.fd_compiler().quant_bound_lsb(pc.ticks) + fd_ref;
      EXPECT_LE(err, bound) << "end of piece " << i << " axis " << a;
    }
  }
  return worst;
}

}  // namespace

TEST(MixedChain, AlternatingKindsManySwitchesNoDrift) {
  std::mt19937_64 rng(test_seed() + 2);
  bcu::MixedChain ch(fd_format(), bcu_format());
  const Path p = build(rng, ch, 400, 5, 60);
  ASSERT_GE(p.switches, 250u);
  const Played got = play(ch, Core::kMinTickSpacing);
  const auto worst = check(ch, p, got, true);
  // every pair of neighbouring kinds occurs
  int pairs[2][2] = {};
  const auto& pcs = ch.pieces();
  for (size_t i = 1; i < pcs.size(); ++i) ++pairs[int(pcs[i - 1].kind)][int(pcs[i].kind)];
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 2; ++y) EXPECT_GT(pairs[x][y], 0) << x << "->" << y;
  // no drift: the worst error of the last 100 pieces is of the same size as
  // that of the first 100 (each piece within its own bound, checked above,
  // which does not depend on its position in the chain)
  double first = 0, last = 0;
  for (size_t i = 0; i < 100; ++i) first = std::max(first, worst[i]);
  for (size_t i = worst.size() - 100; i < worst.size(); ++i) last = std::max(last, worst[i]);
  // and both within the chain-independent bound 1/2 + tol (FD: |e0| + Q(K) <= tol)
  // + 2^-Gb (BCU: Q + 2^-Gb) + the double terms for |x| < 2^15 (the output range)
  const double chain_bound = 0.5 + fd_format().tol_lsb + std::ldexp(1.0, -C_BGUARD) + 256 * kEps * std::ldexp(1.0, 15 + kF);
  EXPECT_LE(first, chain_bound);
  EXPECT_LE(last, chain_bound);
  std::printf("  %zu pieces, %zu kind switches (FD->BCU %d, BCU->FD %d, FD->FD %d, BCU->BCU %d), %zu samples; "
              "worst error first 100 pieces %.4f LSB, last 100 %.4f LSB\n",
              pcs.size(), p.switches, pairs[0][1], pairs[1][0], pairs[0][0], pairs[1][1], got.samples.size(), first,
              last);
}

TEST(MixedChain, LongerPiecesAtMinTickSpacing) {
  std::mt19937_64 rng(test_seed() + 3);
  bcu::MixedChain ch(fd_format(), bcu_format());
  const Path p = build(rng, ch, 40, 7, 150);
  ASSERT_GE(p.switches, 15u);
  const Played got = play(ch, Core::kMinTickSpacing);
  check(ch, p, got, true);
  std::printf("  ticks %d clocks apart (Core::kMinTickSpacing): %zu samples, every one answered on time\n",
              Core::kMinTickSpacing, got.samples.size());
}

TEST(MixedChain, LongFdBezierIsSplitAndChainsExactly) {
  // add_fd_bezier splits a long FD curve by the format's longest segment;
  // the pieces chain exactly and follow the one Bezier.
  std::mt19937_64 rng(test_seed() + 4);
  bcu::MixedChain ch(fd_format(), bcu_format());
  std::vector<double> s0(C_AXES, 1.0);
  const bcu::Controls b0 = random_piece(rng, s0, 30.0);
  ch.add_bcu(b0, 8, "bcu");
  std::vector<double> s1(C_AXES);
  for (int a = 0; a < C_AXES; ++a) s1[a] = b0(a, 3);
  const bcu::Controls b1 = random_piece(rng, s1, 30.0);
  const uint64_t K = 6000;  // > the 2344 ticks a cubic may take at W 64 / G 32, tol 0.5
  const int n = ch.add_fd_bezier(b1, K, kH, "fd", 1);
  EXPECT_EQ(n, 3);
  Path p;
  p.b = {b0};
  p.k0 = {0};
  p.kc = {256};
  for (int i = 0; i < n; ++i) {
    p.b.push_back(b1);
    p.k0.push_back(K * i / n);
    p.kc.push_back(K);
  }
  const Played got = play(ch, Core::kMinTickSpacing);
  check(ch, p, got, true);
}

TEST(MixedChain, Refusals) {
  const bcu::Format bf = bcu_format();
  const fd::Format ff = fd_format();
  bcu::Controls b = bcu::Controls::Zero(C_AXES, 4);
  b(1, 0) = 0.001;  // 65.5 LSB away from the previous end
  const bcu::Segment s0 = bcu::compile_segment(bcu::Controls::Zero(C_AXES, 4), 3, bf);
  try {
    bcu::compile_segment_after(bcu::end_of(s0), b, 3, bf, "piece 7");
    ADD_FAILURE() << "jump accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("piece 7: axis 1 starts 65.536 LSB away"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("the path is not continuous here"), std::string::npos) << e.what();
  }
  bcu::Format other = bf;
  other.frac_bits = 12;
  EXPECT_THROW(bcu::bcu_start(bcu::end_of(s0), other), std::invalid_argument);
  try {
    bcu::MixedChain bad(ff, other);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("output LSBs differ"), std::string::npos) << e.what();
  }
  bcu::Format wide = bf;
  wide.out_width = 40;
  try {
    bcu::MixedChain bad(ff, wide);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sample widths differ"), std::string::npos) << e.what();
  }
  EXPECT_THROW(bcu::fd_start(bcu::EndState{}, ff), std::invalid_argument);
  // BCU -> FD with Gb = 0: the BCU end may be 1/2 LSB off the curve, more than tol/2
  bcu::Format g0 = bcu_format(32, 0, 32);
  bcu::Controls h = bcu::Controls::Zero(C_AXES, 4);
  h(0, 3) = std::ldexp(0.5, -kF);  // exactly half an LSB: rounds away to 1 LSB
  const bcu::Segment sg = bcu::compile_segment(h, 2, g0);
  bcu::Controls nxt = bcu::Controls::Zero(C_AXES, 4);
  for (int k = 0; k < 4; ++k) nxt(0, k) = h(0, 3);
  const std::vector<mpz_class> r0 = bcu::fd_start(bcu::end_of(sg), ff);
  EXPECT_THROW(fd::Compiler(ff).compile(bcu::fd_poly_of_bezier(nxt, 10, kH), &r0), fd::CompileError);
}
