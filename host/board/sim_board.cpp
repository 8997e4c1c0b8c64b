// SPDX-License-Identifier: Apache-2.0
#include "board/sim_board.hpp"

#include <verilated.h>

#include <cmath>

#include "Vtraj_board.h"
#include "Vtraj_board___024root.h"
#include "util/format.hpp"

namespace traj::board {

const uint32_t BoardBuild::kClkHz = TRAJ_BOARD_CLK_HZ;
const uint32_t BoardBuild::kBaud = TRAJ_BOARD_BAUD;
const int BoardBuild::kAxes = 3, BoardBuild::kDegree = 5, BoardBuild::kWidth = 96, BoardBuild::kGuardBits = 48;

namespace {
constexpr uint32_t kClocksPerBit = TRAJ_BOARD_CLK_HZ / TRAJ_BOARD_BAUD;
static_assert(TRAJ_BOARD_CLK_HZ % TRAJ_BOARD_BAUD == 0, "the simulated UART needs whole clocks per bit");
// At most this many cycles per advance(), so that the server reads the port often.
constexpr uint64_t kCyclesPerAdvance = TRAJ_BOARD_CLK_HZ / 1000;
constexpr int kResetCycles = 8;
using util::strf;
}  // namespace

struct SimulatedBoard::Rtl {
  VerilatedContext ctx;
  std::unique_ptr<Vtraj_board> top;
  Rtl() {
    ctx.randReset(2);  // unreset state is random: a dependence on it shows
    top = std::make_unique<Vtraj_board>(&ctx);
  }
  ~Rtl() { top->final(); }
  bool tick() const { return top->rootp->traj_board__DOT__u_tick__DOT__tick_q; }  // traj_tick_gen: tick_o = tick_q
  bool out_valid() const { return top->rootp->traj_board__DOT__out_valid; }
  bool unit_busy() const { return top->rootp->traj_board__DOT__g_scale__DOT__ts_busy; }
  bool engine_tick() const { return top->rootp->traj_board__DOT__g_scale__DOT__ts_eng_tick; }
  bool engine_valid() const { return top->rootp->traj_board__DOT__sample_valid; }
  bool engine_underrun() const { return top->rootp->traj_board__DOT__underrun; }
  // axis a of the output sample, sign-extended (OutWidth = Width - GuardBits bits)
  int64_t out_sample(int a) const {
    const int w = BoardBuild::kWidth - BoardBuild::kGuardBits;
    const auto& words = top->rootp->traj_board__DOT__out_sample;
    uint64_t v = 0;
    for (int b = 0; b < w; ++b) {
      const int bit = a * w + b;
      if ((words[bit / 32] >> (bit % 32)) & 1) v |= uint64_t{1} << b;
    }
    if (w < 64 && ((v >> (w - 1)) & 1)) v |= ~uint64_t{0} << w;
    return static_cast<int64_t>(v);
  }
};

SimulatedBoard::SimulatedBoard()
    : rtl_(std::make_unique<Rtl>()), rx_(kClocksPerBit), tx_(kClocksPerBit),
      decoders_(BoardBuild::kAxes, StepDecoder(StepTiming{})) {
  reset();
}

SimulatedBoard::~SimulatedBoard() = default;

void SimulatedBoard::set_step_timing(StepTiming t) {
  for (auto& d : decoders_) d = StepDecoder(t);
}

void SimulatedBoard::reset() {
  link::Bytes none;
  rtl_->top->rst_ni = 0;
  rtl_->top->rx_i = 1;
  rtl_->top->tick_ext_i = 0;
  rtl_->top->hold_i = 0;
  for (int i = 0; i < kResetCycles; ++i) clock(none);
  rtl_->top->rst_ni = 1;
  // The line idles a character time after reset before the host's first
  // start bit, as a real link does (the receiver takes no edge in its first
  // cycle out of reset).
  quiet_ = 10 * kClocksPerBit;
  status_ = {};
}

void SimulatedBoard::clock(link::Bytes& out) {
  auto& t = *rtl_->top;
  if (!holds_.empty() || !feeds_.empty() || !starves_.empty()) run_events();
  t.rx_i = quiet_ ? (--quiet_, true) : rx_.next();
  t.hold_i = hold_pin_;
  t.clk_i = 0;
  t.eval();
  if (rtl_->tick() && t.rst_ni) ticks_.push_back(cycle_);
  // the tick each engine sample answers (a tick that finds the FIFO empty
  // at a segment end, an underrun, answers none)
  if (rtl_->engine_valid() && !rtl_->engine_underrun() && t.rst_ni && !ticks_.empty() && !time_scaling())
    sample_ticks_.push_back(ticks_.back());
  if (keep_samples_ && rtl_->out_valid() && t.rst_ni) {
    for (int a = 0; a < BoardBuild::kAxes; ++a) samples_.push_back(rtl_->out_sample(a));
    sample_cycles_.push_back(cycle_);
  }
  time_unit();
  for (int a = 0; a < BoardBuild::kAxes; ++a) decoders_[a].sample(cycle_, (t.step_o >> a) & 1, (t.dir_o >> a) & 1);
  if (auto b = tx_.sample(t.tx_o)) out.push_back(*b);
  t.clk_i = 1;
  t.eval();
  ++cycle_;
}

// The time-scale unit's busy runs and the engine's answers to its ticks,
// clock by clock (the unit's strobe is registered: the engine takes it the
// clock it is high).
void SimulatedBoard::time_unit() {
  if (rtl_->unit_busy()) {
    unit_busy_max_ = std::max(unit_busy_max_, ++busy_run_);
  } else {
    busy_run_ = 0;
  }
  if (engine_tick_at_ && rtl_->engine_valid()) {
    engine_answer_max_ = std::max(engine_answer_max_, cycle_ - *engine_tick_at_);
    engine_tick_at_.reset();
  }
  if (rtl_->engine_tick()) engine_tick_at_ = cycle_;
}

void SimulatedBoard::receive(const uint8_t* p, size_t n, link::Bytes&) {
  // whole frames (up to and with their closing flag) to the RX line, so that
  // a scheduled FEED goes between two
  for (size_t i = 0; i < n; ++i) {
    frame_in_.push_back(p[i]);
    if (p[i] == link::kFlag) {
      pass_frame(frame_in_);
      frame_in_.clear();
    }
  }
  watch_requests(p, n);
}

void SimulatedBoard::pass_frame(const link::Bytes& raw) {
  if (starving() || !held_back_.empty()) {
    held_back_.insert(held_back_.end(), raw.begin(), raw.end());
    return;
  }
  for (uint8_t c : raw) rx_.push(c);
}

double SimulatedBoard::play_time() const {
  return play_start_ < 0 ? -1.0 : double(int64_t(cycle_) - play_start_) / BoardBuild::kClkHz;
}

bool SimulatedBoard::starving() const {
  const double t = play_time();
  if (t < 0) return false;
  for (const Window& w : starves_)
    if (t >= w.at && t < w.at + w.for_s) return true;
  return false;
}

// The scheduled events at this cycle (called every cycle: cheap while none are due).
void SimulatedBoard::run_events() {
  if (play_start_ < 0) {
    if (!rtl_->top->run_o) return;
    play_start_ = static_cast<int64_t>(cycle_);
  }
  const double t = play_time();
  bool hold = false;
  for (const Window& w : holds_) hold = hold || (t >= w.at && t < w.at + w.for_s);
  if (hold != was_holding_) {
    event_log_.push_back(strf("%.3f s: hold pin %s", t, hold ? "pressed" : "released"));
    was_holding_ = hold;
  }
  hold_pin_ = hold;
  const bool starve = starving();
  if (starve != was_starving_) {
    event_log_.push_back(strf("%.3f s: link %s", t, starve ? "paused (the host's frames held back)" : "delivering again"));
    was_starving_ = starve;
    if (!starve) {
      for (uint8_t c : held_back_) rx_.push(c);
      held_back_.clear();
    }
  }
  while (feeds_done_ < feeds_.size() && t >= feeds_[feeds_done_].at) {
    const FeedAt& f = feeds_[feeds_done_++];
    if (config_.scale_m == 0) {
      event_log_.push_back(strf("%.3f s: feed %g %% not sent: the job has no time scaling", t, f.percent));
      continue;
    }
    const double servo = double(config_.tick_clocks) / BoardBuild::kClkHz;
    const int p = static_cast<int>(std::lround(std::log2(servo / f.engine_tick)));
    const int sb = 32 + p - config_.scale_shift;
    link::Feed feed;
    feed.override_s = static_cast<uint32_t>(std::llround(std::ldexp(f.percent / 100, sb)));
    const link::Bytes b = link::encode_frame(link::Type::kFeed, 0, link::encode_feed(feed));
    for (uint8_t c : b) rx_.push(c);
    event_log_.push_back(strf("%.3f s: FEED %g %% (S %u)", t, f.percent, feed.override_s));
  }
}

// The host's CONFIG, decoded apart from the RTL: the step shifts for the
// check and the pulse timing the decoders hold the pins to.
void SimulatedBoard::watch_requests(const uint8_t* p, size_t n) {
  std::vector<link::FrameDecoder::Event> ev;
  requests_.feed(p, n, ev);
  for (const auto& e : ev) {
    if (!e.good || e.frame.type != link::Type::kConfig) continue;
    const link::Config c = link::decode_config(e.frame.payload);
    if (c.pulse_clocks != config_.pulse_clocks || c.dir_setup_clocks != config_.dir_setup_clocks)
      set_step_timing({c.pulse_clocks, c.dir_setup_clocks});
    config_ = c;
  }
}

std::vector<int> SimulatedBoard::step_shifts() const {
  return std::vector<int>(config_.step_shift, config_.step_shift + BoardBuild::kAxes);
}

void SimulatedBoard::drain() {
  link::Bytes out;
  run(2 * uint64_t{config_.tick_clocks} + 64 * kClocksPerBit, out);
}

bool SimulatedBoard::playing() const { return rtl_->top->run_o; }

void SimulatedBoard::run(uint64_t cycles, link::Bytes& out) {
  const size_t from = out.size();
  for (uint64_t i = 0; i < cycles; ++i) clock(out);
  watch_answers(link::Bytes(out.begin() + static_cast<long>(from), out.end()));
}

void SimulatedBoard::advance(double, link::Bytes& out) {
  // Idle (nothing to receive, nothing playing): a few bit times let an
  // answer in progress finish; otherwise time would pass for nothing.
  const bool busy = !rx_.idle() || playing();
  run(busy ? kCyclesPerAdvance : 40 * kClocksPerBit, out);
}

// The board's answers, decoded apart from the bytes passed on: next_seq tells
// how many records the board stored (for faults that act after N of them).
void SimulatedBoard::watch_answers(const link::Bytes& bytes) {
  std::vector<link::FrameDecoder::Event> ev;
  answers_.feed(bytes.data(), bytes.size(), ev);
  for (const auto& e : ev) {
    if (!e.good) continue;
    const auto& f = e.frame;
    if (f.type != link::Type::kAck && f.type != link::Type::kNak && f.type != link::Type::kStatus) continue;
    const uint32_t gained = f.seq - next_seq_;
    if (gained < (1u << 31)) stored_total_ += gained;
    next_seq_ = f.seq;
    if (f.type == link::Type::kStatus) status_ = link::decode_status(f);
  }
}

}  // namespace traj::board
