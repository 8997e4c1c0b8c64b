#include "link/upload.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <optional>

namespace traj::link {
namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

class Uploader {
 public:
  Uploader(Transport& port, RecordSource& src, const UploadOptions& o,
           const std::function<void(const UploadProgress&)>& cb)
      : port_(port), src_(src), o_(o), cb_(cb) {}

  UploadResult run() {
    const auto t0 = Clock::now();
    config_ = make_config(o_.clock_hz > 0 ? o_.clock_hz : kDefaultBoardClockHz);  // refused options before the board is touched
    drain_input();
    const Status s = query_status();
    if (o_.resume && !(s.next_seq == 0 && s.segments_played == 0)) {
      continue_job(s);
    } else {
      if (s.flags & status_flag::kPlaying)
        fail("the board is playing a job: wait for its end, or continue it with --resume");
      start_job();
    }
    feed_until_end();
    finish();
    UploadResult r;
    r.records = src_.records();
    r.first_seq = first_seq_;
    r.progress = prog_;
    r.seconds = since(t0);
    return r;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw UploadError(port_.name() + ": " + what); }

  // ---- receiving ------------------------------------------------------

  // Reads for up to timeout_ms and handles every frame; true if any good frame came.
  bool pump(int timeout_ms) {
    uint8_t buf[4096];
    const size_t n = port_.read(buf, sizeof buf, timeout_ms);
    if (n == 0) return false;
    events_.clear();
    dec_.feed(buf, n, events_);
    bool any = false;
    for (auto& e : events_) {
      if (!e.good) continue;  // a damaged answer: the timeout heals it
      any = true;
      handle(e.frame);
    }
    return any;
  }

  void handle(const Frame& f) {
    switch (f.type) {
      case Type::kAck: {
        const Ack a = decode_ack(f);
        on_next_seq(a.next_seq, a.credits);
        last_answer_ = Answer{true, 0};
        break;
      }
      case Type::kNak: {
        const Nak n = decode_nak(f);
        ++prog_.naks;
        on_next_seq(n.next_seq, n.credits);
        on_nak(n);
        last_answer_ = Answer{false, n.reason};
        break;
      }
      case Type::kStatus: {
        const Status s = decode_status(f);
        on_next_seq(s.next_seq, static_cast<uint16_t>(std::min<uint32_t>(s.credits, 0xFFFF)));
        on_status(s);
        break;
      }
      default:
        break;  // a host-to-board type: not for us
    }
    answered_ = true;
  }

  // Every answer carries the board's next_seq; it never goes back except
  // when the board was reset (answers arrive in order on a byte link).
  void on_next_seq(uint32_t n, uint16_t credits) {
    if (!tracking_) return;
    const int32_t d = seq_diff(n, base_);
    if (d < 0)
      fail("the board's next_seq went back from " + std::to_string(base_) + " to " + std::to_string(n) +
           ": the board was reset mid-job and lost its FIFO and position; it holds still. Re-home the machine and "
           "run the job again");
    if (seq_diff(n, sent_end_) > 0) fail("the board acknowledged segment " + std::to_string(n - 1) + ", never sent");
    if (d > 0) {
      window_.erase(window_.begin(), window_.begin() + d);
      base_ = n;
      if (seq_diff(n, send_next_) > 0) send_next_ = n;  // sent before a go-back, and stored
      retries_at_base_ = 0;
      prog_.acked = base_;
      stale_naks_ = 0;
    }
    allowed_end_ = n + credits;
  }

