// SPDX-License-Identifier: Apache-2.0
// trajcore hls: BCU generator. Samples a cubic Bernstein polynomial per axis
// at t = j/2^d, j = 0..2^d-1, in increasing time order, ONE SAMPLE PER CLOCK
// once a segment has started, then holds the end value. Mirrors
// rtl/traj_bcu_gen.sv register for register, cycle for cycle.
//
// Parameters
//   Axes        axes in lockstep (1..8)
//   ChunkWidth  stream word width AND carry-chain chunk width (8..64)
//   CtrlWidth   width of a control value (two's complement); LSB = 2^-GuardBits
//               output LSB
//   GuardBits   control-value bits below the output LSB
//   OutWidth    sample width, >= CtrlWidth-GuardBits+(GuardBits>0) (sign-extended)
//   MaxDepth    largest depth d (K = 2^d samples per segment), 1..30
//
// Arithmetic (exact, scaled form)
//   W = CtrlWidth + 3*MaxDepth bits hold every BCU coefficient; the stream
//   carries Digits = ceil(W/ChunkWidth) digits per value. The host sends
//   every control value multiplied by 8^(MaxDepth-d), so after d scaled
//   mid-subdivisions (L = (8A, 4(A+B), 2(A+2B+C), A+3B+3C+D)) a leaf is
//   8^MaxDepth times the exact value, and the output is one fixed bit slice,
//   rounded once, half up:
//       sample = floor((X + 2^(S-1)) / 2^S),  S = 3*MaxDepth + GuardBits,
//   where X = 8^MaxDepth * sum_i C(3,i) (1-t)^(3-i) t^i c_i exactly.
//
// Method: BCU descent to the first leaf, then exact integer forward
// differences across the whole segment.
//   1. The d scaled mid-subdivisions along the LEFT spine of the subdivision
//      tree (digit-serial BCU, in place in block RAM, one pass per level) give
//      the first leaf (A, B, C, D): the cubic on [0, 1/2^d], scaled by
//      8^MaxDepth. Its polynomial Q(x) = A(1-x)^3 + 3B(1-x)^2 x + 3C(1-x)x^2
//      + D x^3 has integer coefficients in x and Q(j) = X at t = j/2^d for
//      EVERY integer j (the leaf is an affine reparameterisation of the
//      segment's cubic): one leaf determines all 2^d samples.
//   2. One digit-serial pass computes the forward differences of Q at x = 0,
//      exact integers, shifts and adds only:
//          S0 = A + 2^(S-1)  (the output rounding constant folded in),
//          D1 = D - A,   D2 = 6(B - 2C + D),   D3 = 6(D - 3C + 3B - A).
//      (These are the S_0/Delta formulas with m = 0 at the first leaf:
//      c1 = 3(B-A), c2 = 3(A-2B+C), c3 = D-3C+3B-A, Delta1 = c1+c2+c3,
//      Delta2 = 2c2+6c3, Delta3 = 6c3.)
//   3. The forward-difference stage S += D1; D1 += D2; D2 += D3 gives
//      S_j = Q(j) + 2^(S-1) for j = 0, 1, ... exactly: every identity is an
//      integer one, so computing modulo 2^WF (WF = C*ChunkWidth,
//      C = ceil((W+1)/ChunkWidth) chunks) is exact because the true S_j fits
//      W+1 bits; the sample is S_j's bits [S, S+Narrow) (a bit slice: no
//      adder after the stage). The same recurrence one step further gives
//      S_K = 8^MaxDepth*D + 2^(S-1): the end value round(D).
//   Same samples, bit for bit, as the subdivision of every leaf (a
//   depth-first generator): both are the exact value rounded once.
//
// Why not the full depth-first subdivision with an FD stage under each
// level-(d-m) node: the same exactness argument makes one leaf enough, so
// there is no stack, no per-node reload deadline (no 2^m >= (d-m+1)R rule),
// no special case for d < m, one initialisation per segment instead of one
// per node, and 3 additions per sample and axis instead of 3 + the BCU's.
//
// Datapath
//   * Block RAM: one memory per (lane l = A/S0, B/D1, C/D2, D/D3; axis a),
//     ChunkWidth bits wide, 2 banks x C digits (address {bank, digit}). The
//     segment is written there word by word (LOAD), subdivided in place (DESC),
//     turned into differences in place (INIT), then read chunk by chunk into
//     the forward-difference stage. Two banks: the next segment loads while the
//     previous one is still being read out.
//   * Digit-serial pipeline (DESC and INIT passes share it): read address
//     (cycle c) -> rd (c+1, block RAM output) -> hd (c+2, axis multiplexer)
//     -> stage 1 (c+3) -> stage 2 (c+4) -> write register (c+5) -> RAM.
//     Adders are ChunkWidth bits with saved carries (cleared, or set for a
//     subtraction, when the next digit of that stage starts a value), the
//     shifts take the top bits of the previous digit from small flops.
//       BCU:  s1=A+B, s2=B+C, s3=C+D | t1=s1+s2, t2=s2+s3 | m=t1+t2,
//             L = (A<<3, s1<<2, t1<<1, m)
//       INIT: e1=D-A, e2=B-C, e3=D-C | u=e2+e3, y1=(e1<<2)+(e1<<1),
//             y2=(e2<<4)+(e2<<1) | S0=A+half, D1=e1, D2=(u<<2)+(u<<1), D3=y1+y2
//     A DESC pass covers the Digits digits of every value (N = Axes*Digits
//     slots), an INIT pass C digits (Axes*C slots; when C = Digits+1 the top
//     digit is the sign fill of digit Digits-1, made in the hd stage).
//   * Forward-difference stage, per axis four registers (S, D1, D2, D3) of C
//     chunks; chunk k adds with the carry of chunk k-1 registered: a skewed
//     pipeline. All chunks advance together ("adv"); after advance number a,
//     chunk k holds step a-k, so the top chunk holds step a-(C-1), and the
//     output bits of lower chunks wait in small deskew registers (C-1-k
//     stages, output-slice bits only). One sample per advance, latency C-1
//     advances, no carry chain longer than ChunkWidth.
//   * Segments enter the stage skewed: a tag shift register (valid, start,
//     last, end) runs beside the chunks; chunk k loads the new segment's
//     chunk k (from the RAM output register) at the advance where the start
//     tag reaches it, so the next segment follows the last step of the
//     previous one with no gap. The RAM read of chunk k+1 is issued with the
//     load of chunk k (the read port is the transfer's for those C advances).
//
// Schedule
//   prep FSM (one segment at a time):
//     IDLE : accept a header word (depth d, clamped to MaxDepth; the header
//            takes the free bank). tready = (IDLE or LOAD).
//     LOAD : 4*N words (axis, digit, A B C D), each written to its RAM.
//     WAITX: until no transfer is pending or running (the read port and the
//            RAM output register belong to it).
//     DESC : d passes of Pp = max(N, L+1) cycles (L = 5: read -> write).
//     INIT : Pi = Axes*C + L + 1 cycles: one pass, drain, and in its last
//            cycle the hand-off: read chunk 0 of the bank, pending = 1.
//   FD stage: adv = top valid ? (tick processed) : (top is the end tag ?
//     (a newer segment exists) : 1). At an advance the entering tag is the
//     next step of the current segment, else the pending segment's start,
//     else (once) the end tag, else a bubble.
//   Startup (stream not starved, nothing playing): a header accepted at cycle
//     h gives the first sample ready at h + kStartLatency(d) =
//     h + 1 + 4N + 1 + d*Pp + Pi + C (LOAD, WAITX, DESC, INIT, C advances);
//     tick_i at cycle t >= that - 1 -> sample_valid_o at t+2.
//   Once started: a sample per processed tick, ticks on consecutive clocks are
//     all served with latency 2 (one sample per clock).
//   Segment to segment: the next segment enters right behind the last step if
//     it is pending by then, which it is when the current segment has
//     K >= kBackToBack(d_next) = 4N + 2 + d_next*Pp + Pi samples (stream not
//     starved): then consecutive segments also play at one sample per clock.
//     Otherwise the gap is the rest of the next segment's preparation plus
//     C clocks. Uniform ticks kMinTickSpacing = kBackToBack(MaxDepth) apart
//     are always served (263 clocks at the defaults).
//
// Structure: the class mirrors the RTL one to one: the same register names
// (Regs member == RTL flop), the same sections in the same order
// (parameters and derived constants, state, next-state logic per section,
// outputs), each section under the same comment. The RTL's timing copies
// (xk1_q, vlo_q, slo_q) are registers here too, checked against their
// definitions every cycle (always on, also in Release builds); the RTL
// proves the same properties formally (scripts/formal.sh).
//
// Interface rules (shared with traj_fd_engine)
//   * ticks are latched in tick_q; a tick while one is pending and not being
//     processed in the same cycle sets the sticky tick_err.
//   * a pending tick is processed when a sample is ready (top tag valid), or
//     as an underrun when nothing is coming: prep FSM in IDLE with no header
//     offered in the same cycle (the header has priority, as in the FD
//     engine), no segment pending and no sample in the stage. Otherwise it
//     waits (a segment is loading or being prepared).
//   * an underrun tick: underrun pulses; sample_valid pulses only if a segment
//     has been completed since reset, and then the sample is the end value
//     round(D) of the last segment (the stage's end tag, step K). A chained
//     segment starts with A = D: no jump.
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
#include <cstdio>
#include <cstdlib>

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
  // ---------------------------------------------------------------------
  // Parameters and derived constants (the RTL's localparams).
  // ---------------------------------------------------------------------
  static constexpr int kAxes = Axes;
  static constexpr int kOutWidth = OutWidth;
  static constexpr int kW = CtrlWidth + 3 * MaxDepth;                  // value bits needed
  static constexpr int kDigits = (kW + ChunkWidth - 1) / ChunkWidth;   // stream digits per value
  static constexpr int kWP = kDigits * ChunkWidth;                     // stream value width
  static constexpr int kWords = kDigits;                               // stream words per value
  static constexpr int kN = Axes * kDigits;                            // DESC pass slots
  static constexpr int kSegWords = 1 + 4 * kN;                         // words per segment
  static constexpr int kC = (kW + 1 + ChunkWidth - 1) / ChunkWidth;   // FD chunks (digits)
  static constexpr int kWF = kC * ChunkWidth;                          // FD register width
  static constexpr int kNi = Axes * kC;                                // INIT pass slots
  static constexpr int kL = 5;                                         // read -> write latency
  static constexpr int kPp = kN > kL + 1 ? kN : kL + 1;               // DESC pass period
  static constexpr int kPi = kNi + kL + 1;                             // INIT + drain + hand-off
  static constexpr int kShift = 3 * MaxDepth + GuardBits;              // output rounding shift
  static constexpr int kNarrow = CtrlWidth - GuardBits + (GuardBits > 0 ? 1 : 0);
  static constexpr int kDepthBits = bcu_clog2(MaxDepth + 1);
  static constexpr int kDgBits = bcu_clog2(kC) > 0 ? bcu_clog2(kC) : 1;
  static constexpr int kAxBits = bcu_clog2(Axes) > 0 ? bcu_clog2(Axes) : 1;
  static constexpr int kPcBits = bcu_clog2((kPp > kPi ? kPp : kPi) + 1);
  static constexpr int kMemWords = 2 << kDgBits;                       // {bank, digit}
  static constexpr int kHalfDigit = (kShift - 1) / ChunkWidth;         // rounding constant 2^(Shift-1)
  static constexpr int kHalfBit = (kShift - 1) % ChunkWidth;
  static constexpr int kK0 = kShift / ChunkWidth;                      // lowest chunk of the output slice
  // Header accepted at cycle h (stream not starved, no segment in the way):
  // first sample ready (a tick at cycle >= h + kStartLatency(d) - 1 is served
  // with latency 2).
  static constexpr int kStartLatency(int d) { return 1 + 4 * kN + 1 + d * kPp + kPi + kC; }
  static constexpr int kStartLatencyMax = 1 + 4 * kN + 1 + MaxDepth * kPp + kPi + kC;
  // Back to back at one sample per clock: a segment of K samples followed by
  // one of depth dn plays on without a gap (ticks on every clock, stream not
  // starved) when K >= kBackToBack(dn); exact for a segment started from idle
  // (test BackToBackRuleIsExact): its hand-off is followed by the next header
  // (1), LOAD (4N), WAITX (1: the transfer of C chunks is over by then), DESC,
  // INIT; the next start must be pending when the last step enters.
  static constexpr int kBackToBack(int dn) { return 4 * kN + 2 + dn * kPp + kPi; }
  // Uniform ticks at least this far apart are always served with latency 2,
  // whatever the depths (stream never starved). Tight: a depth-0 segment
  // followed by a depth-MaxDepth one needs all of it.
  static constexpr int kMinTickSpacing = kBackToBack(MaxDepth);
  // Once a segment has started, ticks may come on every clock.
  static constexpr int kRunTickSpacing = 1;

  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(ChunkWidth >= 8 && ChunkWidth <= 64, "ChunkWidth must be 8..64");
  static_assert(MaxDepth >= 1 && MaxDepth <= 30, "MaxDepth must be 1..30");
  static_assert(CtrlWidth >= 2, "CtrlWidth must be >= 2");
  static_assert(kWP <= 128, "ceil((CtrlWidth+3*MaxDepth)/ChunkWidth)*ChunkWidth must be <= 128");
  static_assert(GuardBits >= 0 && GuardBits <= CtrlWidth - 2, "GuardBits must be 0..CtrlWidth-2");
  static_assert(OutWidth >= kNarrow && OutWidth <= 64, "OutWidth must be kNarrow..64");
  static_assert(kDepthBits <= ChunkWidth, "the depth field must fit one stream word");

  // Prep FSM states (the RTL's state_e). Only hardware states.
  enum class State : uint8_t { StIdle, StLoad, StWaitx, StDesc, StInit };

  // A view for test drivers, not a state (state()): S_READY = a sample is
  // ready (a pending tick is served now); S_IDLE = nothing coming (a tick
  // would be an underrun); S_BUSY = a segment is loading, being prepared or
  // entering the stage.
  enum View : uint8_t { S_IDLE = 0, S_READY = 5, S_BUSY = 6 };

  struct In {
    bool rst_n = true;
    u128 tdata = 0;
    bool tvalid = false;
    bool tick = false;
  };

  // ---------------------------------------------------------------------
  // State (the RTL's flops, same names, same order). Control is reset, the
  // datapath is not. The memories are mem_ (mem in the RTL).
  // ---------------------------------------------------------------------
  struct Regs {
    // prep FSM
    State fsm_q = State::StIdle;
    int depth_q = 0;
    bool bank_q = false, nbank_q = false;  // bank of the segment in the FSM, of the next header
    int wc_q = 0;                          // LOAD word counters: lane, digit, axis
    int wdg_q = 0;
    int wax_q = 0;
    int pc_q = 0;                          // pass cycle, DESC level, pass slot (digit, axis)
    int lvl_q = 0;
    int sdg_q = 0;
    int sax_q = 0;
    // transfer into the forward-difference stage and the stage's tags
    bool xpend_q = false;                  // a prepared segment waits, its chunk 0 in rd_q
    bool xbusy_q = false;                  // its chunks 1..C-1 are being loaded
    bool xbank_q = false;
    int xdepth_q = 0;
    int xk_q = 0;                          // RAM digit read for the transfer
    int xk1_q = 1;                         // == xk_q + 1 (timing: no adder before the RAM address)
    bool frem_q = false;                   // the feeding segment has steps left to enter
    bool need_end_q = false;               // its last step entered, the end tag not yet
    uint32_t fcnt_q = 0;                   // steps left to enter after the next one
    bool tag_v_q[kC] = {}, tag_last_q[kC] = {}, tag_end_q[kC] = {};  // tag of chunk k's step
    bool tag_start_q[kC] = {};
    bool vlo_q = false, slo_q = false;     // == OR of tag_v_q, tag_start_q below the top
    // digit-serial pipeline slots: rs (RAM output), hs (head), s1, s2 (stages)
    bool rs_v_q = false, rs_first_q = true, rs_init_q = false, rs_ext_q = false;
    bool hs_v_q = false, hs_first_q = true, hs_init_q = false;
    bool s1_v_q = false, s1_first_q = true, s1_init_q = false;
    bool s2_v_q = false, s2_init_q = false;
    bool we_q[4][Axes] = {};               // RAM write enables
    // ticks and outputs
    bool tick_q = false, tick_err_q = false, valid_q = false, underrun_q = false, done_q = false;
    // ---- datapath (not reset) ----
    int rs_ax_q = 0, hs_ax_q = 0, s1_ax_q = 0, s2_ax_q = 0;
    int rs_dg_q = 0, hs_dg_q = 0, s1_dg_q = 0, s2_dg_q = 0;
    bool rs_bank_q = false, hs_bank_q = false, s1_bank_q = false, s2_bank_q = false;
    uint64_t rd_q[4][Axes] = {};           // RAM outputs
    int waddr_q = 0;
    uint64_t wdata_q[4] = {};
    uint64_t hd_q[4] = {};                 // axis-multiplexed head digits A, B, C, D
    // stage 1
    uint64_t s1_q = 0, s2_q = 0, s3_q = 0, a1_q = 0, e1_q = 0, e2_q = 0, e3_q = 0;
    bool cs1_q = false, cs2_q = false, cs3_q = false, ce1_q = true, ce2_q = true, ce3_q = true;
    // stage 2
    uint64_t t1_q = 0, t2_q = 0, a2_q = 0, s12_q = 0, u_q = 0, y1_q = 0, y2_q = 0, e1d_q = 0;
    bool ct1_q = false, ct2_q = false, cu_q = false, cy1_q = false, cy2_q = false;
    uint64_t he1_q = 0;                    // top bits of the previous e1 digit
    uint64_t he2_q = 0;                    // top bits of the previous e2 digit
    // output stage
    bool cm_q = false, cs0_q = false, cd2_q = false, cd3_q = false;
    uint64_t ha_q = 0;
    uint64_t hs1_q = 0;
    uint64_t ht1_q = 0;
    uint64_t hu_q = 0;
    // forward-difference stage: [axis][chunk]
    uint64_t fs_q[Axes][kC] = {}, f1_q[Axes][kC] = {}, f2_q[Axes][kC] = {}, f3_q[Axes][kC] = {};
    bool cs_q[Axes][kC] = {}, c1_q[Axes][kC] = {}, c2_q[Axes][kC] = {};  // carry out of chunk k
    uint64_t dsk_q[Axes][kC][kC] = {};     // deskew: [axis][chunk][stage]
    u128 sample_q[Axes] = {};
  };

  BcuGen() = default;

  // One rising clock edge with inputs `in` held during the cycle.
  void clock(const In& in) {
    const Regs& q = r_;
    Regs n = r_;

    // -------------------------------------------------------------------
    // Stream input and forward-difference stage control: advance, ticks,
    // entering tag.
    // -------------------------------------------------------------------
    const bool accept = tready() && in.tvalid;
    const uint64_t word = static_cast<uint64_t>(in.tdata) & kM;
    const bool top_v = q.tag_v_q[kC - 1];
    const bool top_end = q.tag_end_q[kC - 1];
    const bool newer = q.xpend_q || (kC > 1 && q.vlo_q);
    const bool proc = q.tick_q && top_v;
    const bool under = q.tick_q && !top_v && q.fsm_q == State::StIdle && !in.tvalid && !newer;
    const bool consume = proc || under;
    const bool adv = top_v ? proc : (top_end ? newer : true);
    // entering tag: the next step of the feeding segment, else the pending
    // segment's start, else (once) the end tag, else a bubble
    const bool enter_start = !q.frem_q && q.xpend_q;
    const bool ent_v = q.frem_q || q.xpend_q;
    const bool ent_last = q.frem_q ? q.fcnt_q == 0 : q.xdepth_q == 0;
    const bool ent_end = !q.frem_q && !q.xpend_q && q.need_end_q;
    const bool xfer_step = adv && (enter_start || (kC > 1 && q.slo_q));

    // -------------------------------------------------------------------
    // Prep FSM: IDLE (header) -> LOAD (4N words) -> WAITX (transfer over) ->
    // DESC (d passes) -> INIT (one pass, hand-off) -> IDLE.
    // -------------------------------------------------------------------
    int hdr_depth = static_cast<int>(bits(in.tdata, 0, kDepthBits));
    if (hdr_depth > MaxDepth) hdr_depth = MaxDepth;
    const bool pass_on = q.fsm_q == State::StDesc || q.fsm_q == State::StInit;
    const bool pass_init = q.fsm_q == State::StInit;
    const int npass = pass_init ? kNi : kN;
    const int period = pass_init ? kPi : kPp;
    const int dpass_last = pass_init ? kC - 1 : kDigits - 1;
    const bool issue = pass_on && q.pc_q < npass;  // a pass slot is read this cycle
    const bool hand_off = pass_init && q.pc_q == period - 1;
    switch (q.fsm_q) {
      case State::StIdle:
        if (accept) {
          n.depth_q = hdr_depth;
          n.bank_q = q.nbank_q;
          n.nbank_q = !q.nbank_q;
          n.wc_q = n.wdg_q = n.wax_q = 0;
          n.fsm_q = State::StLoad;
        }
        break;
      case State::StLoad:
        if (accept) {
          n.wc_q = (q.wc_q + 1) & 3;
          if (q.wc_q == 3) {
            if (q.wdg_q == kDigits - 1) {
              n.wdg_q = 0;
              if (q.wax_q == Axes - 1) {
                n.wax_q = 0;
                n.fsm_q = State::StWaitx;
              } else {
                n.wax_q = q.wax_q + 1;
              }
            } else {
              n.wdg_q = q.wdg_q + 1;
            }
          }
        }
        break;
      case State::StWaitx:
        if (!q.xpend_q && !q.xbusy_q) {
          n.fsm_q = q.depth_q == 0 ? State::StInit : State::StDesc;
          n.pc_q = n.lvl_q = n.sdg_q = n.sax_q = 0;
        }
        break;
      case State::StDesc:
      case State::StInit:
        if (issue) {
          if (q.sdg_q == dpass_last) {
            n.sdg_q = 0;
            n.sax_q = (q.sax_q + 1) & ((1 << kAxBits) - 1);
          } else {
            n.sdg_q = q.sdg_q + 1;
          }
        }
        if (q.pc_q == period - 1) {
          n.pc_q = n.sdg_q = n.sax_q = 0;
          if (pass_init) {
            n.fsm_q = State::StIdle;
          } else {
            n.lvl_q = q.lvl_q + 1;
            if (q.lvl_q + 1 == q.depth_q) n.fsm_q = State::StInit;
          }
        } else {
          n.pc_q = q.pc_q + 1;
        }
        break;
    }

    // -------------------------------------------------------------------
    // Transfer and tags: the hand-off makes the prepared segment pending; at
    // an advance the tags shift up by one chunk with the entering tag at 0,
    // and chunk k of a new segment loads where its start tag arrives (chunk
    // 0: as it enters), the RAM reading chunk k+1 in the same cycle.
    // -------------------------------------------------------------------
    if (hand_off) {
      n.xpend_q = true;
      n.xbank_q = q.bank_q;
      n.xdepth_q = q.depth_q;
      n.xk_q = 0;
      n.xk1_q = 1 & kDgMask;
    }
    if (adv) {
      if (q.frem_q) {
        n.frem_q = q.fcnt_q != 0;
        n.fcnt_q = static_cast<uint32_t>(wrap(q.fcnt_q - 1, MaxDepth));
        n.need_end_q = q.fcnt_q == 0;
      } else if (q.xpend_q) {
        n.frem_q = q.xdepth_q != 0;
        // steps left after the one after this: 2^d - 2
        n.fcnt_q = static_cast<uint32_t>(wrap((u128(1) << q.xdepth_q) - 2, MaxDepth));
        n.need_end_q = q.xdepth_q == 0;
        n.xpend_q = false;
        n.xbusy_q = true;
      } else {
        n.need_end_q = false;
      }
      if (xfer_step) {
        if (q.xk_q == kC - 1) {
          n.xbusy_q = false;
        } else {
          n.xk_q = q.xk1_q;
          n.xk1_q = (q.xk1_q + 1) & kDgMask;
        }
      }
      for (int p = kC - 1; p > 0; --p) {
        n.tag_v_q[p] = q.tag_v_q[p - 1];
        n.tag_start_q[p] = q.tag_start_q[p - 1];
        n.tag_last_q[p] = q.tag_last_q[p - 1];
        n.tag_end_q[p] = q.tag_end_q[p - 1];
      }
      n.tag_v_q[0] = ent_v;
      n.tag_start_q[0] = enter_start;
      n.tag_last_q[0] = ent_v && ent_last;
      n.tag_end_q[0] = ent_end;
      n.vlo_q = kC > 1 && (ent_v || any_below(q.tag_v_q, kC - 3));
      n.slo_q = kC > 1 && (enter_start || any_below(q.tag_start_q, kC - 3));
    }

    // -------------------------------------------------------------------
    // Block RAM: one memory per (lane, axis), address {bank, digit}; one
    // registered write port (LOAD words, pass results), one synchronous read
    // port (passes, transfer), shared address for all memories. Read every
    // cycle (old contents, then the write): a pass's slot (digit 0 in its
    // other cycles, so the hand-off cycle reads chunk 0), else the
    // transfer's chunk xk, or xk+1 when chunk xk loads in this cycle.
    // -------------------------------------------------------------------
    {
      const bool rd_bank = pass_on ? q.bank_q : q.xbank_q;
      const int rd_dg_hold = pass_on ? q.sdg_q : q.xk_q;  // sdg_q = 0 between slots
      const int rd_dg = xfer_step ? q.xk1_q : rd_dg_hold;
      const int rd_addr = (rd_bank ? 1 << kDgBits : 0) + rd_dg;
      for (int l = 0; l < 4; ++l)
        for (int a = 0; a < Axes; ++a) n.rd_q[l][a] = mem_[l][a][rd_addr];
      for (int l = 0; l < 4; ++l)
        for (int a = 0; a < Axes; ++a)
          if (q.we_q[l][a]) mem_[l][a][q.waddr_q] = q.wdata_q[l];
    }

    // -------------------------------------------------------------------
    // Digit-serial pipeline: rd -> hd -> stage 1 -> stage 2 -> write register.
    // Slot flags: v (write back), first (first digit of a value, or a bubble),
    // init (INIT pass), ext (sign-fill digit), ax, dg, bank.
    // -------------------------------------------------------------------
    const bool is_first = q.sdg_q == 0;
    const bool is_ext = pass_init && q.sdg_q >= kDigits;
    n.rs_v_q = issue;
    n.rs_first_q = !issue || is_first;
    n.rs_init_q = issue && pass_init;
    n.rs_ext_q = issue && is_ext;
    n.hs_v_q = q.rs_v_q;
    n.hs_first_q = q.rs_first_q;
    n.hs_init_q = q.rs_init_q;
    n.s1_v_q = q.hs_v_q;
    n.s1_first_q = q.hs_first_q;
    n.s1_init_q = q.hs_init_q;
    n.s2_v_q = q.s1_v_q;
    n.s2_init_q = q.s1_init_q;
    n.rs_ax_q = issue ? q.sax_q : 0;
    n.rs_dg_q = issue ? q.sdg_q : 0;
    n.rs_bank_q = issue && q.bank_q;
    n.hs_ax_q = q.rs_ax_q, n.hs_dg_q = q.rs_dg_q, n.hs_bank_q = q.rs_bank_q;
    n.s1_ax_q = q.hs_ax_q, n.s1_dg_q = q.hs_dg_q, n.s1_bank_q = q.hs_bank_q;
    n.s2_ax_q = q.s1_ax_q, n.s2_dg_q = q.s1_dg_q, n.s2_bank_q = q.s1_bank_q;

    // hd: axis multiplexer (or the sign fill of the previous digit)
    for (int l = 0; l < 4; ++l)
      n.hd_q[l] = q.rs_ext_q ? ((q.hd_q[l] >> (ChunkWidth - 1)) ? kM : 0) : q.rd_q[l][q.rs_ax_q];

    // stage 1: BCU s1=A+B, s2=B+C, s3=C+D; INIT e1=D-A, e2=B-C, e3=D-C.
    // Saved carries: cleared (set, for a subtraction) when the digit that will
    // use them (slot rs, next in hd) starts a value.
    {
      const uint64_t a = q.hd_q[0], b = q.hd_q[1], c = q.hd_q[2], d = q.hd_q[3];
      const bool nf = q.rs_first_q;
      bool co;
      n.s1_q = add(a, b, q.cs1_q, co), n.cs1_q = co && !nf;
      n.s2_q = add(b, c, q.cs2_q, co), n.cs2_q = co && !nf;
      n.s3_q = add(c, d, q.cs3_q, co), n.cs3_q = co && !nf;
      n.a1_q = a;
      n.e1_q = add(d, ~a & kM, q.ce1_q, co), n.ce1_q = co || nf;
      n.e2_q = add(b, ~c & kM, q.ce2_q, co), n.ce2_q = co || nf;
      n.e3_q = add(d, ~c & kM, q.ce3_q, co), n.ce3_q = co || nf;
    }

    // stage 2: BCU t1=s1+s2, t2=s2+s3; INIT u=e2+e3, y1=6*e1, y2=18*e2.
    {
      const bool nf = q.hs_first_q;
      bool co;
      n.t1_q = add(q.s1_q, q.s2_q, q.ct1_q, co), n.ct1_q = co && !nf;
      n.t2_q = add(q.s2_q, q.s3_q, q.ct2_q, co), n.ct2_q = co && !nf;
      n.a2_q = q.a1_q;
      n.s12_q = q.s1_q;
      n.u_q = add(q.e2_q, q.e3_q, q.cu_q, co), n.cu_q = co && !nf;
      n.y1_q = add(shl(q.e1_q, 2, q.he1_q), shl(q.e1_q, 1, q.he1_q >> 1), q.cy1_q, co), n.cy1_q = co && !nf;
      n.y2_q = add(shl(q.e2_q, 4, q.he2_q), shl(q.e2_q, 1, q.he2_q >> 3), q.cy2_q, co), n.cy2_q = co && !nf;
      n.e1d_q = q.e1_q;
      n.he1_q = nf ? 0 : top(q.e1_q, 2);
      n.he2_q = nf ? 0 : top(q.e2_q, 4);
    }

    // output stage: BCU m = t1+t2, L = (A<<3, s1<<2, t1<<1, m);
    // INIT S0 = A + half, D1 = e1, D2 = (u<<2)+(u<<1), D3 = y1+y2.
    const bool nf = q.s1_first_q;
    bool co;
    const uint64_t half_dig = q.s2_dg_q == kHalfDigit ? uint64_t(1) << kHalfBit : 0;
    const uint64_t m_sum = add(q.t1_q, q.t2_q, q.cm_q, co);
    n.cm_q = co && !nf;
    const uint64_t s0_sum = add(q.a2_q, half_dig, q.cs0_q, co);
    n.cs0_q = co && !nf;
    const uint64_t dd2_sum = add(shl(q.u_q, 2, q.hu_q), shl(q.u_q, 1, q.hu_q >> 1), q.cd2_q, co);
    n.cd2_q = co && !nf;
    const uint64_t dd3_sum = add(q.y1_q, q.y2_q, q.cd3_q, co);
    n.cd3_q = co && !nf;
    n.ha_q = nf ? 0 : top(q.a2_q, 3);
    n.hs1_q = nf ? 0 : top(q.s12_q, 2);
    n.ht1_q = nf ? 0 : top(q.t1_q, 1);
    n.hu_q = nf ? 0 : top(q.u_q, 2);

    // write register: LOAD word (one lane) or pass result (4 lanes)
    const bool wl_we = q.fsm_q == State::StLoad && accept;
    const int wl_addr = (q.bank_q ? 1 << kDgBits : 0) + q.wdg_q;
    if (wl_we) {
      for (int l = 0; l < 4; ++l) n.wdata_q[l] = word;
      n.waddr_q = wl_addr;
    } else if (q.s2_init_q) {
      n.wdata_q[0] = s0_sum;
      n.wdata_q[1] = q.e1d_q;
      n.wdata_q[2] = dd2_sum;
      n.wdata_q[3] = dd3_sum;
      n.waddr_q = (q.s2_bank_q ? 1 << kDgBits : 0) + q.s2_dg_q;
    } else {
      n.wdata_q[0] = shl(q.a2_q, 3, q.ha_q);
      n.wdata_q[1] = shl(q.s12_q, 2, q.hs1_q);
      n.wdata_q[2] = shl(q.t1_q, 1, q.ht1_q);
      n.wdata_q[3] = m_sum;
      n.waddr_q = (q.s2_bank_q ? 1 << kDgBits : 0) + q.s2_dg_q;
    }
    for (int l = 0; l < 4; ++l)
      for (int a = 0; a < Axes; ++a)
        n.we_q[l][a] = wl_we ? (l == q.wc_q && a == q.wax_q) : (q.s2_v_q && a == q.s2_ax_q);

    // -------------------------------------------------------------------
    // Forward-difference stage: per axis S, D1, D2, D3 of C chunks; chunk k
    // adds with the registered carry of chunk k-1 (one step behind it). All
    // chunks advance together (adv); chunk k loads the new segment where the
    // start tag reaches it (chunk 0: as it enters).
    // -------------------------------------------------------------------
    if (adv) {
      for (int a = 0; a < Axes; ++a) {
        for (int k = 0; k < kC; ++k) {
          const bool load_k = k == 0 ? enter_start : q.tag_start_q[k - 1];
          bool co_s, co_1, co_2;
          const uint64_t ns = add(q.fs_q[a][k], q.f1_q[a][k], k > 0 && q.cs_q[a][k - 1], co_s);
          const uint64_t n1 = add(q.f1_q[a][k], q.f2_q[a][k], k > 0 && q.c1_q[a][k - 1], co_1);
          const uint64_t n2 = add(q.f2_q[a][k], q.f3_q[a][k], k > 0 && q.c2_q[a][k - 1], co_2);
          n.cs_q[a][k] = co_s;
          n.c1_q[a][k] = co_1;
          n.c2_q[a][k] = co_2;
          n.fs_q[a][k] = load_k ? q.rd_q[0][a] : ns;
          n.f1_q[a][k] = load_k ? q.rd_q[1][a] : n1;
          n.f2_q[a][k] = load_k ? q.rd_q[2][a] : n2;
          n.f3_q[a][k] = load_k ? q.rd_q[3][a] : q.f3_q[a][k];
          // Deskew: chunk k (K0 <= k < C-1) waits C-1-k advances, so the
          // slice of the top step is complete.
          if (k >= kK0 && k < kC - 1) {
            n.dsk_q[a][k][0] = q.fs_q[a][k];
            for (int i = 1; i < kC - 1 - k; ++i) n.dsk_q[a][k][i] = q.dsk_q[a][k][i - 1];
          }
        }
      }
    }

    // -------------------------------------------------------------------
    // Ticks and output registers.
    // -------------------------------------------------------------------
    n.tick_q = (q.tick_q && !consume) || in.tick;
    n.tick_err_q = q.tick_err_q || (in.tick && q.tick_q && !consume);
    n.valid_q = consume && (proc || top_end);
    n.underrun_q = under;
    n.done_q = proc && q.tag_last_q[kC - 1];
    // Loaded whenever a tick is pending and the top holds a sample or the end
    // value (a timing choice of the RTL; sample_o is defined with
    // sample_valid_o, and every value emitted with it is unchanged).
    if (q.tick_q && (top_v || top_end))
      for (int a = 0; a < Axes; ++a) n.sample_q[a] = top_sample(q, a);

    check_timing_copies(q, pass_on, xfer_step);
    if (consume) j_ = proc ? (q.tag_last_q[kC - 1] ? 0 : j_ + 1) : j_;
    // Synchronous reset: control state only, as in the RTL.
    if (!in.rst_n) {
      reset(n);
      j_ = 0;
    }
    r_ = n;
  }

  // ---------------------------------------------------------------------
  // Outputs.
  // ---------------------------------------------------------------------
  bool tready() const { return r_.fsm_q == State::StIdle || r_.fsm_q == State::StLoad; }
  bool sample_valid() const { return r_.valid_q; }
  bool underrun() const { return r_.underrun_q; }
  bool seg_done() const { return r_.done_q; }
  bool tick_err() const { return r_.tick_err_q; }
  int64_t sample(int a) const { return static_cast<int64_t>(sext(r_.sample_q[a], OutWidth)); }
  u128 sample_bits(int a) const { return r_.sample_q[a]; }

  // ---------------------------------------------------------------------
  // Model-only views for tests (not hardware ports).
  // ---------------------------------------------------------------------
  struct Tag {
    bool v = false, start = false, last = false, end = false;
  };
  // A few registers for test drivers' traces and tick decisions, and j_q,
  // the samples emitted in the current segment (a model-only count).
  struct Probe {
    bool tick_q;
    int depth_q, lvl_q, pc_q;
    uint32_t j_q;
    Tag tag[kC];
  };
  Probe regs() const {
    Probe p{r_.tick_q, r_.depth_q, r_.lvl_q, r_.pc_q, j_, {}};
    for (int k = 0; k < kC; ++k)
      p.tag[k] = Tag{r_.tag_v_q[k], r_.tag_start_q[k], r_.tag_last_q[k], r_.tag_end_q[k]};
    return p;
  }
  const Regs& state_regs() const { return r_; }
  View state() const {
    if (r_.tag_v_q[kC - 1]) return S_READY;
    if (r_.fsm_q != State::StIdle || r_.xpend_q || any_below(r_.tag_v_q, kC - 2)) return S_BUSY;
    return S_IDLE;
  }

  // The sample of the top step (bits [Shift, Shift+Narrow) of S, sign-extended).
  static u128 top_sample(const Regs& q, int a) {
    u128 v = 0;
    for (int k = kK0; k < kC && (k - kK0) * ChunkWidth < kShift % ChunkWidth + kNarrow; ++k) {
      const uint64_t ch = (k == kC - 1) ? q.fs_q[a][k] : q.dsk_q[a][k][kC - 2 - k];
      v |= u128(ch) << ((k - kK0) * ChunkWidth);
    }
    const u128 narrow = bits(v, kShift % ChunkWidth, kNarrow);
    return wrap(static_cast<u128>(sext(narrow, kNarrow)), OutWidth);
  }

 private:
  static constexpr uint64_t kM = ChunkWidth >= 64 ? ~uint64_t(0) : ((uint64_t(1) << ChunkWidth) - 1);
  static constexpr int kDgMask = (1 << kDgBits) - 1;

  static uint64_t add(uint64_t x, uint64_t y, bool cin, bool& cout) {
    const u128 s = u128(x) + u128(y) + u128(cin ? 1 : 0);
    cout = ((s >> ChunkWidth) & 1) != 0;
    return static_cast<uint64_t>(s) & kM;
  }
  static uint64_t shl(uint64_t x, int s, uint64_t h) { return ((x << s) | h) & kM; }
  static uint64_t top(uint64_t x, int s) { return x >> (ChunkWidth - s); }
  // OR of flags[0..last] (false if last < 0).
  static bool any_below(const bool (&flags)[kC], int last) {
    bool v = false;
    for (int p = 0; p <= last; ++p) v = v || flags[p];
    return v;
  }

  // The RTL's timing copies equal their definitions, and the read-address
  // shortcut is exact (no transfer step in a pass): checked every cycle,
  // always on (the RTL proves the same under FORMAL).
  static void check_timing_copies(const Regs& q, bool pass_on, bool xfer_step) {
    check(q.xk1_q == ((q.xk_q + 1) & kDgMask), "xk1_q != xk_q + 1");
    check(q.vlo_q == any_below(q.tag_v_q, kC - 2), "vlo_q != |tag_v_q[C-2:0]");
    check(q.slo_q == any_below(q.tag_start_q, kC - 2), "slo_q != |tag_start_q[C-2:0]");
    check(!(pass_on && xfer_step), "transfer step during a pass");
  }
  static void check(bool ok, const char* what) {
    if (ok) return;
    std::fprintf(stderr, "BcuGen: %s\n", what);
    std::abort();
  }

  // Control state only; the datapath keeps its value.
  static void reset(Regs& n) {
    n.fsm_q = State::StIdle;
    n.depth_q = 0;
    n.bank_q = n.nbank_q = false;
    n.wc_q = n.wdg_q = n.wax_q = 0;
    n.pc_q = n.lvl_q = n.sdg_q = n.sax_q = 0;
    n.xpend_q = n.xbusy_q = n.xbank_q = false;
    n.xdepth_q = 0;
    n.xk_q = 0;
    n.xk1_q = 1 & kDgMask;
    n.frem_q = n.need_end_q = false;
    n.fcnt_q = 0;
    for (int k = 0; k < kC; ++k) n.tag_v_q[k] = n.tag_start_q[k] = n.tag_last_q[k] = n.tag_end_q[k] = false;
    n.vlo_q = n.slo_q = false;
    n.rs_v_q = false, n.rs_first_q = true, n.rs_init_q = false, n.rs_ext_q = false;
    n.hs_v_q = false, n.hs_first_q = true, n.hs_init_q = false;
    n.s1_v_q = false, n.s1_first_q = true, n.s1_init_q = false;
    n.s2_v_q = false, n.s2_init_q = false;
    for (auto& r : n.we_q)
      for (auto& w : r) w = false;
    n.tick_q = n.tick_err_q = n.valid_q = n.underrun_q = n.done_q = false;
  }

  Regs r_{};
  uint64_t mem_[4][Axes][kMemWords] = {};
  uint32_t j_ = 0;  // model-only: samples emitted in the current segment
};

}  // namespace traj
