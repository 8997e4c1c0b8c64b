// Benchmark program (prints figures, never fails on a slow machine):
// BCU generator vs forward differences (FD) for a 3-axis cubic at K = 4096
// ticks (d = 12), output LSB 2^-16 (units of the input, e.g. mm).
//   * bits needed for a 1-LSB bound (BCU: exact datapath; FD: guard bits G
//     with 1/2 + 2^-G-1 * sum_{i=1..3} C(K,i) <= 1 LSB),
//   * additions per sample and axis,
//   * measured maximum error vs the double-precision curve (BCU: the hls
//     model; FD: the integer recurrence simulated here),
//   * software reference: Horner in double, ns per sample (chrono).
// usage: bench_bcu_vs_fd [seed]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <gmpxx.h>
#include <random>
#include <vector>

#include "bcu/bcu_compiler.hpp"
#include "traj_bcu_gen.hpp"

namespace bcu = traj::bcu;
using Clock = std::chrono::steady_clock;

constexpr int kAxes = 3, kD = 12, kK = 1 << kD, kF = 16;

// ---------------------------------------------------------------------------
// BCU through the hls model.
// ---------------------------------------------------------------------------
template <int Ctrl, int Guard, int Out>
struct BcuRun {
  using Gen = traj::BcuGen<kAxes, 32, Ctrl, Guard, Out, kD>;
  static bcu::Format format() {
    bcu::Format f;
    f.axes = kAxes;
    f.chunk_width = 32;
    f.ctrl_width = Ctrl;
    f.guard_bits = Guard;
    f.out_width = Out;
    f.max_depth = kD;
    f.frac_bits = kF;
    return f;
  }
  // returns max error in output LSB; fills ns per sample and cycles per sample
  static double run(const bcu::Controls& b, double& ns_per_sample, double& cycles_per_sample,
                    double& bound_lsb) {
    const bcu::Segment seg = bcu::compile_segment(b, kD, format());
    bound_lsb = seg.bound / std::ldexp(1.0, -kF);
    Gen g;
    size_t wi = 0;
    std::vector<std::vector<int64_t>> out;
    out.reserve(kK + 1);
    uint64_t cyc = 0;
    const auto t0 = Clock::now();
    while (out.size() < size_t(kK) + 1) {
      typename Gen::In in;
      in.tvalid = wi < seg.words.size();
      in.tdata = in.tvalid ? seg.words[wi] : 0;
      const auto& r = g.regs();
      in.tick = !r.tick_q && (g.state() == Gen::S_READY ||
                              (g.state() == Gen::S_IDLE && wi == seg.words.size() && r.have_last_q));
      if (g.sample_valid()) {
        std::vector<int64_t> v;
        for (int a = 0; a < kAxes; ++a) v.push_back(g.sample(a));
        out.push_back(v);
      }
      const bool acc = g.tready() && in.tvalid;
      g.clock(in);
      wi += acc;
      ++cyc;
    }
    const auto t1 = Clock::now();
    ns_per_sample = std::chrono::duration<double, std::nano>(t1 - t0).count() / (kK + 1);
    cycles_per_sample = double(cyc) / (kK + 1);
    double worst = 0;
    for (int j = 0; j <= kK; ++j)
      for (int a = 0; a < kAxes; ++a) {
        if (out[j][a] != seg.samples[j][a]) {
          std::printf("BCU hls != host prediction at j=%d axis %d\n", j, a);
          std::exit(1);
        }
        const double bb[4] = {b(a, 0), b(a, 1), b(a, 2), b(a, 3)};
        const double ref = bcu::de_casteljau(bb, double(j) / kK);
        worst = std::max(worst, std::fabs(std::ldexp(double(out[j][a]), -kF) - ref));
      }
    return worst / std::ldexp(1.0, -kF);
  }
};