  void on_nak(const Nak& n) {
    switch (static_cast<NakReason>(n.reason)) {
      case NakReason::kBadFrame:
      case NakReason::kOutOfOrder:
      case NakReason::kFifoFull:
        if (!tracking_) return;
        // frames sent before the go-back answer NAK 2 at the same seq: one go-back heals them all
        if (n.next_seq == rewound_to_ && stale_naks_ > 0) {
          --stale_naks_;
          return;
        }
        go_back(n.next_seq);
        return;
      case NakReason::kBadContent:
        if (tracking_ && ++bad_content_ >= 3)
          fail("the board refuses segment " + std::to_string(n.next_seq) + " as bad content: its build takes another "
               "record format than this stream's (" + std::to_string(src_.record_bytes()) + "-byte records; the "
               "board tops take 3 axes, quintic, 96-bit: `trajcore plan --engine-width 96`)");
        if (tracking_) go_back(n.next_seq);
        return;
      case NakReason::kPlaying:
        return;  // the request that caused it reports it
    }
  }

  void go_back(uint32_t to) {
    if (seq_diff(send_next_, to) <= 0) return;
    ++prog_.resends;
    if (++retries_at_base_ > o_.max_retries)
      fail("segment " + std::to_string(to) + " re-sent " + std::to_string(o_.max_retries) +
           " times without being stored (link too noisy?); the board stops at its FIFO's end");
    stale_naks_ = send_next_ - to - 1;
    rewound_to_ = to;
    send_next_ = to;
  }

  void on_status(const Status& s) {
    prog_.status = s;
    prog_.have_status = true;
    ++statuses_;
    if (!watching_) return;
    if (s.flags & status_flag::kTickError) fail("the board reports a tick error (ticks faster than the engine)");
    if ((s.flags & status_flag::kUnderrunHalt) || s.underruns != underruns_at_start_)
      fail("the board underran after " + std::to_string(s.segments_played) + " segments played (FIFO empty before "
           "the job's end: the host or the link was too slow; " + std::to_string(s.underruns) + " underruns, " +
           std::to_string(s.next_seq) + " stored); it holds position and waits: run again with --resume");
    if (!(s.flags & (status_flag::kPlaying | status_flag::kEndReached)))
      fail("the board stopped playing after " + std::to_string(s.segments_played) + " segments (reset, or stopped by "
           "another host?); it holds still");
  }

  // Bytes the board sent before this tool opened the port (periodic STATUS
  // queued in the port's buffer) describe the past: discarded.
  void drain_input() {
    uint8_t buf[4096];
    for (int i = 0; i < 1000 && port_.read(buf, sizeof buf, 10) > 0; ++i) {
    }
  }

  Status query_status() {
    for (int attempt = 0; attempt <= o_.max_retries; ++attempt) {
      const uint64_t before = statuses_;
      send(Type::kStatusReq, 0);
      const auto t = Clock::now();
      while (since(t) * 1e3 < answer_timeout_ms()) {
        pump(5);
        if (statuses_ != before) return prog_.status;
      }
      ++prog_.timeouts;
    }
    fail("no STATUS answer after " + std::to_string(o_.max_retries + 1) + " requests (is a board on this port, at "
         "this baud rate?)");
  }

  // A control command answered by ACK; NAK 1 (damaged on the way) is re-sent.
  void command(Type t, uint32_t seq, const Bytes& payload = {}) {
    for (int attempt = 0; attempt <= o_.max_retries; ++attempt) {
      last_answer_.reset();
      send(t, seq, payload);
      const auto at = Clock::now();
      while (!last_answer_ && since(at) * 1e3 < answer_timeout_ms()) pump(5);
      if (!last_answer_) {
        ++prog_.timeouts;
        continue;
      }
      if (last_answer_->ack) return;
      if (last_answer_->reason == uint8_t(NakReason::kPlaying))
        fail(std::string("the board refuses ") + type_name(t) + " while playing");
      if (last_answer_->reason == uint8_t(NakReason::kBadContent))
        fail(std::string("the board refuses ") + type_name(t) + " as bad content" +
             (t == Type::kConfig ? " (a tick period below its engine's update time, or a step shift out of range)"
                                 : ""));
    }
    fail(std::string("no ACK to ") + type_name(t) + " after " + std::to_string(o_.max_retries + 1) + " attempts");
  }

