// trajcore hls: step/dir generator, cycle-accurate model of
// rtl/traj_step_gen.sv (same registers, same names, same order). The method
// (quadratic sub-chords between consecutive samples, a DDA along them, exact
// step counts, the serial preparation) and the pulse timing are described in
// the RTL header and rtl/README.md.
#pragma once
#include <cstdint>

#include "traj_common.hpp"

namespace traj {

template <int Axes = 3, int OutWidth = 48, int FracBits = 14, int PeriodWidth = 18, int DueWidth = 8,
          int TimeWidth = 16, int SubBits = 3>
class StepGen {
 public:
  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(OutWidth >= 8 && OutWidth <= 64, "OutWidth must be 8..64");
  static_assert(FracBits >= 1 && FracBits <= 16, "FracBits must be 1..16");
  static_assert(PeriodWidth >= 8 && PeriodWidth <= 32, "PeriodWidth must be 8..32");
  static_assert(DueWidth >= 4 && DueWidth <= 32, "DueWidth must be 4..32");
  static_assert(TimeWidth >= 2 && TimeWidth <= 16, "TimeWidth must be 2..16");
  static_assert(SubBits >= 0 && SubBits <= 4, "SubBits must be 0..4");

  static constexpr int F = FracBits;
  static constexpr int RW = PeriodWidth + F + SubBits + 3;
  static constexpr int kPrepClocks = Axes * RW + 3;  // sample (or load) -> next interval's D ready
  static constexpr int kNtW = PeriodWidth + SubBits + 3;  // T / 2^F, signed
  static constexpr int kDl2 = SubBits > 0 ? SubBits : 1;
  static constexpr int kBW = RW <= 2 ? 1 : RW <= 4 ? 2 : RW <= 8 ? 3 : RW <= 16 ? 4 : RW <= 32 ? 5 : 6;  // clog2(RW)

  // sub-chords per tick = 2^sub_bits(P): the most (<= SubBits) that divide P
  // into intervals of at least 2 kPrepClocks clocks
  static int sub_bits(uint32_t period) {
    int m = 0;
    for (int k = 1; k <= SubBits; ++k) {
      if ((period & ((1u << k) - 1)) != 0 || (period >> k) < 2u * kPrepClocks) break;
      m = k;
    }
    return m;
  }

  struct In {
    bool rst_n = true;
    uint8_t shift[Axes] = {};
    uint32_t period = 1;  // held in the clock before sample_valid too
    uint32_t pulse = 1;
    uint32_t setup = 0;
    bool enable = false;
    bool sample_valid = false;
    u128 sample[Axes] = {};  // OutWidth bits; must hold for kPrepClocks after sample_valid
  };
  struct Out {
    bool step[Axes];
    bool dir[Axes];
    bool enable;
    bool err;
  };

  Out outputs() const {
    Out o{};
    for (int a = 0; a < Axes; ++a) {
      o.step[a] = ax_[a].step_q;
      o.dir[a] = ax_[a].dir_q;
    }
    o.enable = en_q_;
    o.err = err_q_;
    return o;
  }

