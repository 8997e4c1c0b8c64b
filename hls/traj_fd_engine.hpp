// SPDX-License-Identifier: Apache-2.0
// trajcore hls: forward-difference sampling engine, cycle-accurate model of
// rtl/traj_fd_engine.sv.
//
// Per axis the engine holds Degree+1 difference registers r[0..Degree] of Width
// bits (two's complement, wrapping). r[0] is the position, r[i] the i-th
// forward difference at the current tick. One tick advances every register by
// additions only:
//
//     r[i] <- r[i] + r[i+1]      for i = 0 .. Degree-1, all from the OLD values
//
// ([FD] prints the recurrence the other way round, r[i+1] += r[i] with the
// output in r[N]; that keeps r[0] constant and does not reproduce p(t0+kh).
// tb/fd/fd_recurrence_test.cpp derives and tests the right one.)
//
// Timing. The carry chain is cut into Chunks = Width/ChunkWidth pieces: a tick
// update takes Chunks clock cycles; in each, every register is rotated right
// by ChunkWidth bits and its lowest chunk is replaced, at the top, by the
// chunk sum (with the carry saved from the previous chunk). After Chunks
// cycles every register is back in place. No multiplexer selects a chunk; the
// adders always see bits [ChunkWidth-1:0].
//
// Segment input: a word stream (valid/ready). The header is K, the 32-bit tick
// count, in ceil(32/ChunkWidth) words, least significant first. Then, axis by axis, register
// by register (r[0] first), chunk by chunk (least significant first), the
// Degree+1 registers of every axis. The words shift into the register chain
// (the same rotate path), so loading costs no wide multiplexer.
// A segment is accepted only while no segment is active and no update runs.
//
// Tick contract: one strobe = one tick. A tick is a cycle with tick_i high
// after a cycle with tick_i low (a rising edge; tick_i is never sampled as a
// level). tick_i high in two consecutive cycles violates the contract: it is
// one tick and sets the sticky tick_err.
//
// Ticks: a new tick is latched into a pending flag. A pending tick is processed when
// no update runs and no segment is half loaded (and no header is being
// accepted that cycle). With a segment active it emits sample = r[0] >> Guard
// (the top OutWidth bits), raises seg_done with the K-th sample, and starts the
// update. With none, it raises underrun; sample_o keeps the last sample and
// sample_valid pulses only if a sample has been emitted since reset (a K = 0
// segment emits none): the
// output never jumps. A tick arriving while one is pending sets the sticky
// tick_err (the servo strobe ran faster than the engine can follow).
//
// Minimum tick spacing for no tick_err: Chunks cycles while running.
#pragma once
#include <cstdint>

#include "traj_common.hpp"

namespace traj {

template <int Axes, int Degree, int Width, int ChunkWidth, int GuardBits>
class FdEngine {
 public:
  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(Degree >= 1 && Degree <= 7, "Degree must be 1..7");
  static_assert(ChunkWidth == 16 || ChunkWidth == 32 || ChunkWidth == 64,
                "ChunkWidth must be 16, 32 or 64");
  static_assert(Width >= ChunkWidth && Width <= kMaxWidth && Width % ChunkWidth == 0,
                "Width must be a multiple of ChunkWidth, at most 128");
  static_assert(GuardBits >= 0 && GuardBits < Width - 1, "GuardBits must leave >= 2 output bits");

  static constexpr int kChunks = Width / ChunkWidth;
  static constexpr int kOutWidth = Width - GuardBits;
  static constexpr int kRegs = Axes * (Degree + 1);
  // Clocks from a tick taken at once to its sample_valid (as FdTm's).
  static constexpr int answer_clocks(bool /*last_tick*/) { return 2; }
  static constexpr int kHdrWords = ChunkWidth < 32 ? 32 / ChunkWidth : 1;
  static constexpr int kWords = kHdrWords + kRegs * kChunks;  // header + registers

  struct In {
    bool rst_n = true;
    uint64_t tdata = 0;  // low ChunkWidth bits used
    bool tvalid = false;
    bool tick = false;
  };

  struct Out {
    bool tready;
    bool sample_valid;
    u128 sample[Axes];  // OutWidth-bit two's complement, wrapped
    bool underrun;
    bool seg_done;
    bool tick_err;
  };

  // Outputs as seen during the current cycle (all registered, except tready,
  // which depends on state only).
  Out outputs() const {
    Out o{};
    o.tready = tready();
    o.sample_valid = sample_valid_q_;
    for (int a = 0; a < Axes; ++a) o.sample[a] = sample_q_[a];
    o.underrun = underrun_q_;
    o.seg_done = seg_done_q_;
    o.tick_err = tick_err_q_;
    return o;
  }

