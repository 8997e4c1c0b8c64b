// The host link under test: the Verilated rtl/traj_link.sv and its hls model
// (hls/traj_link.hpp) clocked together with the same inputs; every output port
// is compared on every cycle from the first reset edge on (m_axis_tdata where
// tvalid is high). Around them, independent of both: a host that encodes
// frames with zlib's crc32 and drives the rx pin bit by bit, a UART decoder of
// the tx pin that parses and checks the answers, and a stand-in engine that
// takes segment words, plays K ticks per segment and raises underrun 2 cycles
// after a tick that found no segment.
//
// Built with LINK_* parameters (CMakeLists.txt): VTOP names the Verilated class.
#pragma once
#include <verilated.h>
#include <zlib.h>

#include <cstdint>
#include <deque>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "traj_common.hpp"
#include "traj_link.hpp"
#include VTOP_H

namespace linktest {

constexpr int kAxes = LINK_AXES, kDegree = LINK_DEGREE, kWidth = LINK_WIDTH, kChunk = LINK_CHUNK;
constexpr int kGuard = LINK_GUARD, kOutWidth = kWidth - kGuard;
constexpr int kScaleWidth = LINK_SCALE;
using Model = traj::Link<LINK_CLK, LINK_BAUD, kAxes, kDegree, kWidth, kChunk, kGuard, LINK_FIFO, LINK_MINTICK,
                         kScaleWidth, LINK_COUNTRAM>;
constexpr int kDiv = Model::kDiv;
constexpr int kSegWords = Model::kSegWords;
constexpr int kCap = Model::kCap;
constexpr int kRegBytes = kAxes * (kDegree + 1) * kWidth / 8;
constexpr int kRecBytes = 16 + kRegBytes;

inline uint32_t crc32(const std::vector<uint8_t>& b) {
  return static_cast<uint32_t>(::crc32(0L, b.data(), static_cast<uInt>(b.size())));
}
inline void put_le(std::vector<uint8_t>& b, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
inline uint64_t get_le(const std::vector<uint8_t>& b, size_t at, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v |= uint64_t{b.at(at + i)} << (8 * i);
  return v;
}

// Unstuffed frame body: header, payload, CRC-32 (LINK.md).
inline std::vector<uint8_t> body(uint8_t type, uint32_t seq, const std::vector<uint8_t>& payload) {
  std::vector<uint8_t> b;
  b.push_back(type);
  b.push_back(0);
  put_le(b, payload.size(), 2);
  put_le(b, seq, 4);
  b.insert(b.end(), payload.begin(), payload.end());
  put_le(b, crc32(b), 4);
  return b;
}
// 0x7E, the stuffed body, 0x7E.
inline std::vector<uint8_t> stuff(const std::vector<uint8_t>& b) {
  std::vector<uint8_t> s{0x7E};
  for (uint8_t x : b) {
    if (x == 0x7E || x == 0x7D) {
      s.push_back(0x7D);
      s.push_back(x ^ 0x20);
    } else {
      s.push_back(x);
    }
  }
  s.push_back(0x7E);
  return s;
}

// One FD segment record (stream version 4) and the engine words it must become.
struct Record {
  uint32_t seq = 0, K = 1;
  std::vector<uint8_t> regs;
  std::vector<uint8_t> bytes() const {
    std::vector<uint8_t> r{1, 0, 0, 0};
    put_le(r, K, 4);
    put_le(r, seq, 4);
    r.insert(r.end(), regs.begin(), regs.end());
    put_le(r, crc32(r), 4);
    return r;
  }
  std::vector<uint64_t> words() const {
    std::vector<uint64_t> w;
    if constexpr (kChunk < 32) {
      for (int s = 0; s < 32; s += kChunk) w.push_back((K >> s) & ((1u << kChunk) - 1));
    } else {
      w.push_back(K);
    }
    for (size_t i = 0; i < regs.size(); i += kChunk / 8) w.push_back(get_le(regs, i, kChunk / 8));
    return w;
  }
};

inline Record random_record(std::mt19937_64& rng, uint32_t seq, uint32_t kmax = 3) {
  Record r;
  r.seq = seq;
  r.K = 1 + static_cast<uint32_t>(rng() % kmax);
  r.regs.resize(kRegBytes);
  for (auto& x : r.regs) {
    x = static_cast<uint8_t>(rng());
    if (rng() % 16 == 0) x = (rng() & 1) ? 0x7E : 0x7D;  // exercise stuffing
  }
  return r;
}

struct Answer {
  uint8_t type = 0;
  uint32_t seq = 0;
  std::vector<uint8_t> payload;
  uint16_t credits() const { return static_cast<uint16_t>(type == 0x81 ? get_le(payload, 0, 2) : get_le(payload, 2, 2)); }
  uint8_t reason() const { return type == 0x82 ? payload.at(0) : 0; }
};

class Bench {
 public:
  explicit Bench(uint64_t seed) : rng_(seed), ctx_(std::make_unique<VerilatedContext>()) {
    ctx_->randReset(2);
    ctx_->randSeed(static_cast<int>(seed % 1000) + 1);
    rtl_ = std::make_unique<VTOP>(ctx_.get());
    model_ = std::make_unique<Model>();
    rtl_->clk_i = 0;
  }
  ~Bench() { rtl_->final(); }

  // ---- host side -------------------------------------------------------
  void send_raw(const std::vector<uint8_t>& bytes, int max_gap_bits = 2) {
    for (uint8_t x : bytes) {
      const int gap = static_cast<int>(rng_() % (max_gap_bits + 1));
      for (int g = 0; g < gap; ++g) push_bit(true);
      push_bit(false);
      for (int i = 0; i < 8; ++i) push_bit((x >> i) & 1);
      push_bit(true);
    }
  }
  void send(uint8_t type, uint32_t seq, const std::vector<uint8_t>& payload = {}) {
    send_raw(stuff(body(type, seq, payload)));
  }
  void send_record(const Record& r) { send(0x10, r.seq, r.bytes()); }
  // Runs until every queued bit is out and one answer frame has arrived.
  Answer await_answer(uint64_t max_cycles = 2000000) {
    const uint64_t end = cycles_ + max_cycles;
    while (answers_.empty() && cycles_ < end && ok()) step();
    if (answers_.empty()) {
      fail("no answer within " + std::to_string(max_cycles) + " cycles");
      return {};
    }
    Answer a = answers_.front();
    answers_.pop_front();
    return a;
  }
  Answer transact(uint8_t type, uint32_t seq, const std::vector<uint8_t>& payload = {}) {
    send(type, seq, payload);
    return await_answer();
  }
  void run(uint64_t n) {
    for (uint64_t i = 0; i < n && ok(); ++i) step();
  }
  void drain_tx() {
    while (!bits_.empty() && ok()) step();
  }

  // ---- engine side -----------------------------------------------------
  std::vector<std::vector<uint64_t>> segments;  // whole segments the engine took, in order
  int tick_period = 300;                        // clocks between ticks while run_o
  int tready_percent = 70;
  uint32_t seg_starts = 0, underruns = 0, ticks = 0;
  std::vector<uint32_t> stored_ks;              // the K of each record stored (stored_o)

  // ---- comparison ------------------------------------------------------
  bool ok() const { return why_.empty(); }
  const std::string& why() const { return why_; }
  std::deque<Answer>& answers() { return answers_; }
  const Model& model() const { return *model_; }
  VTOP& rtl() { return *rtl_; }
  uint64_t cycles() const { return cycles_; }

  void reset(int n = 4) {
    rst_n_ = false;
    run(n);
    rst_n_ = true;
  }

  void step() {
    typename Model::In in;
    in.rst_n = rst_n_;
    in.rx = bits_.empty() ? true : bits_.front();
    if (!bits_.empty()) {
      if (++bit_clk_ == kDiv) {
        bits_.pop_front();
        bit_clk_ = 0;
      }
    }
    engine_inputs(in);
    apply(in);
    rtl_->clk_i = 0;
    rtl_->eval();
    compare(in);
    const auto mo = model_->outputs(in);
    engine_clock(in, mo);
    decode_tx(mo.tx);
    if (!in.rst_n) armed_ = true;
    model_->clock(in);
    rtl_->clk_i = 1;
    rtl_->eval();
    ++cycles_;
  }

 private:
  void push_bit(bool b) { bits_.push_back(b); }

  void apply(const typename Model::In& in) {
    rtl_->rst_ni = in.rst_n;
    rtl_->rx_i = in.rx;
    rtl_->m_axis_tready = in.tready;
    rtl_->tick_i = in.tick;
    rtl_->seg_start_i = in.seg_start;
    rtl_->underrun_i = in.underrun;
    rtl_->tick_err_i = in.tick_err;
    rtl_->eng_tick_i = in.eng_tick;
    rtl_->scale_s_i = in.scale_s;
    rtl_->starved_count_i = in.starved_count;
    rtl_->ahead_i = in.ahead;
    rtl_->starved_i = in.starved;
    rtl_->held_i = in.held;
    set_sample(in);
  }
  void set_sample(const typename Model::In& in) {
    // sample_i: Axes*OutWidth bits, word array or scalar depending on the width
    const int total = kAxes * kOutWidth;
    uint32_t words[16] = {};
    for (int a = 0; a < kAxes; ++a)
      for (int b = 0; b < kOutWidth; ++b)
        if ((in.sample[a] >> b) & 1) {
          const int bit = a * kOutWidth + b;
          words[bit / 32] |= 1u << (bit % 32);
        }
    (void)total;
    put(rtl_->sample_i, words);
  }
  template <std::size_t N>
  static void put(VlWide<N>& port, const uint32_t* w) {
    for (std::size_t i = 0; i < N; ++i) port[i] = w[i];
  }
  static void put(QData& port, const uint32_t* w) { port = w[0] | (static_cast<uint64_t>(w[1]) << 32); }
  static void put(IData& port, const uint32_t* w) { port = w[0]; }

  void compare(const typename Model::In& in) {
    if (!armed_ || !ok()) return;
    const auto m = model_->outputs(in);
    std::ostringstream s;
    auto port = [&](const char* name, uint64_t r, uint64_t h) {
      if (r != h) s << "cycle " << cycles_ << ": " << name << " rtl=" << std::hex << r << " hls=" << h << std::dec << "\n";
    };
    port("tx_o", rtl_->tx_o, m.tx);
    port("m_axis_tvalid", rtl_->m_axis_tvalid, m.tvalid);
    if (m.tvalid) port("m_axis_tdata", rtl_->m_axis_tdata, m.tdata);
    port("run_o", rtl_->run_o, m.run);
    port("tick_period_o", rtl_->tick_period_o, m.tick_period);
    uint64_t shifts = 0;
    for (int a = 0; a < kAxes; ++a) shifts |= uint64_t{m.step_shift[a]} << (6 * a);
    port("step_shift_o", rtl_->step_shift_o, shifts);
    port("pulse_o", rtl_->pulse_o, m.pulse);
    port("setup_o", rtl_->setup_o, m.setup);
    port("enable_o", rtl_->enable_o, m.enable);
    port("scale_m_o", rtl_->scale_m_o, m.scale_m);
    port("scale_s_max_o", rtl_->scale_s_max_o, m.scale_s_max);
    port("scale_override_o", rtl_->scale_override_o, m.scale_override);
    port("scale_shift_o", rtl_->scale_shift_o, m.scale_shift);
    port("scale_auto_o", rtl_->scale_auto_o, m.scale_auto);
    port("hold_o", rtl_->hold_o, m.hold);
    port("stop_o", rtl_->stop_o, m.stop);
    port("end_o", rtl_->end_o, m.end);
    port("resume_o", rtl_->resume_o, m.resume);
    port("stored_o", rtl_->stored_o, m.stored);
    port("cleared_o", rtl_->cleared_o, m.cleared);
    if (m.stored) port("stored_k_o", rtl_->stored_k_o, m.stored_k);
    if (!s.str().empty()) why_ = s.str();
  }
  void fail(const std::string& w) {
    if (why_.empty()) why_ = w;
  }

  // stand-in engine: inputs of this cycle from its state
  void engine_inputs(typename Model::In& in) {
    in.tready = !active_ && static_cast<int>(rng_() % 100) < tready_percent;
    in.tick = false;
    in.seg_start = false;
    in.underrun = under_pipe_[1];
    if (run_prev_) {
      if (++tick_cnt_ >= tick_period) {
        tick_cnt_ = 0;
        in.tick = true;
      }
    } else {
      tick_cnt_ = 0;
    }
    for (int a = 0; a < kAxes; ++a) in.sample[a] = (pos_ + a * 1000) & traj::mask(kOutWidth);
    in.eng_tick = in.tick;
    // the time-scale unit's state as STATUS reports it: values that move
    in.scale_s = static_cast<uint32_t>(pos_ * 7 + 3);
    in.starved_count = static_cast<uint16_t>(underruns + 1);
    in.ahead = static_cast<uint32_t>(left_ + 5);
    in.starved = (pos_ & 1) != 0;
    in.held = (pos_ & 2) != 0;
    in_tick_ = in.tick;
    if (in.tick && active_ && left_ == static_cast<int64_t>(k_)) in.seg_start = true;
    seg_start_now_ = in.seg_start;
    tready_now_ = in.tready;
  }
  void engine_clock(const typename Model::In& in, const typename Model::Out& mo) {
    under_pipe_[1] = under_pipe_[0];
    under_pipe_[0] = false;
    if (in.underrun) ++underruns;
    if (mo.stored) stored_ks.push_back(mo.stored_k);
    if (seg_start_now_) ++seg_starts;
    if (mo.tvalid && tready_now_) {
      loading_.push_back(mo.tdata);
      if (loading_.size() == 1) k_ = static_cast<uint32_t>(mo.tdata);
      if (kChunk < 32 && loading_.size() == 2) k_ |= static_cast<uint32_t>(mo.tdata << 16);
      if (static_cast<int>(loading_.size()) == kSegWords) {
        segments.push_back(loading_);
        loading_.clear();
        active_ = true;
        left_ = k_;
      }
    }
    if (in_tick_) {
      ++ticks;
      if (active_) {
        ++pos_;
        if (--left_ == 0) active_ = false;
      } else if (loading_.empty()) {
        under_pipe_[0] = true;  // underrun_i follows its tick by 2 cycles
      }
    }
    run_prev_ = mo.run;
  }

  // independent UART decoder of tx_o and frame parser
  void decode_tx(bool tx) {
    if (!armed_) return;
    if (rx_cnt_ < 0) {
      if (tx_prev_ && !tx) rx_cnt_ = 0;
    } else {
      ++rx_cnt_;
      const int bit = (rx_cnt_ - kDiv / 2) / kDiv;
      if ((rx_cnt_ - kDiv / 2) % kDiv == 0 && rx_cnt_ >= kDiv / 2) {
        if (bit == 0 && tx) fail("tx: start bit not low at its middle");
        if (bit >= 1 && bit <= 8) rx_byte_ |= (tx ? 1 : 0) << (bit - 1);
        if (bit == 9) {
          if (!tx) fail("tx: framing error");
          tx_byte(static_cast<uint8_t>(rx_byte_));
          rx_byte_ = 0;
          rx_cnt_ = -1;
        }
      }
    }
    tx_prev_ = tx;
  }
  void tx_byte(uint8_t b) {
    if (b == 0x7E) {
      if (!frame_.empty()) parse(frame_);
      frame_.clear();
      esc_ = false;
      return;
    }
    if (b == 0x7D) {
      esc_ = true;
      return;
    }
    frame_.push_back(esc_ ? b ^ 0x20 : b);
    esc_ = false;
  }
  void parse(const std::vector<uint8_t>& f) {
    if (f.size() < 12) return fail("answer shorter than 12 bytes");
    const std::vector<uint8_t> head(f.begin(), f.end() - 4);
    if (crc32(head) != get_le(f, f.size() - 4, 4)) return fail("answer CRC wrong");
    const size_t len = get_le(f, 2, 2);
    if (len + 12 != f.size()) return fail("answer length wrong");
    if (f[1] != 0) return fail("answer flags nonzero");
    Answer a;
    a.type = f[0];
    a.seq = static_cast<uint32_t>(get_le(f, 4, 4));
    a.payload.assign(f.begin() + 8, f.end() - 4);
    answers_.push_back(a);
  }

  std::mt19937_64 rng_;
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<VTOP> rtl_;
  std::unique_ptr<Model> model_;
  std::deque<bool> bits_;
  int bit_clk_ = 0;
  bool rst_n_ = true, armed_ = false;
  uint64_t cycles_ = 0;
  std::string why_;
  std::deque<Answer> answers_;
  // tx decoder
  int rx_cnt_ = -1, rx_byte_ = 0;
  bool tx_prev_ = true, esc_ = false;
  std::vector<uint8_t> frame_;
  // engine
  std::vector<uint64_t> loading_;
  bool active_ = false, run_prev_ = false, in_tick_ = false, seg_start_now_ = false, tready_now_ = false;
  bool under_pipe_[2] = {false, false};
  uint32_t k_ = 0;
  int64_t left_ = 0;
  int tick_cnt_ = 0;
  uint64_t pos_ = 0;
};

}  // namespace linktest