  void clock(const In& in) {
    const uint32_t pmask = static_cast<uint32_t>(mask(PeriodWidth));
    const uint32_t tmask = static_cast<uint32_t>(mask(TimeWidth));
    const uint32_t period = in.period & pmask;
    const uint32_t pulse = in.pulse & tmask, setup = in.setup & tmask;
    const bool take = in.sample_valid && !fetch_q_ && !prep_q_ && !alt_q_st_ && !nready_q_ && subs_q_ == 0;
    const bool load = nready_q_ && (!active_q_ || last_q_);
    const bool subgo = load && subs_q_ != 0;  // the next sub-chord's pass
    const bool last_bit = bit_q_ == RW - 1;
    const bool last_axis = ax_q_ == Axes - 1;
    const bool f_last_bit = fbit_q_ == RW - 1;
    const bool f_last_axis = fax_q_ == Axes - 1;
    const int fax_inc = f_last_axis ? 0 : fax_q_ + 1;
    const bool pulse_one = pulse == 1, setup_zero = setup == 0, hold_zero = hold_q_ == 0;

    // the sample bit of q's bit fbit_q of axis fax_q (0 below bit 0, sign above)
    const u128 s = fax_q_ < Axes ? in.sample[fax_q_] : 0;
    const int j = j_q_;
    const bool sbit = j < 0 ? false : (j >= OutWidth ? ((s >> (OutWidth - 1)) & 1) != 0 : ((s >> j) & 1) != 0);
    // the pass, least significant bit first, on the bit read one clock earlier:
    // tick pass: D1 = q - q_prev, D2 = D1 - D1_prev (0 on a restart),
    //            dY = 2M D1 - (M - 1) D2 (M = 2^m), in nd_q;
    // sub pass:  dY += 2 D2
    const Axis& pass_axis = ax_[ax_q_ < Axes ? ax_q_ : 0];
    const int m = nm_q_;
    const bool pbit = (prd_q_ & 1) != 0 && !(reinit_q_ && bit_q_ < F);
    const bool dbit = sbit_q_ ^ pbit ^ borrow_q_;  // D1
    const bool borrow_d = (!sbit_q_ && pbit) || (!sbit_q_ && borrow_q_) || (pbit && borrow_q_);
    const bool ppbit = (prd_q_ & 2) != 0;
    const bool ddbit_t = !reinit_q_ && (dbit ^ ppbit ^ borrow2_q_);  // D2 (tick pass)
    const bool borrow2_d = !reinit_q_ && ((!dbit && ppbit) || (!dbit && borrow2_q_) || (ppbit && borrow2_q_));
    const bool ddbit = tickp_q_ ? ddbit_t : (prd_q_ & 4) != 0;
    const bool add_a = tickp_q_ ? ((dl1_q_ >> m) & 1) != 0 : (pass_axis.nd_q & 1) != 0;
    const bool add_c = tickp_q_ ? ddbit_t : (dl2_q_ & 1) != 0;
    const bool sub_b = tickp_q_ && (m == 0 ? ddbit_t : ((dl2_q_ >> (m - 1)) & 1) != 0);
    const bool s1 = add_a ^ add_c ^ c1_q_;
    const bool c1_d = (add_a && add_c) || (add_a && c1_q_) || (add_c && c1_q_);
    const bool ndbit = s1 ^ sub_b ^ b2_q_;
    const bool b2_d = (!s1 && sub_b) || (!s1 && b2_q_) || (sub_b && b2_q_);

    bool err_in = in.sample_valid && !take;
    Axis nx[Axes];
    for (int a = 0; a < Axes; ++a) {
      const Axis& q = ax_[a];
      Axis& n = nx[a];
      n = q;
      if (prep_q_ && ax_q_ == a) {
        n.nd_q = (q.nd_q >> 1) | (static_cast<u128>(ndbit) << (RW - 1));
        n.nnz_q = ndbit || (q.nnz_q && bit_q_ != 0);  // nd_q != 0, formed with it in the pass
      }
      // DDA
      // alt_q holds D -/+ T above bit F (T's low bits are 0: below, D's)
      const u128 sum_d = wrap(q.r_q + q.d_q, RW);
      const u128 sum_alt = wrap(q.r_q + ((q.alt_q << F) | (q.d_q & ((u128{1} << F) - 1))), RW);
      const bool up = active_q_ && q.dpos_q && !neg(sum_alt);
      const bool down = active_q_ && !q.dpos_q && neg(sum_d);
      const u128 r_next = !active_q_ ? q.r_q : ((up || down) ? sum_alt : sum_d);
      // D + T for D < 0, else D - T = D + ~T + 1, above bit F
      const u128 alt_d = neg(q.nd_q) ? wrap((q.nd_q >> F) + ntq_q_, kNtW)
                                     : wrap((q.nd_q >> F) + wrap(~ntq_q_, kNtW) + 1, kNtW);
      const bool restart = reinit_q_ && tickp_q_;  // a tick's first sub-chord after a period change
      if (load) {
        n.d_q = q.nd_q;
        n.alt_q = alt_d;
        n.r_q = restart ? 0 : r_next;
        n.dpos_q = !neg(q.nd_q);
        n.dnz_q = q.nnz_q;
      } else {
        n.r_q = r_next;
      }
      // pulses
      const bool due_nz = q.due_q != 0;
      const bool want_dir = due_nz ? !neg_due(q.due_q) : ((active_q_ && q.dnz_q) ? q.dpos_q : q.dir_q);
      const bool can_emit = due_nz && want_dir == q.dir_q &&
                            (q.pg_q == kPgIdle || q.pg_q == kPgHold || (q.pg_q == kPgLow && q.tz_q));
      const bool turn = q.pg_q == kPgIdle && want_dir != q.dir_q;
      const bool t_one = q.timer_q == 1;
      const uint64_t dm = mask(DueWidth);
      const uint64_t due_d =
          (q.due_q + (q.up_q ? 1 : 0) - (q.down_q ? 1 : 0) - (can_emit ? (q.dir_q ? 1 : dm) : 0)) & dm;
      n.up_q = up;
      n.down_q = down;
      n.due_q = due_d;
      if (can_emit) {
        n.step_q = true;
        n.timer_q = (pulse - 1) & tmask;
        n.tz_q = pulse_one;
        n.pg_q = kPgHigh;
      } else {
        switch (q.pg_q) {
          case kPgIdle:
            if (turn) {
              n.dir_q = want_dir;
              n.timer_q = setup;
              n.tz_q = setup_zero;
              n.pg_q = kPgSetup;
            }
            break;
          case kPgSetup:
          case kPgHold:
            if (q.tz_q) {
              n.pg_q = kPgIdle;
            } else {
              n.timer_q = q.timer_q - 1;
              n.tz_q = t_one;
            }
            break;
          case kPgHigh:
            if (q.tz_q) {
              n.step_q = false;
              n.timer_q = (pulse - 1) & tmask;
              n.tz_q = pulse_one;
              n.pg_q = kPgLow;
            } else {
              n.timer_q = q.timer_q - 1;
              n.tz_q = t_one;
            }
            break;
          default:  // kPgLow
            if (q.tz_q) {
              n.timer_q = hold_q_;
              n.tz_q = hold_zero;
              n.pg_q = kPgHold;
            } else {
              n.timer_q = q.timer_q - 1;
              n.tz_q = t_one;
            }
            break;
        }
      }
      const bool alt_neg = ((q.alt_q >> (kNtW - 1)) & 1) != 0;
      const bool too_fast = loaded_q_ && (neg(q.d_q) ? alt_neg : (!alt_neg && (q.alt_q != 0 || (q.d_q & ((u128{1} << F) - 1)) != 0)));
      const bool due_ovf = ((q.due_q >> (DueWidth - 1)) & 1) != ((q.due_q >> (DueWidth - 2)) & 1);
      err_in = err_in || too_fast || due_ovf;
      if (!in.rst_n) {
        n.up_q = false;
        n.down_q = false;
        n.due_q = 0;
        n.pg_q = kPgIdle;
        n.timer_q = 0;
        n.tz_q = true;
        n.step_q = false;
        n.dir_q = true;
      }
    }

    // shared control
    bool fetch_d = fetch_q_, first_d = first_q_, reinit_d = reinit_q_, alt_st_d = alt_q_st_, nready_d = nready_q_;
    bool tickp_d = tickp_q_;
    int fax_d = fax_q_, fbit_d = fbit_q_, nm_d = nm_q_, subs_d = subs_q_;
    if (take) {
      fetch_d = true;
      fax_d = 0;
      fbit_d = 0;
      reinit_d = period != nper_q_;
      tickp_d = true;
      nm_d = pm_q_;
      subs_d = first_q_ ? 0 : (1 << nm_d) - 1;
    } else if (subgo) {
      fetch_d = true;
      fax_d = 0;
      fbit_d = 0;
      tickp_d = false;
      subs_d = subs_q_ - 1;
    } else if (fetch_q_) {
      if (!f_last_bit) {
        fbit_d = fbit_q_ + 1;
      } else {
        fbit_d = 0;
        fax_d = fax_inc;
        if (f_last_axis) fetch_d = false;
      }
    }
    if (prep_q_ && last_bit && last_axis) {
      first_d = false;
      alt_st_d = !first_q_;
    }
    if (alt_q_st_) {
      alt_st_d = false;
      nready_d = true;
    }
    bool active_d = active_q_, last_d = last_q_;
    const bool loaded_d = load;
    uint32_t cnt_d = cnt_q_;
    if (load) {
      nready_d = false;
      active_d = true;
      cnt_d = nlen_q_;
      last_d = nlen_q_ == 1;
    } else if (active_q_) {
      cnt_d = (cnt_q_ - 1) & pmask;
      last_d = cnt_q_ == 2;
      if (last_q_) active_d = false;
    }
    // datapath of the pass
    const uint32_t hold_d = setup > pulse ? setup - pulse : 0;
    uint32_t nper_d = nper_q_;
    int j_d = j_q_;
    bool borrow_dd = borrow_q_, borrow2_dd = borrow2_q_, c1_dd = c1_q_, b2_dd = b2_q_;
    uint32_t dl1_d = dl1_q_, dl2_d = dl2_q_;
    if (take) {
      if (!first_q_) nper_d = period;  // the first sample's pass loads no interval
      j_d = jst_q_[0];
    } else if (fetch_q_) {
      j_d = f_last_bit ? jst_q_[fax_inc] : j_q_ + 1;
    }
    // carries and delay lines: cleared at each axis's bit 0
    if (take || subgo || (prep_q_ && last_bit)) {
      borrow_dd = borrow2_dd = c1_dd = b2_dd = false;
      dl1_d = dl2_d = 0;
    } else if (prep_q_) {
      borrow_dd = borrow_d;
      borrow2_dd = borrow2_d;
      c1_dd = c1_d;
      b2_dd = b2_d;
      dl1_d = ((dl1_q_ << 1) | (dbit ? 1u : 0u)) & ((1u << (SubBits + 1)) - 1);
      dl2_d = ((dl2_q_ << 1) | (ddbit ? 1u : 0u)) & ((1u << kDl2) - 1);
    }
    // the next interval's T / 2^F and length, from nper_q and nm_q (they hold
    // from the take to the loads)
    const u128 ntq_d = static_cast<u128>(nper_q_) << (nm_q_ + 1);
    const uint32_t nlen_d = nper_q_ >> nm_q_;

    // the pass RAM: read at the fetch position, written at the pass position
    const uint8_t prd_d = pram_[(fax_q_ << kBW) | fbit_q_];
    if (prep_q_)
      pram_[(ax_q_ << kBW) | bit_q_] = static_cast<uint8_t>((ddbit ? 4 : 0) | ((tickp_q_ ? dbit : (prd_q_ & 2) != 0) ? 2 : 0) |
                                                            ((tickp_q_ ? sbit_q_ : (prd_q_ & 1) != 0) ? 1 : 0));
    prd_q_ = prd_d;

    for (int a = 0; a < Axes; ++a) ax_[a] = nx[a];
    prep_q_ = fetch_q_;
    ax_q_ = fax_q_;
    bit_q_ = fbit_q_;
    fetch_q_ = fetch_d;
    fax_q_ = fax_d;
    fbit_q_ = fbit_d;
    j_q_ = j_d;
    for (int a = 0; a < Axes; ++a) jst_q_[a] = (in.shift[a] & 63) - F;
    sbit_q_ = sbit;
    borrow_q_ = borrow_dd;
    borrow2_q_ = borrow2_dd;
    c1_q_ = c1_dd;
    b2_q_ = b2_dd;
    dl1_q_ = dl1_d;
    dl2_q_ = dl2_d;
    tickp_q_ = tickp_d;
    subs_q_ = subs_d;
    nm_q_ = nm_d;
    pm_q_ = sub_bits(period);
    first_q_ = first_d;
    reinit_q_ = reinit_d;
    alt_q_st_ = alt_st_d;
    nready_q_ = nready_d;
    nper_q_ = nper_d;
    active_q_ = active_d;
    loaded_q_ = loaded_d;
    last_q_ = last_d;
    cnt_q_ = cnt_d;
    hold_q_ = hold_d;
    ntq_q_ = ntq_d;
    nlen_q_ = nlen_d;
    en_q_ = in.enable;
    err_q_ = err_q_ || err_in;
    if (!in.rst_n) {
      fetch_q_ = false;
      fax_q_ = 0;
      fbit_q_ = 0;
      prep_q_ = false;
      ax_q_ = 0;
      bit_q_ = 0;
      first_q_ = true;
      reinit_q_ = false;
      tickp_q_ = false;
      subs_q_ = 0;
      alt_q_st_ = false;
      nready_q_ = false;
      active_q_ = false;
      loaded_q_ = false;
      last_q_ = false;
      cnt_q_ = 0;
      nper_q_ = 0;
      en_q_ = false;
      err_q_ = false;
    }
  }

