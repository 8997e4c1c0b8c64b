// SPDX-License-Identifier: Apache-2.0
// rtl/traj_bcu.sv (the single combinational BCU, Verilated at InWidth = 4)
// == hls traj::bcu_split, exhaustively: all 16^4 inputs, both halves, and the
// exact rational formula (8x the halves of [BCU]'s eq. 8).
#include <cstdio>
#include <memory>

#include <verilated.h>

#include "Vtraj_bcu.h"
#include "sim/vl_bits.hpp"
#include "traj_bcu.hpp"

int main(int argc, char** argv) {
  constexpr int kIn = 4, kOut = kIn + 3;
  auto ctx = std::make_unique<VerilatedContext>();
  ctx->commandArgs(argc, argv);
  auto top = std::make_unique<Vtraj_bcu>(ctx.get());
  long checked = 0, bad = 0;
  for (int v = 0; v < (1 << (4 * kIn)); ++v) {
    traj::u128 in[4];
    for (int k = 0; k < 4; ++k) in[k] = (v >> (k * kIn)) & ((1 << kIn) - 1);
    top->coef_i = v;
    top->eval();
    const traj::BcuOut o = traj::bcu_split(in, kIn);
    const long A = traj::sext(in[0], kIn), B = traj::sext(in[1], kIn), C = traj::sext(in[2], kIn),
               D = traj::sext(in[3], kIn);
    const long exact_l[4] = {8 * A, 4 * (A + B), 2 * (A + 2 * B + C), A + 3 * B + 3 * C + D};
    const long exact_r[4] = {A + 3 * B + 3 * C + D, 2 * (B + 2 * C + D), 4 * (C + D), 8 * D};
    for (int k = 0; k < 4; ++k) {
      const traj::u128 rl = traj::vl_bits(top->left_o, k * kOut, kOut);
      const traj::u128 rr = traj::vl_bits(top->right_o, k * kOut, kOut);
      if (rl != o.l[k] || rr != o.r[k] || traj::sext(rl, kOut) != exact_l[k] ||
          traj::sext(rr, kOut) != exact_r[k]) {
        if (bad < 10)
          std::printf("MISMATCH input %04x coefficient %d: rtl L %llu R %llu, hls L %llu R %llu\n", v, k,
                      (unsigned long long)rl, (unsigned long long)rr, (unsigned long long)o.l[k],
                      (unsigned long long)o.r[k]);
        ++bad;
      }
    }
    ++checked;
  }
  top->final();
  std::printf("traj_bcu InWidth=%d: %ld inputs, %ld mismatches\n", kIn, checked, bad);
  std::printf("%ld passed, %ld failed\n", checked - (bad ? 1 : 0), bad ? 1L : 0L);
  return bad ? 1 : 0;
}
