// The host side of the link: uploads a segment stream to a board (or the
// loopback board) over a Transport, as rtl/board/LINK.md defines: RESET,
// CONFIG, prefill, START, credits, go-back-N re-sends on NAK or timeout, END,
// then waits until the board has played the job. `--resume` continues a job
// from the board's next_seq after the tool was restarted. A stream planned
// with time scaling (`trajcore plan --time-scale`) is played at a servo tick
// with the feed override and hold of LINK.md (CONFIG's time-scaling fields,
// FEED), changed live through FeedControls (feed_control.hpp).
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "link/feed_control.hpp"
#include "link/frame.hpp"
#include "link/record_source.hpp"
#include "link/transport.hpp"
#include "stream/segment_stream.hpp"
#include "timescale/time_scale.hpp"

namespace traj::link {

// A program pause the board holds at.
struct PauseAt {
  stream::Pause pause;    // as the stream holds it (its segment number, the program's line)
  uint32_t link_seq = 0;  // the link's sequence number of the segment after it (re-ticked: the fine one)
  uint64_t index = 0;     // 1 for the job's first pause, 2 for the next...
};

struct UploadOptions {
  double clock_hz = 0;             // the board's core clock, Hz; 0: as its STATUS reports (given: checked against it)
  std::vector<int> step_shift;     // per axis (one value: every axis); empty: 0
  double pulse_us = 2.0, dir_setup_us = 2.0;
  double status_period_s = 0.1;    // the board's periodic STATUS (0: on request only)
  size_t prefill = 0;              // segments stored before START (0: as many as the FIFO takes)
  size_t ahead = 0;                // segments stored ahead of the one playing (0: as many as the FIFO takes)
  bool resume = false;             // continue the board's job from its next_seq
  int timeout_ms = 100;            // answer timeout, plus the transmission time of what is in flight
  int baud = 1000000;              // for the transmission time (pseudo-terminals and TCP are faster)
  int max_retries = 20;            // re-sends of one segment, or unanswered requests, before giving up
  const std::atomic<bool>* interrupted = nullptr;  // set by SIGINT: STOP and exit
  // Time scaling: only for a stream planned with it (refused otherwise).
  std::optional<double> feed_percent;    // --feed: the initial override, % of the planned speed (default 100)
  std::optional<double> servo_period_s;  // --servo-period: engine tick x 2^p (default: the largest <= 1 ms)
  bool auto_resume = true;               // resume by itself after a starved hold (--no-auto-resume)
  FeedControl* feed_control = nullptr;   // live controls (keyboard, --control), polled every turn
  // Program pauses (the stream's pause records): called about every 20 ms
  // while the board holds at one (it played every segment before the pause
  // and stands at rest, in its underrun halt) until it returns true: the
  // operator's go-ahead. It may throw UploadError (no one to confirm). Unset:
  // the upload stops with UploadError once the board holds at the first
  // pause (at rest; --resume waits there again).
  std::function<bool(const PauseAt&)> pause_confirmed;
};

// Thrown with a message naming what failed; the board is left stopped or
// holding (no motion jumps).
class UploadError : public LinkError {
 public:
  using LinkError::LinkError;
};

// The servo tick by default: the largest engine_tick x 2^p <= 1 ms, p >= 0.
constexpr double kDefaultServoPeriod = 1e-3;

// CONFIG's time-scaling fields for a stream and the options: the servo tick
// (2^p engine ticks at s = 1), timescale::integer_bounds of the header's ramp
// bounds at that tick, the initial override. Without time scaling in the
// header: off, the servo tick is the engine tick, and every time-scaling
// option is refused.
struct TimeScaleSetup {
  bool on = false;
  double engine_tick = 0, servo_period = 0;  // s
  int p = 0;                                 // 2^p engine ticks per servo tick at s = 1
  timescale::IntBounds bounds;               // scale_bits (sb), m, s_max
  int64_t override_s = 0;                    // the initial target S
  double max_percent = 0;                    // the header's scale_max, %
  bool auto_resume = true;

  int shift() const { return 32 - bounds.scale_bits + p; }
  FeedState feed() const;                    // the feed as CONFIG sets it
  void apply(Config& c) const;               // CONFIG's bytes 24..39
};
// Throws UploadError naming the option or the value that does not fit
// (scale bits, shift 0..40, u32 fields).
TimeScaleSetup time_scale_setup(const stream::Header& h, const UploadOptions& o);

// The most clocks traj_board's FD engine (traj_fd_tm, fed from the segment
// FIFO) takes from a tick to its sample, for a stream of format f: at a
// segment boundary the next segment's words, one per clock
// (HdrWords + Axes (Degree+1) Chunks), then its first pass over the
// registers (Axes (Degree+1) Chunks + 2), and the FIFO's read (6). The
// simulated board measures it (tb/simboard: 218 clocks at 3 axes, quintic,
// 96-bit, 16-bit chunks, where this gives 226).
int board_engine_clocks(const fd::Format& f);

// The shortest servo tick, in clocks, in which the board's time-scale unit
// always finishes (timescale::unit_tick_clocks with board_engine_clocks).
uint64_t servo_tick_clocks_needed(const TimeScaleSetup& t, const fd::Format& f);

struct UploadProgress {
  uint64_t acked = 0;         // records the board has stored (next_seq)
  uint64_t read = 0;          // records read from the stream so far
  bool stream_done = false;   // the stream's end record was read
  uint64_t resends = 0, naks = 0, timeouts = 0;
  bool have_status = false;
  Status status;              // the latest STATUS
  bool time_scaling = false;
  FeedState feed;             // time scaling: the feed sent and the board's (from `status`)
  uint64_t pauses = 0;        // program pauses the board held at and went on from
  bool at_pause = false;      // the board holds at a pause, waiting for the operator
};

struct UploadResult {
  uint64_t records = 0, first_seq = 0;  // first_seq > 0 after --resume
  UploadProgress progress;
  double seconds = 0;
};

UploadResult upload(Transport& port, RecordSource& src, const UploadOptions& o,
                    const std::function<void(const UploadProgress&)>& on_progress = {});

}  // namespace traj::link
