// The host link (rtl/traj_link.sv == hls/traj_link.hpp on every cycle, see
// link_bench.hpp) driven at the byte level by an independent frame encoder:
// good frames, corrupted, truncated, duplicated and out-of-order frames and
// garbage; the answers (ACK/NAK/STATUS, parsed and CRC-checked independently)
// and the exact engine words that come out are checked against what the
// protocol (rtl/board/LINK.md) requires.
#include <gtest/gtest.h>

#include "link_bench.hpp"
#include "test_seed.hpp"

namespace {

using namespace linktest;

struct Scale {
  uint32_t m = 0, s_max = 0, override_s = 0;
  uint8_t shift = 0, flags = 0;
};

std::vector<uint8_t> config_payload(uint32_t tick, uint32_t stat, uint8_t shift, uint16_t pulse, uint16_t setup,
                                    uint8_t enable, const Scale& sc = {}) {
  std::vector<uint8_t> p;
  put_le(p, tick, 4);
  put_le(p, stat, 4);
  for (int a = 0; a < 8; ++a) p.push_back(static_cast<uint8_t>(a < kAxes ? shift + a : 0));
  put_le(p, pulse, 2);
  put_le(p, setup, 2);
  p.push_back(enable);
  p.push_back(0);
  p.push_back(0);
  p.push_back(0);
  put_le(p, sc.m, 4);
  put_le(p, sc.s_max, 4);
  put_le(p, sc.override_s, 4);
  p.push_back(sc.shift);
  p.push_back(sc.flags);
  put_le(p, 0, 2);
  return p;
}

std::vector<uint8_t> feed_payload(uint32_t override_s, uint8_t flags, uint8_t reserved = 0) {
  std::vector<uint8_t> p;
  put_le(p, override_s, 4);
  p.push_back(flags);
  p.push_back(reserved);
  p.push_back(0);
  p.push_back(0);
  return p;
}

#define EXPECT_ACK(a, s)                 \
  do {                                   \
    const Answer x_ = (a);               \
    ASSERT_TRUE(bench.ok()) << bench.why(); \
    EXPECT_EQ(x_.type, 0x81);            \
    EXPECT_EQ(x_.seq, (s));              \
  } while (0)
#define EXPECT_NAK(a, r, s)              \
  do {                                   \
    const Answer x_ = (a);               \
    ASSERT_TRUE(bench.ok()) << bench.why(); \
    EXPECT_EQ(x_.type, 0x82);            \
    EXPECT_EQ(x_.reason(), (r));         \
    EXPECT_EQ(x_.seq, (s));              \
  } while (0)

TEST(LinkCosim, FramesFaultsAndPlayback) {
  const uint64_t seed = traj::test::test_seed(1);
  std::mt19937_64 rng(seed);
  Bench bench(seed);
  bench.reset();
  bench.run(50);

  // garbage before the first flag is ignored; garbage between flags is a bad frame
  bench.send_raw({0x12, 0x7D, 0x99});
  bench.send_raw({0x7E, 0x55, 0x66, 0x7E});
  EXPECT_NAK(bench.await_answer(), 1, 0u);

  // RESET to sequence 1000
  EXPECT_ACK(bench.transact(0x01, 1000), 1000u);

  // CONFIG: a good one is applied, a bad one refused and not applied
  EXPECT_ACK(bench.transact(0x02, 0, config_payload(400, 0, 3, 20, 7, 1)), 1000u);
  EXPECT_EQ(bench.rtl().tick_period_o, 400u);
  EXPECT_EQ(bench.rtl().pulse_o, 20u);
  EXPECT_EQ(bench.rtl().setup_o, 7u);
  EXPECT_EQ(bench.rtl().enable_o, 1u);
  EXPECT_EQ(bench.rtl().step_shift_o & 63u, 3u);
  EXPECT_NAK(bench.transact(0x02, 0, config_payload(400, 0, 64, 20, 7, 1)), 4, 1000u);       // shift 64
  EXPECT_NAK(bench.transact(0x02, 0, config_payload(LINK_MINTICK - 1, 0, 1, 20, 7, 1)), 4, 1000u);
  EXPECT_NAK(bench.transact(0x02, 0, config_payload(400, 0, 1, 0, 7, 1)), 4, 1000u);          // pulse 0
  EXPECT_EQ(bench.rtl().pulse_o, 20u);

  std::vector<Record> accepted;
  uint32_t seq = 1000;
  // K ticks of 400 clocks: a segment plays about twice as long as its frame takes to arrive
  const uint32_t K = (kRecBytes + 20) * 10 * kDiv * 2 / 400 + 1;
  auto good = [&]() {
    Record r = random_record(rng, seq);
    r.K = K;
    bench.send_record(r);
    const Answer a = bench.await_answer();
    EXPECT_EQ(a.type, 0x81);
    EXPECT_EQ(a.seq, seq + 1);
    accepted.push_back(r);
    ++seq;
    return a;
  };
  good();
  // corrupted payload byte: CRC fails, NAK 1, nothing stored
  {
    Record r = random_record(rng, seq);
    auto b = body(0x10, r.seq, r.bytes());
    b[20] ^= 0x01;
    bench.send_raw(stuff(b));
    EXPECT_NAK(bench.await_answer(), 1, seq);
  }
  // dropped byte
  {
    Record r = random_record(rng, seq);
    auto s = stuff(body(0x10, r.seq, r.bytes()));
    s.erase(s.begin() + 30);
    bench.send_raw(s);
    EXPECT_NAK(bench.await_answer(), 1, seq);
  }
  // bad escape (0x7D 0x11)
  {
    auto s = stuff(body(0x10, seq, random_record(rng, seq).bytes()));
    s.insert(s.begin() + 10, {0x7D, 0x11});
    bench.send_raw(s);
    EXPECT_NAK(bench.await_answer(), 1, seq);
  }
  good();
  // duplicate of an accepted record: dropped, ACK (a lost ACK heals)
  bench.send_record(accepted.back());
  EXPECT_ACK(bench.await_answer(), seq);
  // a record skipped ahead: NAK 2
  bench.send_record(random_record(rng, seq + 1));
  EXPECT_NAK(bench.await_answer(), 2, seq);
  // bad content with a good CRC: K = 0, record seq != frame seq, wrong length
  {
    Record r = random_record(rng, seq);
    r.K = 0;
    bench.send_record(r);
    EXPECT_NAK(bench.await_answer(), 4, seq);
    Record r2 = random_record(rng, seq);
    bench.send(0x10, seq, Record{seq + 5, 1, r2.regs}.bytes());
    EXPECT_NAK(bench.await_answer(), 4, seq);
    auto bytes = r2.bytes();
    bytes.pop_back();
    bench.send(0x10, seq, bytes);
    EXPECT_NAK(bench.await_answer(), 4, seq);
  }
  // unknown type, nonzero flags
  EXPECT_NAK(bench.transact(0x08, 0), 1, seq);
  {
    auto b = body(0x03, 0, {});
    b[1] = 1;
    b.resize(b.size() - 4);
    put_le(b, crc32(b), 4);
    bench.send_raw(stuff(b));
    EXPECT_NAK(bench.await_answer(), 1, seq);
  }
  // fill the FIFO: credits count down, then NAK 3
  while (static_cast<int>(accepted.size()) < kCap) {
    const Answer a = good();
    EXPECT_EQ(a.credits(), kCap - accepted.size());
  }
  bench.send_record(random_record(rng, seq));
  EXPECT_NAK(bench.await_answer(), 3, seq);

  // STATUS on request
  bench.send(0x06, 0);
  {
    const Answer st = bench.await_answer();
    ASSERT_TRUE(bench.ok()) << bench.why();
    ASSERT_EQ(st.type, 0x83);
    ASSERT_EQ(st.payload.size(), 48u + 8 * kAxes);
    EXPECT_EQ(st.payload[0], kAxes);
    EXPECT_EQ(st.payload[1] & 1, 0);                       // not playing
    EXPECT_EQ(get_le(st.payload, 2, 2), uint64_t(kCap));   // level
    EXPECT_EQ(get_le(st.payload, 16, 4), 6u);              // bad frames: garbage, CRC, drop, escape, type, flags
    EXPECT_EQ(get_le(st.payload, 20, 4), 1u);              // out of order
    EXPECT_EQ(get_le(st.payload, 28, 4), 0u);              // credits
  }
  // CONFIG and RESET are refused while playing; START plays every stored segment once, in order
  bench.tick_period = 400;
  EXPECT_ACK(bench.transact(0x03, 0), seq);
  EXPECT_EQ(bench.rtl().run_o, 1u);
  EXPECT_NAK(bench.transact(0x01, 5), 5, seq);
  // keep feeding while playing, honouring credits (polled by STATUS_REQ), then
  // let it run dry: an underrun halts it
  for (int i = 0; i < 3; ++i) {
    for (int poll = 0; poll < 100; ++poll) {
      const Answer st = bench.transact(0x06, 0);
      ASSERT_EQ(st.type, 0x83);
      if (get_le(st.payload, 28, 4) != 0) break;
    }
    good();
  }
  uint64_t guard = 0;
  while (bench.rtl().run_o && guard++ < 4000000 && bench.ok()) bench.step();
  ASSERT_TRUE(bench.ok()) << bench.why();
  EXPECT_EQ(bench.rtl().run_o, 0u);
  EXPECT_EQ(bench.underruns, 1u);
  ASSERT_EQ(bench.segments.size(), accepted.size());
  for (size_t i = 0; i < accepted.size(); ++i) EXPECT_EQ(bench.segments[i], accepted[i].words()) << "segment " << i;
  EXPECT_EQ(bench.seg_starts, accepted.size());

  // halted: STATUS says so; RESUME with END pending plays to the end without an underrun
  bench.send(0x06, 0);
  {
    const Answer st = bench.await_answer();
    ASSERT_EQ(st.type, 0x83);
    EXPECT_EQ(st.payload[1] & 3, 2);                 // halt, not playing
    EXPECT_EQ(get_le(st.payload, 12, 4), 1u);        // underruns
    EXPECT_EQ(get_le(st.payload, 4, 4), accepted.size());  // segments played
  }
  good();
  good();
  EXPECT_NAK(bench.transact(0x11, seq + 1), 2, seq);
  EXPECT_ACK(bench.transact(0x11, seq), seq);
  EXPECT_ACK(bench.transact(0x05, 0), seq);
  guard = 0;
  while (bench.rtl().run_o && guard++ < 4000000 && bench.ok()) bench.step();
  ASSERT_TRUE(bench.ok()) << bench.why();
  EXPECT_EQ(bench.underruns, 2u);  // the engine's underrun at the end...
  bench.send(0x06, 0);
  {
    const Answer st = bench.await_answer();
    ASSERT_EQ(st.type, 0x83);
    EXPECT_EQ(st.payload[1] & 7, 4);                 // ...is the end reached, not a halt
    EXPECT_EQ(get_le(st.payload, 12, 4), 1u);
  }
  ASSERT_EQ(bench.segments.size(), accepted.size());
  for (size_t i = 0; i < accepted.size(); ++i) EXPECT_EQ(bench.segments[i], accepted[i].words()) << "segment " << i;
  EXPECT_TRUE(bench.answers().empty());
  EXPECT_TRUE(bench.ok()) << bench.why();
}

// Random frames, faults and garbage against a reference of the protocol's
// sequence rules kept by the test; every stored record is played exactly once.
TEST(LinkCosim, RandomFaultsGoBackN) {
  const uint64_t seed = traj::test::test_seed(2);
  std::mt19937_64 rng(seed);
  Bench bench(seed);
  bench.tick_period = 500;
  bench.reset();
  bench.run(20);
  bench.send_raw({0x7E});
  EXPECT_ACK(bench.transact(0x01, 0xFFFFFFF0u), 0xFFFFFFF0u);  // wraps through 2^32
  std::vector<Record> stored;
  uint32_t next = 0xFFFFFFF0u;
  bool started = false;
  for (int n = 0; n < 60 && bench.ok(); ++n) {
    const int kind = static_cast<int>(rng() % 10);
    Record r = random_record(rng, next, 2);
    if (kind == 0) r.seq = next - 1 - static_cast<uint32_t>(rng() % 3);  // re-send of an old one
    if (kind == 1) r.seq = next + 1 + static_cast<uint32_t>(rng() % 3);  // ahead
    auto s = stuff(body(0x10, r.seq, r.bytes()));
    bool corrupt = false;
    if (kind == 2) {
      s[1 + rng() % (s.size() - 2)] ^= static_cast<uint8_t>(1 + rng() % 255);
      corrupt = true;
    }
    if (kind == 3) {
      s.erase(s.begin() + 1 + static_cast<long>(rng() % (s.size() - 2)));
      corrupt = true;
    }
    if (kind == 4) bench.send_raw({0x7E, static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng())});
    bench.send_raw(s);
    if (kind == 4) {
      // the garbage body gets its NAK 1 first (unless it happened to be a flag)
      if (bench.await_answer().type != 0x82) ADD_FAILURE();
    }
    const Answer a = bench.await_answer();
    ASSERT_TRUE(bench.ok()) << bench.why();
    const uint32_t d = r.seq - next;
    if (corrupt) {
      // a corrupted byte may hit a flag or make a different frame; what matters is
      // that no NAK/ACK claims a record that was not stored: checked via the seq
      EXPECT_TRUE(a.type == 0x81 || a.type == 0x82);
      if (a.type == 0x81 && a.seq == next + 1) stored.push_back(r), ++next;
    } else if (d == 0) {
      if (a.type == 0x81) {
        EXPECT_EQ(a.seq, next + 1);
        stored.push_back(r);
        ++next;
      } else {
        EXPECT_EQ(a.reason(), 3);  // only a full FIFO refuses a good in-order record
      }
    } else if (d >> 31) {
      EXPECT_EQ(a.type, 0x81);
      EXPECT_EQ(a.seq, next);
    } else {
      EXPECT_EQ(a.type, 0x82);
      EXPECT_EQ(a.reason(), 2);
    }
    if (!started && stored.size() >= 3) {
      EXPECT_ACK(bench.transact(0x03, 0), next);
      started = true;
    }
    if (bench.rtl().run_o == 0 && started) EXPECT_ACK(bench.transact(0x05, 0), next);
  }
  EXPECT_ACK(bench.transact(0x11, next), next);
  if (bench.rtl().run_o == 0) EXPECT_ACK(bench.transact(0x05, 0), next);
  uint64_t guard = 0;
  while (bench.rtl().run_o && guard++ < 8000000 && bench.ok()) bench.step();
  ASSERT_TRUE(bench.ok()) << bench.why();
  ASSERT_EQ(bench.segments.size(), stored.size());
  for (size_t i = 0; i < stored.size(); ++i) EXPECT_EQ(bench.segments[i], stored[i].words()) << "segment " << i;
}

