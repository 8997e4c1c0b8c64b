#include "link/upload.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <optional>
#include <stdexcept>

#include "util/format.hpp"

namespace traj::link {
namespace {

using util::num;

[[noreturn]] void refuse(const std::string& what) { throw UploadError(what); }

// p of the servo tick engine_tick x 2^p: the option's, or the largest within
// kDefaultServoPeriod (p >= 0).
int servo_exponent(double engine_tick, const std::optional<double>& given) {
  if (!given) {
    int p = 0;
    while (p < 30 && std::ldexp(engine_tick, p + 1) <= kDefaultServoPeriod * (1 + 1e-9)) ++p;
    return p;
  }
  const double r = *given / engine_tick;
  const int p = r >= 1 ? static_cast<int>(std::lround(std::log2(r))) : -1;
  if (p < 0 || p > 30 || std::fabs(r / std::ldexp(1.0, p) - 1) > 1e-6)
    refuse("--servo-period " + num(*given) + " s is not the engine tick (" + num(engine_tick) +
           " s, the stream's tick or its re-ticked one: --max-engine-tick) times a power of two 2^p, p >= 0");
  return p;
}

// A feed the plan allows: 0 .. its scale_max, which the header holds rounded
// down to 1/4096 (`--time-scale 1.2` is 1.19995: 120 % is taken, as S_max).
bool feed_in_plan(double percent, double max_percent) {
  return percent >= 0 && percent < max_percent + 100.0 / stream::kScaleMaxUnit;
}

std::string plan_range(double max_percent) { return "the stream was planned for 0 .. " + num(max_percent) + " %"; }

}  // namespace

int board_engine_clocks(const fd::Format& f) {
  const int slots = f.axes * (f.degree + 1) * (f.width / f.chunk_width);
  const int hdr_words = f.chunk_width < 32 ? 32 / f.chunk_width : 1;
  return hdr_words + slots + slots + 2 + 6;
}

uint64_t servo_tick_clocks_needed(const TimeScaleSetup& t, const fd::Format& f) {
  return timescale::unit_tick_clocks(t.bounds, t.p, f.axes, board_engine_clocks(f));
}

FeedState TimeScaleSetup::feed() const {
  FeedState f;
  f.scale_bits = bounds.scale_bits;
  f.s_max = bounds.s_max;
  f.max_percent = max_percent;
  f.target_s = override_s;
  return f;
}

void TimeScaleSetup::apply(Config& c) const {
  if (!on) return;
  c.scale_m = static_cast<uint32_t>(bounds.m);
  c.scale_s_max = static_cast<uint32_t>(bounds.s_max);
  c.scale_override = static_cast<uint32_t>(override_s);
  c.scale_shift = static_cast<uint8_t>(shift());
  c.scale_flags = auto_resume ? config_flag::kAutoResume : 0;
}

TimeScaleSetup time_scale_setup(const stream::Header& h, const UploadOptions& o) {
  TimeScaleSetup t;
  t.engine_tick = t.servo_period = h.period;
  t.auto_resume = o.auto_resume;
  if (!h.has_time_scaling()) {
    const char* given = o.feed_percent     ? "--feed"
                        : o.servo_period_s ? "--servo-period"
                        : !o.auto_resume   ? "--no-auto-resume"
                        : o.feed_control   ? "live feed control (--control)"
                                           : nullptr;
    if (given)
      refuse(std::string(given) + ": the stream was planned without --time-scale (no feed override or hold; plan it "
             "with `trajcore plan --time-scale S_MAX`)");
    return t;
  }
  t.on = true;
  t.p = servo_exponent(h.period, o.servo_period_s);
  t.servo_period = std::ldexp(h.period, t.p);
  const std::string at = " (servo tick " + num(t.servo_period * 1e3) + " ms = 2^" + std::to_string(t.p) +
                         " engine ticks of " + num(h.period * 1e3) + " ms; --servo-period)";
  try {
    t.bounds = timescale::integer_bounds({h.scale_max, h.scale_rate, h.scale_accel}, t.servo_period);
  } catch (const std::invalid_argument& e) {
    refuse(e.what() + at);
  }
  if (t.shift() < 0 || t.shift() > 40)
    refuse("time scaling: shift = 32 - sb + p = 32 - " + std::to_string(t.bounds.scale_bits) + " + " +
           std::to_string(t.p) + " = " + std::to_string(t.shift()) + " is outside the unit's 0..40" + at);
  if (t.bounds.m > 0xFFFFFFFF || t.bounds.s_max > 0xFFFFFFFF)
    refuse("time scaling: m " + std::to_string(t.bounds.m) + " or S_max " + std::to_string(t.bounds.s_max) +
           " does not fit CONFIG's 32 bits" + at);
  t.max_percent = 100 * h.scale_max;
  const double feed = o.feed_percent.value_or(std::min(100.0, t.max_percent));
  if (!feed_in_plan(feed, t.max_percent))
    refuse("--feed " + num(feed) + " %: " + plan_range(t.max_percent) + " (`trajcore plan --time-scale " +
           num(h.scale_max) + "`)");
  t.override_s = scale_of_percent(feed, t.bounds.scale_bits, t.bounds.s_max);
  return t;
}

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

class Uploader : public FeedPort {
 public:
  Uploader(Transport& port, RecordSource& src, const UploadOptions& o,
           const std::function<void(const UploadProgress&)>& cb)
      : port_(port), src_(src), o_(o), cb_(cb) {}