  // ---- sending --------------------------------------------------------

  void send(Type t, uint32_t seq, const Bytes& payload = {}) { port_.write(encode_frame(Type(t), seq, payload)); }

  double answer_timeout_ms() const {
    const double inflight = double(send_next_ - base_) * double(src_.record_bytes() + 16);
    return o_.timeout_ms + 2e3 * inflight * 10 / o_.baud;
  }

  // Reads records until the window covers [base_, upto).
  bool fill_window(uint32_t upto) {
    while (seq_diff(upto, base_ + uint32_t(window_.size())) > 0) {
      Bytes rec;
      bool more = false;
      try {
        more = src_.next(rec);
      } catch (const LinkError& e) {
        stream_failed(e.what());
      }
      if (!more) {
        prog_.stream_done = true;
        return false;
      }
      window_.push_back(std::move(rec));
      prog_.read = src_.records();
    }
    return true;
  }

  // Sends what the credits allow; true if anything was sent.
  bool send_allowed(uint32_t limit) {
    bool sent = false;
    const uint32_t cap = seq_diff(limit, allowed_end_) < 0 ? limit : allowed_end_;
    while (seq_diff(cap, send_next_) > 0) {
      if (!fill_window(send_next_ + 1)) break;
      port_.write(encode_frame(Type::kSegment, send_next_, window_[send_next_ - base_]));
      ++send_next_;
      if (seq_diff(send_next_, sent_end_) > 0) sent_end_ = send_next_;
      sent = true;
    }
    return sent;
  }

  bool all_sent_and_stored() const { return prog_.stream_done && window_.empty() && send_next_ == base_; }

  void check_interrupt() {
    if (!o_.interrupted || !o_.interrupted->load()) return;
    watching_ = false;
    tracking_ = false;
    send(Type::kStop, 0);  // at once; then again once the answers in flight are in, so its ACK is its own
    const auto t = Clock::now();
    while (since(t) * 1e3 < answer_timeout_ms()) pump(5);
    command(Type::kStop, 0);
    fail("interrupted: STOP sent and acknowledged; the board stops at the end of the segment it plays (" +
         std::to_string(prog_.status.segments_played) + " of " + std::to_string(base_) +
         " stored segments started); `--resume` continues the job");
  }

  // The stream broke off (damaged, or its writer died, e.g. on Ctrl-C): stop
  // the board at a segment end rather than let it underrun.
  [[noreturn]] void stream_failed(const std::string& why) {
    check_interrupt();
    if (tracking_) {
      watching_ = tracking_ = false;
      try {
        command(Type::kStop, 0);
      } catch (const LinkError&) {
        fail(why + "; STOP could not be sent: the board stops when its FIFO runs empty");
      }
      fail(why + "; STOP sent: the board stops at the end of the segment it plays");
    }
    throw UploadError(why);
  }

  // Waits for answers; on a silent link re-sends from base_ and asks for STATUS.
  void wait_answers(Clock::time_point& last_answer_time) {
    answered_ = false;
    pump(2);
    if (answered_) {
      last_answer_time = Clock::now();
      silent_ = 0;
      return;
    }
    if (since(last_answer_time) * 1e3 < answer_timeout_ms()) return;
    ++prog_.timeouts;
    if (++silent_ > o_.max_retries)
      fail("no answer from the board for " + std::to_string(silent_) + " timeouts of " +
           std::to_string(int(answer_timeout_ms())) + " ms (link down?); the board stops at its FIFO's end");
    if (send_next_ != base_) go_back(base_);
    send(Type::kStatusReq, 0);
    last_answer_time = Clock::now();
  }

  // Every turn of the loops (the caller throttles what it shows).
  void report() {
    if (cb_) cb_(prog_);
  }

  // ---- phases ---------------------------------------------------------

