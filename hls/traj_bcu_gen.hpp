// trajcore hls: BCU generator. Samples a cubic Bernstein polynomial per axis
// at t = j/2^d, j = 0..2^d-1, in increasing time order, one sample per servo
// tick, by depth-first de Casteljau mid-subdivision with an explicit stack.
// Mirrors rtl/traj_bcu_gen.sv register for register, cycle for cycle.
//
// Parameters
//   Axes        axes in lockstep (1..8)
//   ChunkWidth  stream word width (8..64)
//   CtrlWidth   width of a control value (two's complement); LSB = 2^-GuardBits
//               output LSB
//   GuardBits   control-value bits below the output LSB
//   OutWidth    sample width, >= CtrlWidth-GuardBits+(GuardBits>0) (sign-extended)
//   MaxDepth    largest depth d (K = 2^d samples per segment), 1..(128-CtrlWidth)/3
//
// Arithmetic (exact, scaled form)
//   W = CtrlWidth + 3*MaxDepth is the datapath width. After loading, every
//   control value is multiplied by 8^(MaxDepth-d) (PRE state, one <<3 per
//   cycle), so that after the d subdivision levels every leaf coefficient is
//   8^MaxDepth times the true value, whatever d is. A coefficient at effective
//   level e (= MaxDepth-d + subdivisions) is 8^e times a convex combination of
//   the control values, so it fits CtrlWidth+3e bits; the BCU input is at level
//   <= MaxDepth-1, i.e. fits W-3 bits, its output W bits: nothing is ever
//   rounded or lost. The leaf value A at t = j/2^d is
//       A = 8^MaxDepth * sum_i C(3,i) (1-t)^(3-i) t^i c_i     (exactly),
//   and the output is rounded once, half up:
//       sample = floor((A + 2^(S-1)) / 2^S),  S = 3*MaxDepth + GuardBits.
//   |A| <= 8^MaxDepth max|c| (convex hull), so the sample fits
//   CtrlWidth-GuardBits bits, plus one when GuardBits > 0 (rounding the largest
//   positive value up reaches 2^(CtrlWidth-1-GuardBits)): no overflow.
//   Error vs the exact fixed-point polynomial: <= 1/2 output LSB for every d.
//
// Schedule (depth-first, explicit stack; one BCU shared by the axes)
//   The current quaternion of every axis is held in cur_q, a ring of Axes
//   quaternions; the BCU works on the head (axis 0 of the ring) and the ring
//   rotates by one quaternion per cycle, so Axes cycles process all axes.
//   stack memory: MaxDepth*Axes entries of 4*W bits, entry lvl*Axes+a holds the
//   right half pushed when axis a descended from level lvl. Synchronous read
//   (rd_q), one write port: it maps onto block RAM.
//     IDLE  : accept a header word (depth d, clamped to MaxDepth); else, if a
//             tick is pending, process it as an underrun.
//     LOAD  : 4*Axes*ceil(CtrlWidth/ChunkWidth) words, shifted into cur_q.
//     PRE   : MaxDepth-d cycles of cur <<= 3 (all values at once), + 1 cycle.
//     DESC  : while lvl < d: per axis (1 cycle each) (L,R) = BCU(cur), push R
//             at stack[lvl*Axes+a], cur = L. Then READY.
//     READY : leaf j is ready: its A (all axes) is sample j. On a pending tick:
//             emit round(A); if j = 2^d-1: seg_done, keep round(D) (the end
//             value) in last_q, go IDLE. Else the next leaf is the right half
//             pushed at stack level p = d-1-(number of trailing ones of j):
//     POP   : Axes+1 cycles (read address, then data into the ring), lvl=p+1,
//             then DESC (down to d) or READY.
//   Every internal node of the subdivision tree is split exactly once:
//   2^d-1 BCU operations (6 additions each, per axis) for 2^d samples.
//
// Timing (clock cycles)
//   tick_i at cycle t -> tick_q at t+1 -> processed at t+1 if READY/IDLE ->
//   sample_valid_o at t+2. Within a segment the next leaf is ready at most
//   2 + d*Axes cycles after a tick was processed (worst at j = 2^(d-1)-1).
//   Between segments (stream words available every cycle):
//   3 + 4*Axes*Words + MaxDepth*Axes cycles from the last tick of one segment
//   to READY of the next. Hence kMinTickSpacing = 3 + 4*Axes*Words +
//   MaxDepth*Axes: with ticks at least that many cycles apart and the stream
//   never starved, no tick is ever late, lost or flagged (tests check it).
//
// Interface rules (shared with traj_fd_engine)
//   * ticks are latched in tick_q; a tick while one is pending and not being
//     processed in the same cycle sets the sticky tick_err.
//   * a pending tick is processed only in READY, or in IDLE when no header word
//     is being accepted in the same cycle (the header has priority, as in the
//     FD engine); never during LOAD/PRE/DESC/POP.
//   * a tick processed in IDLE: underrun pulses; sample_valid pulses only if a
//     segment has been completed since reset, and then the sample is the end
//     value round(D) of the last segment (a chained segment starts with A = D,
//     so that is the same value: no jump). So after the final segment the end
//     value is emitted with the first underrun tick.
//   * seg_done pulses with the K-th sample (j = K-1); the end value t=1 is the
//     first sample (A) of the next segment.
//   * reset (rst_n low, synchronous) clears control state only.
//
// Stream: word 0 = header, depth d in bits [DepthBits-1:0] (higher bits
// ignored; d > MaxDepth is clamped to MaxDepth, the host never sends it);
// then axis 0..Axes-1, value A,B,C,D, each in Words words, LS word first,
// sign-extended; the low CtrlWidth bits are used.
#pragma once
#include <cstdint>

