// SPDX-License-Identifier: Apache-2.0
// The forward-difference engine's samples from a segment's registers, one
// tick at a time, in exact integers: the exact prediction of what the engine
// (rtl/traj_fd_engine.sv) emits, independent of the engine's models. It holds
// one segment's registers, whatever its K.
#pragma once
#include <gmpxx.h>

#include <vector>

namespace traj::fd {

class FdTicker {
 public:
  FdTicker(int width, int guard_bits) : mod_(mpz_class(1) << width), guard_(guard_bits) {}
  // A segment's registers, [axis][i], r[0] first.
  void load(const std::vector<std::vector<mpz_class>>& regs) { reg_ = regs; }
  // The sample of this tick on `axis`: r[0] as the engine holds it (Width
  // bits, two's complement) shifted right by the guard bits (floor); then the
  // axis's registers advance one tick (r[i] += r[i+1], old values).
  long long sample_and_step(int axis) {
    auto& x = reg_[axis];
    v_ = x[0] % mod_;
    if (v_ < 0) v_ += mod_;
    if (v_ >= mod_ / 2) v_ -= mod_;
    mpz_fdiv_q_2exp(v_.get_mpz_t(), v_.get_mpz_t(), guard_);
    for (size_t i = 0; i + 1 < x.size(); ++i) x[i] += x[i + 1];
    return v_.get_si();
  }

 private:
  mpz_class mod_, v_;
  int guard_;
  std::vector<std::vector<mpz_class>> reg_;
};

}  // namespace traj::fd