// STATUS every N ticks, with the sample words sign-extended from OutWidth.
TEST(LinkCosim, PeriodicStatus) {
  const uint64_t seed = traj::test::test_seed(3);
  std::mt19937_64 rng(seed);
  Bench bench(seed);
  bench.tick_period = 300;
  bench.reset();
  bench.send_raw({0x7E});
  EXPECT_ACK(bench.transact(0x01, 0), 0u);
  EXPECT_ACK(bench.transact(0x02, 0, config_payload(300, 4, 0, 1, 0, 0)), 0u);
  for (uint32_t s = 0; s < 2; ++s) {
    Record r = random_record(rng, s, 1);
    r.K = 6;
    bench.send_record(r);
    EXPECT_ACK(bench.await_answer(), s + 1);
  }
  EXPECT_ACK(bench.transact(0x11, 2), 2u);
  EXPECT_ACK(bench.transact(0x03, 0), 2u);
  bench.run(20000);  // 12 ticks, then the end; a STATUS frame takes about 6000 clocks at 8 clocks per bit
  ASSERT_TRUE(bench.ok()) << bench.why();
  EXPECT_EQ(bench.rtl().run_o, 0u);
  int statuses = 0;
  for (const Answer& a : bench.answers()) {
    if (a.type != 0x83) continue;
    ++statuses;
    for (int ax = 0; ax < kAxes; ++ax) {
      const uint64_t v = get_le(a.payload, 48 + 8 * ax, 8);
      const uint64_t hi = v >> (kOutWidth - 1);  // all ones or all zeros above the sign
      EXPECT_TRUE(hi == 0 || hi == (~uint64_t{0} >> (kOutWidth - 1))) << std::hex << v;
    }
  }
  // at ticks 4, 8 and 12; the last two are pending together while the first is sent
  EXPECT_EQ(statuses, 2);
}

}  // namespace

