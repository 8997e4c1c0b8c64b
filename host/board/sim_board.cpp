// SPDX-License-Identifier: Apache-2.0
#include "board/sim_board.hpp"

#include <verilated.h>

#include "Vtraj_board.h"
#include "Vtraj_board___024root.h"

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
  t.rx_i = quiet_ ? (--quiet_, true) : rx_.next();
  t.clk_i = 0;
  t.eval();
  if (rtl_->tick() && t.rst_ni) ticks_.push_back(cycle_);
  for (int a = 0; a < BoardBuild::kAxes; ++a) decoders_[a].sample(cycle_, (t.step_o >> a) & 1, (t.dir_o >> a) & 1);
  if (auto b = tx_.sample(t.tx_o)) out.push_back(*b);
  t.clk_i = 1;
  t.eval();
  ++cycle_;
}

void SimulatedBoard::receive(const uint8_t* p, size_t n, link::Bytes&) {
  for (size_t i = 0; i < n; ++i) rx_.push(p[i]);
  watch_requests(p, n);
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
