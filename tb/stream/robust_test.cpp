// Header errors name the byte of the field at fault; a one-tick quintic whose exact difference
// registers need more than the register width streams with its registers wrapped to the width (the
// engine's adders wrap) and reads back, chained; a value beyond the width is refused naming segment,
// axis and register. References: the header table of host/stream/README.md, the engine's recurrence
// on exact integers reduced to Width bits written here, and x(t) of the test's own polynomial.
#include <gtest/gtest.h>

#include <zlib.h>

#include <cstring>

#include "fd/fd_compiler.hpp"
#include "stream/segment_stream.hpp"

using namespace traj;
using namespace traj::stream;

namespace {
std::vector<uint8_t> stream_of(const Header& h, const std::vector<Record>& recs) {
  std::vector<uint8_t> b = encode_header(h);
  uint64_t ticks = 0;
  for (size_t i = 0; i < recs.size(); ++i) {
    Record r = recs[i];
    r.seq = static_cast<uint32_t>(i);
    const auto e = encode_record(h, r);
    b.insert(b.end(), e.begin(), e.end());
    ticks += r.ticks;
  }
  const auto e = encode_end(static_cast<uint32_t>(recs.size()), ticks);
  b.insert(b.end(), e.begin(), e.end());
  return b;
}

void put_le(std::vector<uint8_t>& b, size_t off, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) b[off + i] = static_cast<uint8_t>(v >> (8 * i));
}
void fix_header_crc(std::vector<uint8_t>& b) {
  put_le(b, 60, crc32(crc32(0L, Z_NULL, 0), b.data(), 60), 4);
}

fd::Format quintic96() {
  fd::Format f;
  f.axes = 1;
  f.degree = 5;
  f.width = 96;
  f.chunk_width = 16;
  f.guard_bits = 48;
  f.frac_bits = 32;
  return f;
}

// The engine's r0 after k ticks: r[i] += r[i+1] on Width-bit two's complement registers.
mpz_class engine_r0(std::vector<mpz_class> r, uint64_t k, int width) {
  const mpz_class mod = mpz_class(1) << width, half = mpz_class(1) << (width - 1);
  auto wrap = [&](mpz_class& v) {
    v %= mod;  // truncating: |v| < mod
    if (v < 0) v += mod;
    if (v >= half) v -= mod;
  };
  for (auto& v : r) wrap(v);
  for (uint64_t t = 0; t < k; ++t)
    for (size_t i = 0; i + 1 < r.size(); ++i) {
      r[i] += r[i + 1];
      wrap(r[i]);
    }
  return r[0];
}
}  // namespace

TEST(StreamHeaderFields, EachFormatErrorNamesItsFieldsByte) {
  Header h;
  h.axes = 2;
  h.degree = 3;
  h.width = 64;
  h.chunk_width = 16;
  h.guard_bits = 32;
  h.frac_bits = 16;
  h.period = 1e-3;
  h.units = "mm";
  Record r;
  r.ticks = 4;
  r.regs.assign(2, std::vector<mpz_class>(4, 0));
  const std::vector<uint8_t> good = stream_of(h, {r});
  ASSERT_TRUE(decode(good, "h.trj").complete);
  struct Bad {
    size_t off;
    uint64_t value;
    int bytes;
  };
  // header table: axes u8 @8, degree u8 @9, width u16 @10, chunk u16 @12, guard u16 @14, frac i16 @16
  const Bad bad[] = {{8, 9, 1}, {8, 0, 1}, {9, 8, 1}, {10, 200, 2}, {12, 24, 2}, {14, 0, 2}, {14, 63, 2}, {16, 100, 2}};
  for (const Bad& x : bad) {
    std::vector<uint8_t> b = good;
    put_le(b, x.off, x.value, x.bytes);
    fix_header_crc(b);
    const ReadResult res = decode(b, "h.trj");
    EXPECT_FALSE(res.complete);
    EXPECT_EQ(res.error.rfind("h.trj: byte " + std::to_string(x.off) + ": ", 0), 0u)
        << "field at " << x.off << " = " << x.value << ": " << res.error;
  }
}

TEST(StreamHeaderFields, TickPeriodShownExactly) {
  Header h = Header::from(quintic96(), -1.0000001e-9, "mm");
  try {
    encode_header(h);
    FAIL() << "accepted";
  } catch (const StreamError& e) {
    EXPECT_NE(std::string(e.what()).find("tick period -1.0000001e-09 s"), std::string::npos) << e.what();
  }
}

// x(t) = 1e4 t^5 mm over one 1-s tick: r[5] = 120 * 1e4 * 2^(F+G) = 2^100.2 exactly needs 102 bits of a
// 96-bit register, while every sample (0 and 1e4 mm) is inside the output range.
TEST(StreamWrappedRegisters, OneTickQuinticStreamsChainedAndExact) {
  const fd::Format f = quintic96();
  const fd::Compiler comp(f);
  fd::PolySegment s1;
  s1.h = 1.0;
  s1.ticks = 1;
  s1.coef = {{0, 0, 0, 0, 0, 1e4}};
  const fd::Compiled c1 = comp.compile(s1);
  const mpz_class lim = mpz_class(1) << (f.width - 1);
  for (const auto& v : c1.regs[0]) EXPECT_TRUE(v >= -lim && v < lim) << v.get_str();
  // the engine's samples, from the streamed registers, equal x(k) 2^F (rounded to nearest: exact here)
  const mpz_class want1 = mpz_class(10000) << f.frac_bits;
  mpz_class r0 = engine_r0(c1.regs[0], 1, f.width);
  mpz_fdiv_q_2exp(r0.get_mpz_t(), r0.get_mpz_t(), f.guard_bits);
  EXPECT_EQ(r0, want1);
  EXPECT_EQ(comp.sample_at(c1, 0, 1), want1);
  EXPECT_EQ(comp.sample_at(c1, 0, 0), 0);
  // chained: the next segment (at rest at 1e4 mm) starts at c1.end; the stream is written and read back
  fd::PolySegment s2;
  s2.h = 1.0;
  s2.ticks = 3;
  s2.coef = {{1e4}};
  const fd::Compiled c2 = comp.compile(s2, &c1.end);
  const Header h = Header::from(f, 1.0, "mm");
  const ReadResult res = decode(stream_of(h, {{c1.ticks, c1.regs}, {c2.ticks, c2.regs}}), "q.trj");
  ASSERT_TRUE(res.complete) << res.error;
  ASSERT_EQ(res.records.size(), 2u);
  EXPECT_EQ(res.records[0].regs, c1.regs);
}

TEST(StreamWrappedRegisters, ValueBeyondTheWidthNamesSegmentAxisRegister) {
  const Header h = Header::from(quintic96(), 1e-3, "mm");
  Record r;
  r.ticks = 1;
  r.seq = 7;
  r.regs.assign(1, std::vector<mpz_class>(6, 0));
  r.regs[0][5] = mpz_class(1) << 100;
  try {
    encode_record(h, r);
    FAIL() << "accepted";
  } catch (const StreamError& e) {
    EXPECT_EQ(std::string(e.what()), "segment 7: axis 0: r[5] = " + r.regs[0][5].get_str() +
                                         " needs 102 bits, the register width is 96");
  }
}