  void start_job() {
    command(Type::kReset, 0);
    const Status s = query_status();
    if (s.next_seq != 0 || s.fifo_level != 0 || (s.flags & (status_flag::kPlaying | status_flag::kUnderrunHalt)))
      fail("the board did not reset (next_seq " + std::to_string(s.next_seq) + ", FIFO level " +
           std::to_string(s.fifo_level) + ")");
    config_ = make_config(board_clock(s));
    command(Type::kConfig, 0, encode_config(config_));
    underruns_at_start_ = s.underruns;
    base_ = send_next_ = sent_end_ = 0;
    allowed_end_ = s.credits;
    tracking_ = true;
    prefill();
    start_playback(Type::kStart);
  }

  // --resume: the board keeps its FIFO and position; skip what it has stored.
  void continue_job(const Status& s) {
    first_seq_ = s.next_seq;
    Bytes rec;
    for (uint32_t i = 0; i < s.next_seq; ++i)
      if (!src_.next(rec))
        fail("--resume: the board expects segment " + std::to_string(s.next_seq) + " but the stream has " +
             std::to_string(src_.records()) + " (another job?)");
    prog_.read = src_.records();
    base_ = send_next_ = sent_end_ = s.next_seq;
    allowed_end_ = s.next_seq + s.credits;
    prog_.acked = base_;
    underruns_at_start_ = s.underruns;
    tracking_ = true;
    if (s.flags & status_flag::kEndReached) return;
    if (s.flags & status_flag::kPlaying) {
      watching_ = true;
      return;
    }
    prefill();
    start_playback((s.flags & status_flag::kUnderrunHalt) ? Type::kResume : Type::kStart);
  }

  // The core clock CONFIG's clock counts are in: the board's (STATUS), which
  // --clock-hz, if given, must match.
  double board_clock(const Status& s) const {
    if (s.clock_hz == 0) {
      if (o_.clock_hz > 0) return o_.clock_hz;
      fail("the board does not report its core clock (STATUS offset 32 is 0: a build before LINK.md gave it); "
           "give --clock-hz");
    }
    if (o_.clock_hz > 0 && std::fabs(o_.clock_hz / s.clock_hz - 1) > 1e-6)
      fail("--clock-hz " + std::to_string(o_.clock_hz) + " but the board reports a core clock of " +
           std::to_string(s.clock_hz) + " Hz (leave --clock-hz out to use the board's)");
    return s.clock_hz;
  }

  Config make_config(double clock_hz) const {
    Config c;
    const double tick_clocks = std::round(src_.header().period * clock_hz);
    if (tick_clocks < 1 || tick_clocks > 4294967295.0)
      fail("tick period " + std::to_string(src_.header().period) + " s at " + std::to_string(clock_hz) +
           " Hz is not a 32-bit clock count");
    c.tick_clocks = static_cast<uint32_t>(tick_clocks);
    c.status_ticks = o_.status_period_s > 0
                         ? static_cast<uint32_t>(std::max(1.0, std::round(o_.status_period_s / src_.header().period)))
                         : 0;
    const size_t axes = static_cast<size_t>(src_.header().axes);
    if (o_.step_shift.size() > 1 && o_.step_shift.size() != axes)
      fail("--step-shift has " + std::to_string(o_.step_shift.size()) + " values for a stream of " +
           std::to_string(axes) + " axes (give one, or one per axis)");
    for (int a = 0; a < src_.header().axes && a < 8; ++a) {
      const int sh = o_.step_shift.empty() ? 0
                     : o_.step_shift.size() == 1 ? o_.step_shift[0]
                                                 : o_.step_shift.at(static_cast<size_t>(a));
      c.step_shift[a] = static_cast<uint8_t>(sh);
    }
    c.pulse_clocks = static_cast<uint16_t>(std::clamp(std::round(o_.pulse_us * 1e-6 * clock_hz), 1.0, 65535.0));
    c.dir_setup_clocks =
        static_cast<uint16_t>(std::clamp(std::round(o_.dir_setup_us * 1e-6 * clock_hz), 0.0, 65535.0));
    c.enable = 1;
    return c;
  }

