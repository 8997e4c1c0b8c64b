// SPDX-License-Identifier: Apache-2.0
// Benchmark (not a test): microseconds per segment of traj::fd::Compiler for the
// main formats, on chained random segments (each starts at the previous end).
//
//   ./build/tb/fd/bench_fd_compile [segments]
//
// Prints per format: compile() per segment (returning a new Compiled, and into
// one reused Compiled: no allocation), words() per segment, state_at() and
// sample_at() per call, and how many segments each compiler path settled.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "fd/fd_compiler.hpp"

using traj::fd::Compiled;
using traj::fd::Compiler;
using traj::fd::Format;
using traj::fd::PolySegment;

namespace {

using Clock = std::chrono::steady_clock;

double horner_ld(const std::vector<double>& c, long double t) {
  long double v = 0;
  for (size_t j = c.size(); j-- > 0;) v = v * t + c[j];
  return static_cast<double>(v);
}

struct Case {
  const char* name;
  int axes, degree, width, chunk, guard, frac;
  uint64_t kmin, kmax;
  double range;  // units
};

volatile uint64_t g_sink = 0;

void run(const Case& cs, int nseg) {
  Format f;
  f.axes = cs.axes;
  f.degree = cs.degree;
  f.width = cs.width;
  f.chunk_width = cs.chunk;
  f.guard_bits = cs.guard;
  f.frac_bits = cs.frac;
  const Compiler comp(f);
  const uint64_t klong = Compiler::longest_segment(f.degree, f.guard_bits, f.tol_lsb);
  const uint64_t kmax = std::min<uint64_t>(cs.kmax, klong);
  const uint64_t kmin = std::min<uint64_t>(cs.kmin, kmax);
  std::mt19937_64 rng(12345);
  std::uniform_int_distribution<uint64_t> Kd(kmin, kmax);
  std::uniform_real_distribution<double> U(-1, 1);
  const double h = 1e-3;

  // Pre-generate a continuous chain of segments.
  std::vector<PolySegment> segs(nseg);
  std::vector<double> x0(f.axes, 0.0);
  for (int s = 0; s < nseg; ++s) {
    PolySegment& seg = segs[s];
    seg.h = h;
    seg.ticks = Kd(rng);
    const double T = seg.ticks * h;
    for (int a = 0; a < f.axes; ++a) {
      std::vector<double> c(f.degree + 1);
      c[0] = x0[a];
      double Tj = 1;
      for (int j = 1; j <= f.degree; ++j) {
        Tj *= T;
        c[j] = U(rng) * cs.range / (4.0 * f.degree) / Tj;
      }
      // pull back towards 0 so the chain stays in range
      c[1] -= x0[a] / T * 0.5;
      x0[a] = horner_ld(c, T);
      seg.coef.push_back(std::move(c));
    }
  }

  // compile (chained)
  std::string paths;
  std::vector<Compiled> out(nseg);
  auto t0 = Clock::now();
  for (int s = 0; s < nseg; ++s) out[s] = comp.compile(segs[s], s ? &out[s - 1].end : nullptr, "bench");
  auto t1 = Clock::now();
  const double us_compile = std::chrono::duration<double, std::micro>(t1 - t0).count() / nseg;

  // compile (chained) into one reused result
  {
    const traj::fd::PathCounts before = traj::fd::path_counts();
    Compiled work;
    t0 = Clock::now();
    for (int s = 0; s < nseg; ++s) {
      comp.compile(segs[s], s ? &work.end : nullptr, "bench", work);
      g_sink += work.ticks;
    }
    t1 = Clock::now();
    const traj::fd::PathCounts& pc = traj::fd::path_counts();
    paths = "grid2 " + std::to_string(pc.grid2 - before.grid2) + ", grid3 " + std::to_string(pc.grid3 - before.grid3) + ", grid4 " + std::to_string(pc.grid4 - before.grid4) +
            ", exact " + std::to_string(pc.exact - before.exact) + ", reference " +
            std::to_string(pc.reference - before.reference);
  }
  const double us_reuse = std::chrono::duration<double, std::micro>(t1 - t0).count() / nseg;

  // words
  t0 = Clock::now();
  for (int s = 0; s < nseg; ++s) g_sink += comp.words(out[s]).size();
  t1 = Clock::now();
  const double us_words = std::chrono::duration<double, std::micro>(t1 - t0).count() / nseg;

  // state_at / sample_at at a few ticks per segment
  long calls = 0;
  t0 = Clock::now();
  for (int s = 0; s < nseg; ++s)
    for (uint64_t k : {uint64_t(0), uint64_t(out[s].ticks / 3), uint64_t(out[s].ticks)}) {
      g_sink += mpz_sizeinbase(Compiler::state_at(out[s], 0, k).get_mpz_t(), 2);
      ++calls;
    }
  t1 = Clock::now();
  const double us_state = std::chrono::duration<double, std::micro>(t1 - t0).count() / calls;
  calls = 0;
  t0 = Clock::now();
  for (int s = 0; s < nseg; ++s)
    for (uint64_t k : {uint64_t(0), uint64_t(out[s].ticks / 3), uint64_t(out[s].ticks)}) {
      g_sink += mpz_sizeinbase(comp.sample_at(out[s], 0, k).get_mpz_t(), 2);
      ++calls;
    }
  t1 = Clock::now();
  const double us_sample = std::chrono::duration<double, std::micro>(t1 - t0).count() / calls;

  std::printf(
      "%-30s K=%4llu..%-5llu compile %7.3f us/seg (reused result %7.3f)   words %6.3f us/seg   state_at %6.3f us   "
      "sample_at %6.3f us   [%s]\n",
      cs.name, static_cast<unsigned long long>(kmin), static_cast<unsigned long long>(kmax), us_compile, us_reuse,
      us_words, us_state, us_sample, paths.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  const int nseg = argc > 1 ? std::atoi(argv[1]) : 20000;
  const Case cases[] = {
      {"main  A3 N5 W96 C16 G48 F32", 3, 5, 96, 16, 48, 32, 20, 400, 1000.0},
      {"dflt  A3 N3 W64 C16 G32 F16", 3, 3, 64, 16, 32, 16, 20, 400, 1000.0},
      {"chain A1 N3 W64 C16 G32 F12", 1, 3, 64, 16, 32, 12, 1, 64, 50.0},
      {"A3 N7 W128 C32 G80 F32", 3, 7, 128, 32, 80, 32, 20, 400, 1000.0},
      {"A2 N1 W48 C16 G16 F16", 2, 1, 48, 16, 16, 16, 20, 400, 1000.0},
  };
  std::printf("bench_fd_compile: %d chained segments per format\n", nseg);
  for (const Case& c : cases) run(c, nseg);
  return g_sink == 42 ? 1 : 0;
}
