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
#include <optional>
#include <string>
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
  // Whether the last good CONFIG turned time scaling on (m != 0): the tick is the servo tick.
  bool time_scaling() const { return config_.scale_m != 0; }
  const link::Config& config() const { return config_; }
  // Step/dir of each axis, decoded from the pins.
  const StepDecoder& axis(int a) const { return decoders_.at(a); }
  void set_step_timing(StepTiming t);
  // The cycle of every tick strobe the engine received (its samples' times).
  const std::vector<uint64_t>& tick_cycles() const { return ticks_; }
  // Without time scaling: the cycle of the tick each engine sample answered,
  // one per sample (a tick at an underrun gives none: a program pause).
  const std::vector<uint64_t>& sample_tick_cycles() const { return sample_ticks_; }
  // The board's hold pin (a button; with time scaling it holds as FEED's hold does).
  void set_hold_pin(bool on) { hold_pin_ = on; }
  bool hold_pin() const { return hold_pin_; }
  // Every output sample the step generator took (the engine's, or with time
  // scaling the unit's interpolated one, one per servo tick), axis-major per
  // sample, and its cycle; kept only after keep_samples(true).
  void keep_samples(bool on) { keep_samples_ = on; }

  // Scheduled events (`trajcore board --hold/--feed/--starve`), in seconds
  // of board time after playback first starts (START):
  //   hold:   the hold pin pressed for `for_s`;
  //   feed:   a FEED frame (override `percent`, hold off) put on the RX line
  //           between the host's frames, as if the host had sent it; its S
  //           from the CONFIG's time scaling and the stream's engine tick
  //           (s = 1 at S = 2^sb, sb = 32 + p - shift, 2^p engine ticks per
  //           servo tick);
  //   starve: the link paused for `for_s`: the host's bytes held back, then
  //           delivered in order (the board plays on from its FIFO; a host
  //           that re-sends meanwhile needs retries for the pause).
  void schedule_hold(double at_s, double for_s) { holds_.push_back({at_s, for_s}); }
  void schedule_feed(double at_s, double percent, double engine_tick_s) {
    feeds_.push_back({at_s, percent, engine_tick_s});
  }
  void schedule_starve(double at_s, double for_s) { starves_.push_back({at_s, for_s}); }
  // What the scheduled events did, a line each.
  const std::vector<std::string>& event_log() const { return event_log_; }
  const std::vector<int64_t>& samples() const { return samples_; }
  const std::vector<uint64_t>& sample_cycles() const { return sample_cycles_; }
  uint64_t cycles() const { return cycle_; }
  // With time scaling: the longest the unit was busy (clocks, from a servo
  // tick to its sample) and the longest the engine took to answer one of its
  // ticks (clocks from the strobe to the sample), for the host's bounds
  // (timescale::unit_tick_clocks, link::board_engine_clocks).
  uint64_t unit_busy_max() const { return unit_busy_max_; }
  uint64_t engine_answer_max() const { return engine_answer_max_; }
  uint64_t tx_framing_errors() const { return tx_.framing_errors(); }

 private:
  void clock(link::Bytes& out);
  void time_unit();
  void watch_answers(const link::Bytes& bytes);
  void watch_requests(const uint8_t* p, size_t n);

  struct Rtl;
  std::unique_ptr<Rtl> rtl_;
  UartPinWriter rx_;
  UartPinReader tx_;
  std::vector<StepDecoder> decoders_;
  std::vector<uint64_t> ticks_, sample_ticks_;
  link::FrameDecoder answers_, requests_;
  link::Config config_;
  link::Status status_;
  uint32_t next_seq_ = 0;
  uint64_t stored_total_ = 0, cycle_ = 0;
  uint64_t busy_run_ = 0, unit_busy_max_ = 0, engine_answer_max_ = 0;
  std::optional<uint64_t> engine_tick_at_;
  uint32_t quiet_ = 0;  // cycles the RX line idles before the queue is sent
  void run_events();
  bool starving() const;
  void pass_frame(const link::Bytes& raw);
  double play_time() const;  // board seconds since playback first started (< 0 before)

  bool hold_pin_ = false, keep_samples_ = false;
  struct Window {
    double at, for_s;
  };
  struct FeedAt {
    double at, percent, engine_tick;
  };
  std::vector<Window> holds_, starves_;
  std::vector<FeedAt> feeds_;
  size_t feeds_done_ = 0;
  std::vector<std::string> event_log_;
  int64_t play_start_ = -1;   // the cycle playback first started
  link::Bytes frame_in_;       // the host's frame in progress (raw, stuffed)
  link::Bytes held_back_;      // the host's frames held back while the link is paused
  bool was_starving_ = false, was_holding_ = false;
  std::vector<int64_t> samples_;
  std::vector<uint64_t> sample_cycles_;
};

}  // namespace traj::board