#include "traj_bcu.hpp"
#include "traj_common.hpp"

namespace traj {

constexpr int bcu_clog2(int v) {
  int r = 0;
  while ((1 << r) < v) ++r;
  return r;
}

template <int Axes, int ChunkWidth, int CtrlWidth, int GuardBits, int OutWidth, int MaxDepth>
class BcuGen {
 public:
  static constexpr int kAxes = Axes;
  static constexpr int kOutWidth = OutWidth;
  static constexpr int kW = CtrlWidth + 3 * MaxDepth;  // datapath width
  static constexpr int kWords = (CtrlWidth + ChunkWidth - 1) / ChunkWidth;
  static constexpr int kAsmWidth = kWords * ChunkWidth;
  static constexpr int kShift = 3 * MaxDepth + GuardBits;  // output rounding shift
  // rounded sample width: round half up of the largest positive value can
  // reach 2^(CtrlWidth-1-GuardBits) when GuardBits > 0: one more bit then.
  static constexpr int kNarrow = CtrlWidth - GuardBits + (GuardBits > 0 ? 1 : 0);
  static constexpr int kDepthBits = bcu_clog2(MaxDepth + 1);
  static constexpr int kStack = MaxDepth * Axes;
  static constexpr int kMinTickSpacing = 3 + 4 * Axes * kWords + MaxDepth * Axes;

  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(ChunkWidth >= 8 && ChunkWidth <= 64, "ChunkWidth must be 8..64");
  static_assert(MaxDepth >= 1 && MaxDepth <= 30, "MaxDepth must be 1..30");
  static_assert(CtrlWidth >= 2, "CtrlWidth must be >= 2");
  static_assert(kW <= 128, "CtrlWidth + 3*MaxDepth must be <= 128 (u128 model)");
  static_assert(kAsmWidth <= 128, "Words*ChunkWidth must be <= 128");
  static_assert(GuardBits >= 0 && GuardBits <= CtrlWidth - 2, "GuardBits must be 0..CtrlWidth-2");
  static_assert(OutWidth >= kNarrow && OutWidth <= 64, "OutWidth must be kNarrow..64");

  enum State : uint8_t { S_IDLE = 0, S_LOAD = 1, S_PRE = 2, S_DESC = 3, S_READY = 4, S_POP = 5 };

  struct In {
    bool rst_n = true;
    u128 tdata = 0;
    bool tvalid = false;
    bool tick = false;
  };

