// The loopback board: a host-side model of the board's protocol behaviour
// (rtl/board/LINK.md): a FIFO of whole segment records, next_seq, ACK/NAK with
// credits, CONFIG/START/STOP/RESUME/END, underrun halt, STATUS. It models a
// build without the time-scale unit: CONFIG with time scaling and FEED are
// refused (NAK 4), STATUS reports S = 0. It plays records by their tick
// counts (it does not evaluate the polynomials), either paced at a tick rate
// or as fast as the link feeds it. It is the reference of the protocol for
// the host and the device of long uploads.
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>

#include "link/frame.hpp"

namespace traj::link {

// The board build's segment format (what a real board is synthesised for).
struct BoardFormat {
  int axes = 3, degree = 5, width = 96, guard = 48;
  size_t record_bytes() const { return 16 + size_t(axes) * size_t(degree + 1) * size_t(width / 8); }
};

struct BoardOptions {
  BoardFormat format;
  size_t fifo_segments = 256;    // FIFO capacity in whole segments
  double clock_hz = kDefaultBoardClockHz;  // core clock: tick period in clocks -> seconds
  uint32_t min_tick_clocks = 64; // shortest tick period the build honours
  // Playback speed as a multiple of real time (tick period from CONFIG);
  // 0: unpaced (a full FIFO plays its older half at once, END plays the rest;
  // no underrun is possible).
  double speed = 1.0;
};

// A board as the byte path sees it: what serve() (board_server.hpp) drives.
// The loopback board below; the Verilated board top plugs in the same way.
class Board {
 public:
  virtual ~Board() = default;
  // Bytes from the host; the bytes the board sends back are appended to `out`.
  virtual void receive(const uint8_t* p, size_t n, Bytes& out) = 0;
  // Runs until `now` (seconds, any monotonic origin); bytes sent meanwhile
  // (periodic STATUS) are appended to `out`.
  virtual void advance(double now, Bytes& out) = 0;
  // Power-on reset: FIFO, next_seq, configuration and counters are lost.
  virtual void reset() = 0;
  virtual bool end_reached() const = 0;
  virtual bool playing() const = 0;
  // Segments stored since construction (reset() does not clear it): the
  // trigger of mid-job faults.
  virtual uint64_t stored_total() const = 0;
};

class LoopbackBoard : public Board {
 public:
  explicit LoopbackBoard(const BoardOptions& o);

  void receive(const uint8_t* p, size_t n, Bytes& out) override;
  void advance(double now, Bytes& out) override;
  void reset() override;

  Status status() const;
  const Config& config() const { return cfg_; }  // the last CONFIG taken
  bool playing() const override { return playing_; }
  bool end_reached() const override { return end_reached_; }
  uint64_t stored_total() const override { return stored_total_; }

  // Called with each record's seq and bytes as its playback starts.
  std::function<void(uint32_t seq, const Bytes& record)> on_played;

 private:
  void on_frame(const Frame& f, Bytes& out);
  void on_segment(const Frame& f, Bytes& out);
  bool content_good(const Frame& f) const;
  bool config_good(const Config& c) const;
  void ack(Bytes& out) const;
  void nak(NakReason r, Bytes& out) const;
  uint16_t credits() const;
  void start_next_segment();
  bool at_boundary();
  void play_ticks(uint64_t ticks);
  void play_unpaced();
  int64_t start_sample(const Bytes& rec, int axis) const;

  BoardOptions o_;
  FrameDecoder dec_;
  std::vector<FrameDecoder::Event> events_;
  std::deque<Bytes> fifo_;
  uint32_t next_seq_ = 0, seq_playing_ = 0;
  bool configured_ = false, playing_ = false, halted_ = false, stop_req_ = false, end_marked_ = false,
       end_reached_ = false, in_segment_ = false;
  Config cfg_;
  uint64_t left_in_segment_ = 0;
  double last_time_ = -1, tick_budget_ = 0;
  uint64_t next_status_tick_ = 0;
  Status st_;  // counters and the position
  uint64_t stored_total_ = 0;
};

}  // namespace traj::link
