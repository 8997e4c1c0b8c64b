// trajcore hls: BCU generator. Samples a cubic Bernstein polynomial per axis
// at t = j/2^d, j = 0..2^d-1, in increasing time order, one sample per servo
// tick, by depth-first de Casteljau mid-subdivision with an explicit stack.
// Mirrors rtl/traj_bcu_gen.sv (and its digit-serial BCU, rtl/traj_bcu_serial.sv)
// register for register, cycle for cycle.
//
// Parameters
//   Axes        axes in lockstep (1..8)
//   ChunkWidth  stream word width AND carry-chain digit width (8..64)
//   CtrlWidth   width of a control value (two's complement); LSB = 2^-GuardBits
//               output LSB
//   GuardBits   control-value bits below the output LSB
//   OutWidth    sample width, >= CtrlWidth-GuardBits+(GuardBits>0) (sign-extended)
//   MaxDepth    largest depth d (K = 2^d samples per segment), 1..30
//
// Arithmetic (exact, scaled form)
//   W = CtrlWidth + 3*MaxDepth bits are enough for every coefficient; the
//   datapath holds Digits = ceil(W/ChunkWidth) digits of ChunkWidth bits
//   (WP = Digits*ChunkWidth bits, two's complement; the bits above W are sign).
//   The host sends every control value already multiplied by 8^(MaxDepth-d)
//   (sign-extended to WP bits), so after the d subdivision levels every leaf
//   coefficient is 8^MaxDepth times the true value whatever d is: the output is
//   one fixed bit slice (no barrel shifter, no pre-scaling pass in hardware).
//   A coefficient at effective level e (= MaxDepth-d + subdivisions) is 8^e
//   times a convex combination of the control values: it fits CtrlWidth+3e
//   bits <= W, so nothing is ever rounded or lost. The leaf value A at
//   t = j/2^d is  A = 8^MaxDepth * sum_i C(3,i) (1-t)^(3-i) t^i c_i  (exactly),
//   and the output is rounded once, half up:
//       sample = floor((A + 2^(S-1)) / 2^S),  S = 3*MaxDepth + GuardBits.
//   |A| <= 8^MaxDepth max|c| (convex hull), so the sample fits
//   CtrlWidth-GuardBits bits, plus one when GuardBits > 0: no overflow.
//   Error vs the exact fixed-point polynomial: <= 1/2 output LSB for every d.
//
// Datapath (digit-serial, no adder wider than ChunkWidth)
//   ring: four lanes (A, B, C, D) of R = N + P digit positions, N = Axes*Digits,
//   P = 2 (BCU pipeline latency). Positions 0..N-1 hold axis a, digit k at
//   a*Digits + k (least significant digit first); positions N..N+1 are spare.
//   A pass shifts every lane by one position per cycle (pos[i] <- pos[i+1],
//   pos[R-1] <- pos[0]) for R cycles, so the ring is aligned again after it.
//   The BCU (stage 1: s1=A+B, s2=B+C, s3=C+D; stage 2: t1=s1+s2, t2=s2+s3;
//   output: m=t1+t2 and the shifted digits) reads the head pos[0] and is
//   pipelined: the digit-k result appears 2 cycles later and is written at
//   pos[N-1] (instead of pos[N]): it lands exactly at position k when the
//   pass ends. Every adder is ChunkWidth bits plus a saved carry, reset at the
//   first digit of each value (the same trick as traj_fd_engine); the shifts
//   <<1, <<2, <<3 take the top bits of the previous digit from 1-3 bit flops.
//   stack: MaxDepth*N entries of 4 digits (one digit of R per lane) = block
//   RAM, one write port, synchronous read; entry lvl*N + a*Digits + k holds
//   digit k of the right half pushed by axis a when descending from lvl.
//
// Schedule (depth-first, time order)
//   IDLE  : accept a header word (depth d, clamped to MaxDepth); else, if a
//           tick is pending, process it as an underrun.
//   LOAD  : 4*N words, digit by digit: axis 0 digit 0 of A, B, C, D, axis 0
//           digit 1 of A..D, ...; every 4th word shifts the ring once, the
//           4 digits entering at pos[N-1]. N shifts: aligned. Then SETTLE
//           (d = 0) or DESC.
//   DESC  : while lvl < d: one pass (R cycles): every axis (L,R) = BCU(cur),
//           R -> stack[lvl*N ..], cur = L. Then SETTLE.
//   SETTLE: one cycle: the output rounding registers (rnd_a_q, rnd_d_q: round
//           of A and D of every axis, computed from the ring every cycle, so
//           no adder is in the path to sample_q) take the leaf. Then READY.
//   READY : leaf j is ready: its A (all axes) is sample j. On a pending tick:
//           emit round(A); if j = 2^d-1: seg_done, -> IDLE (the ring keeps the
//           last leaf; its D is the end value). Else the next leaf is the
//           right half pushed at level p = d-1-(trailing ones of j):
//   POP   : one pass (R cycles) reading stack[p*N ..] (data one cycle later,
//           written at pos[N]), lvl = p+1, then DESC (down to d) or SETTLE.
//   Every internal node of the subdivision tree is split exactly once:
//   2^d-1 BCU operations (6 additions each, per axis) for 2^d samples.
//   p and p*N are computed from j in three pipeline registers every cycle; j
//   only changes at a tick and READY is at least R cycles later.
//
// Timing (clock cycles)
//   tick_i at cycle t -> tick_q at t+1 -> processed at t+1 if READY/IDLE ->
//   sample_valid_o at t+2. Within a segment the next leaf is ready at most
//   2 + d*R cycles after a tick was processed (worst at j = 2^(d-1)-1: a pop
//   from level 0, then d-1 descents, then SETTLE). Between segments (stream
//   never starved): 3 + 4*N + d*R cycles. Hence
//       kMinTickSpacing = 3 + 4*N + MaxDepth*R
//   (267 for 3 axes, 16-bit digits, 40-bit control, MaxDepth 12): with ticks
//   at least that many cycles apart and the stream never starved, every tick
//   is served with latency 2 (tests check it, and that one cycle less fails).
//
// Interface rules (shared with traj_fd_engine)
//   * ticks are latched in tick_q; a tick while one is pending and not being
//     processed in the same cycle sets the sticky tick_err.
//   * a pending tick is processed only in READY, or in IDLE when no header word
//     is being accepted in the same cycle (the header has priority, as in the
//     FD engine); never during LOAD/DESC/POP.
//   * a tick processed in IDLE: underrun pulses; sample_valid pulses only if a
//     segment has been completed since reset, and then the sample is the end
//     value round(D) of the last segment (read from the ring, which still holds
//     the last leaf). A chained segment starts with A = D: no jump.
//   * seg_done pulses with the K-th sample (j = K-1).
//   * reset (rst_n low, synchronous) clears control state only.
//
// Stream: word 0 = header, depth d in bits [DepthBits-1:0] (higher bits
// ignored; d > MaxDepth is clamped to MaxDepth, the host never sends it);
// then for axis 0..Axes-1, for digit k = 0..Digits-1 (least significant
// first): digit k of A, B, C, D, where each value is c * 8^(MaxDepth-d) in WP
// bits two's complement (host: traj::bcu::stream_words).
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
  static constexpr int kW = CtrlWidth + 3 * MaxDepth;                  // value bits needed
  static constexpr int kDigits = (kW + ChunkWidth - 1) / ChunkWidth;   // digits per value
  static constexpr int kWP = kDigits * ChunkWidth;                     // datapath width
  static constexpr int kWords = kDigits;                               // stream words per value
  static constexpr int kN = Axes * kDigits;                            // digits per lane
  static constexpr int kP = 2;                                         // BCU pipeline latency
  static constexpr int kR = kN + kP;                                   // ring positions, pass length
  static constexpr int kSegWords = 1 + 4 * kN;                         // words per segment
  static constexpr int kShift = 3 * MaxDepth + GuardBits;              // output rounding shift
  static constexpr int kNarrow = CtrlWidth - GuardBits + (GuardBits > 0 ? 1 : 0);
  static constexpr int kDepthBits = bcu_clog2(MaxDepth + 1);
  static constexpr int kStack = MaxDepth * kN;
  static constexpr int kAddrBits = bcu_clog2(kStack + 1);
  static constexpr int kMinTickSpacing = 3 + 4 * kN + MaxDepth * kR;

  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(ChunkWidth >= 8 && ChunkWidth <= 64, "ChunkWidth must be 8..64");
  static_assert(MaxDepth >= 1 && MaxDepth <= 30, "MaxDepth must be 1..30");
  static_assert(CtrlWidth >= 2, "CtrlWidth must be >= 2");
  static_assert(kWP <= 128, "ceil((CtrlWidth+3*MaxDepth)/ChunkWidth)*ChunkWidth must be <= 128");
  static_assert(GuardBits >= 0 && GuardBits <= CtrlWidth - 2, "GuardBits must be 0..CtrlWidth-2");
  static_assert(OutWidth >= kNarrow && OutWidth <= 64, "OutWidth must be kNarrow..64");

  enum State : uint8_t { S_IDLE = 0, S_LOAD = 1, S_SETTLE = 2, S_DESC = 3, S_READY = 4, S_POP = 5 };

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
    int depth_q = 0, lvl_q = 0, pc_q = 0, wc_q = 0, lc_q = 0, dg_q = 0, addr_q = 0;
    uint32_t j_q = 0;
    bool pc_last_q = false;  // == (pc_q == kR-1), a flop in the RTL (timing)
    bool rsel_q = true;  // == (state == S_IDLE): sample from rnd_d_q, else rnd_a_q
    // datapath (not reset)
    bool is_last_q = false;             // j == 2^d-1, registered
    bool desc_last_q = false;           // lvl+1 == d, registered
    bool lvl_eq_q = false;              // lvl == d, registered
    uint32_t zero_oh_q = 0;             // pop address pipeline: lowest zero of j (one-hot),
    int pop_lvl_q = 0, pop_base_q = 0;  // p = d-1-(its index), p*N
    uint64_t ring[4][kR] = {};
    uint64_t asm_q[3] = {};
    // BCU stage 1
    uint64_t s1_q = 0, s2_q = 0, s3_q = 0, a1_q = 0, d1_q = 0;
    bool cs1_q = false, cs2_q = false, cs3_q = false, first1_q = false;
    // BCU stage 2
    uint64_t t1_q = 0, t2_q = 0, a2_q = 0, s12_q = 0, s32_q = 0, d2_q = 0;
    bool ct1_q = false, ct2_q = false;
    // BCU output stage: carry of m, top bits of the previous digit for shifts
    bool cm_q = false;
    uint64_t ha_q = 0, hs1_q = 0, ht1_q = 0, ht2_q = 0, hs3_q = 0, hd_q = 0;
    uint64_t rd_q[4] = {};
    u128 rnd_a_q[Axes] = {}, rnd_d_q[Axes] = {};  // round(A), round(D) of the ring, every cycle
    u128 sample_q[Axes] = {};
  };

  BcuGen() = default;

  bool tready() const { return r_.state == S_IDLE || r_.state == S_LOAD; }
  bool sample_valid() const { return r_.valid_q; }
  bool underrun() const { return r_.underrun_q; }
  bool seg_done() const { return r_.done_q; }
  bool tick_err() const { return r_.tick_err_q; }
  int64_t sample(int a) const { return static_cast<int64_t>(sext(r_.sample_q[a], OutWidth)); }
  u128 sample_bits(int a) const { return r_.sample_q[a]; }
  const Regs& regs() const { return r_; }
  uint8_t state() const { return r_.state; }

  // Value of lane l (0..3 = A..D) of axis a in the aligned ring, WP bits.
  static u128 lane_value(const Regs& q, int l, int a) {
    u128 v = 0;
    for (int k = 0; k < kDigits; ++k) v |= u128(q.ring[l][a * kDigits + k]) << (k * ChunkWidth);
    return v;
  }

  // Round a WP-bit leaf value once, half up, to the OutWidth-bit sample.
  static u128 round_out(u128 x) {
    const u128 hi =
        wrap(static_cast<u128>(sext(bits(x, kShift, kWP - kShift), kWP - kShift)), kNarrow);
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
    constexpr uint64_t M = ChunkWidth >= 64 ? ~uint64_t(0) : ((uint64_t(1) << ChunkWidth) - 1);
    n.valid_q = false;
    n.underrun_q = false;
    n.done_q = false;
    bool consume = false;
    const bool accept = tready() && in.tvalid;
    const uint64_t word = static_cast<uint64_t>(in.tdata) & M;

    // ---- digit-serial BCU (free running) ----
    // Saved carries and shift bits are cleared when captured if the digit that
    // will use them is the first of a value (the RTL does it there for timing).
    auto add = [&](uint64_t x, uint64_t y, bool cin, bool& cout) {
      const u128 s = u128(x) + u128(y) + u128(cin ? 1 : 0);
      cout = ((s >> ChunkWidth) & 1) != 0;
      return static_cast<uint64_t>(s) & M;
    };
    // digit index of the head digit (0 = first digit of a value)
    n.dg_q = (q.state == S_DESC && !q.pc_last_q) ? (q.dg_q == kDigits - 1 ? 0 : q.dg_q + 1) : 0;
    const bool f0 = q.dg_q == 0;
    const bool f0_next = n.dg_q == 0;
    {
      const uint64_t a = q.ring[0][0], b = q.ring[1][0], c = q.ring[2][0], d = q.ring[3][0];
      n.s1_q = add(a, b, q.cs1_q, n.cs1_q);
      n.s2_q = add(b, c, q.cs2_q, n.cs2_q);
      n.s3_q = add(c, d, q.cs3_q, n.cs3_q);
      n.cs1_q = n.cs1_q && !f0_next;
      n.cs2_q = n.cs2_q && !f0_next;
      n.cs3_q = n.cs3_q && !f0_next;
      n.a1_q = a;
      n.d1_q = d;
      n.first1_q = f0;
      n.t1_q = add(q.s1_q, q.s2_q, q.ct1_q, n.ct1_q);
      n.t2_q = add(q.s2_q, q.s3_q, q.ct2_q, n.ct2_q);
      n.ct1_q = n.ct1_q && !f0;
      n.ct2_q = n.ct2_q && !f0;
      n.a2_q = q.a1_q;
      n.s12_q = q.s1_q;
      n.s32_q = q.s3_q;
      n.d2_q = q.d1_q;
    }
    const uint64_t mdig = add(q.t1_q, q.t2_q, q.cm_q, n.cm_q);
    n.cm_q = n.cm_q && !q.first1_q;
    auto shl = [&](uint64_t x, int s, uint64_t h) { return ((x << s) | h) & M; };
    const uint64_t outl[4] = {shl(q.a2_q, 3, q.ha_q), shl(q.s12_q, 2, q.hs1_q), shl(q.t1_q, 1, q.ht1_q),
                              mdig};
    const uint64_t outr[4] = {mdig, shl(q.t2_q, 1, q.ht2_q), shl(q.s32_q, 2, q.hs3_q),
                              shl(q.d2_q, 3, q.hd_q)};
    const bool f1 = q.first1_q;
    n.ha_q = f1 ? 0 : q.a2_q >> (ChunkWidth - 3);
    n.hs1_q = f1 ? 0 : q.s12_q >> (ChunkWidth - 2);
    n.ht1_q = f1 ? 0 : q.t1_q >> (ChunkWidth - 1);
    n.ht2_q = f1 ? 0 : q.t2_q >> (ChunkWidth - 1);
    n.hs3_q = f1 ? 0 : q.s32_q >> (ChunkWidth - 2);
    n.hd_q = f1 ? 0 : q.d2_q >> (ChunkWidth - 3);

    // ---- control ----
    bool shift = false, ins_desc = false, ins_load = false, ins_pop = false;
    bool mem_we = false;
    switch (q.state) {
      case S_IDLE: {
        // Only the state (and the tick) depend on accept (timing): depth is
        // taken from every word offered in IDLE (the accepted header is the
        // last), j, lvl and addr are cleared in every IDLE cycle, and wc, lc
        // and pc are always 0 in IDLE.
        int d = static_cast<int>(bits(in.tdata, 0, kDepthBits));
        if (d > MaxDepth) d = MaxDepth;
        n.depth_q = d;
        n.j_q = 0;
        n.lvl_q = 0;
        n.addr_q = 0;
        if (accept) {
          n.state = S_LOAD;
        } else if (q.tick_q) {
          consume = true;
          n.underrun_q = true;
          if (q.have_last_q) {
            n.valid_q = true;
            for (int a = 0; a < Axes; ++a) n.sample_q[a] = q.rsel_q ? q.rnd_d_q[a] : q.rnd_a_q[a];
          }
        }
        break;
      }
      case S_LOAD:
        if (accept) {
          if (q.wc_q == 3) {
            n.wc_q = 0;
            shift = true;
            ins_load = true;
            if (q.lc_q == kN - 1) {
              n.lc_q = 0;
              n.state = (q.depth_q == 0) ? S_SETTLE : S_DESC;
            } else {
              n.lc_q = q.lc_q + 1;
            }
          } else {
            n.asm_q[q.wc_q] = word;
            n.wc_q = q.wc_q + 1;
          }
        }
        break;
      case S_DESC:
        shift = true;
        ins_desc = true;
        if (q.pc_q >= kP) {
          mem_we = true;
          n.addr_q = wrap(q.addr_q + 1, kAddrBits);
        }
        if (q.pc_last_q) {
          n.pc_q = 0;
          n.lvl_q = q.lvl_q + 1;
          if (q.desc_last_q) n.state = S_SETTLE;
        } else {
          n.pc_q = q.pc_q + 1;
        }
        break;
      case S_SETTLE:  // one cycle for rnd_a_q to see the leaf (the ring is static)
        n.state = S_READY;
        break;
      case S_READY:
        if (q.tick_q) {
          consume = true;
          n.valid_q = true;
          for (int a = 0; a < Axes; ++a) n.sample_q[a] = q.rsel_q ? q.rnd_d_q[a] : q.rnd_a_q[a];
          if (q.is_last_q) {
            n.done_q = true;
            n.have_last_q = true;
            n.state = S_IDLE;
          } else {
            n.lvl_q = static_cast<int>(wrap(q.pop_lvl_q + 1, kDepthBits));
            n.addr_q = q.pop_base_q;
            n.pc_q = 0;
            n.j_q = static_cast<uint32_t>(wrap(q.j_q + 1, MaxDepth));
            n.state = S_POP;
          }
        }
        break;
      case S_POP:
        shift = true;
        ins_pop = true;
        if (q.pc_q < kN) n.addr_q = wrap(q.addr_q + 1, kAddrBits);
        if (q.pc_last_q) {
          n.pc_q = 0;
          n.state = q.lvl_eq_q ? S_SETTLE : S_DESC;
        } else {
          n.pc_q = q.pc_q + 1;
        }
        break;
      default:
        n.state = S_IDLE;
        break;
    }
    n.desc_last_q = static_cast<int>(wrap(q.lvl_q + 1, kDepthBits)) == q.depth_q;
    n.lvl_eq_q = q.lvl_q == q.depth_q;
    n.is_last_q = q.j_q == static_cast<uint32_t>(wrap((u128(1) << q.depth_q) - 1, MaxDepth));
    // pop address pipeline: lowest zero of j (one-hot), p = d-1-(its index)
    // = d-1-(trailing ones of j), then p*N
    n.zero_oh_q = static_cast<uint32_t>(wrap(~u128(q.j_q) & (u128(q.j_q) + 1), MaxDepth));
    int tones = 0;
    for (int i = 0; i < MaxDepth; ++i)
      if ((q.zero_oh_q >> i) & 1u) tones |= i;
    n.pop_lvl_q = static_cast<int>(wrap(static_cast<u128>(q.depth_q - 1 - tones), kDepthBits));
    n.pop_base_q = static_cast<int>(wrap(static_cast<u128>(q.pop_lvl_q) * kN, kAddrBits));

    // ---- output rounding, registered every cycle (the ring is static in
    // SETTLE/READY/IDLE; IDLE is entered only from READY or reset) ----
    for (int a = 0; a < Axes; ++a) {
      n.rnd_a_q[a] = round_out(lane_value(q, 0, a));
      n.rnd_d_q[a] = round_out(lane_value(q, 3, a));
    }

    // ---- ring ----
    if (shift) {
      const uint64_t quad[4] = {q.asm_q[0], q.asm_q[1], q.asm_q[2], word};
      for (int l = 0; l < 4; ++l) {
        for (int i = 0; i < kR - 1; ++i) n.ring[l][i] = q.ring[l][i + 1];
        n.ring[l][kR - 1] = q.ring[l][0];
        if (ins_desc) n.ring[l][kN - 1] = outl[l];
        if (ins_load) n.ring[l][kN - 1] = quad[l];
        if (ins_pop) n.ring[l][kN] = q.rd_q[l];
      }
    }

    // ---- stack: synchronous read of the old contents, then write ----
    for (int l = 0; l < 4; ++l) n.rd_q[l] = mem_[q.addr_q][l];
    if (mem_we)
      for (int l = 0; l < 4; ++l) mem_[q.addr_q][l] = outr[l];

    n.tick_q = (q.tick_q && !consume) || in.tick;
    n.tick_err_q = q.tick_err_q || (in.tick && q.tick_q && !consume);

    if (!in.rst_n) {
      n.state = S_IDLE;
      n.tick_q = n.tick_err_q = n.have_last_q = false;
      n.valid_q = n.underrun_q = n.done_q = false;
      n.depth_q = n.lvl_q = n.pc_q = n.wc_q = n.lc_q = n.dg_q = n.addr_q = 0;
      n.j_q = 0;
    }
    n.rsel_q = n.state == S_IDLE;
    n.pc_last_q = n.pc_q == kR - 1;
    r_ = n;
  }

 private:
  Regs r_{};
  uint64_t mem_[1 << kAddrBits][4] = {};
};

}  // namespace traj
