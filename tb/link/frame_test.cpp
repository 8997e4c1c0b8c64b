// The frame codec against hand-built frames and zlib, and the decoder's
// resynchronisation after garbage and corruption.
#include <gtest/gtest.h>
#include <zlib.h>

#include <random>

#include "link/frame.hpp"
#include "test_seed.hpp"

namespace traj::link {
namespace {

std::vector<Frame> decode_all(const Bytes& wire, size_t* bad = nullptr) {
  FrameDecoder d;
  std::vector<FrameDecoder::Event> ev;
  d.feed(wire.data(), wire.size(), ev);
  std::vector<Frame> good;
  size_t nbad = 0;
  for (auto& e : ev) {
    if (e.good) good.push_back(e.frame);
    else ++nbad;
  }
  if (bad) *bad = nbad;
  return good;
}

TEST(Frame, Crc32IsZlibsCheckValue) {
  const char* s = "123456789";
  EXPECT_EQ(crc32(reinterpret_cast<const uint8_t*>(s), 9), 0xCBF43926u);
}

TEST(Frame, HandBuiltAckWithStuffing) {
  // ACK, seq 0x7E (stuffed), credits 0x7D (stuffed): body by hand, CRC by zlib
  Bytes body = {0x81, 0x00, 0x04, 0x00, 0x7E, 0x00, 0x00, 0x00, 0x7D, 0x00, 0x00, 0x00};
  const uint32_t c = static_cast<uint32_t>(::crc32(0, body.data(), static_cast<uInt>(body.size())));
  for (int i = 0; i < 4; ++i) body.push_back((c >> (8 * i)) & 0xFF);
  Bytes want = {0x7E};
  for (uint8_t b : body) {
    if (b == 0x7E) want.insert(want.end(), {0x7D, 0x5E});
    else if (b == 0x7D) want.insert(want.end(), {0x7D, 0x5D});
    else want.push_back(b);
  }
  want.push_back(0x7E);
  EXPECT_EQ(encode_frame(Type::kAck, 0x7E, encode_ack({0x7E, 0x7D})), want);
  const auto got = decode_all(want);
  ASSERT_EQ(got.size(), 1u);
  const Ack a = decode_ack(got[0]);
  EXPECT_EQ(a.next_seq, 0x7Eu);
  EXPECT_EQ(a.credits, 0x7D);
}

Frame random_frame(std::mt19937_64& rng) {
  Frame f;
  const Type types[] = {Type::kSegment, Type::kStatusReq, Type::kAck, Type::kStatus, Type::kEnd};
  f.type = types[rng() % 5];
  f.seq = static_cast<uint32_t>(rng());
  f.payload.resize(rng() % 300);
  for (auto& b : f.payload) b = (rng() % 4 == 0) ? (rng() % 2 ? 0x7E : 0x7D) : static_cast<uint8_t>(rng());
  return f;
}

TEST(Frame, RoundTripSplitAnywhereWithGarbageBetween) {
  std::mt19937_64 rng(test::test_seed(1));
  std::vector<Frame> sent;
  Bytes wire = {0x12, 0x7D, 0x34};  // garbage before the first flag: not a body
  for (int i = 0; i < 200; ++i) {
    sent.push_back(random_frame(rng));
    const Bytes w = encode_frame(sent.back());
    for (size_t k = 1; k + 1 < w.size(); ++k) ASSERT_NE(w[k], 0x7E) << "a flag inside a stuffed body";
    wire.insert(wire.end(), w.begin(), w.end());
    if (i % 7 == 0) wire.insert(wire.end(), {0x55, 0x7D, 0x7D, 0x99});  // garbage: one bad body, then resync
  }
  FrameDecoder d;
  std::vector<FrameDecoder::Event> ev;
  for (size_t at = 0; at < wire.size();) {  // fed in random pieces
    const size_t n = std::min<size_t>(1 + rng() % 50, wire.size() - at);
    d.feed(wire.data() + at, n, ev);
    at += n;
  }
  std::vector<Frame> got;
  size_t bad = 0;
  for (auto& e : ev) {
    if (e.good) got.push_back(e.frame);
    else ++bad;
  }
  ASSERT_EQ(got.size(), sent.size());
  for (size_t i = 0; i < sent.size(); ++i) {
    EXPECT_EQ(got[i].type, sent[i].type);
    EXPECT_EQ(got[i].seq, sent[i].seq);
    EXPECT_EQ(got[i].payload, sent[i].payload);
  }
  EXPECT_EQ(bad, 29u);  // the 29 garbage runs (i = 0, 7, ..., 196)
}

// Every single-bit error in a frame: never a good frame with other content,
// and the next frame decodes (resynchronisation).
TEST(Frame, EveryBitFlipIsCaughtAndTheNextFrameDecodes) {
  std::mt19937_64 rng(test::test_seed(1));
  const Frame f = random_frame(rng);
  const Bytes w = encode_frame(f);
  const Bytes next = encode_frame(Type::kStatusReq, 42);
  for (size_t i = 0; i < w.size(); ++i)
    for (int bit = 0; bit < 8; ++bit) {
      Bytes x = w;
      x[i] ^= static_cast<uint8_t>(1 << bit);
      x.insert(x.end(), next.begin(), next.end());
      const auto got = decode_all(x);
      ASSERT_FALSE(got.empty()) << "byte " << i;
      const Frame& last = got.back();
      EXPECT_EQ(last.type, Type::kStatusReq) << "byte " << i << " bit " << bit;
      EXPECT_EQ(last.seq, 42u);
      for (size_t k = 0; k + 1 < got.size(); ++k)
        EXPECT_TRUE(got[k].type == f.type && got[k].seq == f.seq && got[k].payload == f.payload)
            << "a corrupted frame decoded as another one: byte " << i << " bit " << bit;
    }
}

TEST(Frame, BadBodiesAreNamed) {
  auto why = [](const Bytes& body) {
    Frame f;
    return parse_body(body, f);
  };
  auto body = [](Bytes b) {
    const uint32_t c = static_cast<uint32_t>(::crc32(0, b.data(), static_cast<uInt>(b.size())));
    for (int i = 0; i < 4; ++i) b.push_back((c >> (8 * i)) & 0xFF);
    return b;
  };
  EXPECT_EQ(why(body({0x06, 0, 0, 0, 1, 0, 0, 0})), "");
  EXPECT_NE(why(body({0x06, 0, 1, 0, 1, 0, 0, 0})).find("len 1"), std::string::npos);  // length mismatch
  EXPECT_NE(why(body({0x06, 1, 0, 0, 1, 0, 0, 0})).find("flags"), std::string::npos);
  EXPECT_NE(why(body({0x42, 0, 0, 0, 1, 0, 0, 0})).find("unknown type"), std::string::npos);
  EXPECT_NE(why(body({0x06, 0, 0x01, 0x08, 1, 0, 0, 0})).find("> 2048"), std::string::npos);
  Bytes b = body({0x06, 0, 0, 0, 1, 0, 0, 0});
  b[11] ^= 1;
  EXPECT_NE(why(b).find("CRC"), std::string::npos);
  size_t bad = 0;
  EXPECT_TRUE(decode_all({0x7E, 0x06, 0x7D, 0x11, 0x7E}, &bad).empty());  // bad escape
  EXPECT_EQ(bad, 1u);
  EXPECT_TRUE(decode_all({0x7E, 0x7E, 0x7E}, &bad).empty());  // empty bodies are ignored
  EXPECT_EQ(bad, 0u);
}

TEST(Frame, StatusAndConfigRoundTrip) {
  Status s;
  s.next_seq = 77;
  s.axes = 3;
  s.flags = status_flag::kPlaying | status_flag::kFifoEmpty;
  s.fifo_level = 513;
  s.segments_played = 1000000;
  s.ticks_played = 0xFFFFFFFE;
  s.underruns = 2;
  s.credits = 9;
  s.sample = {-1, INT64_MIN, (int64_t(1) << 47) - 1};
  const Bytes p = encode_status(s);
  ASSERT_EQ(p.size(), 48u + 8 * 3);
  EXPECT_EQ(p[48], 0xFF);  // -1, little-endian
  const Status t = decode_status({Type::kStatus, 77, p});
  EXPECT_EQ(t.sample, s.sample);
  EXPECT_EQ(t.fifo_level, 513);
  EXPECT_EQ(t.ticks_played, 0xFFFFFFFEu);
  EXPECT_EQ(t.flags, s.flags);
  Config c;
  c.tick_clocks = 48000;
  c.step_shift[2] = 63;
  c.pulse_clocks = 96;
  const Bytes cp = encode_config(c);
  ASSERT_EQ(cp.size(), 40u);
  EXPECT_EQ(cp[0] | cp[1] << 8 | cp[2] << 16, 48000);
  EXPECT_EQ(cp[10], 63);
  EXPECT_EQ(Bytes(cp.begin() + 24, cp.end()), Bytes(16, 0));  // no time scaling: bytes 24..39 are 0
  EXPECT_EQ(decode_config(cp).pulse_clocks, 96);
  EXPECT_THROW(decode_status({Type::kStatus, 0, Bytes(49)}), LinkError);
}

// LINK.md's STATUS layout, byte by byte: S at 36, starved holds at 40, engine
// ticks ahead at 44, the samples from 48; flags bit 6 starved, bit 7 held.
TEST(Frame, StatusTimeScalingFieldsAtTheirOffsets) {
  Bytes p(48 + 8 * 2, 0);
  p[0] = 2;
  p[1] = 0x80 | 0x40 | 0x01;
  const auto put = [&](size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) p[at + size_t(i)] = uint8_t(v >> (8 * i));
  };
  put(36, 0x00080000);  // S = 2^19
  put(40, 3);
  put(44, 0x12345678);
  put(48, 5);           // axis 0: 5
  put(56, 0xFFFFFFFE);  // axis 1: -2
  put(60, 0xFFFFFFFF);
  const Status s = decode_status({Type::kStatus, 9, p});
  EXPECT_EQ(s.scale_s, 0x80000u);
  EXPECT_EQ(s.starved_holds, 3u);
  EXPECT_EQ(s.ticks_ahead, 0x12345678u);
  EXPECT_EQ(s.sample, (std::vector<int64_t>{5, -2}));
  EXPECT_EQ(status_flag::kStarved, 0x40);
  EXPECT_EQ(status_flag::kHeld, 0x80);
  EXPECT_TRUE(s.flags & status_flag::kHeld);
  EXPECT_TRUE(s.flags & status_flag::kStarved);
  EXPECT_EQ(encode_status(s), p);
  // the layout of 40 + 8 axes bytes is refused, naming the sizes
  Bytes old_layout(40 + 8 * 2, 0);
  old_layout[0] = 2;
  try {
    decode_status({Type::kStatus, 9, old_layout});
    FAIL() << "a 56-byte STATUS for 2 axes was taken";
  } catch (const LinkError& e) {
    EXPECT_NE(std::string(e.what()).find("not 64"), std::string::npos) << e.what();
  }
}

// CONFIG's time-scaling fields at LINK.md's offsets; sizes other than 40 refused.
TEST(Frame, ConfigTimeScalingFieldsAtTheirOffsets) {
  Config c;
  c.scale_m = 0x01020304;
  c.scale_s_max = 0x000C0000;
  c.scale_override = 0x00080000;
  c.scale_shift = 18;
  c.scale_flags = config_flag::kAutoResume;
  const Bytes p = encode_config(c);
  ASSERT_EQ(p.size(), 40u);
  EXPECT_EQ(Bytes(p.begin() + 24, p.end()),
            (Bytes{0x04, 0x03, 0x02, 0x01, 0x00, 0x00, 0x0C, 0x00, 0x00, 0x00, 0x08, 0x00, 18, 1, 0, 0}));
  Bytes q = p;
  q[38] = 0x34;
  q[39] = 0x12;
  const Config d = decode_config(q);
  EXPECT_EQ(d.scale_m, 0x01020304u);
  EXPECT_EQ(d.scale_s_max, 0xC0000u);
  EXPECT_EQ(d.scale_override, 0x80000u);
  EXPECT_EQ(d.scale_shift, 18);
  EXPECT_EQ(d.scale_flags, 1);
  EXPECT_EQ(d.scale_reserved, 0x1234);  // decoded as is: the board judges it
  EXPECT_EQ(encode_config(d), q);
  for (size_t n : {24u, 39u, 41u}) {
    try {
      decode_config(Bytes(n, 0));
      FAIL() << "a CONFIG of " << n << " bytes was taken";
    } catch (const LinkError& e) {
      EXPECT_NE(std::string(e.what()).find(std::to_string(n) + " bytes, not 40"), std::string::npos) << e.what();
    }
  }
}

TEST(Frame, FeedPayloadAndType) {
  EXPECT_TRUE(known_type(0x07));
  EXPECT_STREQ(type_name(Type::kFeed), "FEED");
  EXPECT_EQ(static_cast<uint8_t>(Type::kFeed), 0x07);
  EXPECT_EQ(encode_feed({0x00012345, true}), (Bytes{0x45, 0x23, 0x01, 0x00, 0x01, 0, 0, 0}));
  EXPECT_EQ(encode_feed({7, false}), (Bytes{7, 0, 0, 0, 0, 0, 0, 0}));
  const Feed f = decode_feed({0x00, 0x00, 0x08, 0x00, 0x01, 0, 0, 0});
  EXPECT_EQ(f.override_s, 0x80000u);
  EXPECT_TRUE(f.hold);
  EXPECT_FALSE(decode_feed({1, 0, 0, 0, 0, 0, 0, 0}).hold);
  // a FEED frame decodes as a good frame of its type
  const auto got = decode_all(encode_frame(Type::kFeed, 0, encode_feed({100, false})));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, Type::kFeed);
  EXPECT_EQ(decode_feed(got[0].payload).override_s, 100u);
  // refused: other sizes, reserved flag bits, reserved bytes
  EXPECT_THROW(decode_feed(Bytes(7, 0)), LinkError);
  EXPECT_THROW(decode_feed(Bytes(9, 0)), LinkError);
  EXPECT_THROW(decode_feed({0, 0, 0, 0, 0x02, 0, 0, 0}), LinkError);
  EXPECT_THROW(decode_feed({0, 0, 0, 0, 0x01, 0, 0, 1}), LinkError);
  EXPECT_THROW(decode_feed({0, 0, 0, 0, 0x00, 1, 0, 0}), LinkError);
}

}  // namespace
}  // namespace traj::link