// ---------------------------------------------------------------------------
// FD: registers r_i = round(Delta^i x(0) * 2^(F+G)) (exact rationals), then
// r0 += r1, r1 += r2, r2 += r3 per tick (old values), output round(r0 / 2^G).
// ---------------------------------------------------------------------------
static double run_fd(const bcu::Controls& b, int G, double& ns_per_sample, int& max_reg_bits) {
  double worst = 0;
  max_reg_bits = 0;
  double ns = 0;
  for (int a = 0; a < kAxes; ++a) {
    // power basis in j: x(j) = sum_i p_i (j/K)^i, exact from the doubles
    const mpq_class b0(b(a, 0)), b1(b(a, 1)), b2(b(a, 2)), b3(b(a, 3));
    const mpq_class p0 = b0, p1 = 3 * (b1 - b0), p2 = 3 * (b0 - 2 * b1 + b2),
                    p3 = b3 - 3 * b2 + 3 * b1 - b0;
    auto x = [&](long j) -> mpq_class {
      const mpq_class t(j, kK);
      return ((p3 * t + p2) * t + p1) * t + p0;
    };
    const mpq_class X0 = x(0), X1 = x(1), X2 = x(2), X3 = x(3);
    const mpq_class D[4] = {X0, X1 - X0, X2 - 2 * X1 + X0, X3 - 3 * X2 + 3 * X1 - X0};
    mpz_class scale = 1;
    scale <<= (kF + G);
    __int128 r[4];
    for (int i = 0; i < 4; ++i) {
      mpq_class v = D[i] * scale + mpq_class(1, 2);
      mpz_class fl;
      mpz_fdiv_q(fl.get_mpz_t(), v.get_num_mpz_t(), v.get_den_mpz_t());
      // two 64-bit halves (registers are below 127 bits here)
      mpz_class hi = fl >> 64, lo = fl - (hi << 64);
      r[i] = (static_cast<__int128>(hi.get_si()) << 64) + static_cast<__int128>(lo.get_ui());
    }
    const double bb[4] = {b(a, 0), b(a, 1), b(a, 2), b(a, 3)};
    const auto t0 = Clock::now();
    std::vector<__int128> outs(kK + 1);
    __int128 maxabs = 0;
    for (int j = 0; j <= kK; ++j) {
      outs[j] = (r[0] + (static_cast<__int128>(1) << (G - 1))) >> G;  // round half up
      for (int i = 0; i < 3; ++i) {
        r[i] += r[i + 1];
        const __int128 m = r[i] < 0 ? -r[i] : r[i];
        if (m > maxabs) maxabs = m;
      }
    }
    ns += std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
    int nb = 1;
    while (nb < 127 && (maxabs >> nb) != 0) ++nb;
    max_reg_bits = std::max(max_reg_bits, nb + 1);
    for (int j = 0; j <= kK; ++j) {
      const double ref = bcu::de_casteljau(bb, double(j) / kK);
      worst = std::max(worst, std::fabs(std::ldexp(double(outs[j]), -kF) - ref));
    }
  }
  ns_per_sample = ns / (kK + 1);
  return worst / std::ldexp(1.0, -kF);
}