  struct Regs {
    // control (reset)
    uint8_t state = S_IDLE;
    bool tick_q = false, tick_err_q = false, have_last_q = false;
    bool valid_q = false, underrun_q = false, done_q = false;
    int depth_q = 0, cnt_q = 0, lvl_q = 0, ax_q = 0, wc_q = 0, vc_q = 0, pidx_q = 0;
    uint32_t j_q = 0;
    // datapath (not reset)
    u128 cur_q[Axes][4] = {};
    u128 asm_q = 0;
    u128 rd_q[4] = {};
    u128 sample_q[Axes] = {};
    u128 last_q[Axes] = {};
  };

  BcuGen() = default;

  // Combinational / registered outputs of the current cycle (before the edge).
  bool tready() const { return r_.state == S_IDLE || r_.state == S_LOAD; }
  bool sample_valid() const { return r_.valid_q; }
  bool underrun() const { return r_.underrun_q; }
  bool seg_done() const { return r_.done_q; }
  bool tick_err() const { return r_.tick_err_q; }
  // Sample of axis a, OutWidth bits, as a signed value.
  int64_t sample(int a) const { return static_cast<int64_t>(sext(r_.sample_q[a], OutWidth)); }
  u128 sample_bits(int a) const { return r_.sample_q[a]; }
  const Regs& regs() const { return r_; }
  uint8_t state() const { return r_.state; }

  // Round a W-bit leaf value once, half up, to the OutWidth-bit sample.
  static u128 round_out(u128 x) {
    // x >>> S, sign-extended to kNarrow bits (one more than W-S when G > 0)
    const u128 hi = wrap(static_cast<u128>(sext(bits(x, kShift, kW - kShift), kW - kShift)), kNarrow);
    const u128 half = bits(x, kShift - 1, 1);
    const u128 narrow = wrap(hi + half, kNarrow);
    return wrap(static_cast<u128>(sext(narrow, kNarrow)), OutWidth);
  }

  // Trailing ones of j (bounded loop; mirrors the RTL priority chain).
  static int trailing_ones(uint32_t j) {
    int n = 0;
    bool stop = false;
    for (int i = 0; i < MaxDepth; ++i) {
      if (!stop) {
        if ((j >> i) & 1u)
          ++n;
        else
          stop = true;
      }
    }
    return n;
  }

