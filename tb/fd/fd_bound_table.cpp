// SPDX-License-Identifier: Apache-2.0
// Prints the forward-difference error-bound table: for each degree and
// register width (output width fixed, guard bits = width - out_width), the
// longest segment K the compiler accepts at the tolerance, and what it means
// in time at a given tick period. Then, for a few (degree, K), the fraction
// bits each difference register needs on its own (Compiler::register_needs;
// the rules are in host/fd/fd_compiler.hpp), which register binds, and the one
// common guard-bit count the compiler requires.
//   usage: fd_bound_table [out_width=32] [tol_lsb=0.5] [period_s=0.001]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

#include "fd/fd_compiler.hpp"

int main(int argc, char** argv) {
  const int out_width = argc > 1 ? std::atoi(argv[1]) : 32;
  const double tol = argc > 2 ? std::atof(argv[2]) : 0.5;
  const double period = argc > 3 ? std::atof(argv[3]) : 1e-3;
  const int widths[] = {48, 64, 80, 96, 128};
  std::printf("Longest segment K (ticks) with register error <= tol/2 = %g LSB per segment "
              "(out_width %d, guard = width - %d; K capped at 2^32-1):\n\n",
              tol / 2, out_width, out_width);
  std::printf("| degree |");
  for (int w : widths) std::printf(" W=%d |", w);
  std::printf("\n|---|");
  for (int i = 0; i < 5; ++i) std::printf("---|");
  std::printf("\n");
  for (int deg = 1; deg <= 7; ++deg) {
    std::printf("| %d |", deg);
    for (int w : widths) {
      const int g = w - out_width;
      unsigned long long k = traj::fd::Compiler::longest_segment(deg, g, tol);
      if (k > 0xffffffffull) k = 0xffffffffull;
      std::printf(" %llu (%.3g s) |", k, static_cast<double>(k) * period);
    }
    std::printf("\n");
  }
  std::printf("\n(seconds at a %g ms tick)\n", period * 1e3);

  // Per-register needs. alone: register i with the whole budget tol/2 (no
  // format can give it fewer bits); share: within an equal share tol/(2N)
  // (every register meeting it is enough); common: the least common guard
  // count, max alone <= common <= max share. The rule of thumb 12/23/34 for a
  // cubic over 4096 ticks are the alone rule at tol = 1 (1/2 LSB per register).
  std::printf("\nFraction bits below the output LSB needed per difference register (tol = %g LSB):\n\n", tol);
  std::printf("| degree | K | alone r[1..N] | equal share r[1..N] | binding | common (guard_bits) |\n");
  std::printf("|---|---|---|---|---|---|\n");
  const std::pair<int, unsigned long long> cases[] = {{3, 4096},  {5, 4096},  {3, 2344},  {3, 100000},
                                                      {5, 192},   {7, 74},    {7, 5},     {1, 1ull << 20},
                                                      {2, 65535}, {4, 7624}};
  for (const auto& [deg, k] : cases) {
    const auto nd = traj::fd::Compiler::register_needs(deg, k, tol);
    auto list = [&](const std::vector<int>& v) {
      std::string s;
      for (int i = 1; i <= deg; ++i) s += (i > 1 ? "/" : "") + std::to_string(v[i]);
      return s;
    };
    std::printf("| %d | %llu | %s | %s | r[%d] | %d |\n", deg, k, list(nd.alone).c_str(), list(nd.share).c_str(),
                nd.binding, nd.common);
  }
  {
    const auto nd = traj::fd::Compiler::register_needs(3, 4096, 1.0);
    std::printf("\nDesign notes' rule (1/2 output LSB per register, i.e. alone at tol = 1): cubic, K = 4096: "
                "%d/%d/%d\n",
                nd.alone[1], nd.alone[2], nd.alone[3]);
    const auto nq = traj::fd::Compiler::register_needs(5, 4096, 1.0);
    std::printf("                                                      quintic, K = 4096: r[5] %d "
                "(log2 C(4096,5) = 53.09)\n",
                nq.alone[5]);
  }
  return 0;
}
