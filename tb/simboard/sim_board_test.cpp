// SPDX-License-Identifier: Apache-2.0
// The simulated board (rtl/traj_board.sv Verilated, pins driven and decoded
// outside the RTL) against the protocol: frames built by the test's own
// encoder (link::encode_frame is checked against zlib's CRC in tb/link).
#include <gtest/gtest.h>

#include "board/sim_board.hpp"
#include "link/frame.hpp"

namespace traj::board {
namespace {

std::vector<link::Frame> answers(SimulatedBoard& b, const link::Bytes& request, uint64_t cycles) {
  link::Bytes out;
  b.receive(request.data(), request.size(), out);
  b.run(cycles, out);
  link::FrameDecoder d;
  std::vector<link::FrameDecoder::Event> ev;
  d.feed(out.data(), out.size(), ev);
  std::vector<link::Frame> f;
  for (auto& e : ev) {
    EXPECT_TRUE(e.good) << e.why;
    if (e.good) f.push_back(e.frame);
  }
  return f;
}

const uint64_t kFrameCycles = 400ull * BoardBuild::kClkHz / BoardBuild::kBaud * 10;  // 400 bytes

TEST(SimulatedBoard, AnswersStatusRequestWithStatus) {
  SimulatedBoard b;
  const auto f = answers(b, link::encode_frame(link::Type::kStatusReq, 0), kFrameCycles);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].type, link::Type::kStatus);
  const link::Status s = link::decode_status(f[0]);
  EXPECT_EQ(s.axes, BoardBuild::kAxes);
  EXPECT_EQ(s.next_seq, 0u);
  EXPECT_EQ(b.tx_framing_errors(), 0u);
}

TEST(SimulatedBoard, ResetSetsNextSeqAndGarbageIsNakedOrIgnored) {
  SimulatedBoard b;
  auto f = answers(b, link::encode_frame(link::Type::kReset, 7), kFrameCycles);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].type, link::Type::kAck);
  EXPECT_EQ(f[0].seq, 7u);
  link::Bytes bad = link::encode_frame(link::Type::kStatusReq, 0);
  bad[3] ^= 0x01;  // a bit of the length field
  f = answers(b, bad, kFrameCycles);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].type, link::Type::kNak);
  EXPECT_EQ(link::decode_nak(f[0]).reason, static_cast<uint8_t>(link::NakReason::kBadFrame));
  EXPECT_EQ(f[0].seq, 7u);
}

}  // namespace
}  // namespace traj::board