  // One rising clock edge with inputs `in` held during the cycle.
  void clock(const In& in) {
    const Regs& q = r_;
    Regs n = r_;
    n.valid_q = false;
    n.underrun_q = false;
    n.done_q = false;
    bool consume = false;
    const bool accept = tready() && in.tvalid;

    // Stack read port: address of this cycle (POP only), data next cycle.
    int raddr = 0;
    bool mem_we = false;
    int waddr = 0;
    u128 wdata[4] = {};

    switch (q.state) {
      case S_IDLE:
        if (accept) {
          int d = static_cast<int>(bits(in.tdata, 0, kDepthBits));
          if (d > MaxDepth) d = MaxDepth;
          n.depth_q = d;
          n.cnt_q = MaxDepth - d;
          n.wc_q = 0;
          n.vc_q = 0;
          n.j_q = 0;
          n.lvl_q = 0;
          n.ax_q = 0;
          n.state = S_LOAD;
        } else if (q.tick_q) {
          consume = true;
          n.underrun_q = true;
          if (q.have_last_q) {
            n.valid_q = true;
            for (int a = 0; a < Axes; ++a) n.sample_q[a] = q.last_q[a];
          }
        }
        break;
      case S_LOAD:
        if (accept) {
          const u128 asm_d = (q.asm_q >> ChunkWidth) |
                             (wrap(in.tdata, ChunkWidth) << ((kWords - 1) * ChunkWidth));
          n.asm_q = asm_d;
          if (q.wc_q == kWords - 1) {
            n.wc_q = 0;
            const u128 val = wrap(static_cast<u128>(sext(asm_d, CtrlWidth)), kW);
            // flat shift chain: flat[i] <- flat[i+1], flat[last] <- val
            for (int i = 0; i < 4 * Axes - 1; ++i)
              n.cur_q[i / 4][i % 4] = q.cur_q[(i + 1) / 4][(i + 1) % 4];
            n.cur_q[Axes - 1][3] = val;
            if (q.vc_q == 4 * Axes - 1) {
              n.vc_q = 0;
              n.state = S_PRE;
            } else {
              n.vc_q = q.vc_q + 1;
            }
          } else {
            n.wc_q = q.wc_q + 1;
          }
        }
        break;
      case S_PRE:
        if (q.cnt_q != 0) {
          n.cnt_q = q.cnt_q - 1;
          for (int a = 0; a < Axes; ++a)
            for (int k = 0; k < 4; ++k) n.cur_q[a][k] = wrap(q.cur_q[a][k] << 3, kW);
        } else {
          n.state = (q.depth_q == 0) ? S_READY : S_DESC;
        }
        break;
      case S_DESC: {
        u128 in4[4];
        for (int k = 0; k < 4; ++k) in4[k] = wrap(q.cur_q[0][k], kW - 3);
        const BcuOut o = bcu_split(in4, kW - 3);
        for (int a = 0; a < Axes - 1; ++a)
          for (int k = 0; k < 4; ++k) n.cur_q[a][k] = q.cur_q[a + 1][k];
        for (int k = 0; k < 4; ++k) n.cur_q[Axes - 1][k] = o.l[k];
        mem_we = true;
        waddr = q.lvl_q * Axes + q.ax_q;
        for (int k = 0; k < 4; ++k) wdata[k] = o.r[k];
        if (q.ax_q == Axes - 1) {
          n.ax_q = 0;
          n.lvl_q = q.lvl_q + 1;
          if (q.lvl_q + 1 == q.depth_q) n.state = S_READY;
        } else {
          n.ax_q = q.ax_q + 1;
        }
        break;
      }
      case S_READY:
        if (q.tick_q) {
          consume = true;
          n.valid_q = true;
          for (int a = 0; a < Axes; ++a) n.sample_q[a] = round_out(q.cur_q[a][0]);
          const uint32_t last_j = (1u << q.depth_q) - 1u;
          if (q.j_q == last_j) {
            n.done_q = true;
            n.have_last_q = true;
            for (int a = 0; a < Axes; ++a) n.last_q[a] = round_out(q.cur_q[a][3]);
            n.state = S_IDLE;
          } else {
            const int p = q.depth_q - 1 - trailing_ones(q.j_q);
            n.pidx_q = p;
            n.lvl_q = p + 1;
            n.ax_q = 0;
            n.j_q = q.j_q + 1;
            n.state = S_POP;
          }
        }
        break;
      case S_POP:
        if (q.ax_q < Axes) raddr = q.pidx_q * Axes + q.ax_q;
        if (q.ax_q != 0) {
          for (int a = 0; a < Axes - 1; ++a)
            for (int k = 0; k < 4; ++k) n.cur_q[a][k] = q.cur_q[a + 1][k];
          for (int k = 0; k < 4; ++k) n.cur_q[Axes - 1][k] = q.rd_q[k];
        }
        if (q.ax_q == Axes) {
          n.ax_q = 0;
          n.state = (q.lvl_q == q.depth_q) ? S_READY : S_DESC;
        } else {
          n.ax_q = q.ax_q + 1;
        }
        break;
      default:
        n.state = S_IDLE;
        break;
    }

    // memory: synchronous read of the old contents, then write
    for (int k = 0; k < 4; ++k) n.rd_q[k] = mem_[raddr][k];
    if (mem_we)
      for (int k = 0; k < 4; ++k) mem_[waddr][k] = wdata[k];

    n.tick_q = (q.tick_q && !consume) || in.tick;
    n.tick_err_q = q.tick_err_q || (in.tick && q.tick_q && !consume);

    if (!in.rst_n) {
      n.state = S_IDLE;
      n.tick_q = n.tick_err_q = n.have_last_q = false;
      n.valid_q = n.underrun_q = n.done_q = false;
      n.depth_q = n.cnt_q = n.lvl_q = n.ax_q = n.wc_q = n.vc_q = n.pidx_q = 0;
      n.j_q = 0;
    }
    r_ = n;
  }

 private:
  Regs r_{};
  u128 mem_[kStack][4] = {};
};

}  // namespace traj
