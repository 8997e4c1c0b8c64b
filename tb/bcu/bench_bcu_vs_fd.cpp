// SPDX-License-Identifier: Apache-2.0
// Benchmark program (prints figures, never fails on a slow machine):
// BCU generator vs forward differences (FD) for a 3-axis cubic Bezier at
// K = 4096 ticks (d = 12), output LSB 2^-16 (units of the input, e.g. mm),
// control values in [-1000, 1000].
//
// Every figure comes from the real models:
//   * FD : traj::fd::Compiler (exact GMP registers, its stated bound) and the
//          cycle-accurate traj_fd_engine hls model (hls/traj_fd_engine.hpp);
//   * BCU: traj::bcu::compile_segment and the traj_bcu_gen hls model
//          (hls/traj_bcu_gen.hpp);
// each model's samples are checked bit for bit against its host's exact
// prediction, and the error is measured against the EXACT value of the Bezier
// with the given (double) control points (GMP rationals), so the table's
// errors are the engines' own.
//   * cycles per sample, two figures, each the smallest uniform tick spacing
//     (bisection) at which the hls model plays the whole segment correctly
//     (no tick_err, no underrun, every sample equal to the prediction):
//       sustained: ticks may wait for the engine (one pending tick), none lost;
//       latency 2: every tick answered exactly 2 clocks later (no waiting: the
//                  worst per-sample service time);
//     driven through the models' public interface only. Also printed: the
//     models' own constants (FD: Width/ChunkWidth per update; BCU:
//     kMinTickSpacing, which includes a segment switch).
//   * bits for a 1-LSB bound: FD needs 1/2 + Q(K) <= 1 LSB, Q(K) = 1/2 sum_{i=1..3}
//     C(K,i) 2^-G: the least G (fd::Compiler::guard_bits_needed at tol = 1);
//     plus the integer bits of the range, rounded up to a buildable width
//     (a multiple of ChunkWidth 16). BCU: exact datapath, G = 0 gives
//     1/2 + 2^-(G+1) = 1 LSB.
//   * Horner in double: the software reference (3 mul + 3 add per axis),
//     error vs exact and ns per sample (host timing, varies run to run).
// usage: bench_bcu_vs_fd [seed]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <gmpxx.h>
#include <random>
#include <string>
#include <vector>

#include "bcu/bcu_compiler.hpp"
#include "bcu/chain.hpp"
#include "fd/fd_compiler.hpp"
#include "traj_bcu_gen.hpp"
#include "traj_fd_engine.hpp"

namespace bcu = traj::bcu;
namespace fd = traj::fd;
using Clock = std::chrono::steady_clock;

constexpr int kAxes = 3, kD = 12, kK = 1 << kD, kF = 16, kChunk = 16;
constexpr double kH = 1.0 / 1024;  // tick period: T = K h = 4 s, a power of two

