// Prints the forward-difference error-bound table: for each degree and
// register width (output width fixed, guard bits = width - out_width), the
// longest segment K the compiler accepts at the tolerance, and what it means
// in time at a given tick period.
//   usage: fd_bound_table [out_width=32] [tol_lsb=0.5] [period_s=0.001]
#include <cstdio>
#include <cstdlib>

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
  return 0;
}
