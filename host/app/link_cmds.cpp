#include "link_cmds.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>


#include "board/step_check.hpp"
#include "fd/fd_ticker.hpp"
#include "util/format.hpp"

namespace traj::app {
namespace {

using util::strf;

std::atomic<bool> g_interrupted{false};
void on_signal(int) { g_interrupted.store(true); }

void catch_signals(std::initializer_list<int> sigs) {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (int s : sigs) sigaction(s, &sa, nullptr);
}

// The effective feed s = S 2^-sb from STATUS, the target, the flags.
std::string feed_text(const link::FeedState& f) {
  std::string flags = f.hold ? ", hold" : "";
  if (f.held) flags += ", held";
  if (f.starved) flags += ", starved";
  return strf(", feed %s (target %.1f %%%s), starved holds %u",
              f.have_status ? strf("%.1f %%", f.effective_percent()).c_str() : "?", f.target_percent(),
              flags.c_str(), f.starved_holds);
}

// Live status on stderr: on a terminal one line updated 5 times a second,
// otherwise (a log) a line every 5 s.
class StatusLine {
 public:
  StatusLine(double lsb, const std::string& units) : tty_(::isatty(2)), lsb_(lsb), units_(units) {}
  void show(const link::UploadProgress& p, bool force) {
    const auto now = std::chrono::steady_clock::now();
    if (!force && now - last_ < std::chrono::milliseconds(tty_ ? 200 : 5000)) return;
    last_ = now;
    std::string pos;  // the engine holds no position before its first tick
    if (p.have_status && p.status.ticks_played > 0)
      for (size_t a = 0; a < p.status.sample.size(); ++a)
        pos += strf("%s%.4f", a ? " " : "", double(p.status.sample[a]) * lsb_);
    const std::string line = strf(
        "[upload] %llu segments stored%s, %u played, FIFO %u, position %s %s, underruns %u, re-sends %llu%s%s",
        static_cast<unsigned long long>(p.acked),
        p.stream_done ? strf(" of %llu", static_cast<unsigned long long>(p.read)).c_str() : "",
        p.status.segments_played, p.status.fifo_level, pos.empty() ? "?" : pos.c_str(), units_.c_str(),
        p.status.underruns, static_cast<unsigned long long>(p.resends),
        p.time_scaling ? feed_text(p.feed).c_str() : "", p.at_pause ? ", holding at a program pause" : "");
    std::fprintf(stderr, tty_ ? "\r%s   " : "%s\n", line.c_str());
    shown_ = true;
  }
  // A message between status lines (what a key did).
  void say(const std::string& what) {
    std::fprintf(stderr, tty_ && shown_ ? "\r[upload] %s\033[K\n" : "[upload] %s\n", what.c_str());
    last_ = {};
  }
  ~StatusLine() {
    if (tty_ && shown_) std::fprintf(stderr, "\n");
  }

