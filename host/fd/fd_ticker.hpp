// SPDX-License-Identifier: Apache-2.0
// The forward-difference engine's samples from a segment's registers, one
// tick at a time, in exact integers: the exact prediction of what the engine
// (rtl/traj_fd_engine.sv) emits, independent of the engine's models. It holds
// one segment's registers, whatever its K.
//
// The engine's registers are Width-bit two's complement and wrap; Width is at
// most 128 (fd::Format), so they are kept modulo 2^128, where the additions
// are exact ring operations, and read as Width-bit values: the same numbers
// the engine holds, at a few machine additions a tick (the report, `sim` and
// the upload check predict every tick of a stream).
#pragma once
#include <gmpxx.h>

#include <array>
#include <stdexcept>
#include <vector>

#include "fd/multiword.hpp"

namespace traj::fd {

class FdTicker {
 public:
  static constexpr int kMaxRegs = 8;  // degree <= 7

  FdTicker(int width, int guard_bits) : width_(width), guard_(guard_bits) {
    if (width < 2 || width > 128 || guard_bits < 0 || guard_bits >= width)
      throw std::invalid_argument("FdTicker: width must be 2..128 and guard bits below it");
  }
  // A segment's registers, [axis][i], r[0] first.
  void load(const std::vector<std::vector<mpz_class>>& regs) {
    reg_.resize(regs.size());
    n_ = regs.empty() ? 0 : static_cast<int>(regs[0].size());
    if (n_ > kMaxRegs) throw std::invalid_argument("FdTicker: at most 8 registers per axis");
    for (size_t a = 0; a < regs.size(); ++a)
      for (int i = 0; i < n_; ++i) reg_[a][i] = mw::low128(regs[a][i].get_mpz_t());
  }
  // Whether r[0] of `axis` holds r0 as the engine would (modulo 2^Width).
  bool holds(int axis, const mpz_class& r0) const {
    return held(reg_[axis][0]) == held(mw::low128(r0.get_mpz_t()));
  }
  // The sample of this tick on `axis`: r[0] as the engine holds it shifted
  // right by the guard bits (floor); then the axis's registers advance one
  // tick (r[i] += r[i+1], old values). A sample beyond 64 bits (an output
  // wider than 64 bits holding a position that far out) is refused.
  long long sample_and_step(int axis) {
    auto& x = reg_[axis];
    const mw::i128 v = held(x[0]) >> guard_;  // arithmetic shift: floor
    if (v != static_cast<long long>(v)) throw std::range_error("FdTicker: a sample beyond 64 bits");
    for (int i = 0; i + 1 < n_; ++i) x[i] += x[i + 1];
    return static_cast<long long>(v);
  }

 private:
  // The low Width bits of a register, sign-extended.
  mw::i128 held(mw::u128 r) const {
    const int up = 128 - width_;
    return static_cast<mw::i128>(r << up) >> up;
  }

  int width_, guard_;
  int n_ = 0;
  std::vector<std::array<mw::u128, kMaxRegs>> reg_;
};

}  // namespace traj::fd