namespace {

mpq_class exact(double x) {
  mpq_class q;
  mpq_set_d(q.get_mpq_t(), x);
  return q;
}

// Exact x(j/K) 2^F per axis and sample (the reference for every engine).
std::vector<std::vector<mpq_class>> exact_reference(const bcu::Controls& b) {
  std::vector<std::vector<mpq_class>> ref(kK + 1, std::vector<mpq_class>(kAxes));
  const mpz_class K = kK;
  for (int j = 0; j <= kK; ++j) {
    const mpz_class jj = j, kj = K - jj;
    for (int a = 0; a < kAxes; ++a) {
      mpq_class n = mpq_class(kj * kj * kj) * exact(b(a, 0)) + mpq_class(3 * kj * kj * jj) * exact(b(a, 1)) +
                    mpq_class(3 * kj * jj * jj) * exact(b(a, 2)) + mpq_class(jj * jj * jj) * exact(b(a, 3));
      n /= mpq_class(K * K * K);
      n *= mpq_class(mpz_class(1) << kF);
      ref[j][a] = n;
    }
  }
  return ref;
}

double max_err(const std::vector<std::vector<int64_t>>& s, const std::vector<std::vector<mpq_class>>& ref) {
  double w = 0;
  for (size_t j = 0; j < s.size(); ++j)
    for (int a = 0; a < kAxes; ++a) w = std::max(w, std::fabs(mpq_class(mpq_class(s[j][a]) - ref[j][a]).get_d()));
  return w;
}

// Smallest S in [1, hi] with ok(S), assuming ok is monotone; checks S and S-1.
int min_spacing(int hi, const std::function<bool(int)>& ok) {
  while (!ok(hi)) hi *= 2;
  int lo = 0;  // ok(lo) false (spacing 0 = no ticks is not a spacing)
  while (hi - lo > 1) {
    const int mid = lo + (hi - lo) / 2;
    (ok(mid) ? hi : lo) = mid;
  }
  return hi;
}

// ---------------------------------------------------------------------------
// FD: fd::Compiler + the traj_fd_engine hls model.
// ---------------------------------------------------------------------------
struct Row {
  std::string name;
  int guard = 0, width = 0, out_bits = 0;
  double err = 0, bound = 0;
  int cycles = 0;        // measured: smallest uniform tick spacing, no tick lost
  int cycles_l2 = 0;     // measured: smallest uniform tick spacing with latency 2 throughout
  std::string spec;      // the model's own timing constant
  double range = 0;      // |x| the format holds, units
};

template <int W, int G>
Row run_fd(const bcu::Controls& b, double tol, const std::vector<std::vector<mpq_class>>& ref) {
  using Eng = traj::FdEngine<kAxes, 3, W, kChunk, G>;
  fd::Format f{kAxes, 3, W, kChunk, G, kF};
  f.tol_lsb = tol;
  const fd::Compiler comp(f);
  const fd::Compiled c = comp.compile(bcu::fd_poly_of_bezier(b, kK, kH), nullptr, "bench");
  const std::vector<uint64_t> words = comp.words(c);
  std::vector<std::vector<int64_t>> pred(kK + 1, std::vector<int64_t>(kAxes));
  for (int k = 0; k <= kK; ++k)
    for (int a = 0; a < kAxes; ++a) pred[k][a] = comp.sample_at(c, a, k).get_si();

  // Play the segment with ticks every S cycles (public interface only).
  std::vector<std::vector<int64_t>> got;
  bool need_l2 = false;
  auto play = [&](int S) {
    Eng e;
    got.clear();
    size_t wi = 0;
    uint64_t next = ~0ull, last_tick = 0;
    int issued = 0;
    for (uint64_t cyc = 0; got.size() < size_t(kK) && cyc < uint64_t(kK + 8) * S + 10000; ++cyc) {
      const auto o = e.outputs();
      if (o.tick_err || o.underrun) return false;
      if (o.sample_valid) {
        if (need_l2 && cyc != last_tick + 2) return false;
        std::vector<int64_t> v;
        for (int a = 0; a < kAxes; ++a) v.push_back(static_cast<int64_t>(traj::sext(o.sample[a], Eng::kOutWidth)));
        if (v != pred[got.size()]) return false;
        got.push_back(v);
      }
      typename Eng::In in;
      in.tvalid = wi < words.size();
      in.tdata = in.tvalid ? words[wi] : 0;
      if (next == ~0ull && wi == words.size()) next = cyc + 1;  // loaded
      in.tick = cyc == next && issued < kK;
      if (in.tick) {
        ++issued;
        next += S;
        last_tick = cyc;
      }
      if (in.tvalid && o.tready) ++wi;
      e.clock(in);
    }
    return got.size() == size_t(kK);
  };
  Row r;
  r.guard = G;
  r.width = W;
  r.out_bits = W - G;
  r.range = std::ldexp(1.0, W - G - 1 - kF);
  need_l2 = true;
  r.cycles_l2 = min_spacing(Eng::kChunks, play);
  need_l2 = false;
  r.cycles = min_spacing(Eng::kChunks, play);
  play(r.cycles);
  got.push_back(pred[kK]);  // the end sample (the next segment's first), from the exact prediction
  r.err = max_err(got, ref);
  r.bound = 0.5 + c.bound_lsb;
  r.spec = std::to_string(Eng::kChunks) + " (Width/ChunkWidth per update)";
  return r;
}

// ---------------------------------------------------------------------------
// BCU: traj::bcu + the traj_bcu_gen hls model.
// ---------------------------------------------------------------------------
template <int Ctrl, int G, int Out>
Row run_bcu(const bcu::Controls& b, const std::vector<std::vector<mpq_class>>& ref) {
  using Gen = traj::BcuGen<kAxes, kChunk, Ctrl, G, Out, kD>;
  bcu::Format f{kAxes, kChunk, Ctrl, G, Out, kD, kF};
  const bcu::Segment seg = bcu::compile_segment(b, kD, f);
  std::vector<std::vector<int64_t>> got;
  bool need_l2 = false;
  // Ticks every S cycles from a minimum spacing after the last word (the
  // segment is then ready whatever the schedule); K samples, then one
  // underrun tick for the end value.
  auto play = [&](int S) {
    Gen g;
    got.clear();
    size_t wi = 0;
    uint64_t next = ~0ull, last_tick = 0;
    int issued = 0;
    for (uint64_t cyc = 0; got.size() < size_t(kK) + 1 && cyc < uint64_t(kK + 8) * S + 100000; ++cyc) {
      if (g.tick_err()) return false;
      if (g.sample_valid()) {
        if (need_l2 && cyc != last_tick + 2) return false;
        if (g.underrun() != (got.size() == size_t(kK))) return false;
        std::vector<int64_t> v;
        for (int a = 0; a < kAxes; ++a) v.push_back(g.sample(a));
        if (v != seg.samples[got.size()]) return false;
        got.push_back(v);
      } else if (g.underrun()) {
        return false;
      }
      typename Gen::In in;
      in.tvalid = wi < seg.words.size();
      in.tdata = in.tvalid ? seg.words[wi] : 0;
      if (next == ~0ull && wi == seg.words.size()) next = cyc + Gen::kMinTickSpacing;
      in.tick = cyc == next && issued <= kK;
      if (in.tick) {
        ++issued;
        next += S;
        last_tick = cyc;
      }
      if (in.tvalid && g.tready()) ++wi;
      g.clock(in);
    }
    return got.size() == size_t(kK) + 1;
  };
  Row r;
  r.guard = G;
  r.width = f.words_per_value() * kChunk;
  r.out_bits = Ctrl - G + (G > 0);
  r.range = std::ldexp(1.0, Ctrl - 1 - G - kF);
  need_l2 = true;
  r.cycles_l2 = min_spacing(std::max(1, Gen::kMinTickSpacing / 4), play);
  need_l2 = false;
  r.cycles = min_spacing(std::max(1, Gen::kMinTickSpacing / 4), play);
  play(r.cycles);
  r.err = max_err(got, ref);
  r.bound = 0;
  for (int j = 0; j <= kK; ++j)
    for (int a = 0; a < kAxes; ++a) r.bound = std::max(r.bound, seg.exact_bound_lsb(a, j));
  r.spec = "kMinTickSpacing " + std::to_string(Gen::kMinTickSpacing) + " (incl. a segment switch)";
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const uint64_t seed = argc > 1 ? std::strtoull(argv[1], nullptr, 0) : 1;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1000.0, 1000.0);
  bcu::Controls b(kAxes, 4);
  for (int a = 0; a < kAxes; ++a)
    for (int i = 0; i < 4; ++i) b(a, i) = U(rng);
  std::printf("bench_bcu_vs_fd: 3-axis cubic Bezier, control values in [-1000, 1000], K = %d (d = %d), "
              "output LSB 2^-%d, ChunkWidth %d, seed %llu\n", kK, kD, kF, kChunk, (unsigned long long)seed);
  std::printf("errors vs the exact Bezier of the (double) control points (GMP), in output LSB\n\n");
  const auto ref = exact_reference(b);

