// SPDX-License-Identifier: Apache-2.0
// trajcore hls: time-scale unit, cycle-accurate model of
// rtl/traj_time_scale.sv (same registers, same names, same order).
//
// Between the servo tick and an engine that ticks 2^p times finer: trajectory
// time advances by s servo ticks per servo tick (feed override, feed hold, a
// stop on the path when the data ahead would not cover a stop), the engine is
// ticked as far as trajectory time needs, and the output is the linear
// interpolation between the engine samples around it. Per servo tick it does
// exactly what host/timescale's TimeScaler::tick does (the exact reference;
// tb/timescale checks the identity). The datapath is narrow: the wide values
// are handled a bit per clock and the samples live in block RAM.
//   * The S-curve: s = S 2^-sb; its rate k (|k| <= m) changes by -1, 0 or +1
//     per servo tick, S by the new k (greedy, lands on its target exactly).
//     k is kept as a sign and a magnitude c, beside x = c (c + 1) / 2 (the
//     shortest stop from k covers x - c). With a = |target - S|, moving toward
//     the target: up (c + 1) if c < m and a >= x + c + 1, else hold if c = 0
//     or a >= x, else down (c - 1); moving away from it (or on it): down. A
//     step takes 4 clocks: a = |t - S| and c < m; the two comparisons; the
//     choice, c and x; S. The real curve (cs, cc, cks, cx) is copied into the
//     work registers (ws, wc, wks, wx) that the step works on.
//   * Trajectory time: only its fraction (frac, 32 bits) and the engine
//     samples available beyond the window (avail, latched in `av` with the
//     end flag added where it counts) are kept: the window is always at the
//     integer part of trajectory time. The check "one more tick at the target
//     then a stop fits in the data" and the move of trajectory time compare
//     X 2^sh + frac with (av + cin) 2^32 bit-serially (LSB first, kNCmp
//     clocks; X = the stop's travel `sum`, or S), and the move writes the
//     fraction and the number of engine ticks (back into av) from the same
//     serial sum.
//   * The window: y0 (sample floor(phi)) in two 1-bit-wide RAMs (y0a read at
//     bit j, y0b at bit j - 32), y1 (floor(phi) + 1) in the engine's own
//     sample RAM, read word by word through its port (eng_addr_o,
//     eng_word_i: the word at the address of the clock before). Before the
//     last engine tick of an advance the engine's sample is copied into y0
//     (Axes*OutWidth + 1 clocks).
//   * Output per axis: y0 + floor((y1 - y0) frac / 2^32), bit-serially in a
//     pipeline of three (the reads of bit i; the difference's bit, from a
//     serial subtractor, the bit of weight -2^OutWidth last; the product):
//     the difference's bits times the parallel frac (acc = (acc +/- d_j
//     frac) / 2, 33 bits, product bit j out), the product's bits 32.. added
//     to y0's bits (serial adder) into the output RAM. The result is presented at the next
//     servo tick: its bits shifted into sample_o, then sample_valid_o.
// Configuration: m_i, s_max_i, shift_i are held while running; override_i,
// hold_i, auto_resume_i, end_i and avail_i are sampled when a servo tick is
// taken (after the window is primed, at the first one). A servo tick while a
// previous one is in progress sets err_o (sticky) and is dropped.
#pragma once
#include <cstdint>

#include "traj_common.hpp"

