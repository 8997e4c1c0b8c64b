// trajcore hls: the host link's STATUS counters in block RAM, cycle-accurate
// model of rtl/traj_status_count.sv (same registers, same names). N counters
// of one-cycle events, one RAM word each, one adder: a word read each clock,
// written back the clock after plus its pending events; want asks for a
// counter, ld gives its value at its next write (the RTL's header).
#pragma once
#include <cstdint>

#include "traj_common.hpp"

namespace traj {

template <int N = 6>
class StatusCount {
 public:
  static_assert(N >= 2 && N <= 6, "N must be 2..6");

  struct In {
    bool rst_n = true;
    uint8_t ev = 0;  // bit k: an event of counter k (none in two consecutive cycles)
    bool want = false;
    int k = 0;
  };
  struct Out {
    bool wait, ld;
    uint32_t sum;
  };

  Out outputs() const { return {wait_q_, ld(), sum()}; }

  void clock(const In& in) {
    const StatusCount q = *this;  // the registers at the start of the cycle
    const uint8_t ev = static_cast<uint8_t>(in.ev & ((1u << N) - 1));
    // datapath (not reset): the RAM, its read register, pw_q, ck_q
    if (q.cwv_q_) mem_[q.cw_q_] = q.sum();
    rd_q_ = q.mem_[q.cr_q_];
    pw_q_ = static_cast<uint8_t>((q.pend_q_[q.cr_q_] + ((ev >> q.cr_q_) & 1)) & 3);
    if (in.want) ck_q_ = in.k & 7;
    if (!in.rst_n) {
      cr_q_ = cw_q_ = 0;
      cwv_q_ = wait_q_ = false;
      clr_q_ = true;
      for (auto& p : pend_q_) p = 0;
      return;
    }
    for (int k = 0; k < N; ++k)
      pend_q_[k] = static_cast<uint8_t>((((q.cwv_q_ && q.cw_q_ == k) ? 0 : q.pend_q_[k]) + ((ev >> k) & 1)) & 3);
    if (q.cwv_q_ && q.cw_q_ == N - 1) clr_q_ = false;
    cwv_q_ = true;
    cw_q_ = q.cr_q_;
    cr_q_ = q.cr_q_ == N - 1 ? 0 : q.cr_q_ + 1;
    if (in.want) wait_q_ = true;
    else if (q.ld()) wait_q_ = false;
  }

 private:
  uint32_t sum() const { return (clr_q_ ? 0u : rd_q_) + pw_q_; }
  bool ld() const { return wait_q_ && cwv_q_ && cw_q_ == ck_q_; }

  uint32_t mem_[8] = {};
  int cr_q_ = 0, cw_q_ = 0, ck_q_ = 0;
  bool cwv_q_ = false, clr_q_ = true, wait_q_ = false;
  uint8_t pend_q_[8] = {};
  uint8_t pw_q_ = 0;
  uint32_t rd_q_ = 0;
};

}  // namespace traj
