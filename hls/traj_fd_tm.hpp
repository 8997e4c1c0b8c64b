// trajcore hls: time-multiplexed forward-difference engine, cycle-accurate
// model of rtl/traj_fd_tm.sv.
//
// The same segment word stream, tick contract, samples and status outputs as
// FdEngine (traj_fd_engine.hpp), with one ChunkWidth-bit adder shared by every
// register of every axis and the registers in one RAM:
//   * RAM word {axis, chunk, register}: (a << (ChB+RgB)) | (c << RgB) | i;
//   * a tick is one pass over kSlots = Axes*Chunks*(Degree+1) words, order
//     axis, chunk, register (register fastest), one read per clock; at the
//     word of register i >= 1 the adder writes
//     r[i-1] <- r[i-1] + r[i] + carry[i-1] (chunk c), all from old values;
//   * the old r[0] chunks read in the pass are captured into the sample
//     register; sample_valid pulses when the pass is done. The pass of a
//     segment's last tick reads the r[0] words only (Axes*Chunks clocks): the
//     next segment replaces the registers.
//   * the same r[0] chunks are also written, whole, to a second RAM of
//     Axes*Chunks words (the sample RAM, address (a << ChB) | c) with a
//     registered read port: sample_word = the word at the sample_addr of the
//     clock before. Consumers that take the samples a word at a time (and
//     the area figures) read them there; the parallel sample register is
//     then unused and synthesis removes it.
// Ticks kMinTickClocks = Axes*Chunks*(Degree+2) + HdrWords + 1 clocks apart
// never wait (segment boundaries included); within a segment kRunTickClocks =
// kSlots + 1 is enough.
#pragma once
#include <cstdint>

#include "traj_common.hpp"

namespace traj {

constexpr int fd_tm_clog2(int n) {
  int b = 0;
  while ((1 << b) < n) ++b;
  return b;
}

template <int Axes, int Degree, int Width, int ChunkWidth, int GuardBits>
class FdTm {
 public:
  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(Degree >= 1 && Degree <= 7, "Degree must be 1..7");
  static_assert(ChunkWidth == 16 || ChunkWidth == 32, "ChunkWidth must be 16 or 32");
  static_assert(Width >= ChunkWidth && Width <= kMaxWidth && Width % ChunkWidth == 0,
                "Width must be a multiple of ChunkWidth, at most 128");
  static_assert(GuardBits >= 0 && GuardBits < Width - 1, "GuardBits must leave >= 2 output bits");

  static constexpr int kChunks = Width / ChunkWidth;
  static constexpr int kOutWidth = Width - GuardBits;
  static constexpr int kRegs = Axes * (Degree + 1);
  static constexpr int kHdrWords = ChunkWidth < 32 ? 32 / ChunkWidth : 1;
  static constexpr int kWords = kHdrWords + kRegs * kChunks;  // header + registers
  static constexpr int kSlots = kRegs * kChunks;              // RAM words read per pass
  // Tick spacing (clocks) at which no tick waits within a segment: a pass and
  // the clock after it (and one more clock when the next pass's first word is
  // the last one written: Axes = Chunks = Degree = 1).
  static constexpr bool kWaitWrite = Axes == 1 && kChunks == 1 && Degree == 1;
  static constexpr int kRunTickClocks = kSlots + 1 + (kWaitWrite ? 1 : 0);
  // Tick spacing at which no tick ever waits while the stream delivers a word
  // per clock when asked: the last tick's pass (r[0] words only, Axes*Chunks),
  // the clock after it, and the next segment's load (kWords).
  static constexpr int kMinTickClocks = Axes * kChunks + 1 + kWords;
  // Clocks from a tick taken at once to its sample_valid: the pass (kSlots
  // words, or Axes*Chunks for a segment's last tick) and 2.
  static constexpr int answer_clocks(bool last_tick) { return (last_tick ? Axes * kChunks : kSlots) + 2; }
  static constexpr int kAxB = fd_tm_clog2(Axes);
  static constexpr int kChB = fd_tm_clog2(kChunks);
  static constexpr int kRgB = fd_tm_clog2(Degree + 1);
  static constexpr int kMemWords = 1 << (kAxB + kChB + kRgB);
  static constexpr int kSampleAddrWidth = kAxB + kChB > 0 ? kAxB + kChB : 1;
  static constexpr int kSampleWords = 1 << kSampleAddrWidth;

