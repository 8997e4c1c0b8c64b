#include "link_cmds.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#include <cstdarg>

#include "board/step_check.hpp"

namespace traj::app {
namespace {

std::string strf(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string strf(const char* f, ...) {
  char b[512];
  va_list ap;
  va_start(ap, f);
  std::vsnprintf(b, sizeof b, f, ap);
  va_end(ap);
  return b;
}

std::atomic<bool> g_interrupted{false};
void on_signal(int) { g_interrupted.store(true); }

void catch_signals(std::initializer_list<int> sigs) {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (int s : sigs) sigaction(s, &sa, nullptr);
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
        "[upload] %llu segments stored%s, %u played, FIFO %u, position %s %s, underruns %u, re-sends %llu",
        static_cast<unsigned long long>(p.acked),
        p.stream_done ? strf(" of %llu", static_cast<unsigned long long>(p.read)).c_str() : "",
        p.status.segments_played, p.status.fifo_level, pos.empty() ? "?" : pos.c_str(), units_.c_str(),
        p.status.underruns, static_cast<unsigned long long>(p.resends));
    std::fprintf(stderr, tty_ ? "\r%s   " : "%s\n", line.c_str());
    shown_ = true;
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
      ->capture_default_str();
  c->add_flag("--resume", a.opt.resume,
              "continue the board's job from its next sequence number (after the tool was stopped or killed)");
  c->add_option("--timeout-ms", a.opt.timeout_ms, "answer timeout, ms, plus the transmission time in flight")
      ->capture_default_str();
  c->add_option("--retries", a.opt.max_retries, "re-sends of one segment or unanswered requests before giving up")
      ->capture_default_str();
  c->footer("Exit status 0 once the board has played the whole job; otherwise a message names what failed. Ctrl-C "
            "sends STOP: the board stops at the end of the segment it plays.");
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
  c->footer("Prints the port for --port on standard output, a summary on standard error at exit (SIGINT, SIGTERM, "
            "or --once).");
}

}  // namespace

void add_link_commands(CLI::App& app, LinkCommands& lc) {
  add_upload(app, lc);
  add_board(app, lc);
}

int upload_command(const UploadArgs& a) {
  link::RecordSource src(a.input, a.max_engine_tick);
  auto port = link::open_port(a.port, a.opt.baud);
  catch_signals({SIGINT, SIGTERM});
  link::UploadOptions o = a.opt;
  o.interrupted = &g_interrupted;
  const auto& h = src.header();
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
  StatusLine line(std::ldexp(1.0, -h.frac_bits), h.units);
  const auto r = link::upload(*port, src, o, [&](const link::UploadProgress& p) { line.show(p, false); });
  line.show(r.progress, true);
  std::fprintf(stderr, "\n");
  const double motion = double(r.progress.status.ticks_played) * h.period;
  std::printf("upload: %llu segments%s to %s in %.2f s (%.0f segments/s), %u played, %.3f s of motion; re-sends "
              "%llu, NAKs %llu, timeouts %llu; board: bad frames %u, out of order %u, underruns %u\n",
              static_cast<unsigned long long>(r.records - r.first_seq),
              r.first_seq ? strf(" (resumed at %llu)", static_cast<unsigned long long>(r.first_seq)).c_str() : "",
              port->name().c_str(), r.seconds, double(r.records - r.first_seq) / std::max(r.seconds, 1e-9),
              r.progress.status.segments_played, motion, static_cast<unsigned long long>(r.progress.resends),
              static_cast<unsigned long long>(r.progress.naks), static_cast<unsigned long long>(r.progress.timeouts),
              r.progress.status.bad_frames, r.progress.status.out_of_order, r.progress.status.underruns);
  return 0;
}

namespace {

link::FaultOptions faults_of(const BoardArgs& a) {
  link::FaultOptions f = a.faults;
  f.to_board = a.faults_dir != "host";
  f.to_host = a.faults_dir != "board";
  return f;
}

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
    link::serve(*t, board, g_interrupted, faults_of(a), stats, a.once ? 0.5 : 0);
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
  if (b.tick_clocks() == 0) return expect;
  const double engine_tick = double(b.tick_clocks()) / board::BoardBuild::kClkHz;
  const double ratio = expect.header.period / engine_tick;
  const long n = std::lround(ratio);
  if (n <= 1 || std::fabs(ratio - double(n)) > 1e-3 * double(n)) return expect;
  std::fprintf(stderr, "board: the expected stream's %g ms tick is played at %ld engine ticks of %g ms; its "
               "prediction re-ticked as the tool re-ticks the stream\n",
               expect.header.period * 1e3, n, engine_tick * 1e3);
  return stream::retick(expect, static_cast<uint32_t>(n));
}

int simulated_board_command(const BoardArgs& a) {
  stream::ReadResult expect;
  if (!a.expect.empty()) {
    expect = stream::read_file(a.expect);
    if (!expect.complete) throw std::runtime_error(expect.error);
  }
  board::SimulatedBoard board;
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
  if (a.expect.empty()) return 0;
  const board::StepCheck c = board::check_steps(as_played(std::move(expect), board), board.step_shifts(), board);
  std::fprintf(stderr, "%s", board::describe(c).c_str());
  return c.ok() ? 0 : 1;
}

}  // namespace

int board_command(const BoardArgs& a) { return a.loopback ? loopback_board_command(a) : simulated_board_command(a); }

}  // namespace traj::app