  // Stores segments until the FIFO (or --prefill) is full or the stream ends.
  void prefill() {
    const uint32_t limit = o_.prefill ? base_ + uint32_t(o_.prefill) : base_ + 0x7FFFFFFF;
    auto last = Clock::now();
    for (;;) {
      check_interrupt();
      send_allowed(limit);
      const bool full = seq_diff(send_next_, limit) >= 0 || seq_diff(send_next_, allowed_end_) >= 0;
      if (send_next_ == base_ && (full || prog_.stream_done)) break;
      wait_answers(last);
      report();
    }
    if (prog_.stream_done) command(Type::kEnd, base_);
  }

  void start_playback(Type t) {
    for (int attempt = 0; attempt <= o_.max_retries; ++attempt) {
      command(t, 0);
      const Status s = query_status();
      if (s.flags & (status_flag::kPlaying | status_flag::kEndReached)) {
        watching_ = true;
        return;
      }
    }
    fail(std::string(type_name(t)) + " acknowledged but the board does not play");
  }

  void feed_until_end() {
    auto last = Clock::now();
    auto last_poll = Clock::now();
    while (!all_sent_and_stored()) {
      check_interrupt();
      send_allowed(base_ + 0x7FFFFFFF);
      wait_answers(last);
      // blocked by credits and nothing in flight: ask, the board may have made room
      if (send_next_ == base_ && since(last_poll) > 0.02 && !all_sent_and_stored()) {
        send(Type::kStatusReq, 0);
        last_poll = Clock::now();
      }
      report();
    }
  }

  // END (re-sent until the end is reached: an ACK cannot tell which frame it
  // answers), then STATUS until the board has played everything.
  void finish() {
    const uint32_t end_seq = static_cast<uint32_t>(src_.records());
    for (int silent = 0;;) {
      check_interrupt();
      send(Type::kEnd, end_seq);
      const uint64_t before = statuses_;
      send(Type::kStatusReq, 0);
      const auto t = Clock::now();
      while (statuses_ == before && since(t) * 1e3 < answer_timeout_ms()) pump(5);
      report();
      if (statuses_ == before) {
        ++prog_.timeouts;
        if (++silent > o_.max_retries)
          fail("no STATUS from the board while waiting for the job's end (link down?)");
        continue;
      }
      silent = 0;
      if (prog_.status.flags & status_flag::kEndReached) break;
      const auto wait = Clock::now();
      while (since(wait) < 0.1) pump(5);  // periodic STATUS frames keep the progress current
    }
    report();
  }

  struct Answer {
    bool ack = false;
    uint8_t reason = 0;
  };

  Transport& port_;
  RecordSource& src_;
  const UploadOptions& o_;
  std::function<void(const UploadProgress&)> cb_;
  FrameDecoder dec_;
  std::vector<FrameDecoder::Event> events_;
  std::deque<Bytes> window_;  // records base_ .. base_ + size - 1
  uint32_t base_ = 0, send_next_ = 0, sent_end_ = 0, allowed_end_ = 0, rewound_to_ = 0, stale_naks_ = 0;
  uint64_t first_seq_ = 0, statuses_ = 0;
  uint32_t underruns_at_start_ = 0;
  int retries_at_base_ = 0, silent_ = 0, bad_content_ = 0;
  bool tracking_ = false, watching_ = false, answered_ = false;
  std::optional<Answer> last_answer_;
  UploadProgress prog_;
  Config config_;
};

}  // namespace

UploadResult upload(Transport& port, RecordSource& src, const UploadOptions& o,
                    const std::function<void(const UploadProgress&)>& on_progress) {
  return Uploader(port, src, o, on_progress).run();
}

}  // namespace traj::link