  struct In {
    bool rst_n = true;
    uint64_t tdata = 0;  // low ChunkWidth bits used
    bool tvalid = false;
    bool tick = false;
    int sample_addr = 0;  // low kSampleAddrWidth bits used
  };

  struct Out {
    bool tready;
    bool sample_valid;
    u128 sample[Axes];  // OutWidth-bit two's complement, wrapped
    bool underrun;
    bool seg_done;
    bool tick_err;
    uint64_t sample_word;     // the sample RAM word read at the last sample_addr
    bool sample_word_known;   // model-only: that word was written since power-up
  };

  Out outputs() const {
    Out o{};
    o.tready = tready();
    o.sample_valid = sample_valid_q_;
    for (int a = 0; a < Axes; ++a) o.sample[a] = sample_q_[a];
    o.underrun = underrun_q_;
    o.seg_done = seg_done_q_;
    o.tick_err = tick_err_q_;
    o.sample_word = sample_word_q_;
    o.sample_word_known = sample_word_known_q_;
    return o;
  }

  // One rising clock edge with the given inputs.
  void clock(const In& in) {
    const bool ready = tready();
    const bool accept = in.tvalid && ready;
    const bool header = accept && hdr_q_;
    const bool load_shift = accept && !hdr_q_;
    const bool wr_wait = kWaitWrite && wpend_q_;
    const bool consume = tick_q_ && !busy_q_ && !wr_wait && !mid_q_ && !accept;
    const bool run = tick_q_ && active_q_ && !busy_q_ && !wr_wait;
    const bool walk = run || iss_q_;
    const bool fast = run ? cnt_one_q_ : (iss_q_ && last_tick_q_);  // last tick: r[0] only
    const bool step = walk || load_shift;
    const bool i_wrap = i_q_ == Degree;
    const bool c_wrap = c_q_ == kChunks - 1;
    const bool a_wrap = a_q_ == Axes - 1;
    const bool at_last = (i_wrap || fast) && c_wrap && a_wrap;
    const bool hdr_last = kHdrWords == 1 || hword_q_;
    const bool tick_new = in.tick && !tick_in_q_;
    const bool tick_held = in.tick && tick_in_q_;

    // Datapath: the shared adder and the RAM write port.
    const uint64_t cmask = static_cast<uint64_t>(mask(ChunkWidth));
    const int ri_m1 = (ri_q_ - 1) & ((1 << kRgB) - 1);
    const bool carry_in = carry_q_[0];  // the head of the carry queue
    const uint64_t wide = prev_q_ + rd_q_ + (carry_in ? 1 : 0);
    const uint64_t sum = wide & cmask;
    const bool upd_wr = busy_q_ && ri_q_ != 0;
    const int rd_addr = addr(a_q_, c_q_, i_q_);
    const uint64_t rd_d = mem_[rd_addr];  // read before this edge's write
    // write port: a load word at once, an update a clock after its slot
    if (load_shift) mem_[addr(a_q_, c_q_, i_q_)] = in.tdata & cmask;
    else if (wpend_q_) mem_[waddr_q_] = sum_q_;

    // carry queue: a slot pops the head; the carry out of the update in
    // sum_q (0 after the top chunk) is pushed a clock late, derived from the
    // operands' top bits and the sum's: a == b ? a : !s
    const bool sa = ((sum_q_ >> (ChunkWidth - 1)) & 1) != 0;
    const bool carry_late = !top_q_ && (pa_q_ == pb_q_ ? pa_q_ : !sa);
    bool carry_d[Degree];
    for (int n = 0; n < Degree; ++n) carry_d[n] = carry_q_[n];
    if (upd_wr) {
      for (int n = 0; n + 1 < Degree; ++n) carry_d[n] = carry_q_[n + 1];
      if (wpend_q_ && Degree > 1) carry_d[Degree - 2] = carry_late;
    } else if (wpend_q_) {
      carry_d[Degree - 1] = carry_late;
    }
    const bool pa_d = ((prev_q_ >> (ChunkWidth - 1)) & 1) != 0;
    const bool pb_d = ((rd_q_ >> (ChunkWidth - 1)) & 1) != 0;
    const bool top_d = rc_q_ == kChunks - 1;

    // Sample capture: old r[0] chunks, bits GuardBits and above.
    u128 sample_d[Axes];
    for (int a = 0; a < Axes; ++a) sample_d[a] = sample_q_[a];
    if (busy_q_ && ri_q_ == 0 && (rc_q_ + 1) * ChunkWidth > GuardBits) {
      const int lo = rc_q_ * ChunkWidth > GuardBits ? rc_q_ * ChunkWidth : GuardBits;  // register bit
      const int nbits = (rc_q_ + 1) * ChunkWidth - lo;
      const u128 field = bits(u128(rd_q_), lo - rc_q_ * ChunkWidth, nbits);
      const int at = lo - GuardBits;
      sample_d[ra_q_] = (sample_q_[ra_q_] & ~(mask(nbits) << at)) | (field << at);
    }

    // Sample RAM: read before this edge's write; written with every r[0]
    // chunk the pass reads.
    const int s_addr = in.sample_addr & (kSampleWords - 1);
    const uint64_t sample_word_d = smem_[s_addr];
    const bool sample_word_known_d = smem_known_[s_addr];
    if (busy_q_ && ri_q_ == 0) {
      smem_[saddr(ra_q_, rc_q_)] = rd_q_;
      smem_known_[saddr(ra_q_, rc_q_)] = true;
    }

    // Field counters.
    int a_d = a_q_, c_d = c_q_, i_d = i_q_;
    if (step) {
      if (walk ? !fast : c_wrap) i_d = i_wrap ? 0 : i_q_ + 1;
      if (!walk || i_wrap || fast) c_d = c_wrap ? 0 : c_q_ + 1;
      if ((i_wrap || fast) && c_wrap) a_d = a_wrap ? 0 : a_q_ + 1;
    }

    // Control.
    bool active_d = active_q_, mid_d = mid_q_, hdr_d = hdr_q_, hword_d = hword_q_;
    if (header) {
      mid_d = true;
      hword_d = !hword_q_ && kHdrWords > 1;
      if (hdr_last) hdr_d = false;
    }
    if (load_shift && at_last) {
      mid_d = false;
      hdr_d = true;
      active_d = count_q_ != 0;
    }
    if (walk && at_last && fast) active_d = false;

    uint32_t count_d = count_q_;
    bool cnt_one_d = cnt_one_q_, last_tick_d = last_tick_q_;
    if (header) {
      count_d = ChunkWidth < 32
                    ? static_cast<uint32_t>((count_q_ >> ChunkWidth) |
                                            (static_cast<uint32_t>(in.tdata) << (32 - ChunkWidth)))
                    : static_cast<uint32_t>(in.tdata);
    } else if (run) {
      count_d = count_q_ - 1;
      cnt_one_d = count_q_ == 2;
    }
    if (load_shift && at_last) cnt_one_d = count_q_ == 1;  // decoded at the segment's last word
    if (run) last_tick_d = cnt_one_q_;

    const bool iss_d = walk && !at_last;
    const bool busy_d = walk;
    const bool last1_d = walk && at_last;
    const bool tick_d = (tick_q_ && !consume) || tick_new;
    const bool tick_err_d = tick_err_q_ || (tick_new && tick_q_ && !consume) || tick_held;
    const bool sample_valid_d = (consume && !active_q_ && primed_q_) || last1_q_;
    const bool primed_d = primed_q_ || last1_q_;
    const bool underrun_d = consume && !active_q_;
    const bool seg_done_d = last1_q_ && last_tick_q_;

    // Commit.
    wpend_q_ = upd_wr;
    pa_q_ = pa_d;
    pb_q_ = pb_d;
    top_q_ = top_d;
    waddr_q_ = addr(ra_q_, rc_q_, ri_m1);
    sum_q_ = sum;
    prev_q_ = rd_q_;
    rd_q_ = rd_d;
    ra_q_ = a_q_;
    rc_q_ = c_q_;
    ri_q_ = i_q_;
    for (int n = 0; n < Degree; ++n) carry_q_[n] = carry_d[n];
    for (int a = 0; a < Axes; ++a) sample_q_[a] = sample_d[a];
    sample_word_q_ = sample_word_d;
    sample_word_known_q_ = sample_word_known_d;
    a_q_ = a_d;
    c_q_ = c_d;
    i_q_ = i_d;
    count_q_ = count_d;
    cnt_one_q_ = cnt_one_d;
    last_tick_q_ = last_tick_d;
    active_q_ = active_d;
    mid_q_ = mid_d;
    hdr_q_ = hdr_d;
    hword_q_ = hword_d;
    iss_q_ = iss_d;
    busy_q_ = busy_d;
    last1_q_ = last1_d;
    primed_q_ = primed_d;
    tick_q_ = tick_d;
    tick_in_q_ = in.tick;
    tick_err_q_ = tick_err_d;
    sample_valid_q_ = sample_valid_d;
    underrun_q_ = underrun_d;
    seg_done_q_ = seg_done_d;
    // Synchronous reset: control state only, as in the RTL (the datapath
    // above took this cycle's enables; it is never read before a reload).
    if (!in.rst_n) reset();
  }