namespace traj {

constexpr int ts_clog2(int n) {
  int b = 0;
  while ((1 << b) < n) ++b;
  return b;
}

template <int Axes = 3, int OutWidth = 48, int SW = 16, int WordWidth = 16>
class TimeScale {
 public:
  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(OutWidth >= 8 && OutWidth <= 64, "OutWidth must be 8..64");
  static_assert(SW >= 4 && SW <= 24, "SW (the width of S) must be 4..24");
  static_assert((WordWidth == 8 || WordWidth == 16 || WordWidth == 32) && OutWidth % WordWidth == 0,
                "WordWidth must be 8, 16 or 32 and divide OutWidth");
  static constexpr int kXW = 2 * SW - 1;    // x = c (c + 1) / 2, c < 2^SW
  static constexpr int kSumW = 2 * SW + 3;  // the stop's travel: (stop + 1) S values
  static constexpr int kAW = 33;            // avail (+ end), the engine ticks to do
  static constexpr int kNCmp = (kSumW + 42 > 65) ? kSumW + 42 : 65;  // serial pass: X 2^41 + frac, (av + 1) 2^32
  static constexpr int kNMul = 32 + OutWidth;  // product bits to the output's top bit
  static constexpr int kN = Axes * OutWidth;
  static constexpr int kBB = ts_clog2(OutWidth);
  static constexpr int kAxB = ts_clog2(Axes);
  static constexpr int kRamWords = 1 << (kAxB + kBB);
  static constexpr int kWB = ts_clog2(OutWidth / WordWidth);
  static constexpr int kWBit = ts_clog2(WordWidth);
  static constexpr int kEngAddrW = (kAxB + kWB > 0) ? kAxB + kWB : 1;
  // Clocks of a serial pass over av (the decrement of the engine ticks to do).
  static constexpr int kNDec = kAW;

  enum State {
    kIdle, kPrime, kPrimeWait, kCopy, kLatch, kReadout, kPlan, kS1, kS2, kS3, kS4, kCommit, kPass, kPassEnd, kAdv,
    kDec, kAdvTick, kAdvWait, kMul
  };
  enum Mode { kFirst, kLoop, kReal };  // the S-curve step: the check's first, its stop's, the tick's own
  enum Pass { kCheck, kPhiCmp, kPhiApply };

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
    uint64_t eng_word = 0;      // the engine's sample RAM word at eng_addr of the clock before
  };
  struct Out {
    bool eng_tick;
    uint32_t eng_addr;
    bool eng_addr_used;  // model only: the unit reads the engine's word this clock (copy, product)
    bool sample_valid;
    u128 sample[Axes];
    uint32_t s;
    bool starved;
    uint32_t starved_count;
    bool busy;
    bool err;
  };

  // The RAM read addresses and the engine word address: combinational from
  // the counters (the RAMs register the read).
  int clamp_bit() const { return i_q_ < OutWidth ? i_q_ : OutWidth - 1; }
  uint32_t eng_addr() const {
    return static_cast<uint32_t>((ax_q_ << kWB) | (clamp_bit() >> kWBit)) & static_cast<uint32_t>(mask(kEngAddrW));
  }

  Out outputs() const {
    Out o{};
    o.eng_tick = eng_tick_q_;
    o.eng_addr = eng_addr();
    o.eng_addr_used = st_q_ == kCopy || st_q_ == kMul;
    o.sample_valid = valid_q_;
    for (int a = 0; a < Axes; ++a) o.sample[a] = out_q_[a];
    o.s = static_cast<uint32_t>(cs_q_);
    o.starved = starved_q_;
    o.starved_count = cnt_q_;
    o.busy = st_q_ != kIdle;
    o.err = err_q_;
    return o;
  }