 private:
  enum { kPgIdle, kPgSetup, kPgHigh, kPgLow, kPgHold };

  static bool neg(u128 v) { return ((v >> (RW - 1)) & 1) != 0; }
  static bool neg_due(uint64_t v) { return ((v >> (DueWidth - 1)) & 1) != 0; }

  struct Axis {
    u128 nd_q = 0;  // RW bits
    u128 d_q = 0, r_q = 0;  // RW bits, two's complement
    u128 alt_q = 0;          // kNtW bits: D -/+ T above bit F (below, D's)
    bool dpos_q = false, dnz_q = false, nnz_q = false;
    bool up_q = false, down_q = false;   // the DDA's steps, one clock later
    uint64_t due_q = 0;                  // DueWidth bits, two's complement
    int pg_q = kPgIdle;
    uint32_t timer_q = 0;
    bool tz_q = true;  // timer_q == 0
    bool step_q = false, dir_q = true;
  };

  Axis ax_[Axes];
  bool fetch_q_ = false;
  int fax_q_ = 0, fbit_q_ = 0, j_q_ = 0;
  int jst_q_[Axes] = {};  // axis a: its first sample bit, shift - F
  bool sbit_q_ = false;
  bool prep_q_ = false;
  int ax_q_ = 0, bit_q_ = 0;
  bool borrow_q_ = false, first_q_ = true, reinit_q_ = false, alt_q_st_ = false, nready_q_ = false;
  bool borrow2_q_ = false, c1_q_ = false, b2_q_ = false;
  uint32_t dl1_q_ = 0, dl2_q_ = 0;  // the pass's last D1 and D2 bits, newest in bit 0
  bool tickp_q_ = false;            // the pass (or the last one) is a tick pass
  // q_prev, D1_prev, D2 of every axis bit by bit (block RAM in the RTL):
  // word (axis << kBW) | bit = {D2, D1_prev, q_prev}; prd_q_ the word read
  uint8_t pram_[Axes << kBW] = {};
  uint8_t prd_q_ = 0;
  int subs_q_ = 0, nm_q_ = 0;       // sub-chords left to prepare; m of the tick
  int pm_q_ = 0;                    // m of the period in the clock before (the RTL's pm_q)
  uint32_t nper_q_ = 0, nlen_q_ = 0;  // nper_q_: at a take, the period of the last interval loaded
  u128 ntq_q_ = 0;  // kNtW bits: T / 2^F of the next interval
  bool active_q_ = false, loaded_q_ = false, last_q_ = false;
  uint32_t cnt_q_ = 0;
  uint32_t hold_q_ = 0;
  bool en_q_ = false, err_q_ = false;
};

}  // namespace traj