  // Model-only views for tests (not hardware ports).
  u128 reg(int axis, int i) const {
    u128 r = 0;
    for (int c = kChunks - 1; c >= 0; --c) r = (r << ChunkWidth) | u128(mem_[addr(axis, c, i)]);
    return r;
  }
  bool active() const { return active_q_; }
  bool busy() const { return busy_q_ || mid_q_; }

 private:
  bool tready() const { return !active_q_ && !busy_q_; }

  static int addr(int a, int c, int i) { return (a << (kChB + kRgB)) | (c << kRgB) | i; }
  static int saddr(int a, int c) { return (a << kChB) | c; }

  void reset() {
    for (int n = 0; n < Degree; ++n) carry_q_[n] = false;
    wpend_q_ = false;
    a_q_ = c_q_ = i_q_ = 0;
    active_q_ = false;
    primed_q_ = false;
    mid_q_ = false;
    hdr_q_ = true;
    hword_q_ = false;
    iss_q_ = false;
    busy_q_ = false;
    last1_q_ = false;
    tick_q_ = false;
    tick_in_q_ = false;
    tick_err_q_ = false;
    sample_valid_q_ = false;
    underrun_q_ = false;
    seg_done_q_ = false;
  }

  uint64_t mem_[kMemWords] = {};
  uint64_t rd_q_ = 0, prev_q_ = 0;
  bool wpend_q_ = false;  // an update write is in flight (registered)
  bool pa_q_ = false, pb_q_ = false, top_q_ = false;  // that update's operand top bits, top chunk
  int waddr_q_ = 0;
  uint64_t sum_q_ = 0;
  bool carry_q_[Degree] = {};
  int a_q_ = 0, c_q_ = 0, i_q_ = 0;     // field counters
  int ra_q_ = 0, rc_q_ = 0, ri_q_ = 0;  // the slot of rd_q
  u128 sample_q_[Axes] = {};
  uint64_t smem_[kSampleWords] = {};
  bool smem_known_[kSampleWords] = {};  // model-only (the RTL's RAM is not reset)
  uint64_t sample_word_q_ = 0;
  bool sample_word_known_q_ = false;
  uint32_t count_q_ = 0;
  bool cnt_one_q_ = false;
  bool last_tick_q_ = false;
  bool active_q_ = false;
  bool primed_q_ = false;
  bool mid_q_ = false;
  bool hdr_q_ = true;
  bool hword_q_ = false;
  bool iss_q_ = false;
  bool busy_q_ = false;
  bool last1_q_ = false;
  bool tick_q_ = false;
  bool tick_in_q_ = false;
  bool tick_err_q_ = false;
  bool sample_valid_q_ = false;
  bool underrun_q_ = false;
  bool seg_done_q_ = false;
};

}  // namespace traj