  void clock(const In& in) {
    const uint64_t ms = mask(SW);
    const uint64_t m = in.m & ms;
    const uint64_t smax = in.s_max & ms, ovr = in.override_s & ms;
    const int shift = static_cast<int>(in.shift & 63);
    // RAM reads (registered: the old contents at this clock's addresses)
    const int ra = (ax_q_ << kBB) | clamp_bit();
    const int rb = (ax_q_ << kBB) | ((i_q_ - 33) & static_cast<int>(mask(kBB)));  // for jd = i - 2
    const int ro = (ax_q_ << kBB) | (i_q_ & static_cast<int>(mask(kBB)));
    const bool y0a_rd = y0a_q_, y0b_rd = y0b_q_, rout_rd = rout_q_;  // read at the clock before
    const bool y0a_nx = y0a_[ra], y0b_nx = y0b_[rb], rout_nx = rout_[ro];
    bool err_d = err_q_ || (in.tick && st_q_ != kIdle);
    bool eng_tick_d = false, valid_d = false, dn_d = false;
    State st_d = st_q_;

    switch (st_q_) {
      case kIdle:
        if (in.tick) {
          if (primed_q_) st_d = kLatch;
          else if (in.avail >= 2) st_d = kPrime;
        }
        break;
      case kPrime:  // one engine tick of the two that fill the window
        eng_tick_d = true;
        st_d = kPrimeWait;
        break;
      case kPrimeWait:
        if (in.eng_valid) {
          if (!fill_q_) {  // sample 0: into y0; sample 1 stays in the engine (y1)
            fill_q_ = true;
            start_walk();
            st_d = kCopy;
          } else {
            fill_q_ = false;
            primed_q_ = true;
            st_d = kLatch;
          }
        }
        break;
      case kCopy: {  // y0 <- the engine's sample, a bit per clock
        if (pv_q_) {
          const bool b = ((in.eng_word >> (j_q_ & (WordWidth - 1))) & 1) != 0;
          y0a_[(pax_q_ << kBB) | j_q_] = b;
          y0b_[(pax_q_ << kBB) | j_q_] = b;
        }
        if (walk()) st_d = primed_q_ ? kAdvTick : kPrime;
        break;
      }
      case kLatch:
        end_q_ = in.end;
        hold_q_ = in.hold;
        aut_q_ = in.auto_resume;
        ov_q_ = ovr > smax ? smax : ovr;
        av_q_ = in.avail;
        start_walk();
        st_d = have_q_ ? kReadout : kPlan;
        break;
      case kReadout:  // the previous servo tick's output, a bit per clock, into sample_o
        if (pv_q_) shift_out(rout_rd);
        if (walk()) {
          valid_d = true;
          st_d = kPlan;
        }
        break;
      case kPlan:
        tz_q_ = hold_q_ || (starved_q_ && !end_q_);
        pend_q_ = false;
        sum_q_ = 0;  // (a serial pass also leaves it 0: the commit adds S to it)
        if (!end_q_ && !starved_q_) {
          // the check: one step toward the target (hold ? 0 : ov), then a stop
          resume_q_ = false;
          load_work();
          mode_q_ = kFirst;
        } else if (!end_q_ && aut_q_ && !hold_q_) {
          // starved: resume once twice a tick at the target and a stop from
          // it (from S = ov at rest) fit
          resume_q_ = true;
          ws_q_ = ov_q_;  // its travel starts with this S (S1 adds it)
          wc_q_ = 0;
          wks_q_ = false;
          wx_q_ = 0;
          pend_q_ = true;
          mode_q_ = kLoop;
        } else {
          load_work();
          mode_q_ = kReal;
        }
        st_d = kS1;
        break;
      case kS1: {  // the stop's last S into its travel; a = |t - S|, c < m
        bool rest = false;
        if (pend_q_) {
          sum_q_ = (sum_q_ + ws_q_) & mask(kSumW);
          rest = ws_q_ == 0 && wc_q_ == 0;
          pend_q_ = false;
        }
        const uint64_t t = (mode_q_ == kLoop || tz_q_) ? 0 : ov_q_;
        es_q_ = t < ws_q_;
        ez_q_ = t == ws_q_;
        a_q_ = es_q_ ? ws_q_ - t : t - ws_q_;
        upok_q_ = wc_q_ < m;
        y_q_ = (wx_q_ & mask(SW)) + wc_q_ + 1;  // x + c + 1's low bits and their carry out
        if (rest) {
          start_pass(kCheck, resume_q_ ? shift + 1 : shift, false);
          st_d = kPass;
        } else {
          st_d = kS2;
        }
        break;
      }
      case kS2: {  // the choice: up if it can land from one up (a >= x + c + 1), hold if from
                   // here (a >= x), else down; down when moving away
        const bool xhz = (wx_q_ >> SW) == 0;  // (a < 2^SW)
        const bool lk = wc_q_ == 0 || (xhz && a_q_ >= (wx_q_ & mask(SW)));
        const bool lu = xhz && (y_q_ >> SW) == 0 && a_q_ >= y_q_;
        const bool away = wc_q_ != 0 && (ez_q_ || es_q_ != wks_q_);
        up_q_ = !away && !ez_q_ && upok_q_ && lu;
        dn_d = away || (!ez_q_ && !up_q_ && !lk);  // (only in S3, where it is the x adder's mode)
        st_d = kS3;
        break;
      }
      case kS3:  // c and x
        if (up_q_) {
          wx_q_ = (wx_q_ + wc_q_ + 1) & mask(kXW);
          wc_q_ = (wc_q_ + 1) & ms;
          wks_q_ = es_q_;
        } else if (dn_q_) {
          wx_q_ = (wx_q_ - wc_q_) & mask(kXW);
          wc_q_ = (wc_q_ - 1) & ms;
        }
        st_d = kS4;
        break;
      case kS4:  // S moves by the new k
        ws_q_ = (wks_q_ ? ws_q_ - wc_q_ : ws_q_ + wc_q_) & ms;
        if (mode_q_ == kReal) {
          st_d = kCommit;
        } else {
          pend_q_ = true;
          mode_q_ = kLoop;
          st_d = kS1;
        }
        break;
      case kCommit:
        cs_q_ = ws_q_;
        cc_q_ = wc_q_;
        cks_q_ = wks_q_;
        cx_q_ = wx_q_;
        sum_q_ = (sum_q_ + ws_q_) & mask(kSumW);  // X of the move: S (sum is 0 after a pass or the plan)
        start_pass(kPhiCmp, shift, end_q_);
        st_d = kPass;
        break;
      case kPass: {  // X 2^sh + frac against (av + cin) 2^32, a bit per clock, LSB first
        const bool xb = dl_q_ == 0 && (sum_q_ & 1);
        if (dl_q_ == 0) sum_q_ >>= 1;
        else dl_q_ = dl_q_ - 1;
        const bool in_f = i_q_ < 32, in_a = i_q_ >= 32 && i_q_ < 32 + kAW;
        const bool fb = in_f && (frac_q_ & 1);
        const bool ab = in_a && (av_q_ & 1);
        const bool l = xb ^ fb ^ c1_q_;
        const bool r = i_q_ >= 32 && (ab ^ c2_q_);
        const bool apply = pk_q_ == kPhiApply;
        c1_q_ = (xb && fb) || (c1_q_ && (xb || fb));
        if (i_q_ >= 32) c2_q_ = ab && c2_q_;
        if (l != r) gt_q_ = l;
        snz_q_ = snz_q_ || xb;
        fnz_q_ = fnz_q_ || fb;
        if (in_f) frac_q_ = (frac_q_ >> 1) | (static_cast<uint64_t>(apply ? l : fb) << 31);
        if (in_a) {
          const bool na = apply ? l : ab;
          av_q_ = (av_q_ >> 1) | (static_cast<uint64_t>(na) << (kAW - 1));
          zacc_q_ = zacc_q_ || na;
        }
        if (i_q_ == kNCmp - 1) st_d = kPassEnd;
        i_q_ = (i_q_ + 1) & 127;
        break;
      }
      case kPassEnd:
        if (pk_q_ == kCheck) {
          const bool za = !zacc_q_;  // no sample ahead: the room is 0
          if (!resume_q_) {
            if (za ? snz_q_ : gt_q_) {  // a stop from the next tick would pass the data: stop now
              starved_q_ = true;
              cnt_q_ = (cnt_q_ + 1) & 0xffffu;
              tz_q_ = true;
            }
          } else if (za ? !snz_q_ : !gt_q_) {  // twice fits
            starved_q_ = false;
            tz_q_ = false;
          }
          load_work();
          mode_q_ = kReal;
          st_d = kS1;
        } else if (pk_q_ == kPhiCmp) {
          if (gt_q_) {
            // at the trajectory's end (without end_i it cannot happen: the
            // check keeps every stop within the data): there, at rest; never
            // back (a last sample behind phi: only after end_i fell)
            if (!end_q_) err_d = true;
            if (!zacc_q_ && !end_q_ && fnz_q_) {
              av_q_ = 0;
              za_q_ = true;
              extra_q_ = false;
            } else {
              frac_q_ = 0;
              za_q_ = !zacc_q_;
              extra_q_ = end_q_;
            }
            st_d = kAdv;
          } else {
            sum_q_ = (sum_q_ + ws_q_) & mask(kSumW);  // S again (the pass shifted it out: 0)
            start_pass(kPhiApply, shift, end_q_);
            st_d = kPass;
          }
        } else {
          za_q_ = !zacc_q_;
          extra_q_ = false;
          st_d = kAdv;
        }
        break;
      case kAdv:  // the engine ticks trajectory time needs (av, and one more at the end)
        if (za_q_) {
          start_walk();  // the copy's, or the product's
          if (extra_q_) {
            extra_q_ = false;
            st_d = kCopy;
          } else {
            acc_q_ = 0;
            bor_q_ = false;
            oc_q_ = false;
            dv_q_ = false;
            st_d = kMul;
          }
        } else {
          i_q_ = 0;
          c1_q_ = true;  // the decrement's borrow
          zacc_q_ = false;
          st_d = kDec;
        }
        break;
      case kDec: {  // av - 1, a bit per clock; the last tick of the advance copies y0 first
        const bool ab = (av_q_ & 1) != 0;
        const bool nb = ab ^ c1_q_;
        c1_q_ = !ab && c1_q_;
        av_q_ = (av_q_ >> 1) | (static_cast<uint64_t>(nb) << (kAW - 1));
        zacc_q_ = zacc_q_ || nb;
        if (i_q_ == kNDec - 1) {
          za_q_ = !zacc_q_;
          start_walk();  // the copy's (when this is the advance's last tick: y0 first)
          st_d = (!zacc_q_ && !extra_q_) ? kCopy : kAdvTick;
        } else {
          i_q_ = i_q_ + 1;
        }
        break;
      }
      case kAdvTick:
        eng_tick_d = true;
        st_d = kAdvWait;
        break;
      case kAdvWait:
        if (in.eng_valid) st_d = kAdv;
        break;
      case kMul: {  // output bit jd - 32 of axis ax: y0 + floor(d frac / 2^32); a pipeline of three
        if (dv_q_) {  // the product: acc +/- d frac, its bit jd; the output bit jd - 32
          const i128 f = static_cast<i128>(frac_q_);
          const i128 t = acc_q_ + (dq_q_ ? (sg_q_ ? -f : f) : 0);
          const bool p = (t & 1) != 0;
          acc_q_ = t >> 1;  // floor
          if (jd_q_ >= 32) {
            const bool ob = y0b_rd ^ p ^ oc_q_;
            oc_q_ = (y0b_rd && p) || (oc_q_ && (y0b_rd || p));
            rout_[(ax_q_ << kBB) | (jd_q_ - 32)] = ob;
          }
        }
        dv_q_ = pv_q_;
        if (pv_q_) {  // the difference y1 - y0, its bit j (sign-extended past the top)
          const int jc = j_q_ < OutWidth ? j_q_ : OutWidth - 1;
          const bool y1 = ((in.eng_word >> (jc & (WordWidth - 1))) & 1) != 0;
          dq_q_ = j_q_ <= OutWidth && (y1 ^ y0a_rd ^ bor_q_);
          if (j_q_ < OutWidth) bor_q_ = (!y1 && y0a_rd) || (!(y1 ^ y0a_rd) && bor_q_);
          sg_q_ = j_q_ == OutWidth;  // the difference's sign bit: weight -2^OutWidth
          jd_q_ = j_q_;
        }
        if (!fin_q_) {  // the read of bit i
          pv_q_ = true;
          j_q_ = i_q_;
          if (i_q_ == kNMul - 1) fin_q_ = true;
          i_q_ = (i_q_ + 1) & 127;
        } else if (pv_q_) {
          pv_q_ = false;
        } else if (ax_q_ == Axes - 1) {
          have_q_ = true;
          st_d = kIdle;
        } else {
          ax_q_ = ax_q_ + 1;
          i_q_ = 0;
          fin_q_ = false;
          acc_q_ = 0;
          bor_q_ = false;
          oc_q_ = false;
        }
        break;
      }
    }
    y0a_q_ = y0a_nx;
    y0b_q_ = y0b_nx;
    rout_q_ = rout_nx;
    st_q_ = st_d;
    dn_q_ = dn_d;
    eng_tick_q_ = eng_tick_d;
    valid_q_ = valid_d;
    err_q_ = err_d;
    if (!in.rst_n) reset();
  }