  // One rising clock edge with the given inputs.
  void clock(const In& in) {
    const bool accept = in.tvalid && tready();
    const bool header = accept && wcnt_q_ < kHdrWords;
    const bool consume = tick_q_ && !busy_q_ && wcnt_q_ == 0 && !accept;
    const bool run = consume && active_q_;
    const bool step = run || busy_q_;  // a chunk of the update this cycle
    const bool last_phase = step && (busy_q_ ? phase_q_ == kChunks - 1 : kChunks == 1);

    // Next-state values (nonblocking semantics: all computed from the _q state).
    u128 reg_d[kRegs];
    bool carry_d[kRegs];
    for (int n = 0; n < kRegs; ++n) {
      reg_d[n] = reg_q_[n];
      carry_d[n] = carry_q_[n];
    }
    if (accept && !header) {
      // Shift the register chain right by one chunk; the word enters at the top.
      for (int n = 0; n < kRegs; ++n) {
        const u128 in_chunk = (n == kRegs - 1) ? u128(in.tdata) & mask(ChunkWidth)
                                               : bits(reg_q_[n + 1], 0, ChunkWidth);
        reg_d[n] = rot_in(reg_q_[n], in_chunk);
      }
    } else if (step) {
      for (int a = 0; a < Axes; ++a) {
        for (int i = 0; i <= Degree; ++i) {
          const int n = a * (Degree + 1) + i;
          const u128 lo = bits(reg_q_[n], 0, ChunkWidth);
          if (i == Degree) {
            reg_d[n] = rot_in(reg_q_[n], lo);  // constant: rotate only
          } else {
            // carry_q is 0 at the start of every update (cleared below).
            const u128 sum = lo + bits(reg_q_[n + 1], 0, ChunkWidth) + u128(carry_q_[n]);
            reg_d[n] = rot_in(reg_q_[n], sum & mask(ChunkWidth));
            carry_d[n] = !last_phase && ((sum >> ChunkWidth) & 1) != 0;
          }
        }
      }
    }

    // Control.
    uint32_t count_d = count_q_;
    bool active_d = active_q_;
    bool primed_d = primed_q_;
    int wcnt_d = wcnt_q_;
    if (accept) {
      if (header) {
        count_d = ChunkWidth < 32
                      ? static_cast<uint32_t>((count_q_ >> ChunkWidth) |
                                              (static_cast<uint32_t>(in.tdata) << (32 - ChunkWidth)))
                      : static_cast<uint32_t>(in.tdata);
      }
      if (wcnt_q_ == kWords - 1) {
        wcnt_d = 0;
        active_d = count_q_ != 0;
      } else {
        wcnt_d = wcnt_q_ + 1;
      }
    }
    bool busy_d = busy_q_;
    int phase_d = phase_q_;
    bool last_tick_d = last_tick_q_;
    if (run) {
      count_d = count_q_ - 1;
      last_tick_d = count_q_ == 1;
    }
    if (step) {
      if (last_phase) {
        busy_d = false;
        phase_d = 0;
        if (run ? count_q_ == 1 : last_tick_q_) active_d = false;
      } else {
        busy_d = true;
        phase_d = busy_q_ ? phase_q_ + 1 : 1;
      }
    }

    bool sample_valid_d = false, underrun_d = false, seg_done_d = false;
    u128 sample_d[Axes];
    for (int a = 0; a < Axes; ++a) sample_d[a] = sample_q_[a];
    if (consume) {
      if (active_q_) {
        for (int a = 0; a < Axes; ++a)
          sample_d[a] = bits(reg_q_[a * (Degree + 1)], GuardBits, kOutWidth);
        sample_valid_d = true;
        seg_done_d = count_q_ == 1;
        primed_d = true;  // a real sample has left (a K = 0 segment emits none)
      } else {
        underrun_d = true;
        sample_valid_d = primed_q_;
      }
    }
    const bool tick_new = in.tick && !tick_in_q_;   // tick_i rises
    const bool tick_held = in.tick && tick_in_q_;   // high a second cycle: violation
    const bool tick_d = (tick_q_ && !consume) || tick_new;
    const bool tick_err_d = tick_err_q_ || (tick_new && tick_q_ && !consume) || tick_held;

    // Commit.
    for (int n = 0; n < kRegs; ++n) {
      reg_q_[n] = reg_d[n];
      carry_q_[n] = carry_d[n];
    }
    for (int a = 0; a < Axes; ++a) sample_q_[a] = sample_d[a];
    count_q_ = count_d;
    active_q_ = active_d;
    primed_q_ = primed_d;
    wcnt_q_ = wcnt_d;
    busy_q_ = busy_d;
    phase_q_ = phase_d;
    last_tick_q_ = last_tick_d;
    tick_q_ = tick_d;
    tick_in_q_ = in.tick;
    tick_err_q_ = tick_err_d;
    sample_valid_q_ = sample_valid_d;
    underrun_q_ = underrun_d;
    seg_done_q_ = seg_done_d;
    // Synchronous reset: control state only, as in the RTL (the datapath above
    // still took this cycle's enables; it is never read before a full reload).
    if (!in.rst_n) reset();
  }

  // Model-only views for tests (not hardware ports).
  u128 reg(int axis, int i) const { return reg_q_[axis * (Degree + 1) + i]; }
  bool active() const { return active_q_; }
  bool busy() const { return busy_q_ || wcnt_q_ != 0; }

 private:
  bool tready() const { return !active_q_ && !busy_q_; }

  static u128 rot_in(u128 r, u128 top) {
    return wrap((r >> ChunkWidth) | (top << (Width - ChunkWidth)), Width);
  }

  void reset() {
    // Control state only; the datapath (registers, samples, count) keeps its value.
    for (int n = 0; n < kRegs; ++n) carry_q_[n] = false;
    active_q_ = false;
    primed_q_ = false;
    wcnt_q_ = 0;
    busy_q_ = false;
    phase_q_ = 0;
    tick_q_ = false;
    tick_in_q_ = false;
    tick_err_q_ = false;
    sample_valid_q_ = false;
    underrun_q_ = false;
    seg_done_q_ = false;
  }

  u128 reg_q_[kRegs] = {};
  bool carry_q_[kRegs] = {};
  u128 sample_q_[Axes] = {};
  uint32_t count_q_ = 0;
  bool active_q_ = false;
  bool primed_q_ = false;
  int wcnt_q_ = 0;
  bool busy_q_ = false;
  int phase_q_ = 0;
  bool last_tick_q_ = false;
  bool tick_q_ = false;
  bool tick_in_q_ = false;  // tick_i of the previous cycle (edge detection)
  bool tick_err_q_ = false;
  bool sample_valid_q_ = false;
  bool underrun_q_ = false;
  bool seg_done_q_ = false;
};

}  // namespace traj
