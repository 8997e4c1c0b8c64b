// trajcore hls: step/dir generator, cycle-accurate model of
// rtl/traj_step_gen.sv (same registers, same names, same order). The method
// (a DDA along the chord between consecutive samples, restarted exactly at
// every tick from frac(q) * P), its exactness argument and the pulse timing
// are described in the RTL header and rtl/README.md.
#pragma once
#include <cstdint>

#include "traj_common.hpp"

namespace traj {

template <int Axes = 3, int OutWidth = 48, int FracBits = 8, int PeriodWidth = 24, int DeltaWidth = 32,
          int DueWidth = 16, int TimeWidth = 16>
class StepGen {
 public:
  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(OutWidth >= 8 && OutWidth <= 64, "OutWidth must be 8..64");
  static_assert(FracBits >= 1 && FracBits <= 16, "FracBits must be 1..16");
  static_assert(PeriodWidth >= 8 && PeriodWidth <= 32, "PeriodWidth must be 8..32");
  static_assert(DeltaWidth >= 8 && DeltaWidth <= PeriodWidth + FracBits + 1 && DeltaWidth <= OutWidth + FracBits,
                "DeltaWidth must be 8..PeriodWidth+FracBits+1");
  static_assert(DueWidth >= 4 && DueWidth <= 32, "DueWidth must be 4..32");
  static_assert(TimeWidth >= 2 && TimeWidth <= 16, "TimeWidth must be 2..16");

  static constexpr int F = FracBits;
  static constexpr int QW = OutWidth + F;
  static constexpr int RW = PeriodWidth + F + 2;
  static constexpr int kPrepClocks = 66 + F;  // sample -> next interval's operands ready

  struct In {
    bool rst_n = true;
    uint8_t shift[Axes] = {};
    uint32_t period = 0;
    uint32_t pulse = 1;
    uint32_t setup = 0;
    bool enable = false;
    bool sample_valid = false;
    u128 sample[Axes] = {};  // OutWidth bits
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
    const uint32_t period = in.period & static_cast<uint32_t>(mask(PeriodWidth));
    const uint32_t tmask = static_cast<uint32_t>(mask(TimeWidth));
    const bool take = in.sample_valid && sq_q_ == kIdle && !nready_q_;
    const bool load = nready_q_ && (!active_q_ || last_q_);

    bool err_in = in.sample_valid && !take;
    Axis nx[Axes];
    for (int a = 0; a < Axes; ++a) {
      const Axis& q = ax_[a];
      Axis& n = nx[a];
      n = q;
      // shift, difference, product, D -/+ T
      const u128 diff = wrap(q.sh_q - q.qprev_q, QW);
      const u128 top = diff >> (DeltaWidth - 1);
      const bool fits = top == 0 || top == mask(QW - DeltaWidth + 1);
      if (take) {
        n.sh_q = wrap(in.sample[a] << F, QW);
      } else if (sq_q_ == kShift && scnt_q_ < (in.shift[a] & 63)) {
        n.sh_q = wrap(static_cast<u128>(sext(q.sh_q, QW) >> 1), QW);
      }
      if (sq_q_ == kDiff) {
        n.qprev_q = q.sh_q;
        n.frac_q = static_cast<uint32_t>(bits(q.qprev_q, 0, F));
        n.nd_q = sext(diff, DeltaWidth);
        n.nr_q = 0;
      } else if (sq_q_ == kMul) {
        n.nr_q = w(2 * q.nr_q + (((q.frac_q >> (F - 1)) & 1) ? static_cast<int64_t>(nper_q_) : 0));
        n.frac_q = (q.frac_q << 1) & static_cast<uint32_t>(mask(F));
      } else if (sq_q_ == kAlt) {
        n.nalt_q = q.nd_q < 0 ? w(q.nd_q + nt_q_) : w(q.nd_q - nt_q_);
      }
      // DDA
      const int64_t sum_d = w(q.r_q + q.d_q), sum_alt = w(q.r_q + q.alt_q);
      const bool up = active_q_ && q.dpos_q && sum_alt >= 0;
      const bool down = active_q_ && !q.dpos_q && sum_d < 0;
      if (load) {
        n.d_q = q.nd_q;
        n.alt_q = q.nalt_q;
        n.r_q = q.nr_q;
        n.dpos_q = q.nd_q >= 0;
      } else if (active_q_) {
        n.r_q = (up || down) ? sum_alt : sum_d;
      }
      // pulses
      const bool want_dir = q.due_q != 0 ? q.due_q > 0 : ((active_q_ && q.d_q != 0) ? q.dpos_q : q.dir_q);
      const bool turn = q.pg_q == kPgIdle && want_dir != q.dir_q && q.since_q >= (in.setup & tmask);
      const bool emit = q.pg_q == kPgIdle && q.due_q != 0 && want_dir == q.dir_q;
      const int64_t due_d = wd(q.due_q + (up ? 1 : 0) - (down ? 1 : 0) - (emit ? (q.dir_q ? 1 : -1) : 0));
      n.due_q = due_d;
      if (q.since_q != tmask) n.since_q = q.since_q + 1;
      switch (q.pg_q) {
        case kPgIdle:
          if (turn) {
            n.dir_q = want_dir;
            n.timer_q = in.setup & tmask;
            n.pg_q = kPgSetup;
          } else if (emit) {
            n.step_q = true;
            n.timer_q = (in.pulse - 1) & tmask;
            n.pg_q = kPgHigh;
          }
          break;
        case kPgSetup:
          if (q.timer_q == 0) n.pg_q = kPgIdle;
          else n.timer_q = q.timer_q - 1;
          break;
        case kPgHigh:
          if (q.timer_q == 0) {
            n.step_q = false;
            n.since_q = 0;
            n.timer_q = (in.pulse - 1) & tmask;
            n.pg_q = kPgLow;
          } else {
            n.timer_q = q.timer_q - 1;
          }
          break;
        default:  // kPgLow
          if (q.timer_q == 0) n.pg_q = kPgIdle;
          else n.timer_q = q.timer_q - 1;
          break;
      }
      // errors
      const bool too_fast = load && (q.nd_q < 0 ? q.nalt_q < 0 : q.nalt_q > 0);
      const bool due_ovf = due_d >= (int64_t(1) << (DueWidth - 2)) || due_d < -(int64_t(1) << (DueWidth - 2));
      err_in = err_in || (sq_q_ == kDiff && !first_q_ && !fits) || too_fast || due_ovf;
      if (!in.rst_n) {
        n.due_q = 0;
        n.pg_q = kPgIdle;
        n.timer_q = 0;
        n.since_q = tmask;
        n.step_q = false;
        n.dir_q = true;
      }
    }