 private:
  bool tty_, shown_ = false;
  double lsb_;
  std::string units_;
  std::chrono::steady_clock::time_point last_{};
};

void add_upload(CLI::App& app, LinkCommands& lc) {
  auto& a = lc.up;
  auto* c = lc.upload = app.add_subcommand("upload", "Upload a segment stream to a board (rtl/board/LINK.md)");
  c->add_option("stream", a.input, "segment stream (.trj, version 4), or - for standard input")->required();
  c->add_option("--port", a.port, "serial port (/dev/ttyUSB1), pseudo-terminal (/dev/pts/N) or tcp:HOST:PORT")
      ->required();
  c->add_option("--baud", a.opt.baud, "serial baud rate (8N1, no flow control)")->capture_default_str();
  c->add_option("--clock-hz", a.opt.clock_hz,
                "the board's core clock, Hz (tick period and pulse times in clocks); default: as the board's "
                "STATUS reports it; given: checked against it")
      ->check(CLI::PositiveNumber);
  c->add_option("--step-shift", a.opt.step_shift, "per axis: one step = 2^shift output LSB (one value: all axes)")
      ->delimiter(',')
      ->check(CLI::Range(0, 63));
  c->add_option("--pulse-us", a.opt.pulse_us, "step pulse width, us")->capture_default_str();
  c->add_option("--dir-setup-us", a.opt.dir_setup_us, "direction setup and hold time, us")->capture_default_str();
  c->add_option("--status-period", a.opt.status_period_s, "the board's STATUS period, s (0: on request only)")
      ->capture_default_str();
  c->add_option("--max-engine-tick", a.max_engine_tick,
                "longest engine tick, s: a stream with a longer tick is played at ceil(tick / this) engine ticks per "
                "tick, its segments re-compiled exactly (the step edges' 10 us bound holds up to 1 ms); 0: always "
                "the stream's own tick")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  c->add_option("--prefill", a.opt.prefill, "segments stored before START (0: as many as the FIFO takes)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  c->add_option("--ahead", a.opt.ahead,
                "segments stored ahead of the one playing, as the board's STATUS reports it (0: as many as the FIFO "
                "takes); a short look-ahead bounds how long the board plays on when the host is gone, too short a one "
                "underruns when the host answers late")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  c->add_flag("--resume", a.opt.resume,
              "continue the board's job from its next sequence number (after the tool was stopped or killed)");
  c->add_option("--timeout-ms", a.opt.timeout_ms, "answer timeout, ms, plus the transmission time in flight")
      ->capture_default_str();
  c->add_option("--retries", a.opt.max_retries, "re-sends of one segment or unanswered requests before giving up")
      ->capture_default_str();
  c->add_option("--feed", a.feed_percent,
                "time scaling: the initial feed override, % of the planned speed (0 .. the plan's --time-scale x 100; "
                "default 100)");
  c->add_option("--servo-period", a.servo_period,
                "time scaling: the servo tick, s: the engine tick x 2^p (default: the largest within 1 ms)");
  c->add_flag("--no-auto-resume", a.no_auto_resume,
              "time scaling: after a starved hold (data ran out) resume only on a feed change or RESUME, not by "
              "itself");
  c->add_option("--control", a.control,
                "time scaling: a Unix-domain socket to create at this path for live feed control: lines `feed "
                "<percent>`, `hold`, `resume`, `status`, each answered `ok ...` or `error: ...`");
  c->footer("Exit status 0 once the board has played the whole job; otherwise a message names what failed. Ctrl-C "
            "sends STOP: the board stops at the end of the segment it plays (time scaling: on the path). A stream "
            "planned with --time-scale on a terminal (not read from standard input): keys h or space hold/resume, "
            "+ / - feed +/-10 %, 1 feed 100 %, q stop. A stream with program pauses (`plan --pause-wait`: M0/M60) "
            "stops at each: the board holds at rest until a line (Enter) on standard input, or on the terminal when "
            "the stream comes from standard input.");
}

void add_board(CLI::App& app, LinkCommands& lc) {
  auto& a = lc.bd;
  auto* c = lc.board = app.add_subcommand(
      "board", "A board on a pseudo-terminal (printed) or TCP port, for `trajcore upload --port`");
  c->add_flag("--loopback", a.loopback,
              "the loopback board: the protocol model (FIFO, ACK/NAK, credits, STATUS); without it, the simulated "
              "board: rtl/traj_board.sv Verilated, its pins driven and decoded");
  c->add_option("--expect", a.expect,
                "simulated board: the stream the tool uploads; the decoded step/dir pins are checked against its "
                "exact prediction (exit status 1 if they differ)");
  c->add_option("--tcp", a.tcp_port, "listen on this TCP port of 127.0.0.1 (0: any free port) instead of a pty");
  c->add_option("--fifo", a.board.fifo_segments, "loopback: FIFO capacity, whole segments")
      ->check(CLI::Range(1, 65535))
      ->capture_default_str();
  c->add_option("--speed", a.board.speed, "playback speed, multiple of real time (0: as fast as the link feeds it)")
      ->capture_default_str();
  c->add_option("--clock-hz", a.board.clock_hz, "core clock, Hz (tick period in clocks -> seconds)")
      ->capture_default_str();
  c->add_option("--axes", a.board.format.axes, "the build's segment format: axes")->capture_default_str();
  c->add_option("--degree", a.board.format.degree, "FD degree")->capture_default_str();
  c->add_option("--width", a.board.format.width, "FD register width, bits")->capture_default_str();
  c->add_option("--guard", a.board.format.guard, "FD guard bits")->capture_default_str();
  auto& f = a.faults;
  c->add_option("--corrupt", f.corrupt, "fault: probability per byte of a flipped bit")->check(CLI::Range(0.0, 1.0));
  c->add_option("--drop", f.drop, "fault: probability per byte of its loss")->check(CLI::Range(0.0, 1.0));
  c->add_option("--dup-frames", f.dup_frames, "fault: probability per frame of a duplicate")
      ->check(CLI::Range(0.0, 1.0));
  c->add_option("--delay-ms", f.delay_ms, "fault: every byte arrives this late")->check(CLI::NonNegativeNumber);
  c->add_option("--faults-to", a.faults_dir, "which direction the byte faults hit")
      ->check(CLI::IsMember({"board", "host", "both"}))
      ->capture_default_str();
  c->add_option("--reset-after", f.reset_after, "fault: reset the board once it has stored this many segments");
  c->add_option("--cut-after", f.cut_after, "fault: the link goes dead once the board has stored this many segments");
  c->add_option("--seed", f.seed, "fault random seed")->capture_default_str();
  c->add_flag("--once", a.once, "exit after one job's end (and the tool's last request)");
  c->add_option("--played", a.played, "write the bytes of every record the board plays to this file");
  c->add_option("--hold", a.holds,
                "simulated board, time scaling: AT:FOR, the hold pin (a button) pressed at AT s of playback for FOR s "
                "(repeatable)");
  c->add_option("--feed", a.feeds,
                "simulated board, time scaling: AT:PERCENT, a FEED frame (feed override) at AT s of playback, as if "
                "from the host (needs --expect: the stream's engine tick gives S) (repeatable)");
  c->add_option("--starve", a.starves,
                "simulated board, time scaling: AT:FOR, the link paused from AT s of playback for FOR s: the host's "
                "bytes held back, then delivered (the tool needs --retries to outlast it) (repeatable)");
  c->footer("Prints the port for --port on standard output, a summary on standard error at exit (SIGINT, SIGTERM, "
            "or --once).");
}

}  // namespace

void add_link_commands(CLI::App& app, LinkCommands& lc) {
  add_upload(app, lc);
  add_board(app, lc);
}

namespace {

link::UploadOptions upload_options(const UploadArgs& a) {
  link::UploadOptions o = a.opt;
  o.interrupted = &g_interrupted;
  if (!std::isnan(a.feed_percent)) o.feed_percent = a.feed_percent;
  if (!std::isnan(a.servo_period)) o.servo_period_s = a.servo_period;
  o.auto_resume = !a.no_auto_resume;
  return o;
}

// The operator's go-ahead at a program pause: a line (Enter) on standard
// input, or on the terminal when the stream comes from standard input. One
// byte at a time, so that lines typed ahead answer one pause each.
class PausePrompt {
 public:
  PausePrompt(bool stream_on_stdin, StatusLine& line) : line_(line) {
    if (!stream_on_stdin) return;
    fd_ = ::open("/dev/tty", O_RDONLY | O_CLOEXEC);
    owned_ = fd_ >= 0;
  }
  ~PausePrompt() {
    if (owned_) ::close(fd_);
  }
  PausePrompt(const PausePrompt&) = delete;
  PausePrompt& operator=(const PausePrompt&) = delete;

