// SPDX-License-Identifier: Apache-2.0
// trajcore hls: time-scale unit, cycle-accurate model of
// rtl/traj_time_scale.sv (same registers, same names, same order).
//
// Between the servo tick and an engine that ticks 2^p times finer: trajectory
// time advances by s servo ticks per servo tick (feed override, feed hold, a
// stop on the path when the data ahead would not cover a stop), the engine is
// ticked as far as trajectory time needs, and the output is the linear
// interpolation between the engine samples around it. Per servo tick it does
// exactly what host/timescale's TimeScaler::tick does (the exact reference,
// tb/timescale checks the identity):
//   * s = S 2^-sb; its rate k (|k| <= m) changes by -1, 0 or +1 per servo
//     tick, S by the new k (SCurve: greedy, lands on its target exactly);
//     b = |k| (|k| - 1) / 2, the shortest stop from k, is kept beside k (no
//     multiplier); one step takes 4 clocks (the distance and candidates, the
//     distances left, the choice, the move), one adder or comparator deep each;
//   * trajectory time phi, 64 bits: engine sample index (32) . fraction (32);
//     phi += S << shift (shift = 32 - sb + p, <= 40), the shift done a bit
//     per clock, as is ahead >> shift for the check below;
//   * before the step, unless `end`: one more servo tick at the target then a
//     stop (simulated, one S-curve step per clock) must fit within the
//     samples ahead, else the unit holds by itself (starved, counted); once
//     starved, it resumes (auto_resume) when twice a tick at the target
//     and a stop from it (simulated from S = target, k = 0) fit;
//   * the engine is ticked (eng_tick_o, one strobe, the next after its
//     eng_valid_i) until the window (y0, y1) holds samples index(phi) and
//     index(phi) + 1; the first servo tick with 2 samples available primes
//     the window;
//   * output per axis: y0 + floor((y1 - y0) frac / 2^32), by 32 shift-add
//     steps per axis (acc = floor((acc + bit ? d : 0) / 2), LSB first),
//     d and the final sum in clocks of their own.
// sample_valid_o pulses once per servo tick taken (none before the window is
// primed). A servo tick while a previous one is in progress sets err_o
// (sticky) and is dropped. Configuration inputs are held while running.
#pragma once
#include <cstdint>

#include "traj_common.hpp"

namespace traj {

template <int Axes = 3, int OutWidth = 48, int SW = 16>
class TimeScale {
 public:
  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(OutWidth >= 8 && OutWidth <= 64, "OutWidth must be 8..64");
  static_assert(SW >= 4 && SW <= 24, "SW (the width of S) must be 4..24");
  static constexpr int kLW = 66;  // last, ahead, the increment: 34-bit index . 32-bit fraction
  enum State {
    kIdle, kPrime, kPrimeWait, kTick, kAhead, kShr, kStA, kStA2, kStB, kStC, kDecide, kShl, kPhi, kAdv, kAdvWait,
    kMulD, kMul, kMulW, kOut
  };
  enum Mode { kFirst, kLoop, kReal };  // the S-curve step in flight: the stop's first, its next, the tick's

  struct In {
    bool rst_n = true;
    bool tick = false;          // servo strobe
    uint32_t m = 1;             // |k| <= m, >= 1
    uint32_t s_max = 0;         // S <= s_max
    uint32_t override_s = 0;    // target S when not held (clamped to s_max)
    uint32_t shift = 0;         // phi increment shift, 0..40
    bool hold = false, auto_resume = true, end = false;
    uint32_t avail = 0;         // engine samples available beyond those ticked
    bool eng_valid = false;     // the engine's sample_valid (real or repeated)
    u128 eng_sample[Axes] = {};  // OutWidth-bit two's complement
  };
  struct Out {
    bool eng_tick;
    bool sample_valid;
    u128 sample[Axes];
    uint32_t s;
    bool starved;
    uint32_t starved_count;
    bool busy;
    bool err;
  };

