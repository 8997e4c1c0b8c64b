// trajcore hls: servo tick generator, cycle-accurate model of
// rtl/traj_tick_gen.sv (same registers, same names, same order).
//
// One strobe per tick (the engines' tick contract): internal ticks every
// `period` clocks while `run` is high (the first one `period` clocks after run
// rises), or, with period == 0, one strobe per rising edge of the external
// tick after a 2-flop synchroniser. period_o: the period in use (for the
// external tick, the clocks between its last two rising edges, ExtWidth bits,
// saturating).
#pragma once
#include <cstdint>

#include "traj_common.hpp"

namespace traj {

template <int PeriodWidth = 32, int ExtWidth = PeriodWidth>
class TickGen {
 public:
  static_assert(PeriodWidth >= 2 && PeriodWidth <= 32, "PeriodWidth must be 2..32");
  static_assert(ExtWidth >= 2 && ExtWidth <= PeriodWidth, "ExtWidth must be 2..PeriodWidth");
  static constexpr uint32_t kMask = static_cast<uint32_t>(mask(PeriodWidth));
  static constexpr uint32_t kExtMask = static_cast<uint32_t>(mask(ExtWidth));

  struct In {
    bool rst_n = true;
    bool run = false;
    uint32_t period = 0;
    bool tick_ext = false;
  };
  struct Out {
    bool tick;
    uint32_t period;
  };

  // outputs of the current cycle (period_o depends on this cycle's period input)
  Out outputs(const In& in) const {
    const uint32_t p = in.period & kMask;
    return {tick_q_, p != 0 ? p : ext_per_q_};
  }

  void clock(const In& in) {
    const uint32_t period = in.period & kMask;
    const bool internal = period != 0;
    const bool ext_rise = ext_sync_q_ && !ext_prev_q_;
    const bool int_tick = in.run && internal && cnt_q_ == 1;
    const bool ext_tick = in.run && !internal && ext_rise;

    const uint32_t cnt_d = (!in.run || cnt_q_ == 1) ? period : (cnt_q_ - 1) & kMask;
    uint32_t ext_cnt_d = ext_cnt_q_, ext_per_d = ext_per_q_;
    bool ext_seen_d = ext_seen_q_;
    if (ext_rise) {
      ext_cnt_d = 1;
      ext_seen_d = true;
      if (ext_seen_q_) ext_per_d = ext_cnt_q_;
    } else if (ext_cnt_q_ != kExtMask) {
      ext_cnt_d = ext_cnt_q_ + 1;
    }

    ext_prev_q_ = ext_sync_q_;
    ext_sync_q_ = ext_meta_q_;
    ext_meta_q_ = in.tick_ext;
    cnt_q_ = cnt_d;
    ext_cnt_q_ = ext_cnt_d;
    ext_per_q_ = ext_per_d;
    ext_seen_q_ = ext_seen_d;
    tick_q_ = int_tick || ext_tick;
    if (!in.rst_n) *this = TickGen();
  }

 private:
  bool ext_meta_q_ = false, ext_sync_q_ = false, ext_prev_q_ = false;  // synchroniser, edge detector
  uint32_t cnt_q_ = 1, ext_cnt_q_ = 0, ext_per_q_ = 0;  // cnt_q_: clocks to the next tick
  bool ext_seen_q_ = false;
  bool tick_q_ = false;
};

}  // namespace traj