  bool operator()(const link::PauseAt& p) {
    const std::string where = "program pause " + std::to_string(p.index) + " (line " + std::to_string(p.pause.line) + ")";
    if (fd_ < 0)
      throw link::UploadError(where + ": the board holds at rest, but the stream comes from standard input and there "
                              "is no terminal to confirm on; `--resume` continues the job");
    if (asked_ != p.index) {
      asked_ = p.index;
      const std::string what = p.pause.text.empty() ? "" : " \"" + p.pause.text + "\";";
      line_.say(where + ":" + what + " the machine holds at rest (" +
                (::isatty(fd_) ? "press Enter" : "a line on standard input") +
                " to go on; Ctrl-C stops, `--resume` continues later)");
    }
    for (;;) {
      pollfd q{fd_, POLLIN, 0};
      if (::poll(&q, 1, 0) <= 0) return false;
      char c = 0;
      const ssize_t n = ::read(fd_, &c, 1);
      if (n == 0)
        throw link::UploadError(where + ": input ended before the operator's go-ahead; the board holds at rest, "
                                "`--resume` continues the job");
      if (n < 0) return false;
      if (c == '\n') return true;
    }
  }

 private:
  StatusLine& line_;
  int fd_ = 0;
  bool owned_ = false;
  uint64_t asked_ = 0;
};

// Keys only from a terminal this process has in the foreground, and not when
// the stream comes from standard input.
bool keyboard_wanted(const UploadArgs& a) {
  return a.input != "-" && ::isatty(0) && ::tcgetpgrp(0) == ::getpgrp();
}

}  // namespace

int upload_command(const UploadArgs& a) {
  link::RecordSource src(a.input, a.max_engine_tick);
  link::UploadOptions o = upload_options(a);
  link::FeedControls controls;
  if (!a.control.empty()) o.feed_control = &controls;
  const auto& h = src.header();
  const link::TimeScaleSetup ts = link::time_scale_setup(h, o);  // refused options before the port is opened
  auto port = link::open_port(a.port, a.opt.baud);
  StatusLine line(std::ldexp(1.0, -h.frac_bits), h.units);
  catch_signals({SIGINT, SIGTERM});
  if (ts.on) {
    if (!a.control.empty()) controls.add(std::make_unique<link::ControlSocket>(a.control));
    if (keyboard_wanted(a)) {
      catch_signals({SIGHUP, SIGQUIT});  // the terminal's mode is restored on the way out
      controls.add(std::make_unique<link::KeyboardControl>(0, g_interrupted,
                                                           [&](const std::string& m) { line.say(m); }));
      std::fprintf(stderr, "upload: %s\n", link::KeyboardControl::help());
    }
    std::fprintf(stderr,
                 "upload: time scaling: servo tick %g ms (2^%d engine ticks), scale bits %d, m %lld, S_max %lld "
                 "(%g %%), feed %.2f %%%s\n",
                 ts.servo_period * 1e3, ts.p, ts.bounds.scale_bits, static_cast<long long>(ts.bounds.m),
                 static_cast<long long>(ts.bounds.s_max), ts.max_percent, ts.feed().target_percent(),
                 ts.auto_resume ? "" : ", no auto-resume");
  }
  o.feed_control = controls.empty() ? nullptr : &controls;
  if (src.engine_ticks_per_tick() > 1)
    std::fprintf(stderr,
                 "upload: stream tick %g ms played at %u engine ticks per tick (%g ms), the segments re-compiled "
                 "exactly, so that the step edges keep within 10 us of the motion (--max-engine-tick)\n",
                 src.stream_period() * 1e3, src.engine_ticks_per_tick(), h.period * 1e3);
  else if (h.period > stream::kMaxStepEngineTick)  // the step generator's timing bound (rtl/README.md)
    std::fprintf(stderr,
                 "upload: note: tick period %g ms: the board's step edges are within 10 us of the motion's "
                 "boundary crossings only for engine ticks up to 1 ms (leave out --max-engine-tick 0)\n",
                 h.period * 1e3);
  PausePrompt prompt(a.input == "-", line);
  o.pause_confirmed = [&](const link::PauseAt& p) { return prompt(p); };
  const auto r = link::upload(*port, src, o, [&](const link::UploadProgress& p) { line.show(p, false); });
  line.show(r.progress, true);
  std::fprintf(stderr, "\n");
  // STATUS counts servo ticks: with time scaling 2^p engine ticks each at s = 1
  const double motion = double(r.progress.status.ticks_played) * (ts.on ? ts.servo_period : h.period);
  std::printf("upload: %llu segments%s to %s in %.2f s (%.0f segments/s), %u played, %.3f s of motion; re-sends "
              "%llu, NAKs %llu, timeouts %llu; board: bad frames %u, out of order %u, underruns %u (%llu at program "
              "pauses)\n",
              static_cast<unsigned long long>(r.records - r.first_seq),
              r.first_seq ? strf(" (resumed at %llu)", static_cast<unsigned long long>(r.first_seq)).c_str() : "",
              port->name().c_str(), r.seconds, double(r.records - r.first_seq) / std::max(r.seconds, 1e-9),
              r.progress.status.segments_played, motion, static_cast<unsigned long long>(r.progress.resends),
              static_cast<unsigned long long>(r.progress.naks), static_cast<unsigned long long>(r.progress.timeouts),
              r.progress.status.bad_frames, r.progress.status.out_of_order, r.progress.status.underruns,
              static_cast<unsigned long long>(r.progress.pauses));
  return 0;
}

namespace {

link::FaultOptions faults_of(const BoardArgs& a) {
  link::FaultOptions f = a.faults;
  f.to_board = a.faults_dir != "host";
  f.to_host = a.faults_dir != "board";
  return f;
}

// With --once the board ends after the job's end and this much silence from
// the tool. The pty's own slave descriptor hides the tool's hang-up, so
// silence is the sign; it must outlast a tool waiting out its answer timeout
// after a lost frame (the tests give --timeout-ms 3000).
constexpr double kOnceIdleS = 5;

// Serves `board` to one tool after another on a pty or TCP port (printed on
// stdout) until SIGINT/SIGTERM, or with --once until a job's end.
template <class Board>
link::ServeStats serve_tools(const BoardArgs& a, Board& board) {
  auto listener = a.tcp_port >= 0 ? link::listen_tcp(a.tcp_port) : link::listen_pty();
  std::printf("%s\n", listener->port_spec().c_str());
  std::fflush(stdout);
  catch_signals({SIGINT, SIGTERM});
  link::ServeStats stats;
  while (!g_interrupted.load()) {
    auto t = listener->accept(100);
    if (!t) continue;
    link::serve(*t, board, g_interrupted, faults_of(a), stats, a.once ? kOnceIdleS : 0);
    if (a.once && board.end_reached()) break;
  }
  return stats;
}

std::string fault_summary(const link::ServeStats& stats) {
  return strf("faults: %llu bytes corrupted, %llu dropped, %llu frames duplicated, %llu board resets",
              static_cast<unsigned long long>(stats.corrupted), static_cast<unsigned long long>(stats.dropped),
              static_cast<unsigned long long>(stats.duplicated), static_cast<unsigned long long>(stats.resets));
}

int loopback_board_command(const BoardArgs& a) {
  link::LoopbackBoard board(a.board);
  std::ofstream played;
  if (!a.played.empty()) {
    played.open(a.played, std::ios::binary | std::ios::trunc);
    if (!played) throw std::runtime_error("cannot write " + a.played);
  }
  uint64_t n_played = 0;
  uint32_t crc = 0;
  board.on_played = [&](uint32_t, const link::Bytes& rec) {
    ++n_played;
    crc = link::crc32_update(crc, rec.data(), rec.size());
    if (played) played.write(reinterpret_cast<const char*>(rec.data()), static_cast<std::streamsize>(rec.size()));
  };
  const link::ServeStats stats = serve_tools(a, board);
  played.flush();
  const link::Status s = board.status();
  std::fprintf(stderr,
               "board: %llu segments played (CRC-32 of their bytes %08x), %u ticks, next_seq %u, end %s, underruns "
               "%u, bad frames %u, out of order %u; %s\n",
               static_cast<unsigned long long>(n_played), crc, s.ticks_played, s.next_seq,
               board.end_reached() ? "reached" : "not reached", s.underruns, s.bad_frames, s.out_of_order,
               fault_summary(stats).c_str());
  return 0;
}

// The expected stream as the board was given it: one with a longer tick than
// the engine tick the tool configured was re-ticked by the tool
// (link::RecordSource), the same way here.
stream::ReadResult as_played(stream::ReadResult expect, const board::SimulatedBoard& b) {
  if (b.tick_clocks() == 0 || b.time_scaling()) return expect;
  const double engine_tick = double(b.tick_clocks()) / board::BoardBuild::kClkHz;
  const double ratio = expect.header.period / engine_tick;
  const long n = std::lround(ratio);
  if (n <= 1 || std::fabs(ratio - double(n)) > 1e-3 * double(n)) return expect;
  std::fprintf(stderr, "board: the expected stream's %g ms tick is played at %ld engine ticks of %g ms; its "
               "prediction re-ticked as the tool re-ticks the stream\n",
               expect.header.period * 1e3, n, engine_tick * 1e3);
  return stream::retick(expect, static_cast<uint32_t>(n));
}

// A time-scaled job: the pins against the board's own output samples, and
// those on the path of the stream's exact prediction (re-timed: at most
// s_max engine ticks per engine tick apart, from the CONFIG the tool sent).
int check_time_scaled(const stream::ReadResult& expect, const board::SimulatedBoard& board) {
  const int axes = board::BoardBuild::kAxes;
  std::vector<int64_t> engine;
  fd::FdTicker t(expect.header.width, expect.header.guard_bits);
  for (const auto& rec : expect.records) {
    t.load(rec.regs);
    for (uint32_t k = 0; k < rec.ticks; ++k)
      for (int a = 0; a < axes; ++a) engine.push_back(a < expect.header.axes ? t.sample_and_step(a) : 0);
  }
  const board::StepCheck c = board::check_steps_scaled(board.step_shifts(), board);
  std::fprintf(stderr, "%s", board::describe(c).c_str());
  // S_max 2^(shift - 32) = s_max 2^p: the most engine ticks a servo tick advances
  const link::Config& cfg = board.config();
  const double advance = std::ldexp(double(cfg.scale_s_max), int(cfg.scale_shift) - 32);
  // 2 LSB: the engine samples' own rounding and the interpolation's floor
  const board::PathCheck p = board::check_on_path(engine, board.samples(), axes, 2.0, advance);
  std::fprintf(stderr, "%s", board::describe(p).c_str());
  return c.ok() && p.ok() ? 0 : 1;
}

// "AT:X" of --hold, --feed, --starve: two numbers, AT >= 0 and X within [lo, hi].
std::pair<double, double> event_arg(const std::string& opt, const std::string& v, double lo, double hi) {
  const size_t c = v.find(':');
  char* end = nullptr;
  const double at = c == std::string::npos ? NAN : std::strtod(v.c_str(), &end);
  const bool at_ok = c != std::string::npos && end == v.c_str() + c;
  const double x = at_ok ? std::strtod(v.c_str() + c + 1, &end) : NAN;
  if (!at_ok || *end != '\0' || c + 1 == v.size() || !(at >= 0 && std::isfinite(at)) || !(x >= lo && x <= hi))
    throw std::runtime_error(opt + " " + v + ": expected AT:" + (opt == "--feed" ? "PERCENT" : "FOR") +
                             " (seconds of playback, AT >= 0; " + (opt == "--feed" ? "PERCENT 0..200" : "FOR > 0") + ")");
  return {at, x};
}

int simulated_board_command(const BoardArgs& a) {
  stream::ReadResult expect;
  if (!a.expect.empty()) {
    expect = stream::read_file(a.expect);
    if (!expect.complete) throw std::runtime_error(expect.error);
  }
  if (!a.feeds.empty() && a.expect.empty())
    throw std::runtime_error("--feed needs --expect: the stream's engine tick gives the override's S");
  board::SimulatedBoard board;
  for (const auto& v : a.holds) {
    const auto [at, len] = event_arg("--hold", v, 1e-9, 1e9);
    board.schedule_hold(at, len);
  }
  for (const auto& v : a.starves) {
    const auto [at, len] = event_arg("--starve", v, 1e-9, 1e9);
    board.schedule_starve(at, len);
  }
  for (const auto& v : a.feeds) {
    const auto [at, pct] = event_arg("--feed", v, 0, 200);
    board.schedule_feed(at, pct, expect.header.period);
  }
  board.keep_samples(!a.expect.empty());  // a time-scaled job is checked on them
  std::fprintf(stderr, "board: rtl/traj_board.sv Verilated, %.0f MHz, %u baud\n", board::BoardBuild::kClkHz / 1e6,
               board::BoardBuild::kBaud);
  const link::ServeStats stats = serve_tools(a, board);
  board.drain();
  const link::Status s = board.status();
  std::fprintf(stderr,
               "board: %u segments played, %u ticks, next_seq %u, end %s, underruns %u, bad frames %u, out of order "
               "%u; %.3f s simulated; %s\n",
               s.segments_played, s.ticks_played, s.next_seq, board.end_reached() ? "reached" : "not reached",
               s.underruns, s.bad_frames, s.out_of_order, double(board.cycles()) / board::BoardBuild::kClkHz,
               fault_summary(stats).c_str());
  for (const std::string& e : board.event_log()) std::fprintf(stderr, "board: %s\n", e.c_str());
  if (board.time_scaling())
    std::fprintf(stderr, "board: time scaling: S %u at the end, %u starved holds\n", s.scale_s, s.starved_holds);
  if (a.expect.empty()) return 0;
  if (board.time_scaling()) return check_time_scaled(expect, board);
  const board::StepCheck c = board::check_steps(as_played(std::move(expect), board), board.step_shifts(), board);
  std::fprintf(stderr, "%s", board::describe(c).c_str());
  return c.ok() ? 0 : 1;
}

}  // namespace

int board_command(const BoardArgs& a) { return a.loopback ? loopback_board_command(a) : simulated_board_command(a); }

}  // namespace traj::app