  Out outputs() const {
    Out o{};
    o.eng_tick = eng_tick_q_;
    o.sample_valid = valid_q_;
    for (int a = 0; a < Axes; ++a) o.sample[a] = out_q_[a];
    o.s = static_cast<uint32_t>(cur_s_q_);
    o.starved = starved_q_;
    o.starved_count = cnt_q_;
    o.busy = st_q_ != kIdle;
    o.err = err_q_;
    return o;
  }

  void clock(const In& in) {
    const int64_t m = in.m;
    const int64_t ov = in.override_s > in.s_max ? static_cast<int64_t>(in.s_max) : static_cast<int64_t>(in.override_s);
    const int shift = static_cast<int>(in.shift & 63);
    bool err_d = err_q_ || (in.tick && st_q_ != kIdle);
    State st_d = st_q_;
    bool eng_tick_d = false, valid_d = false;

    switch (st_q_) {
      case kIdle:
        if (in.tick) {
          if (primed_q_) st_d = kTick;
          else if (in.avail >= 2) st_d = kPrime;
        }
        break;
      case kPrime:  // one engine tick of the two that fill the window
        eng_tick_d = true;
        st_d = kPrimeWait;
        break;
      case kPrimeWait:
        if (in.eng_valid) {
          take_sample(in);
          fill_q_ = !fill_q_;
          if (fill_q_) st_d = kPrime;  // the first of the two
          else {
            primed_q_ = true;
            st_d = kTick;
          }
        }
        break;
      case kTick: {
        end_q_ = in.end;
        // the last sample phi may reach, saturated at 2^32 - 1 (32-bit
        // index): the last available one at the end, else the one before it
        // (the window at phi needs the sample after phi's)
        const uint64_t li = static_cast<uint64_t>(w_q_) + (in.end ? 1 : 0) + in.avail;
        last_q_ = static_cast<uint32_t>(li > 0xffffffffu ? 0xffffffffu : li);
        sc_q_ = shift;
        const int64_t tgt0 = (in.hold || starved_q_) ? 0 : ov;
        tgt_q_ = in.end ? (in.hold ? 0 : ov) : tgt0;
        mode_q_ = kReal;
        if (in.end) st_d = kStA;
        else if (!starved_q_) {
          resume_q_ = false;
          sim_tgt_q_ = tgt0;
          st_d = kAhead;
        } else if (in.auto_resume && !in.hold) {
          // resume when twice a tick at the target and a stop from it fit:
          // the stop simulated from S = the target, k = 0
          resume_q_ = true;
          sim_tgt_q_ = ov;
          sim_s_q_ = ov;
          sim_k_q_ = 0;
          sim_b_q_ = 0;
          sum_q_ = static_cast<uint64_t>(ov);
          st_d = kAhead;
        } else {
          st_d = kStA;
        }
        break;
      }
      case kAhead: {  // the trajectory time ahead, up to the last sample
        const u128 last = static_cast<u128>(last_q_) << 32;
        room_q_ = last > phi_q_ ? last - phi_q_ : 0;
        st_d = kShr;
        break;
      }
      case kShr:  // room = ahead >> shift, a bit per clock
        if (sc_q_ == 0) {
          mode_q_ = resume_q_ ? kLoop : kFirst;
          st_d = kStA;
        } else {
          room_q_ >>= 1;
          sc_q_ = sc_q_ - 1;
        }
        break;
      case kStA: {  // S-curve step, stage 1: the target's distance and the candidates
        const bool loop = mode_q_ == kLoop;
        const int64_t s = loop ? sim_s_q_ : cur_s_q_, k = loop ? sim_k_q_ : cur_k_q_;
        const uint64_t b = loop ? sim_b_q_ : cur_b_q_;
        const int64_t t = mode_q_ == kFirst ? sim_tgt_q_ : (loop ? 0 : tgt_q_);
        const int64_t e = t - s, a = k < 0 ? -k : k;
        pa_s_q_ = s;
        pa_k_q_ = k;
        pa_b_q_ = b;
        pa_e_q_ = e;
        pa_pos_q_ = k > 0;
        pa_away_q_ = k != 0 && (e == 0 || (e > 0) != (k > 0));
        pa_dir_q_ = e > 0 ? 1 : -1;
        pa_up_q_ = k + pa_dir_q_;
        pa_bu_q_ = b + static_cast<uint64_t>(a);
        pa_bd_q_ = b - static_cast<uint64_t>(a) + 1;
        pa_upok_q_ = a + 1 <= m;
        st_d = kStA2;
        break;
      }
      case kStA2:  // stage 2: the distance left after each candidate
        pa_eup_q_ = pa_e_q_ - pa_up_q_;
        pa_ek_q_ = pa_e_q_ - pa_k_q_;
        st_d = kStB;
        break;
      case kStB: {  // stage 3: the choice (greedy: up if it can land, else hold, else brake)
        int64_t nk = pa_k_q_;
        uint64_t nb = pa_b_q_;
        if (pa_away_q_) {
          nk = pa_pos_q_ ? pa_k_q_ - 1 : pa_k_q_ + 1;
          nb = pa_bd_q_;
        } else if (pa_e_q_ != 0) {
          if (pa_upok_q_ && land(pa_eup_q_, pa_up_q_, pa_bu_q_)) {
            nk = pa_up_q_;
            nb = pa_bu_q_;
          } else if (!land(pa_ek_q_, pa_k_q_, pa_b_q_)) {
            nk = pa_k_q_ - pa_dir_q_;
            nb = pa_bd_q_;
          }
        }
        pb_k_q_ = nk;
        pb_b_q_ = nb;
        st_d = kStC;
        break;
      }
      case kStC: {  // stage 4: S moves by the new k
        const int64_t ns = pa_s_q_ + pb_k_q_;
        if (mode_q_ == kReal) {
          cur_s_q_ = ns;
          cur_k_q_ = pb_k_q_;
          cur_b_q_ = pb_b_q_;
          inc_q_ = static_cast<u128>(static_cast<uint64_t>(ns));
          sc_q_ = shift;
          st_d = kShl;
        } else {
          sim_s_q_ = ns;
          sim_k_q_ = pb_k_q_;
          sim_b_q_ = pb_b_q_;
          sum_q_ = (mode_q_ == kFirst ? 0 : sum_q_) + static_cast<uint64_t>(ns);
          mode_q_ = kLoop;
          st_d = (ns == 0 && pb_k_q_ == 0) ? kDecide : kStA;  // the stop ends at rest
        }
        break;
      }
      case kDecide:
        // sum << shift > ahead  <=>  sum > floor(ahead / 2^shift) (sum an integer)
        if (!resume_q_) {
          if (static_cast<u128>(sum_q_) > room_q_) {
            starved_q_ = true;
            cnt_q_ = (cnt_q_ + 1) & 0xffffu;
            tgt_q_ = 0;
          }
        } else if (static_cast<u128>(sum_q_) <= (room_q_ >> 1)) {  // twice the stop fits
          starved_q_ = false;
          tgt_q_ = ov;
        }
        mode_q_ = kReal;
        st_d = kStA;
        break;
      case kShl:  // inc = S << shift, a bit per clock; then the sum
        if (sc_q_ == 0) {
          phisum_q_ = phi_q_ + inc_q_;
          st_d = kPhi;
        } else {
          inc_q_ = (inc_q_ << 1) & mask(kLW);
          sc_q_ = sc_q_ - 1;
        }
        break;
      case kPhi: {
        const u128 last = static_cast<u128>(last_q_) << 32;
        if (phisum_q_ > last) {
          if (last >= phi_q_) phi_q_ = last;  // never back
          if (!end_q_) err_d = true;  // cannot happen: the check before keeps a stop within the data
        } else {
          phi_q_ = phisum_q_ & mask(64);
        }
        st_d = kAdv;
        break;
      }
      case kAdv:
        if (w_q_ < static_cast<uint32_t>(phi_q_ >> 32)) {
          eng_tick_d = true;
          st_d = kAdvWait;
        } else {
          ax_q_ = 0;
          st_d = kMulD;
        }
        break;
      case kAdvWait:
        if (in.eng_valid) {
          take_sample(in);
          w_q_ = w_q_ + 1;
          st_d = kAdv;
        }
        break;
      case kMulD:  // the axis's step between the samples
        d_q_ = sext(y1_q_[ax_q_], OutWidth) - sext(y0_q_[ax_q_], OutWidth);
        acc_q_ = 0;
        bit_q_ = 0;
        st_d = kMul;
        break;
      case kMul: {  // floor(d frac / 2^32), LSB first
        const bool fb = ((phi_q_ >> bit_q_) & 1) != 0;
        acc_q_ = (acc_q_ + (fb ? d_q_ : 0)) >> 1;  // floor
        if (bit_q_ == 31) st_d = kMulW;
        else bit_q_ = bit_q_ + 1;
        break;
      }
      case kMulW:
        out_q_[ax_q_] = wrap(static_cast<u128>(sext(y0_q_[ax_q_], OutWidth) + acc_q_), OutWidth);
        if (ax_q_ == Axes - 1) st_d = kOut;
        else {
          ax_q_ = ax_q_ + 1;
          st_d = kMulD;
        }
        break;
      case kOut:
        valid_d = true;
        st_d = kIdle;
        break;
    }
    st_q_ = st_d;
    eng_tick_q_ = eng_tick_d;
    valid_q_ = valid_d;
    err_q_ = err_d;
    if (!in.rst_n) reset();
  }