  // --- bits for a 1-LSB bound ----------------------------------------------
  const mpz_class sumC = fd::Compiler::quant_bound_x2(3, kK);
  const int G1 = fd::Compiler::guard_bits_needed(3, kK, 1.0);  // 1/2 + Q(K) <= 1
  const int ibits = 1 + static_cast<int>(std::ceil(std::log2(1000.0 * 65536 + 1)));  // |x| <= 1000: 27 bits signed
  const int wmin = ibits + G1, wbuild = (wmin + kChunk - 1) / kChunk * kChunk;
  std::printf("1-LSB bound (1/2 LSB output rounding + at most 1/2 LSB from the rest):\n");
  std::printf("  FD : sum_{i=1..3} C(%d,i) = %s = 2^%.2f -> Q(K) <= 1/2 needs G >= %d guard bits in every register;\n",
              kK, sumC.get_str().c_str(), std::log2(sumC.get_d()), G1);
  std::printf("       |x| <= 1000 needs %d integer bits: %d bits, buildable (multiple of ChunkWidth %d): Width %d,\n",
              ibits, wmin, kChunk, wbuild);
  std::printf("       which at G = %d leaves %d output bits (|x| < %g units; the core's G = 32 keeps 32 bits, |x| < %g)\n",
              G1, wbuild - G1, std::ldexp(1.0, wbuild - G1 - 1 - kF), std::ldexp(1.0, 64 - 32 - 1 - kF));
  std::printf("  BCU: exact datapath, G = 0 -> 1/2 + 2^-1 = 1 LSB; CtrlWidth %d (sign + %d integer bits),\n"
              "       the datapath grows 3 bits per level: W = CtrlWidth + 3*MaxDepth = %d bits\n\n",
              ibits + 1, ibits, ibits + 1 + 3 * kD);