namespace {

using namespace linktest;

// Time scaling (LINK.md): CONFIG's fields and FEED are taken by a build with
// the unit (within its ScaleWidth) and refused by one without; FEED also
// while playing; STATUS carries the unit's state; each stored record's K
// reaches the board (its count of engine ticks ahead).
TEST(LinkCosim, TimeScaleConfigAndFeed) {
  const uint64_t seed = traj::test::test_seed(4);
  std::mt19937_64 rng(seed);
  Bench bench(seed);
  bench.tick_period = 300;
  bench.reset();
  bench.send_raw({0x7E});
  EXPECT_ACK(bench.transact(0x01, 0), 0u);
  const Scale good{5, 3000, 2048, 17, 1};
  if (kScaleWidth == 0) {
    EXPECT_NAK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0, good)), 4, 0u);
    EXPECT_NAK(bench.transact(0x07, 0, feed_payload(100, 0)), 4, 0u);
    EXPECT_EQ(bench.rtl().scale_m_o, 0u);
  } else {
    const uint32_t wide = 1u << kScaleWidth;
    EXPECT_NAK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0, {wide, 3000, 2048, 17, 1})), 4, 0u);
    EXPECT_NAK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0, {5, wide, 2048, 17, 1})), 4, 0u);
    EXPECT_NAK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0, {5, 3000, wide, 17, 1})), 4, 0u);
    EXPECT_NAK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0, {5, 3000, 2048, 41, 1})), 4, 0u);
    EXPECT_NAK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0, {5, 3000, 2048, 17, 2})), 4, 0u);
    EXPECT_EQ(bench.rtl().scale_m_o, 0u);
    EXPECT_ACK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0, good)), 0u);
    EXPECT_EQ(bench.rtl().scale_m_o, 5u);
    EXPECT_EQ(bench.rtl().scale_s_max_o, 3000u);
    EXPECT_EQ(bench.rtl().scale_override_o, 2048u);
    EXPECT_EQ(bench.rtl().scale_shift_o, 17u);
    EXPECT_EQ(bench.rtl().scale_auto_o, 1u);
    EXPECT_EQ(bench.rtl().hold_o, 0u);
    EXPECT_NAK(bench.transact(0x07, 0, feed_payload(wide, 0)), 4, 0u);
    EXPECT_NAK(bench.transact(0x07, 0, feed_payload(100, 2)), 4, 0u);
    EXPECT_NAK(bench.transact(0x07, 0, feed_payload(100, 0, 1)), 4, 0u);
    EXPECT_NAK(bench.transact(0x07, 0, std::vector<uint8_t>(4, 0)), 4, 0u);
    EXPECT_ACK(bench.transact(0x07, 0, feed_payload(1234, 1)), 0u);
    EXPECT_EQ(bench.rtl().scale_override_o, 1234u);
    EXPECT_EQ(bench.rtl().hold_o, 1u);
  }
  // with m = 0 every other time-scaling byte must be 0
  EXPECT_NAK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0, {0, 3000, 0, 0, 0})), 4, 0u);
  EXPECT_NAK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0, {0, 0, 0, 0, 1})), 4, 0u);
  // the old 24-byte CONFIG is refused
  {
    std::vector<uint8_t> p = config_payload(300, 0, 0, 1, 0, 0);
    p.resize(24);
    EXPECT_NAK(bench.transact(0x02, 0, p), 4, 0u);
  }
  if (kScaleWidth != 0) EXPECT_ACK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0, good)), 0u);
  else EXPECT_ACK(bench.transact(0x02, 0, config_payload(300, 0, 0, 1, 0, 0)), 0u);

  // records with random K: each stored one's K comes out with stored_o
  std::vector<uint32_t> ks;
  for (uint32_t s = 0; s < 3; ++s) {
    Record r = random_record(rng, s, 1);
    r.K = static_cast<uint32_t>(1 + rng() % 0x01000000);
    ks.push_back(r.K);
    bench.send_record(r);
    EXPECT_ACK(bench.await_answer(), s + 1);
  }
  EXPECT_EQ(bench.stored_ks, ks);
  EXPECT_ACK(bench.transact(0x03, 0), 3u);
  EXPECT_EQ(bench.rtl().run_o, 1u);
  bench.run(3000);
  // FEED while playing (no NAK 5), and STATUS with the unit's state
  if (kScaleWidth != 0) {
    EXPECT_ACK(bench.transact(0x07, 0, feed_payload(4000, 0)), 3u);
    EXPECT_EQ(bench.rtl().hold_o, 0u);
    EXPECT_EQ(bench.rtl().scale_override_o, 4000u);
  }
  const Answer st = bench.transact(0x06, 0);
  ASSERT_TRUE(bench.ok()) << bench.why();
  ASSERT_EQ(st.type, 0x83);
  ASSERT_EQ(st.payload.size(), 48u + 8 * kAxes);
  const uint64_t s_now = get_le(st.payload, 36, 4);
  EXPECT_EQ((s_now - 3) % 7, 0u) << s_now;  // the bench's S = 7 pos + 3
  EXPECT_EQ(get_le(st.payload, 40, 4), 1u);  // starved holds: the bench reports underruns + 1
  EXPECT_GE(get_le(st.payload, 44, 4), 5u);  // ahead: the bench's rest + 5
  ASSERT_TRUE(bench.ok()) << bench.why();
}

}  // namespace