  // Model-only views for tests.
  int64_t k() const { return cks_q_ ? -static_cast<int64_t>(cc_q_) : static_cast<int64_t>(cc_q_); }
  uint32_t frac() const { return static_cast<uint32_t>(frac_q_); }

 private:
  // The walk over every (axis, bit) of the samples (copy, readout): counters
  // ax, i give this clock's address; pv, pax, j the address whose data
  // arrives now. Returns true in its last clock (the last data).
  void start_walk() {
    ax_q_ = 0;
    i_q_ = 0;
    pv_q_ = false;
    fin_q_ = false;
  }
  bool walk() {
    if (fin_q_) {
      pv_q_ = false;
      return true;
    }
    pv_q_ = true;
    pax_q_ = ax_q_;
    j_q_ = i_q_;
    if (i_q_ == OutWidth - 1) {
      i_q_ = 0;
      if (ax_q_ == Axes - 1) fin_q_ = true;
      else ax_q_ = ax_q_ + 1;
    } else {
      i_q_ = i_q_ + 1;
    }
    return false;
  }
  void shift_out(bool b) {  // sample_o >> 1, b at its top
    for (int a = 0; a < Axes; ++a) {
      const bool in = a == Axes - 1 ? b : (out_q_[a + 1] & 1) != 0;
      out_q_[a] = (out_q_[a] >> 1) | (static_cast<u128>(in) << (OutWidth - 1));
    }
  }
  void load_work() {
    ws_q_ = cs_q_;
    wc_q_ = cc_q_;
    wks_q_ = cks_q_;
    wx_q_ = cx_q_;
  }
  void start_pass(Pass k, int sh, bool cin) {
    pk_q_ = k;
    i_q_ = 0;
    dl_q_ = sh & 63;
    c1_q_ = false;
    c2_q_ = cin;
    gt_q_ = false;
    zacc_q_ = false;
    fnz_q_ = false;
    snz_q_ = false;
  }