  std::vector<Row> rows;
  {
    Row r = run_fd<64, 34>(b, 1.0, ref);
    r.name = "FD, W 64, G 34 (tol 1: the 1-LSB setting)";
    rows.push_back(r);
  }
  {
    Row r = run_fd<64, 32>(b, 3.0, ref);
    r.name = "FD, W 64, G 32 (the core's FD format; tol 3)";
    rows.push_back(r);
  }
  {
    Row r = run_fd<48, 20>(b, 16384.0, ref);
    r.name = "FD, W 48, G 20 (tol 2^14)";
    rows.push_back(r);
  }
  {
    Row r = run_bcu<28, 0, 28>(b, ref);
    r.name = "BCU, CtrlWidth 28, G 0 (the 1-LSB setting)";
    rows.push_back(r);
  }
  {
    Row r = run_bcu<40, 9, 32>(b, ref);
    r.name = "BCU, CtrlWidth 40, G 9 (the core's BCU format)";
    rows.push_back(r);
  }

  // --- Horner in double -------------------------------------------------------
  double pc[kAxes][4];
  for (int a = 0; a < kAxes; ++a) {
    pc[a][0] = b(a, 0);
    pc[a][1] = 3 * (b(a, 1) - b(a, 0));
    pc[a][2] = 3 * (b(a, 0) - 2 * b(a, 1) + b(a, 2));
    pc[a][3] = b(a, 3) - 3 * b(a, 2) + 3 * b(a, 1) - b(a, 0);
  }
  volatile double sink = 0;
  const int reps = 400;
  const auto h0 = Clock::now();
  for (int r = 0; r < reps; ++r)
    for (int j = 0; j <= kK; ++j) {
      const double t = double(j) / kK;
      for (int a = 0; a < kAxes; ++a) sink = sink + (((pc[a][3] * t + pc[a][2]) * t + pc[a][1]) * t + pc[a][0]);
    }
  const double ns_horner =
      std::chrono::duration<double, std::nano>(Clock::now() - h0).count() / (double(reps) * (kK + 1));
  double e_horner = 0;
  for (int j = 0; j <= kK; ++j) {
    const double t = double(j) / kK;
    for (int a = 0; a < kAxes; ++a) {
      const double h = ((pc[a][3] * t + pc[a][2]) * t + pc[a][1]) * t + pc[a][0];
      const mpq_class d = exact(h) * mpq_class(mpz_class(1) << kF) - ref[j][a];
      e_horner = std::max(e_horner, std::fabs(d.get_d()));
    }
  }

  std::printf("| engine (hls model + host compiler) | guard bits | register / datapath bits | output bits (range) | "
              "additions / sample / axis | max error [LSB] | bound [LSB] | cycles / sample: sustained, latency 2 (measured) | "
              "model constant |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    const bool is_bcu = r.name.rfind("BCU", 0) == 0;
    char adds[64];
    // BCU generator: d scaled subdivisions (6 additions each) down the left
    // spine, 9 additions to form S0, D1, D2, D3 (rounding folded into S0),
    // then 3 additions per sample (rtl/traj_bcu_gen.sv, rtl/README.md)
    if (is_bcu) std::snprintf(adds, sizeof adds, "3 + (6d + 9)/K = %.3f (rounding folded in)", 3.0 + (6.0 * 12 + 9) / kK);
    else std::snprintf(adds, sizeof adds, "3 + 0 (rounding is the +1/2 in r[0])");
    std::printf("| %s | %d | %d%s | %d (|x| < %g) | %s | %.4f | %.4f | %d, %d | %s |\n", r.name.c_str(), r.guard,
                r.width, is_bcu ? " (4 lanes per axis in BRAM; 4 registers of W+1 bits per axis)" : " x 4 registers per axis", r.out_bits,
                r.range, adds, r.err, r.bound, r.cycles, r.cycles_l2, r.spec.c_str());
  }
  std::printf("| Horner, double (software reference) | - | 53-bit mantissa | - | 3 mul + 3 add | %.2e | - | %.2f ns "
              "(host) | - |\n", e_horner, ns_horner);
  std::printf("\n(bounds vs the exact polynomial of each engine's input: FD 1/2 + |e0| + Q(K) from fd::Compiler, BCU\n"
              " max_j Segment::exact_bound_lsb; the FD power basis is converted in double, which moves the FD\n"
              " polynomial by < 256 eps max|b| 2^F = %.1e LSB from the Bezier. sink %g)\n",
              256 * 1.1102230246251565e-16 * 1000 * 65536, double(sink) * 0);
  return 0;
}