    // shared control
    int sq_d = sq_q_;
    int scnt_d = scnt_q_, mcnt_d = mcnt_q_;
    bool first_d = first_q_, nready_d = nready_q_;
    uint32_t nper_d = nper_q_;
    int64_t nt_d = nt_q_;
    switch (sq_q_) {
      case kIdle:
        if (take) {
          sq_d = kShift;
          scnt_d = 0;
        }
        break;
      case kShift:
        if (scnt_q_ == 63) sq_d = kDiff;
        else scnt_d = scnt_q_ + 1;
        break;
      case kDiff:
        first_d = false;
        sq_d = first_q_ ? kIdle : kMul;
        mcnt_d = 0;
        nper_d = period;
        nt_d = static_cast<int64_t>(period) << F;
        break;
      case kMul:
        if (mcnt_q_ == F - 1) sq_d = kAlt;
        else mcnt_d = mcnt_q_ + 1;
        break;
      default:  // kAlt
        sq_d = kIdle;
        nready_d = true;
        break;
    }
    bool active_d = active_q_, last_d = last_q_;
    uint32_t cnt_d = cnt_q_;
    if (load) {
      nready_d = false;
      active_d = true;
      cnt_d = nper_q_;
      last_d = nper_q_ == 1;
    } else if (active_q_) {
      cnt_d = (cnt_q_ - 1) & static_cast<uint32_t>(mask(PeriodWidth));
      last_d = cnt_q_ == 2;
      if (last_q_) active_d = false;
    }

    for (int a = 0; a < Axes; ++a) ax_[a] = nx[a];
    sq_q_ = sq_d;
    scnt_q_ = scnt_d;
    mcnt_q_ = mcnt_d;
    first_q_ = first_d;
    nready_q_ = nready_d;
    nper_q_ = nper_d;
    nt_q_ = nt_d;
    active_q_ = active_d;
    last_q_ = last_d;
    cnt_q_ = cnt_d;
    en_q_ = in.enable;
    err_q_ = err_q_ || err_in;
    if (!in.rst_n) {
      sq_q_ = kIdle;
      scnt_q_ = 0;
      mcnt_q_ = 0;
      first_q_ = true;
      nready_q_ = false;
      active_q_ = false;
      last_q_ = false;
      cnt_q_ = 0;
      en_q_ = false;
      err_q_ = false;
    }
  }

 private:
  enum { kIdle, kShift, kDiff, kMul, kAlt };
  enum { kPgIdle, kPgSetup, kPgHigh, kPgLow };

  // wrap to RW bits, signed
  static int64_t w(int64_t v) { return static_cast<int64_t>(sext(static_cast<u128>(v), RW)); }
  static int64_t wd(int64_t v) { return static_cast<int64_t>(sext(static_cast<u128>(v), DueWidth)); }

  struct Axis {
    u128 sh_q = 0, qprev_q = 0;       // q (QW bits)
    uint32_t frac_q = 0;              // frac(q_prev), consumed from the top
    int64_t nd_q = 0, nr_q = 0, nalt_q = 0;  // next interval (RW bits, signed)
    int64_t d_q = 0, alt_q = 0, r_q = 0;     // running interval
    bool dpos_q = false;
    int64_t due_q = 0;
    int pg_q = kPgIdle;
    uint32_t timer_q = 0, since_q = 0;
    bool step_q = false, dir_q = true;
  };

  Axis ax_[Axes];
  int sq_q_ = kIdle;
  int scnt_q_ = 0, mcnt_q_ = 0;
  bool first_q_ = true, nready_q_ = false;
  uint32_t nper_q_ = 0;
  int64_t nt_q_ = 0;
  bool active_q_ = false, last_q_ = false;
  uint32_t cnt_q_ = 0;
  bool en_q_ = false, err_q_ = false;
};

}  // namespace traj
