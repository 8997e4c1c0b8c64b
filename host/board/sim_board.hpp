// SPDX-License-Identifier: Apache-2.0
// The simulated board: the portable board logic (rtl/traj_board.sv, the same
// RTL the board tops carry) Verilated and clocked cycle by cycle. Its UART RX
// pin is driven bit by bit from the bytes the host sends, its TX pin decoded
// into bytes for the host (uart_pins.hpp), and its step/dir pins decoded per
// axis (step_decoder.hpp), all outside the RTL. It answers the host link
// protocol (rtl/board/LINK.md) exactly as the hardware does, so `trajcore
// upload` talks to it on a pseudo-terminal as to a board.
//
// It is a link::Board, as the loopback board is, so the same server
// (link::serve, with fault injection) serves either.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "board/step_decoder.hpp"
#include "board/uart_pins.hpp"
#include "link/board.hpp"
#include "link/frame.hpp"

namespace traj::board {

// The Verilated build (host/board/CMakeLists.txt): clock, baud and segment format.
struct BoardBuild {
  static const uint32_t kClkHz, kBaud;
  static const int kAxes, kDegree, kWidth, kGuardBits;
};

class SimulatedBoard : public link::Board {
 public:
  SimulatedBoard();
  ~SimulatedBoard();
  SimulatedBoard(const SimulatedBoard&) = delete;
  SimulatedBoard& operator=(const SimulatedBoard&) = delete;

  // Bytes from the host, queued on the RX pin; the answers come from advance().
  void receive(const uint8_t* p, size_t n, link::Bytes& out) override;
  // Clocks the board: every queued byte is sent on the RX pin and at most
  // `max_cycles` more cycles run (idle cycles are skipped while the board
  // neither plays nor has bytes to send); the TX bytes are appended to `out`.
  void advance(double now_s, link::Bytes& out) override;
  void run(uint64_t cycles, link::Bytes& out);
  // Power-on reset of the board logic (a reset mid-job, a fault).
  void reset() override;
  // Runs two tick periods more, so that the last tick's steps reach the pins.
  void drain();

  bool playing() const override;
  bool end_reached() const override { return status_.flags & link::status_flag::kEndReached; }
  uint64_t stored_total() const override { return stored_total_; }
  link::Status status() const { return status_; }

  // The step shift of each axis, from the last good CONFIG the host sent
  // (decoded from the bytes on the RX pin, apart from the RTL).
  std::vector<int> step_shifts() const;
  // The engine's tick period in clocks from the last good CONFIG (0: none yet).
  uint32_t tick_clocks() const { return config_.tick_clocks; }
  // Step/dir of each axis, decoded from the pins.
  const StepDecoder& axis(int a) const { return decoders_.at(a); }
  void set_step_timing(StepTiming t);
  // The cycle of every tick strobe the engine received (its samples' times).
  const std::vector<uint64_t>& tick_cycles() const { return ticks_; }
  uint64_t cycles() const { return cycle_; }
  uint64_t tx_framing_errors() const { return tx_.framing_errors(); }

 private:
  void clock(link::Bytes& out);
  void watch_answers(const link::Bytes& bytes);
  void watch_requests(const uint8_t* p, size_t n);

  struct Rtl;
  std::unique_ptr<Rtl> rtl_;
  UartPinWriter rx_;
  UartPinReader tx_;
  std::vector<StepDecoder> decoders_;
  std::vector<uint64_t> ticks_;
  link::FrameDecoder answers_, requests_;
  link::Config config_;
  link::Status status_;
  uint32_t next_seq_ = 0;
  uint64_t stored_total_ = 0, cycle_ = 0;
  uint32_t quiet_ = 0;  // cycles the RX line idles before the queue is sent
};

}  // namespace traj::board