  UploadResult run() {
    const auto t0 = Clock::now();
    // refused options before the board is touched
    ts_ = time_scale_setup(src_.header(), o_);
    prog_.time_scaling = ts_.on;
    prog_.feed = ts_.feed();
    config_ = make_config(o_.clock_hz > 0 ? o_.clock_hz : kDefaultBoardClockHz);
    if (ts_.on && o_.clock_hz > 0) check_servo_tick(config_.tick_clocks, o_.clock_hz);  // else at the board's clock
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
    if (ts_.on) {
      FeedState& f = prog_.feed;
      f.have_status = true;
      f.s = s.scale_s;
      f.held = s.flags & status_flag::kHeld;
      f.starved = s.flags & status_flag::kStarved;
      f.starved_holds = s.starved_holds;
    }
    if (!watching_) return;
    if (s.flags & status_flag::kTickError) fail("the board reports a tick error (ticks faster than the engine)");
    if (holds_at_pause(s)) return;
    if ((s.flags & status_flag::kUnderrunHalt) || s.underruns != underruns_at_start_)
      fail("the board underran after " + std::to_string(s.segments_played) + " segments played (FIFO empty before "
           "the job's end: the host or the link was too slow; " + std::to_string(s.underruns) + " underruns, " +
           std::to_string(s.next_seq) + " stored" +
           (o_.ahead ? "; --ahead " + std::to_string(o_.ahead) + " stores too little ahead for this stream" : "") +
           "); it holds position and waits: run again with --resume");
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

  // A control command: 0 for its ACK, or the NAK reason 4 or 5; other NAKs
  // (1: damaged on the way) and silence re-send it.
  uint8_t request(Type t, uint32_t seq, const Bytes& payload = {}) {
    for (int attempt = 0; attempt <= o_.max_retries; ++attempt) {
      last_answer_.reset();
      send(t, seq, payload);
      const auto at = Clock::now();
      while (!last_answer_ && since(at) * 1e3 < answer_timeout_ms()) pump(5);
      if (!last_answer_) {
        ++prog_.timeouts;
        continue;
      }
      if (last_answer_->ack) return 0;
      if (last_answer_->reason == uint8_t(NakReason::kPlaying) ||
          last_answer_->reason == uint8_t(NakReason::kBadContent))
        return last_answer_->reason;
    }
    fail(std::string("no ACK to ") + type_name(t) + " after " + std::to_string(o_.max_retries + 1) + " attempts");
  }

  // A control command that must be acknowledged.
  void command(Type t, uint32_t seq, const Bytes& payload = {}) {
    const uint8_t nak = request(t, seq, payload);
    if (nak == uint8_t(NakReason::kPlaying))
      fail(std::string("the board refuses ") + type_name(t) + " while playing");
    if (nak == uint8_t(NakReason::kBadContent))
      fail(std::string("the board refuses ") + type_name(t) + " as bad content" +
           (t == Type::kConfig ? config_refusal() : std::string()));
  }

  std::string config_refusal() const {
    const std::string other = "a tick period below its engine's update time, or a step shift out of range";
    if (!ts_.on) return " (" + other + ")";
    return ": time scaling m " + std::to_string(config_.scale_m) + ", S_max " + std::to_string(config_.scale_s_max) +
           ", override " + std::to_string(config_.scale_override) + ", shift " +
           std::to_string(config_.scale_shift) + " (scale bits " + std::to_string(ts_.bounds.scale_bits) +
           ", servo tick " + num(ts_.servo_period * 1e3) + " ms = 2^" + std::to_string(ts_.p) +
           " engine ticks). A build without the time-scale unit (the loopback board is one) refuses any time "
           "scaling; a build with it refuses values at or above 2^SW (SW = 20 on the simulated board and the HX8K, "
           "16 on the iCEBreaker: a longer --servo-period makes the scale bits, m and S_max smaller); or " + other;
  }

  // ---- live feed control (FeedPort) -------------------------------------

  FeedState feed_state() const override { return prog_.feed; }

  void set_feed(double percent, bool hold) override {
    if (!ts_.on) throw FeedRefused("the stream was planned without --time-scale: no feed override or hold");
    if (!feed_in_plan(percent, ts_.max_percent))
      throw FeedRefused("feed " + num(percent) + " %: " + plan_range(ts_.max_percent));
    const int64_t s = scale_of_percent(percent, ts_.bounds.scale_bits, ts_.bounds.s_max);
    send_feed(s, hold);
  }

  void send_feed(int64_t s, bool hold) {
    quiesce();
    const uint8_t nak = request(Type::kFeed, 0, encode_feed({static_cast<uint32_t>(s), hold}));
    if (nak != 0)
      throw FeedRefused("the board refuses FEED override " + std::to_string(s) + " (" +
                        num(scale_percent(s, ts_.bounds.scale_bits)) + " %)" + (hold ? " with hold" : "") + ": " +
                        nak_name(nak) + (nak == uint8_t(NakReason::kBadContent)
                                             ? " (a build without the time-scale unit, or an override at or above "
                                               "2^SW of the build)"
                                             : ""));
    prog_.feed.target_s = s;
    prog_.feed.hold = hold;
    report();
  }

  // An ACK does not tell which frame it answers: a FEED goes out once every
  // segment sent was answered (or a timeout passed: go-back-N heals the rest).
  void quiesce() {
    const auto t = Clock::now();
    while (tracking_ && send_next_ != base_ && since(t) * 1e3 < answer_timeout_ms()) pump(5);
  }

  // --resume: the board's feed as this tool shows it (--feed, no hold).
  void resume_feed() {
    try {
      send_feed(ts_.override_s, false);
    } catch (const FeedRefused& e) {
      fail(std::string(e.what()) + "; --resume of a time-scaled job needs a board whose CONFIG has time scaling");
    }
  }

  void poll_controls() {
    if (ts_.on && o_.feed_control) o_.feed_control->poll(*this);
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
      if (src_.pause()) note_pause(*src_.pause(), base_ + uint32_t(window_.size()));
      window_.push_back(std::move(rec));
      prog_.read = src_.records();
    }
    return true;
  }

