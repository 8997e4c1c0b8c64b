// Unit co-simulation of the link's building blocks, RTL == hls on every cycle
// from the first reset edge on, each against an independent reference:
//   * traj_seg_fifo: random tentative writes, commits, rollbacks and clears;
//     the words that leave are exactly the committed segments, in order, each
//     once (a reference queue kept by the test);
//   * traj_uart_rx: bytes at rates up to 2 percent off, start-bit glitches and
//     framing errors; the bytes received are the good ones sent.
#include <gtest/gtest.h>
#include <verilated.h>

#include <deque>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "Vlink_fifo.h"
#include "Vlink_uart_rx.h"
#include "test_seed.hpp"
#include "traj_seg_fifo.hpp"
#include "traj_uart_rx.hpp"

namespace {

constexpr int kChunk = 16, kSegWords = 5, kDepth = 23;  // 4 slots
using Fifo = traj::SegFifo<kChunk, kSegWords, kDepth>;
using Rx = traj::UartRx<8000000, 1000000>;  // 8 clocks per bit

TEST(LinkUnits, SegFifoCommitRollbackClear) {
  const uint64_t seed = traj::test::test_seed(11);
  std::mt19937_64 rng(seed);
  auto ctx = std::make_unique<VerilatedContext>();
  ctx->randReset(2);
  auto rtl = std::make_unique<Vlink_fifo>(ctx.get());
  auto model = std::make_unique<Fifo>();

  std::deque<std::vector<uint64_t>> committed;  // reference: stored, not yet (fully) out
  std::vector<uint64_t> tentative, out;
  std::vector<std::vector<uint64_t>> played, expected;
  int out_done = 0, committed_n = 0;
  bool armed = false;
  int gap = 0;
  uint16_t tag = 0;
  std::string why;
  for (uint64_t cyc = 0; cyc < 200000 && why.empty(); ++cyc) {
    Fifo::In in;
    in.rst_n = cyc >= 3;
    const bool room = committed_n - out_done < Fifo::kCap;
    if (in.rst_n && gap == 0 && rng() % 3 == 0) {
      const int r = static_cast<int>(rng() % 100);
      if (r < 70 && room && static_cast<int>(tentative.size()) < kSegWords) {
        in.wr = true;
        in.wr_data = ++tag;
        tentative.push_back(tag);
      } else if (r < 85 && !tentative.empty()) {
        in.commit = true;
        if (static_cast<int>(tentative.size()) == kSegWords) {
          committed.push_back(tentative);
          expected.push_back(tentative);
          ++committed_n;
        }
        tentative.clear();
      } else if (r < 95 && !tentative.empty()) {
        in.rollback = true;
        tentative.clear();
      } else if (r < 97 && tentative.empty() && !model->outputs().busy && !model->outputs().tvalid) {
        in.clear = true;
        // every stored segment not yet started is dropped
        while (committed_n > out_done) {
          expected.pop_back();
          --committed_n;
        }
        committed.clear();
      }
      gap = 1;  // writes at most every other cycle
    } else if (gap > 0) {
      --gap;
    }
    in.release = rng() % 4 != 0;
    in.tready = rng() % 3 != 0;
    rtl->rst_ni = in.rst_n;
    rtl->wr_i = in.wr;
    rtl->wr_data_i = static_cast<uint16_t>(in.wr_data);
    rtl->commit_i = in.commit;
    rtl->rollback_i = in.rollback;
    rtl->clear_i = in.clear;
    rtl->release_i = in.release;
    rtl->m_axis_tready = in.tready;
    rtl->clk_i = 0;
    rtl->eval();
    const Fifo::Out m = model->outputs();
    if (armed) {
      std::ostringstream s;
      if (rtl->m_axis_tvalid != m.tvalid) s << "tvalid ";
      if (m.tvalid && rtl->m_axis_tdata != m.tdata) s << "tdata ";
      if (rtl->level_o != m.level) s << "level ";
      if (rtl->credits_o != m.credits) s << "credits ";
      if (rtl->busy_o != m.busy) s << "busy ";
      if (!s.str().empty()) why = "cycle " + std::to_string(cyc) + ": " + s.str();
      if (m.tvalid && in.tready) {
        out.push_back(m.tdata);
        if (static_cast<int>(out.size()) == kSegWords) {
          played.push_back(out);
          out.clear();
          ++out_done;
          if (!committed.empty()) committed.pop_front();
        }
      }
    }
    if (!in.rst_n) armed = true;
    model->clock(in);
    rtl->clk_i = 1;
    rtl->eval();
  }
  ASSERT_TRUE(why.empty()) << why;
  ASSERT_GT(played.size(), 100u);
  for (size_t i = 0; i < played.size() && i < expected.size(); ++i) ASSERT_EQ(played[i], expected[i]) << "segment " << i;
  ASSERT_LE(played.size(), expected.size());
  for (size_t i = 0; i < played.size(); ++i) ASSERT_EQ(played[i], expected[i]) << "segment " << i;
  rtl->final();
}

TEST(LinkUnits, UartRxRatesGlitchesFramingErrors) {
  const uint64_t seed = traj::test::test_seed(12);
  std::mt19937_64 rng(seed);
  auto ctx = std::make_unique<VerilatedContext>();
  ctx->randReset(2);
  auto rtl = std::make_unique<Vlink_uart_rx>(ctx.get());
  Rx model;
  // the line, one level per cycle: good bytes at a rate within 2 percent,
  // glitches shorter than half a bit, bytes with a low stop bit
  std::vector<bool> line(40, true);
  std::vector<int> sent;
  int errors_sent = 0;
  for (int n = 0; n < 400; ++n) {
    const double bit = 8.0 * (1.0 + (static_cast<int>(rng() % 9) - 4) * 0.005);
    const int kind = static_cast<int>(rng() % 8);
    if (kind == 0) {
      const int len = 1 + static_cast<int>(rng() % 3);
      for (int i = 0; i < len; ++i) line.push_back(false);
      for (int i = 0; i < 12; ++i) line.push_back(true);
      continue;
    }
    const int byte = static_cast<int>(rng() % 256);
    const bool bad_stop = kind == 1;
    double t = 0;
    for (int b = 0; b < 10; ++b) {
      const bool level = b == 0 ? false : b == 9 ? !bad_stop : ((byte >> (b - 1)) & 1);
      const double end = (b + 1) * bit;
      while (t < end) {
        line.push_back(level);
        t += 1;
      }
    }
    for (int i = 0; i < 2 + static_cast<int>(rng() % 6); ++i) line.push_back(true);
    if (bad_stop) {
      ++errors_sent;
      for (int i = 0; i < 10; ++i) line.push_back(true);  // the line returns high
    } else {
      sent.push_back(byte);
    }
  }
  std::vector<int> got;
  int errors = 0;
  std::string why;
  for (size_t cyc = 0; cyc < line.size() + 20 && why.empty(); ++cyc) {
    Rx::In in;
    in.rst_n = cyc >= 2;
    in.rx = cyc < line.size() ? line[cyc] : true;
    rtl->rst_ni = in.rst_n;
    rtl->rx_i = in.rx;
    rtl->clk_i = 0;
    rtl->eval();
    const Rx::Out m = model.outputs();
    if (cyc >= 2) {
      if (rtl->valid_o != m.valid || rtl->err_o != m.err || (m.valid && rtl->data_o != m.data))
        why = "cycle " + std::to_string(cyc) + ": rtl != hls";
      if (m.valid) got.push_back(m.data);
      if (m.err) ++errors;
    }
    model.clock(in);
    rtl->clk_i = 1;
    rtl->eval();
  }
  ASSERT_TRUE(why.empty()) << why;
  EXPECT_EQ(got, sent);
  EXPECT_EQ(errors, errors_sent);
  rtl->final();
}

}  // namespace