  void reset() {
    st_q_ = kIdle;
    eng_tick_q_ = valid_q_ = err_q_ = false;
    primed_q_ = fill_q_ = have_q_ = starved_q_ = dn_q_ = false;
    cs_q_ = cc_q_ = cx_q_ = 0;
    cks_q_ = false;
    frac_q_ = 0;
    cnt_q_ = 0;
  }

  State st_q_ = kIdle;
  bool eng_tick_q_ = false, valid_q_ = false, err_q_ = false;
  bool primed_q_ = false, fill_q_ = false, have_q_ = false, starved_q_ = false;
  uint32_t cnt_q_ = 0;
  // the tick's configuration
  bool end_q_ = false, hold_q_ = false, aut_q_ = false;
  uint64_t ov_q_ = 0;
  // the S-curve: the real one, the work copy, the step's stage registers
  uint64_t cs_q_ = 0, cc_q_ = 0, cx_q_ = 0;
  bool cks_q_ = false;
  uint64_t ws_q_ = 0, wc_q_ = 0, wx_q_ = 0;
  bool wks_q_ = false;
  Mode mode_q_ = kReal;
  bool tz_q_ = false, resume_q_ = false, pend_q_ = false;
  uint64_t a_q_ = 0, y_q_ = 0;
  bool es_q_ = false, ez_q_ = false, upok_q_ = false, up_q_ = false, dn_q_ = false;
  uint64_t sum_q_ = 0;
  // trajectory time and the serial passes
  uint64_t frac_q_ = 0, av_q_ = 0;
  Pass pk_q_ = kCheck;
  int i_q_ = 0, dl_q_ = 0;
  bool c1_q_ = false, c2_q_ = false, gt_q_ = false, zacc_q_ = false, fnz_q_ = false, snz_q_ = false;
  bool za_q_ = false, extra_q_ = false;
  // walks over the samples, the product
  int ax_q_ = 0, pax_q_ = 0, j_q_ = 0;
  bool pv_q_ = false, fin_q_ = false;
  i128 acc_q_ = 0;
  bool bor_q_ = false, oc_q_ = false, dq_q_ = false, sg_q_ = false, dv_q_ = false;
  int jd_q_ = 0;
  u128 out_q_[Axes] = {};
  // RAMs (1 bit wide, {axis, bit}): y0 twice, the output
  bool y0a_[kRamWords] = {}, y0b_[kRamWords] = {}, rout_[kRamWords] = {};
  bool y0a_q_ = false, y0b_q_ = false, rout_q_ = false;  // their registered read ports
};

}  // namespace traj