  // Model-only views for tests.
  int64_t k() const { return cur_k_q_; }
  uint64_t phi() const { return static_cast<uint64_t>(phi_q_); }

 private:
  // Whether S, moving at k (after the change), can land exactly e ahead:
  // the shortest stop from k covers need = |k| (|k| - 1) / 2.
  static bool land(int64_t e, int64_t k, uint64_t need) {
    if (k == 0) return true;
    return k > 0 ? e >= static_cast<int64_t>(need) : -e >= static_cast<int64_t>(need);
  }

  void take_sample(const In& in) {
    for (int a = 0; a < Axes; ++a) {
      y0_q_[a] = y1_q_[a];
      y1_q_[a] = wrap(in.eng_sample[a], OutWidth);
    }
  }

  void reset() {
    st_q_ = kIdle;
    mode_q_ = kReal;
    eng_tick_q_ = valid_q_ = err_q_ = false;
    primed_q_ = fill_q_ = starved_q_ = resume_q_ = end_q_ = false;
    cur_s_q_ = cur_k_q_ = 0;
    cur_b_q_ = 0;
    phi_q_ = 0;
    w_q_ = 0;
    cnt_q_ = 0;
  }

  State st_q_ = kIdle;
  bool eng_tick_q_ = false, valid_q_ = false, err_q_ = false;
  bool primed_q_ = false, fill_q_ = false, starved_q_ = false, resume_q_ = false, end_q_ = false;
  Mode mode_q_ = kReal;
  int64_t cur_s_q_ = 0, cur_k_q_ = 0, sim_s_q_ = 0, sim_k_q_ = 0;
  uint64_t cur_b_q_ = 0, sim_b_q_ = 0;
  int64_t tgt_q_ = 0, sim_tgt_q_ = 0;
  // the step's stage registers
  int64_t pa_s_q_ = 0, pa_k_q_ = 0, pa_e_q_ = 0, pa_dir_q_ = 0, pa_up_q_ = 0, pa_eup_q_ = 0, pa_ek_q_ = 0;
  uint64_t pa_b_q_ = 0, pa_bu_q_ = 0, pa_bd_q_ = 0;
  bool pa_pos_q_ = false, pa_away_q_ = false, pa_upok_q_ = false;
  int64_t pb_k_q_ = 0;
  uint64_t pb_b_q_ = 0;
  uint64_t sum_q_ = 0;
  uint32_t last_q_ = 0;  // the last sample's index
  u128 room_q_ = 0, inc_q_ = 0, phisum_q_ = 0, phi_q_ = 0;
  int sc_q_ = 0;  // shift steps left
  uint32_t w_q_ = 0;  // engine sample index of y0
  uint32_t cnt_q_ = 0;
  u128 y0_q_[Axes] = {}, y1_q_[Axes] = {};
  int ax_q_ = 0, bit_q_ = 0;
  i128 d_q_ = 0, acc_q_ = 0;
  u128 out_q_[Axes] = {};
};

}  // namespace traj