  // The sequence number --ahead stops at: that many past the segment playing
  // in the latest STATUS (segments_played counts from the job's RESET, as seq).
  uint32_t ahead_limit() const {
    if (o_.ahead == 0) return base_ + 0x7FFFFFFF;
    return (prog_.have_status ? prog_.status.segments_played : 0) + uint32_t(o_.ahead);
  }

  // Sends what the credits allow; true if anything was sent.
  bool send_allowed(uint32_t limit) {
    bool sent = false;
    const uint32_t cap = seq_diff(limit, allowed_end_) < 0 ? limit : allowed_end_;
    while (seq_diff(cap, send_next_) > 0) {
      if (!fill_window(send_next_ + 1) || at_barrier()) break;
      port_.write(encode_frame(Type::kSegment, send_next_, window_[send_next_ - base_]));
      ++send_next_;
      if (seq_diff(send_next_, sent_end_) > 0) sent_end_ = send_next_;
      sent = true;
    }
    return sent;
  }

  // ---- program pauses ------------------------------------------------

  // The record at `seq` follows a pause: nothing from it on is sent before
  // the board has played up to the pause and the operator said go.
  void note_pause(const stream::Pause& p, uint32_t seq) {
    if (ts_.on)
      stream_failed("the stream has a program pause (line " + std::to_string(p.line) + ") and time scaling: the "
                    "board's time-scale unit would hold short of the pause's stop");
    pause_ = PauseAt{p, seq, prog_.pauses + 1};
  }