int main(int argc, char** argv) {
  const uint64_t seed = argc > 1 ? std::strtoull(argv[1], nullptr, 0) : 1;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1000.0, 1000.0);
  bcu::Controls b(kAxes, 4);
  for (int a = 0; a < kAxes; ++a)
    for (int i = 0; i < 4; ++i) b(a, i) = U(rng);
  std::printf("bench_bcu_vs_fd: 3-axis cubic, control values in [-1000, 1000], K = %d (d = %d), "
              "output LSB 2^-%d, seed %llu\n\n", kK, kD, kF, (unsigned long long)seed);

  // --- bits for a 1-LSB bound --------------------------------------------
  const double sumC = double(kK) + double(kK) * (kK - 1) / 2 + double(kK) * (kK - 1) * (kK - 2) / 6;
  const int G_fd = static_cast<int>(std::ceil(std::log2(sumC)));  // 2^-G-1 sumC <= 1/2
  std::printf("1-LSB bound (1/2 LSB output rounding + at most 1/2 LSB from the registers):\n");
  std::printf("  FD : sum_{i=1..3} C(K,i) = %.6g = 2^%.2f -> G = %d guard bits in every register\n",
              sumC, std::log2(sumC), G_fd);
  std::printf("       (register error bound 2^-G-1 * sum C = %.3f LSB)\n",
              std::ldexp(sumC, -G_fd - 1));
  std::printf("  BCU: exact datapath, grows 3 bits per level: 3d = %d bits above the control\n"
              "       value; control rounding 2^-G-1 <= 1/2 LSB -> G = 0 guard bits\n", 3 * kD);
  std::printf("  integer part: |x| < 2^10 * 2^%d -> 27 bits signed\n", kF);
  std::printf("  register widths: FD 27 + %d = %d bits x 4 registers/axis;\n", G_fd, 27 + G_fd);
  std::printf("                   BCU W = 28 + 3*12 = 64 bits (CtrlWidth 28, G = 0) x (4 current + 4 per stack level)/axis\n\n");

  // --- measured errors ------------------------------------------------------
  double ns_bcu0, cyc_bcu0, bnd0, ns_bcu9, cyc_bcu9, bnd9;
  const double e_bcu0 = BcuRun<28, 0, 28>::run(b, ns_bcu0, cyc_bcu0, bnd0);
  const double e_bcu9 = BcuRun<40, 9, 32>::run(b, ns_bcu9, cyc_bcu9, bnd9);
  double ns_fd, ns_fd32;
  int bits_fd, bits_fd32;
  const double e_fd = run_fd(b, G_fd, ns_fd, bits_fd);
  const double e_fd32 = run_fd(b, 32, ns_fd32, bits_fd32);
  const double e_fd20 = [&] { double n; int bb; return run_fd(b, 20, n, bb); }();

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
      const double bb[4] = {b(a, 0), b(a, 1), b(a, 2), b(a, 3)};
      e_horner = std::max(e_horner, std::fabs(h - bcu::de_casteljau(bb, t)));
    }
  }

  std::printf("| engine | guard bits | register bits | additions / sample / axis | max error [LSB] | bound [LSB] | host ns / sample, 3 axes (hls: cycle-accurate model, not a software evaluator) |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  std::printf("| BCU (hls model), CtrlWidth 28, G = 0 | 0 (+36 growth) | 64 | %.3f (6 per BCU x (K-1)/K) + 1 rounding | %.4f | %.4f | %.1f (%.1f model cycles) |\n",
              6.0 * (kK - 1) / kK, e_bcu0, bnd0, ns_bcu0, cyc_bcu0);
  std::printf("| BCU (hls model), CtrlWidth 40, G = 9 | 9 (+36 growth) | 76 | %.3f + 1 rounding | %.4f | %.4f | %.1f (%.1f model cycles) |\n",
              6.0 * (kK - 1) / kK, e_bcu9, bnd9, ns_bcu9, cyc_bcu9);
  std::printf("| FD (integer sim), G = %d | %d | %d (measured max %d) | 3 + 1 rounding | %.4f | %.4f | %.1f |\n",
              G_fd, G_fd, 27 + G_fd, bits_fd, e_fd, 0.5 + std::ldexp(sumC, -G_fd - 1), ns_fd * kAxes);
  std::printf("| FD (integer sim), G = 32 | 32 | 59 (measured max %d) | 3 + 1 rounding | %.4f | %.4f | %.1f |\n",
              bits_fd32, e_fd32, 0.5 + std::ldexp(sumC, -33), ns_fd32 * kAxes);
  std::printf("| FD (integer sim), G = 20 | 20 | 47 | 3 + 1 rounding | %.4f | %.1f | - |\n", e_fd20,
              0.5 + std::ldexp(sumC, -21));
  std::printf("| Horner, double (software reference) | - | 53-bit mantissa | 3 mul + 3 add | %.2e | - | %.2f |\n",
              e_horner / std::ldexp(1.0, -kF), ns_horner);
  std::printf("\n(sink %g)\n", double(sink) * 0);
  return 0;
}
