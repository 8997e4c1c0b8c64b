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
// Arithmetic (exact, scaled form; unchanged from the digit-serial generator)
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
//      (This is the brief's S_0/Delta formulas with m = 0 at the first leaf:
//      c1 = 3(B-A), c2 = 3(A-2B+C), c3 = D-3C+3B-A, Delta1 = c1+c2+c3,
//      Delta2 = 2c2+6c3, Delta3 = 6c3.)
//   3. The forward-difference stage S += D1; D1 += D2; D2 += D3 gives
//      S_j = Q(j) + 2^(S-1) for j = 0, 1, ... exactly: every identity is an
//      integer one, so computing modulo 2^WF (WF = C*ChunkWidth,
//      C = ceil((W+1)/ChunkWidth) chunks) is exact because the true S_j fits
//      W+1 bits; the sample is S_j's bits [S, S+Narrow) (a bit slice: no
//      adder after the stage). The same recurrence one step further gives
//      S_K = 8^MaxDepth*D + 2^(S-1): the end value round(D).
//   Same samples, bit for bit, as the subdivision of every leaf (the old
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
  static constexpr int kDigits = (kW + ChunkWidth - 1) / ChunkWidth;   // stream digits per value
  static constexpr int kWP = kDigits * ChunkWidth;                     // stream value width
  static constexpr int kWords = kDigits;                               // stream words per value
  static constexpr int kN = Axes * kDigits;                            // digits per lane
  static constexpr int kSegWords = 1 + 4 * kN;                         // words per segment
  static constexpr int kShift = 3 * MaxDepth + GuardBits;              // output rounding shift
  static constexpr int kNarrow = CtrlWidth - GuardBits + (GuardBits > 0 ? 1 : 0);
  static constexpr int kDepthBits = bcu_clog2(MaxDepth + 1);
  static constexpr int kC = (kW + 1 + ChunkWidth - 1) / ChunkWidth;   // FD chunks (digits)
  static constexpr int kWF = kC * ChunkWidth;                          // FD register width
  static constexpr int kDgBits = bcu_clog2(kC) > 0 ? bcu_clog2(kC) : 1;
  static constexpr int kNi = Axes * kC;                                // INIT pass slots
  static constexpr int kL = 5;                                         // read -> write latency
  static constexpr int kPp = kN > kL + 1 ? kN : kL + 1;               // DESC pass period
  static constexpr int kPi = kNi + kL + 1;                             // INIT + drain + hand-off
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
  // whatever the depths (stream never starved; the old contract). Tight: a
  // depth-0 segment followed by a depth-MaxDepth one needs all of it.
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

  // prep FSM states; S_READY is only a view (state()): a sample is ready.
  enum State : uint8_t { S_IDLE = 0, S_LOAD = 1, S_WAITX = 2, S_DESC = 3, S_INIT = 4, S_READY = 5, S_BUSY = 6 };

  struct In {
    bool rst_n = true;
    u128 tdata = 0;
    bool tvalid = false;
    bool tick = false;
  };

  struct Tag {
    bool v = false, start = false, last = false, end = false;
  };

  // One slot of the digit-serial pipeline.
  struct Slot {
    bool v = false;      // a digit to write back
    bool first = true;   // first digit of a value (or a bubble)
    bool init = false;   // INIT pass (else DESC)
    bool ext = false;    // sign-fill digit (INIT, C > Digits)
    int ax = 0, dg = 0;  // axis, digit
    bool bank = false;
  };

  struct Regs {
    // ---- control (reset) ----
    uint8_t fsm = S_IDLE;
    bool tick_q = false, tick_err_q = false, have_last_q = false;
    bool valid_q = false, underrun_q = false, done_q = false;
    int depth_q = 0;               // depth of the segment in the prep FSM
    bool bank_q = false;           // its bank
    bool nbank_q = false;          // bank of the next header
    int wc_q = 0, wdg_q = 0, wax_q = 0;  // LOAD word counters (lane, digit, axis)
    int pc_q = 0, lvl_q = 0;       // pass cycle, DESC level
    int sdg_q = 0, sax_q = 0;      // pass slot counters (digit, axis)
    bool xpend_q = false;          // a prepared segment waits, its chunk 0 in rd
    bool xbusy_q = false;          // its chunks 1..C-1 are being loaded
    bool xbank_q = false;
    int xdepth_q = 0;
    int xk_q = 0;                  // RAM digit being read for the transfer
    bool frem_q = false;           // the feeding segment has steps left to enter
    bool need_end_q = false;       // its last step entered, end tag not yet
    uint32_t fcnt_q = 0;           // steps left to enter after the next one
    Tag tag[kC];
    Slot rs, hs, s1, s2;           // pipeline slots (reset: bubbles)
    bool we_q[4][Axes] = {};       // RAM write enables (reset)
    uint32_t j_q = 0;              // samples emitted in the current segment (debug view)
    // ---- datapath (not reset) ----
    int waddr_q = 0;
    uint64_t wdata_q[4] = {};
    uint64_t rd[4][Axes] = {};     // RAM output registers
    uint64_t hd[4] = {};           // axis-multiplexed head digits
    // stage 1
    uint64_t s1_q = 0, s2_q = 0, s3_q = 0, a1_q = 0;
    uint64_t e1_q = 0, e2_q = 0, e3_q = 0;
    bool cs1_q = false, cs2_q = false, cs3_q = false, ce1_q = true, ce2_q = true, ce3_q = true;
    // stage 2
    uint64_t t1_q = 0, t2_q = 0, a2_q = 0, s12_q = 0;
    uint64_t u_q = 0, y1_q = 0, y2_q = 0, e1d_q = 0;
    bool ct1_q = false, ct2_q = false, cu_q = false, cy1_q = false, cy2_q = false;
    uint64_t he1_q = 0, he2_q = 0;  // top bits of the previous e1 (2), e2 (4) digit
    // output stage
    bool cm_q = false, cs0_q = false, cd2_q = false, cd3_q = false;
    uint64_t ha_q = 0, hs1_q = 0, ht1_q = 0, hu_q = 0;
    // forward-difference stage: [axis][chunk]
    uint64_t fs[Axes][kC] = {}, f1[Axes][kC] = {}, f2[Axes][kC] = {}, f3[Axes][kC] = {};
    bool cs[Axes][kC] = {}, c1[Axes][kC] = {}, c2[Axes][kC] = {};  // carry out of chunk k
    uint64_t dsk[Axes][kC][kC] = {};  // deskew: [axis][chunk][stage]
    u128 sample_q[Axes] = {};
  };

  BcuGen() = default;

  bool tready() const { return r_.fsm == S_IDLE || r_.fsm == S_LOAD; }
  bool sample_valid() const { return r_.valid_q; }
  bool underrun() const { return r_.underrun_q; }
  bool seg_done() const { return r_.done_q; }
  bool tick_err() const { return r_.tick_err_q; }
  int64_t sample(int a) const { return static_cast<int64_t>(sext(r_.sample_q[a], OutWidth)); }
  u128 sample_bits(int a) const { return r_.sample_q[a]; }
  const Regs& regs() const { return r_; }
  // A view for test drivers: S_READY = a sample is ready (a pending tick is
  // served now); S_IDLE = nothing coming (a tick would be an underrun);
  // else the prep FSM's state, or S_BUSY (a segment is entering the stage).
  uint8_t state() const {
    if (r_.tag[kC - 1].v) return S_READY;
    if (newer(r_)) return r_.fsm == S_IDLE ? uint8_t(S_BUSY) : r_.fsm;
    return r_.fsm;
  }

  // The sample of the top step (bits [Shift, Shift+Narrow) of S, sign-extended).
  static u128 top_sample(const Regs& q, int a) {
    constexpr int k0 = kShift / ChunkWidth, o = kShift % ChunkWidth;
    u128 v = 0;
    for (int k = k0; k < kC && (k - k0) * ChunkWidth < o + kNarrow; ++k) {
      const uint64_t ch = (k == kC - 1) ? q.fs[a][k] : q.dsk[a][k][kC - 2 - k];
      v |= u128(ch) << ((k - k0) * ChunkWidth);
    }
    const u128 narrow = bits(v, o, kNarrow);
    return wrap(static_cast<u128>(sext(narrow, kNarrow)), OutWidth);
  }

  // One rising clock edge with inputs `in` held during the cycle.
  void clock(const In& in) {
    const Regs& q = r_;
    Regs n = r_;
    constexpr uint64_t M = ChunkWidth >= 64 ? ~uint64_t(0) : ((uint64_t(1) << ChunkWidth) - 1);
    const bool accept = tready() && in.tvalid;
    const uint64_t word = static_cast<uint64_t>(in.tdata) & M;
    n.valid_q = n.underrun_q = n.done_q = false;

    auto add = [&](uint64_t x, uint64_t y, bool cin, bool& cout) {
      const u128 s = u128(x) + u128(y) + u128(cin ? 1 : 0);
      cout = ((s >> ChunkWidth) & 1) != 0;
      return static_cast<uint64_t>(s) & M;
    };
    auto shl = [&](uint64_t x, int s, uint64_t h) { return ((x << s) | h) & M; };
    auto top = [&](uint64_t x, int s) { return x >> (ChunkWidth - s); };

    // ================= forward-difference stage and ticks =================
    const Tag& tp = q.tag[kC - 1];
    const bool nw = newer(q);
    const bool proc = q.tick_q && tp.v;
    const bool under = q.tick_q && !tp.v && q.fsm == S_IDLE && !in.tvalid && !nw;
    const bool consume = proc || under;
    const bool adv = tp.v ? proc : (tp.end ? nw : true);
    if (consume) {
      n.valid_q = proc || tp.end;
      n.underrun_q = under;
      n.done_q = proc && tp.last;

      if (n.done_q) n.have_last_q = true;
      n.j_q = proc ? (tp.last ? 0 : q.j_q + 1) : q.j_q;
    }
    // sample register: loaded whenever a tick is pending and the top holds a
    // sample or the end value (a timing choice of the RTL; it is defined with
    // sample_valid)
    if (q.tick_q && (tp.v || tp.end))
      for (int a = 0; a < Axes; ++a) n.sample_q[a] = top_sample(q, a);
    // entering tag
    Tag ent;
    const bool enter_start = !q.frem_q && q.xpend_q;
    if (q.frem_q) {
      ent.v = true;
      ent.last = q.fcnt_q == 0;
    } else if (q.xpend_q) {
      ent.v = ent.start = true;
      ent.last = q.xdepth_q == 0;
    } else if (q.need_end_q) {
      ent.end = true;
    }
    bool xfer_step = adv && enter_start;  // a chunk of the next segment loads
    for (int k = 1; k < kC; ++k) xfer_step = xfer_step || (adv && q.tag[k - 1].start);
    if (adv) {
      for (int p = kC - 1; p > 0; --p) n.tag[p] = q.tag[p - 1];
      n.tag[0] = ent;
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
      // transfer: chunk k loads where the start tag arrives (chunk 0: as it
      // enters); the RAM reads chunk k+1 in the same cycle
      if (xfer_step) {
        if (q.xk_q == kC - 1) n.xbusy_q = false;
        else n.xk_q = q.xk_q + 1;
      }
      for (int a = 0; a < Axes; ++a) {
        for (int k = 0; k < kC; ++k) {
          const bool cin_s = k > 0 && q.cs[a][k - 1];
          const bool cin_1 = k > 0 && q.c1[a][k - 1];
          const bool cin_2 = k > 0 && q.c2[a][k - 1];
          bool co_s, co_1, co_2;
          const uint64_t ns = add(q.fs[a][k], q.f1[a][k], cin_s, co_s);
          const uint64_t n1 = add(q.f1[a][k], q.f2[a][k], cin_1, co_1);
          const uint64_t n2 = add(q.f2[a][k], q.f3[a][k], cin_2, co_2);
          n.cs[a][k] = co_s;
          n.c1[a][k] = co_1;
          n.c2[a][k] = co_2;
          const bool load = k == 0 ? enter_start : q.tag[k - 1].start;
          if (load) {
            n.fs[a][k] = q.rd[0][a];
            n.f1[a][k] = q.rd[1][a];
            n.f2[a][k] = q.rd[2][a];
            n.f3[a][k] = q.rd[3][a];
          } else {
            n.fs[a][k] = ns;
            n.f1[a][k] = n1;
            n.f2[a][k] = n2;
          }
          if (k < kC - 1) {
            n.dsk[a][k][0] = q.fs[a][k];
            for (int i = 1; i < kC - 1 - k; ++i) n.dsk[a][k][i] = q.dsk[a][k][i - 1];
          }
        }
      }
    }

    // ================= prep FSM and the digit-serial pipeline =================
    Slot issue;  // slot read this cycle (bubble by default)
    bool wl_we = false;
    int wl_lane = 0, wl_ax = 0, wl_addr = 0;
    switch (q.fsm) {
      case S_IDLE:
        if (accept) {
          int d = static_cast<int>(bits(in.tdata, 0, kDepthBits));
          if (d > MaxDepth) d = MaxDepth;
          n.depth_q = d;
          n.bank_q = q.nbank_q;
          n.nbank_q = !q.nbank_q;
          n.wc_q = n.wdg_q = n.wax_q = 0;
          n.fsm = S_LOAD;
        }
        break;
      case S_LOAD:
        if (accept) {
          wl_we = true;
          wl_lane = q.wc_q;
          wl_ax = q.wax_q;
          wl_addr = (q.bank_q ? 1 << kDgBits : 0) + q.wdg_q;
          n.wc_q = (q.wc_q + 1) & 3;
          if (q.wc_q == 3) {
            if (q.wdg_q == kDigits - 1) {
              n.wdg_q = 0;
              if (q.wax_q == Axes - 1) {
                n.wax_q = 0;
                n.fsm = S_WAITX;
              } else {
                n.wax_q = q.wax_q + 1;
              }
            } else {
              n.wdg_q = q.wdg_q + 1;
            }
          }
        }
        break;
      case S_WAITX:
        if (!q.xpend_q && !q.xbusy_q) {
          n.fsm = q.depth_q == 0 ? S_INIT : S_DESC;
          n.pc_q = n.lvl_q = n.sdg_q = n.sax_q = 0;
        }
        break;
      case S_DESC:
      case S_INIT: {
        const bool init = q.fsm == S_INIT;
        const int npass = init ? kNi : kN;
        const int dpass = init ? kC : kDigits;
        const int period = init ? kPi : kPp;
        if (q.pc_q < npass) {
          issue.v = true;
          issue.first = q.sdg_q == 0;
          issue.init = init;
          issue.ext = init && q.sdg_q >= kDigits;
          issue.ax = q.sax_q;
          issue.dg = q.sdg_q;
          issue.bank = q.bank_q;
          if (q.sdg_q == dpass - 1) {
            n.sdg_q = 0;
            n.sax_q = q.sax_q + 1;
          } else {
            n.sdg_q = q.sdg_q + 1;
          }
        }
        if (q.pc_q == period - 1) {
          n.pc_q = 0;
          n.sdg_q = n.sax_q = 0;
          if (init) {
            // hand-off: chunk 0 of the prepared bank into rd, pending
            n.fsm = S_IDLE;
            n.xpend_q = true;
            n.xbank_q = q.bank_q;
            n.xdepth_q = q.depth_q;
            n.xk_q = 0;
          } else {
            n.lvl_q = q.lvl_q + 1;
            if (q.lvl_q + 1 == q.depth_q) n.fsm = S_INIT;
          }
        } else {
          n.pc_q = q.pc_q + 1;
        }
        break;
      }
      default:
        n.fsm = S_IDLE;
        break;
    }

    // pipeline: rd (RAM output) -> hd -> stage 1 -> stage 2 -> write register
    n.rs = issue;
    n.hs = q.rs;
    n.s1 = q.hs;
    n.s2 = q.s1;
    if (q.rs.ext) {
      for (int l = 0; l < 4; ++l) n.hd[l] = (q.hd[l] >> (ChunkWidth - 1)) ? M : 0;
    } else {
      for (int l = 0; l < 4; ++l) n.hd[l] = q.rd[l][q.rs.ax];
    }
    // stage 1 (input hd, slot hs; next slot rs)
    {
      const uint64_t a = q.hd[0], b = q.hd[1], c = q.hd[2], d = q.hd[3];
      const bool nf = q.rs.first;
      bool co;
      n.s1_q = add(a, b, q.cs1_q, co), n.cs1_q = co && !nf;
      n.s2_q = add(b, c, q.cs2_q, co), n.cs2_q = co && !nf;
      n.s3_q = add(c, d, q.cs3_q, co), n.cs3_q = co && !nf;
      n.e1_q = add(d, ~a & M, q.ce1_q, co), n.ce1_q = co || nf;
      n.e2_q = add(b, ~c & M, q.ce2_q, co), n.ce2_q = co || nf;
      n.e3_q = add(d, ~c & M, q.ce3_q, co), n.ce3_q = co || nf;
      n.a1_q = a;
    }
    // stage 2 (input stage-1 registers, slot s1; next slot hs)
    {
      const bool nf = q.hs.first;
      bool co;
      n.t1_q = add(q.s1_q, q.s2_q, q.ct1_q, co), n.ct1_q = co && !nf;
      n.t2_q = add(q.s2_q, q.s3_q, q.ct2_q, co), n.ct2_q = co && !nf;
      n.u_q = add(q.e2_q, q.e3_q, q.cu_q, co), n.cu_q = co && !nf;
      n.y1_q = add(shl(q.e1_q, 2, q.he1_q), shl(q.e1_q, 1, q.he1_q >> 1), q.cy1_q, co), n.cy1_q = co && !nf;
      n.y2_q = add(shl(q.e2_q, 4, q.he2_q), shl(q.e2_q, 1, q.he2_q >> 3), q.cy2_q, co), n.cy2_q = co && !nf;
      n.he1_q = nf ? 0 : top(q.e1_q, 2);
      n.he2_q = nf ? 0 : top(q.e2_q, 4);
      n.a2_q = q.a1_q;
      n.s12_q = q.s1_q;
      n.e1d_q = q.e1_q;
    }
    // output stage (input stage-2 registers, slot s2; next slot s1) -> write register
    {
      const bool nf = q.s1.first;
      bool co;
      const uint64_t m = add(q.t1_q, q.t2_q, q.cm_q, co);
      n.cm_q = co && !nf;
      constexpr int kHalfDigit = (kShift - 1) / ChunkWidth;
      const uint64_t half = q.s2.dg == kHalfDigit ? (uint64_t(1) << ((kShift - 1) % ChunkWidth)) : 0;
      const uint64_t s0 = add(q.a2_q, half, q.cs0_q, co);
      n.cs0_q = co && !nf;
      const uint64_t dd2 = add(shl(q.u_q, 2, q.hu_q), shl(q.u_q, 1, q.hu_q >> 1), q.cd2_q, co);
      n.cd2_q = co && !nf;
      const uint64_t dd3 = add(q.y1_q, q.y2_q, q.cd3_q, co);
      n.cd3_q = co && !nf;
      n.ha_q = nf ? 0 : top(q.a2_q, 3);
      n.hs1_q = nf ? 0 : top(q.s12_q, 2);
      n.ht1_q = nf ? 0 : top(q.t1_q, 1);
      n.hu_q = nf ? 0 : top(q.u_q, 2);
      if (wl_we) {
        for (int l = 0; l < 4; ++l) n.wdata_q[l] = word;
        n.waddr_q = wl_addr;
      } else if (q.s2.init) {
        n.wdata_q[0] = s0;
        n.wdata_q[1] = q.e1d_q;
        n.wdata_q[2] = dd2;
        n.wdata_q[3] = dd3;
        n.waddr_q = (q.s2.bank ? 1 << kDgBits : 0) + q.s2.dg;
      } else {
        n.wdata_q[0] = shl(q.a2_q, 3, q.ha_q);
        n.wdata_q[1] = shl(q.s12_q, 2, q.hs1_q);
        n.wdata_q[2] = shl(q.t1_q, 1, q.ht1_q);
        n.wdata_q[3] = m;
        n.waddr_q = (q.s2.bank ? 1 << kDgBits : 0) + q.s2.dg;
      }
      for (int l = 0; l < 4; ++l)
        for (int a = 0; a < Axes; ++a)
          n.we_q[l][a] = wl_we ? (l == wl_lane && a == wl_ax) : (q.s2.v && a == q.s2.ax);
    }

    // ---- block RAM: synchronous read (every cycle) of the old contents, then
    // write. Read address: a pass's slot (digit 0 in its other cycles: the
    // hand-off reads chunk 0), else the transfer's chunk (the next one when a
    // chunk loads in this cycle).
    {
      const bool pass = q.fsm == S_DESC || q.fsm == S_INIT;
      const bool bank = pass ? q.bank_q : q.xbank_q;
      const int dg = pass ? q.sdg_q  // 0 between slots: the hand-off reads chunk 0
                          : static_cast<int>(wrap(static_cast<u128>(xfer_step ? q.xk_q + 1 : q.xk_q), kDgBits));
      const int addr = (bank ? 1 << kDgBits : 0) + dg;
      for (int l = 0; l < 4; ++l)
        for (int a = 0; a < Axes; ++a) n.rd[l][a] = mem_[l][a][addr];
    }
    for (int l = 0; l < 4; ++l)
      for (int a = 0; a < Axes; ++a)
        if (q.we_q[l][a]) mem_[l][a][q.waddr_q] = q.wdata_q[l];

    n.tick_q = (q.tick_q && !consume) || in.tick;
    n.tick_err_q = q.tick_err_q || (in.tick && q.tick_q && !consume);

    if (!in.rst_n) {
      n.fsm = S_IDLE;
      n.tick_q = n.tick_err_q = n.have_last_q = false;
      n.valid_q = n.underrun_q = n.done_q = false;
      n.depth_q = 0;
      n.bank_q = n.nbank_q = false;
      n.wc_q = n.wdg_q = n.wax_q = n.pc_q = n.lvl_q = n.sdg_q = n.sax_q = 0;
      n.xpend_q = n.xbusy_q = n.xbank_q = false;
      n.xdepth_q = n.xk_q = 0;
      n.frem_q = n.need_end_q = false;
      n.fcnt_q = 0;
      for (auto& t : n.tag) t = Tag{};
      n.rs = n.hs = n.s1 = n.s2 = Slot{};
      for (auto& r : n.we_q)
        for (auto& w : r) w = false;
      n.j_q = 0;
    }
    r_ = n;
  }

 private:
  // A newer segment exists behind the top: a sample tag in the stage below the
  // top, or a prepared segment pending.
  static bool newer(const Regs& q) {
    bool v = q.xpend_q;
    for (int p = 0; p < kC - 1; ++p) v = v || q.tag[p].v;
    return v;
  }

  Regs r_{};
  uint64_t mem_[4][Axes][2 << kDgBits] = {};
};

}  // namespace traj
