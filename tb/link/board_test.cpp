// The loopback board against LINK.md's rules, frame by frame.
#include <gtest/gtest.h>

#include "link/board.hpp"

namespace traj::link {
namespace {

constexpr BoardFormat kFormat{1, 1, 16, 8};  // 1 axis, degree 1, 16-bit registers: 20-byte records

Bytes record(uint32_t seq, uint32_t k = 10, int16_t r0 = 0x1234) {
  Bytes r = {1, 0, 0, 0};
  put_u32(r, k);
  put_u32(r, seq);
  put_u16(r, static_cast<uint16_t>(r0));
  put_u16(r, 1);
  put_u32(r, crc32(r.data(), r.size()));
  return r;
}

struct Answer {
  Type type;
  uint32_t seq;
  uint8_t reason;   // NAK
  uint16_t credits;
};

class BoardTest : public ::testing::Test {
 protected:
  BoardTest() : board_(options()) {}
  static BoardOptions options() {
    BoardOptions o;
    o.format = kFormat;
    o.fifo_segments = 3;
    o.clock_hz = 1e6;
    o.speed = 1.0;
    o.min_tick_clocks = 10;
    return o;
  }
  std::vector<Answer> send(const Bytes& wire) {
    Bytes out;
    board_.receive(wire.data(), wire.size(), out);
    return answers(out);
  }
  std::vector<Answer> send(Type t, uint32_t seq, const Bytes& payload = {}) {
    return send(encode_frame(t, seq, payload));
  }
  static std::vector<Answer> answers(const Bytes& out) {
    FrameDecoder d;
    std::vector<FrameDecoder::Event> ev;
    d.feed(out.data(), out.size(), ev);
    std::vector<Answer> a;
    for (auto& e : ev) {
      EXPECT_TRUE(e.good);
      if (e.frame.type == Type::kAck) a.push_back({Type::kAck, e.frame.seq, 0, decode_ack(e.frame).credits});
      else if (e.frame.type == Type::kNak) {
        const Nak n = decode_nak(e.frame);
        a.push_back({Type::kNak, n.next_seq, n.reason, n.credits});
      } else a.push_back({e.frame.type, e.frame.seq, 0, 0});
    }
    return a;
  }
  void expect_one(const std::vector<Answer>& a, Type t, uint32_t seq, uint8_t reason, uint16_t credits) {
    ASSERT_EQ(a.size(), 1u);
    EXPECT_EQ(a[0].type, t);
    EXPECT_EQ(a[0].seq, seq);
    EXPECT_EQ(a[0].reason, reason);
    EXPECT_EQ(a[0].credits, credits);
  }
  Bytes config(uint32_t tick_clocks = 1000) {
    Config c;
    c.tick_clocks = tick_clocks;  // 1 ms at 1 MHz
    return encode_config(c);
  }
  LoopbackBoard board_;
};

TEST_F(BoardTest, SequenceRules) {
  expect_one(send(Type::kReset, 5), Type::kAck, 5, 0, 3);
  expect_one(send(Type::kSegment, 5, record(5)), Type::kAck, 6, 0, 2);
  expect_one(send(Type::kSegment, 5, record(5)), Type::kAck, 6, 0, 2);  // a re-send: ACK, not stored again
  expect_one(send(Type::kSegment, 7, record(7)), Type::kNak, 6, 2, 2);  // a gap
  expect_one(send(Type::kSegment, 6, record(7)), Type::kNak, 6, 4, 2);  // record seq != frame seq
  expect_one(send(Type::kSegment, 6, record(6, 0)), Type::kNak, 6, 4, 2);  // K = 0
  Bytes wrong_size = record(6);
  wrong_size.push_back(0);
  expect_one(send(Type::kSegment, 6, wrong_size), Type::kNak, 6, 4, 2);
  Bytes flags = record(6);
  flags[1] = 1;
  expect_one(send(Type::kSegment, 6, flags), Type::kNak, 6, 4, 2);
  expect_one(send(Type::kSegment, 6, record(6)), Type::kAck, 7, 0, 1);
  expect_one(send(Type::kSegment, 7, record(7)), Type::kAck, 8, 0, 0);
  expect_one(send(Type::kSegment, 8, record(8)), Type::kNak, 8, 3, 0);  // FIFO full
  expect_one(send(Type::kEnd, 9), Type::kNak, 8, 2, 0);
  expect_one(send(Type::kEnd, 8), Type::kAck, 8, 0, 0);
  const Status s = board_.status();
  EXPECT_EQ(s.fifo_level, 3);
  EXPECT_EQ(s.out_of_order, 2u);  // the gap and the early END
  // seq wraps modulo 2^32: 2^32 - 1 is "already accepted" after a RESET to 0
  expect_one(send(Type::kReset, 0), Type::kAck, 0, 0, 3);
  expect_one(send(Type::kSegment, 0xFFFFFFFF, record(0xFFFFFFFF)), Type::kAck, 0, 0, 3);
}

TEST_F(BoardTest, BadFramesAndGarbageGetNak1) {
  Bytes w = encode_frame(Type::kSegment, 0, record(0));
  w[10] ^= 0x01;
  expect_one(send(w), Type::kNak, 0, 1, 3);
  expect_one(send(Bytes{0x7E, 0x01, 0x02, 0x7E}), Type::kNak, 0, 1, 3);
  expect_one(send(Type::kAck, 0, encode_ack({})), Type::kNak, 0, 1, 3);  // a board-to-host type
  EXPECT_EQ(board_.status().bad_frames, 3u);
  EXPECT_EQ(board_.status().fifo_level, 0);
}

TEST_F(BoardTest, PlaybackUnderrunHaltResumeAndEnd) {
  std::vector<uint32_t> played;
  board_.on_played = [&](uint32_t seq, const Bytes&) { played.push_back(seq); };
  send(Type::kReset, 0);
  expect_one(send(Type::kConfig, 0, config(5)), Type::kNak, 0, 4, 3);  // below the engine's update time
  expect_one(send(Type::kConfig, 0, config()), Type::kAck, 0, 0, 3);
  send(Type::kSegment, 0, record(0, 10, 100));
  send(Type::kSegment, 1, record(1, 10, -3 * 256));
  Bytes out;
  board_.advance(0.0, out);
  EXPECT_FALSE(board_.playing());
  send(Type::kStart, 0);
  expect_one(send(Type::kReset, 0), Type::kNak, 2, 5, 1);  // not while playing
  expect_one(send(Type::kConfig, 0, config()), Type::kNak, 2, 5, 1);
  board_.advance(0.0, out);   // segment 0 starts at once
  board_.advance(0.015, out);  // 15 ticks: into segment 1
  EXPECT_EQ(played, (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(board_.status().sample[0], -3);  // r0 >> 8 guard bits, sign-extended from 16 bits
  EXPECT_EQ(board_.status().ticks_played, 15u);
  board_.advance(0.030, out);  // FIFO empty at segment 1's end, no END: underrun, halt
  Status s = board_.status();
  EXPECT_EQ(s.underruns, 1u);
  EXPECT_TRUE(s.flags & status_flag::kUnderrunHalt);
  EXPECT_FALSE(s.flags & status_flag::kPlaying);
  EXPECT_EQ(s.ticks_played, 20u);  // holds: no tick is played past the end
  send(Type::kSegment, 2, record(2));
  board_.advance(0.100, out);
  EXPECT_EQ(played.size(), 2u);  // nothing more without RESUME
  send(Type::kResume, 0);
  send(Type::kEnd, 3);
  board_.advance(0.101, out);
  board_.advance(0.2, out);
  s = board_.status();
  EXPECT_EQ(played, (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_TRUE(s.flags & status_flag::kEndReached);
  EXPECT_EQ(s.underruns, 1u);
  EXPECT_EQ(s.ticks_played, 30u);
}

TEST_F(BoardTest, StopEndsAtASegmentEnd) {
  std::vector<uint32_t> played;
  board_.on_played = [&](uint32_t seq, const Bytes&) { played.push_back(seq); };
  send(Type::kReset, 0);
  send(Type::kConfig, 0, config());
  for (uint32_t i = 0; i < 3; ++i) send(Type::kSegment, i, record(i));
  send(Type::kStart, 0);
  Bytes out;
  board_.advance(0.0, out);
  board_.advance(0.004, out);
  send(Type::kStop, 0);
  board_.advance(0.050, out);
  const Status s = board_.status();
  EXPECT_EQ(played, (std::vector<uint32_t>{0}));
  EXPECT_EQ(s.ticks_played, 10u);  // segment 0 to its end, nothing after
  EXPECT_EQ(s.fifo_level, 2);
  EXPECT_EQ(s.underruns, 0u);
  EXPECT_FALSE(board_.playing());
}

TEST_F(BoardTest, StatusOnRequestAndPeriodic) {
  send(Type::kReset, 0);
  Config c;
  c.tick_clocks = 1000;
  c.status_ticks = 4;
  send(Type::kConfig, 0, encode_config(c));
  const auto a = send(Type::kStatusReq, 0);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].type, Type::kStatus);
  send(Type::kSegment, 0, record(0, 10));
  send(Type::kEnd, 1);
  send(Type::kStart, 0);
  size_t statuses = 0;
  for (int ms = 0; ms <= 12; ++ms) {
    Bytes out;
    board_.advance(ms * 1e-3, out);
    for (const auto& x : answers(out)) statuses += x.type == Type::kStatus;
  }
  EXPECT_EQ(statuses, 2u);  // at 4 and 8 ticks played (10 ticks in all)
}

// A build without the time-scale unit (LINK.md): CONFIG with m != 0 is
// refused, and with m = 0 every byte 28..39 must be 0; FEED is refused
// (NAK 4, before NAK 5: the verdict order); STATUS reports no time scaling.
TEST_F(BoardTest, WithoutTheTimeScaleUnit) {
  send(Type::kReset, 0);
  const Bytes whole = config();
  expect_one(send(Type::kConfig, 0, Bytes(whole.begin(), whole.begin() + 24)), Type::kNak, 0, 4, 3);
  Config c;
  c.tick_clocks = 1000;
  c.scale_m = 1;
  expect_one(send(Type::kConfig, 0, encode_config(c)), Type::kNak, 0, 4, 3);
  for (size_t at = 28; at < 40; ++at) {
    Bytes p = config();
    p[at] = 1;
    expect_one(send(Type::kConfig, 0, p), Type::kNak, 0, 4, 3);
  }
  Bytes m_only = config();
  m_only[27] = 0x80;  // m's top byte
  expect_one(send(Type::kConfig, 0, m_only), Type::kNak, 0, 4, 3);
  expect_one(send(Type::kFeed, 0, encode_feed({1, false})), Type::kNak, 0, 4, 3);
  expect_one(send(Type::kConfig, 0, config()), Type::kAck, 0, 0, 3);
  send(Type::kSegment, 0, record(0, 10));
  send(Type::kStart, 0);
  ASSERT_TRUE(board_.playing());
  expect_one(send(Type::kFeed, 0, encode_feed({1, true})), Type::kNak, 1, 4, 2);
  expect_one(send(Type::kConfig, 0, encode_config(c)), Type::kNak, 1, 4, 2);  // bad content before "playing"
  expect_one(send(Type::kConfig, 0, config()), Type::kNak, 1, 5, 2);
  Bytes out;
  board_.advance(0.0, out);
  board_.advance(0.004, out);
  const auto a = send(Type::kStatusReq, 0);
  ASSERT_EQ(a.size(), 1u);
  const Status s = board_.status();
  EXPECT_EQ(s.scale_s, 0u);
  EXPECT_EQ(s.starved_holds, 0u);
  EXPECT_EQ(s.ticks_ahead, 0u);
  EXPECT_EQ(s.flags & (status_flag::kStarved | status_flag::kHeld), 0);
  EXPECT_TRUE(s.flags & status_flag::kPlaying);
  EXPECT_EQ(board_.config().tick_clocks, 1000u);  // the refused CONFIGs changed nothing
}

}  // namespace
}  // namespace traj::link