  // Sending has reached a pause the board has not yet held at.
  bool at_barrier() const { return pause_ && send_next_ == pause_->link_seq; }

  // The board holds at the pause: it played every segment before it and ran
  // dry there (the underrun halt), at rest.
  bool holds_at_pause(const Status& s) const {
    return pause_ && s.next_seq == pause_->link_seq && s.segments_played == pause_->link_seq &&
           (s.flags & status_flag::kUnderrunHalt) && !(s.flags & status_flag::kPlaying);
  }

  // Everything before the pause is stored: waits until the board holds
  // there, then for the operator, then refills the FIFO and resumes.
  void wait_at_pause() {
    for (;;) {
      check_interrupt();
      const Status s = query_status();
      report();
      if (holds_at_pause(s)) break;
      pump(20);
    }
    const std::string& text = pause_->pause.text;
    if (!o_.pause_confirmed)
      fail("the board holds at rest at the program pause at line " + std::to_string(pause_->pause.line) +
           (text.empty() ? "" : " (\"" + text + "\")") + " and no one is here to confirm it; `--resume` continues the job");
    prog_.at_pause = true;
    report();
    while (!o_.pause_confirmed(*pause_)) {
      check_interrupt();
      pump(20);  // the board's periodic STATUS, kept current
      report();
    }
    prog_.at_pause = false;
    ++prog_.pauses;
    // STATUS frames still show the halt until the RESUME: not watched until
    // the board plays again (as a --resume from an underrun halt)
    watching_ = false;
    underruns_at_start_ = prog_.status.underruns;  // the pause's own underrun is no failure
    pause_.reset();
    prefill();
    start_playback(Type::kResume);
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
    if (ts_.on)
      fail("interrupted: STOP sent and acknowledged; the board holds: it slows along its S-curve and stops on the "
           "path, then stops playing (" + std::to_string(prog_.status.segments_played) + " of " +
           std::to_string(base_) + " stored segments started); START (`--resume`) continues the job where it stopped");
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
      fail(why + (ts_.on ? "; STOP sent: the board stops on the path (a hold), START (`--resume`) continues"
                         : "; STOP sent: the board stops at the end of the segment it plays"));
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
    const double clock_hz = board_clock(s);
    config_ = make_config(clock_hz);
    if (ts_.on) check_servo_tick(config_.tick_clocks, clock_hz);
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
    if (ts_.on) resume_feed();
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

  // A servo tick shorter than the unit's work would find it busy (STATUS tick
  // error mid-job): refused before CONFIG (at the board's clock, or before
  // the board is touched with --clock-hz), naming a period that fits.
  void check_servo_tick(double tick_clocks, double clock_hz) const {
    const fd::Format f = src_.header().format();
    const double need = static_cast<double>(servo_tick_clocks_needed(ts_, f));
    if (tick_clocks >= need) return;
    std::string fits = "a longer one";
    UploadOptions longer = o_;
    for (int p = ts_.p + 1; p <= 30; ++p) {  // the shortest servo tick that fits, with its own bounds
      longer.servo_period_s = std::ldexp(ts_.engine_tick, p);
      try {
        if (static_cast<double>(servo_tick_clocks_needed(time_scale_setup(src_.header(), longer), f)) <=
            std::round(*longer.servo_period_s * clock_hz)) {
          fits = num(*longer.servo_period_s) + " s or longer";
          break;
        }
      } catch (const UploadError&) {
        break;
      }
    }
    fail("the servo tick of " + num(ts_.servo_period * 1e6) + " us is " + num(tick_clocks) + " clocks at " +
         num(clock_hz / 1e6) + " MHz, but the board's time-scale unit may need up to " + num(need) +
         " clocks of it (2^" + std::to_string(ts_.p + 1) + " engine ticks of up to " +
         std::to_string(board_engine_clocks(f)) + " clocks, a simulated stop of up to " +
         std::to_string(timescale::stop_ticks_bound(ts_.bounds)) + " S-curve steps): give --servo-period " + fits);
  }

  // The tick CONFIG gives: the servo tick with time scaling, else the engine tick.
  Config make_config(double clock_hz) const {
    Config c;
    const double tick = ts_.servo_period;
    const double tick_clocks = std::round(tick * clock_hz);
    if (tick_clocks < 1 || tick_clocks > 4294967295.0)
      fail("tick period " + std::to_string(tick) + " s at " + std::to_string(clock_hz) +
           " Hz is not a 32-bit clock count");
    c.tick_clocks = static_cast<uint32_t>(tick_clocks);
    c.status_ticks =
        o_.status_period_s > 0 ? static_cast<uint32_t>(std::max(1.0, std::round(o_.status_period_s / tick))) : 0;
    ts_.apply(c);
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
    const uint32_t prefill_end = o_.prefill ? base_ + uint32_t(o_.prefill) : base_ + 0x7FFFFFFF;
    auto last = Clock::now();
    for (;;) {
      const uint32_t limit = seq_diff(prefill_end, ahead_limit()) < 0 ? prefill_end : ahead_limit();
      check_interrupt();
      poll_controls();
      send_allowed(limit);
      const bool full = seq_diff(send_next_, limit) >= 0 || seq_diff(send_next_, allowed_end_) >= 0 || at_barrier();
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
      // started and already run dry (a short --ahead): named as an underrun.
      // The count, not the halt flag: a RESUME after an underrun may still
      // see the flag of the old one.
      const bool underran = s.underruns != underruns_at_start_;
      if ((s.flags & (status_flag::kPlaying | status_flag::kEndReached)) || underran) {
        watching_ = true;
        on_status(s);
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
      poll_controls();
      if (at_barrier() && send_next_ == base_) {
        wait_at_pause();
        continue;
      }
      send_allowed(ahead_limit());
      wait_answers(last);
      // blocked by credits (or --ahead) and nothing in flight: ask, the board may have made room (or played on)
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
      while (since(wait) < 0.1) {  // periodic STATUS frames keep the progress current
        pump(5);
        poll_controls();
      }
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
  TimeScaleSetup ts_;
  std::optional<PauseAt> pause_;  // the next pause, once its record was read
};

}  // namespace

UploadResult upload(Transport& port, RecordSource& src, const UploadOptions& o,
                    const std::function<void(const UploadProgress&)>& on_progress) {
  return Uploader(port, src, o, on_progress).run();
}

}  // namespace traj::link
