// SPDX-License-Identifier: Apache-2.0
// Segment stream format v1 (FD records) and v2 (v1 + the BCU format in the
// header + BCU records): round trip, and every corruption or truncation is
// reported with its place (byte offset and segment) while every record before
// it stays accepted; version-1 files are read as before, and a header without
// a BCU format is still written as version 1, byte for byte.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "stream/segment_stream.hpp"

#include <zlib.h>

using namespace traj::stream;

namespace {

Header header() {
  Header h;
  h.axes = 2;
  h.degree = 3;
  h.width = 64;
  h.chunk_width = 16;
  h.guard_bits = 32;
  h.frac_bits = 16;
  h.period = 1e-3;
  h.units = "mm";
  return h;
}

std::vector<Record> records(std::mt19937_64& rng, const Header& h, int n) {
  std::vector<Record> v;
  for (int s = 0; s < n; ++s) {
    Record r;
    r.ticks = 1 + rng() % 1000;
    r.regs.assign(h.axes, std::vector<mpz_class>(h.degree + 1));
    for (auto& ax : r.regs)
      for (auto& x : ax) {
        x = mpz_class(static_cast<long>(rng() >> 2));
        x <<= 1;
        if (rng() & 1) x = -x;
      }
    v.push_back(r);
  }
  // extremes of the range
  v[0].regs[0][0] = -(mpz_class(1) << (h.width - 1));
  v[0].regs[1][0] = (mpz_class(1) << (h.width - 1)) - 1;
  return v;
}

std::vector<uint8_t> encode(const Header& h, const std::vector<Record>& recs) {
  auto all = encode_header(h);
  uint64_t t = 0;
  for (auto& r : recs) {
    auto b = encode_record(h, r);
    all.insert(all.end(), b.begin(), b.end());
    t += r.ticks;
  }
  auto e = encode_end(static_cast<uint32_t>(recs.size()), t);
  all.insert(all.end(), e.begin(), e.end());
  return all;
}

int get_version(const std::vector<uint8_t>& b) { return b[4] | (b[5] << 8); }

}  // namespace

TEST(Stream, RoundTrip) {
  std::mt19937_64 rng(5);
  const Header h = header();
  const auto recs = records(rng, h, 20);
  const auto res = decode(encode(h, recs), "mem");
  ASSERT_TRUE(res.complete) << res.error;
  EXPECT_EQ(res.header.axes, h.axes);
  EXPECT_EQ(res.header.period, h.period);
  EXPECT_EQ(res.header.units, "mm");
  ASSERT_EQ(res.records.size(), recs.size());
  for (size_t i = 0; i < recs.size(); ++i) {
    EXPECT_EQ(res.records[i].ticks, recs[i].ticks);
    EXPECT_EQ(res.records[i].regs, recs[i].regs);
  }
}

TEST(Stream, EverySingleByteCorruptionIsDetected) {
  std::mt19937_64 rng(6);
  const Header h = header();
  const auto recs = records(rng, h, 4);
  const auto good = encode(h, recs);
  const size_t rb = 12 + size_t(h.axes) * (h.degree + 1) * 8;
  for (size_t i = 0; i < good.size(); ++i) {
    for (uint8_t flip : {0x01, 0x80, 0xFF}) {
      auto bad = good;
      bad[i] ^= flip;
      const auto res = decode(bad, "link");
      ASSERT_FALSE(res.complete) << "byte " << i << " flip " << int(flip) << " not detected";
      ASSERT_NE(res.error.find("link: byte "), std::string::npos) << res.error;
      // records wholly before the damaged byte are all accepted
      if (i >= kHeaderBytes) {
        const size_t before = std::min<size_t>((i - kHeaderBytes) / rb, recs.size());
        ASSERT_GE(res.records.size(), before) << "byte " << i << ": " << res.error;
        for (size_t k = 0; k < res.records.size() && k < before; ++k) ASSERT_EQ(res.records[k].regs, recs[k].regs);
      }
    }
  }
}

TEST(Stream, EveryTruncationIsReported) {
  std::mt19937_64 rng(7);
  const Header h = header();
  const auto recs = records(rng, h, 3);
  const auto good = encode(h, recs);
  for (size_t n = 0; n < good.size(); ++n) {
    std::vector<uint8_t> cut(good.begin(), good.begin() + n);
    const auto res = decode(cut, "file.trj");
    ASSERT_FALSE(res.complete) << "length " << n;
    ASSERT_FALSE(res.error.empty());
  }
  auto extra = good;
  extra.push_back(0);
  EXPECT_NE(decode(extra, "f").error.find("trailing"), std::string::npos);
}

TEST(Stream, RefusesToWriteBadContent) {
  const Header h = header();
  Record r;
  r.ticks = 0;
  r.regs.assign(2, std::vector<mpz_class>(4, 0));
  EXPECT_THROW(encode_record(h, r), StreamError);
  r.ticks = 1;
  r.regs[0][0] = mpz_class(1) << 63;  // does not fit 64-bit two's complement
  EXPECT_THROW(encode_record(h, r), StreamError);
  r.regs[0][0] = -(mpz_class(1) << 63) - 1;  // one below the most negative
  EXPECT_THROW(encode_record(h, r), StreamError);
  r.regs[0][0] = -(mpz_class(1) << 63);  // the most negative fits
  EXPECT_NO_THROW(encode_record(h, r));
  Header bad = h;
  bad.period = -1;
  EXPECT_THROW(encode_header(bad), StreamError);
  bad = h;
  bad.units = "a very long unit name";
  EXPECT_THROW(encode_header(bad), StreamError);
}

TEST(Stream, WriteFileIsAtomic) {
  std::mt19937_64 rng(8);
  const Header h = header();
  const std::string path = ::testing::TempDir() + "/trajcore_stream_test.trj";
  write_file(path, h, records(rng, h, 5));
  auto res = read_file(path);
  EXPECT_TRUE(res.complete) << res.error;
  EXPECT_EQ(res.records.size(), 5u);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  EXPECT_THROW(read_file(path + ".missing"), StreamError);
}

// ---------------------------------------------------------------------------
// Version 2: BCU records (type 2) mixed with FD records.
// ---------------------------------------------------------------------------
namespace {

Header header_v2() {
  Header h = header();
  h.axes = 3;
  h.bcu_ctrl_width = 40;
  h.bcu_guard_bits = 9;
  h.bcu_max_depth = 12;
  h.bcu_out_width = h.width - h.guard_bits;
  return h;
}

// FD and BCU records, kinds mixed (both present, every arrangement of
// neighbours), control values at the extremes of CtrlWidth too.
std::vector<Record> mixed_records(std::mt19937_64& rng, const Header& h, int n) {
  auto fd = records(rng, h, n);
  const mpz_class lim = mpz_class(1) << (h.bcu_ctrl_width - 1);
  for (int s = 0; s < n; ++s) {
    if (s % 3 == 0) continue;  // FD, BCU, BCU, FD, ...: every pair of neighbouring kinds
    Record r;
    r.kind = RecordKind::kBcu;
    r.ticks = 1u << (rng() % (h.bcu_max_depth + 1));
    r.regs.assign(h.axes, std::vector<mpz_class>(4));
    for (auto& ax : r.regs)
      for (auto& x : ax) {
        x = mpz_class(static_cast<long>(rng() >> 1)) % lim;
        if (rng() & 1) x = -x;
      }
    r.regs[0][0] = lim - 1;
    r.regs[h.axes - 1][3] = -lim;
    fd[s] = r;
  }
  return fd;
}

// Byte offset of every record (and of the end record, last).
std::vector<size_t> offsets(const Header& h, const std::vector<Record>& recs) {
  std::vector<size_t> o{static_cast<size_t>(header_bytes(h.version()))};
  for (const auto& r : recs) o.push_back(o.back() + record_size(h, r.kind));
  return o;
}

}  // namespace

TEST(StreamV2, RoundTripMixedKinds) {
  std::mt19937_64 rng(15);
  const Header h = header_v2();
  const auto recs = mixed_records(rng, h, 24);
  const auto bytes = encode(h, recs);
  EXPECT_EQ(get_version(bytes), 2);
  EXPECT_EQ(bytes.size(), offsets(h, recs).back() + 16);
  const auto res = decode(bytes, "mem");
  ASSERT_TRUE(res.complete) << res.error;
  EXPECT_TRUE(res.header.has_bcu());
  EXPECT_EQ(res.header.bcu_ctrl_width, 40);
  EXPECT_EQ(res.header.bcu_guard_bits, 9);
  EXPECT_EQ(res.header.bcu_max_depth, 12);
  EXPECT_EQ(res.header.bcu_out_width, 32);
  const traj::bcu::Format bf = res.header.bcu_format();
  EXPECT_EQ(bf.axes, 3);
  EXPECT_EQ(bf.chunk_width, 16);
  EXPECT_EQ(bf.frac_bits, 16);
  ASSERT_EQ(res.records.size(), recs.size());
  size_t nb = 0;
  for (size_t i = 0; i < recs.size(); ++i) {
    EXPECT_EQ(res.records[i].kind, recs[i].kind) << i;
    EXPECT_EQ(res.records[i].ticks, recs[i].ticks) << i;
    EXPECT_EQ(res.records[i].regs, recs[i].regs) << i;
    nb += recs[i].is_bcu();
  }
  EXPECT_GE(nb, 8u);
  EXPECT_LT(nb, recs.size());
}

TEST(StreamV2, VersionOneIsStillWrittenAndRead) {
  // No BCU format: version 1, 48-byte header, exactly the v1 layout.
  std::mt19937_64 rng(16);
  const Header h = header();
  const auto bytes = encode(h, records(rng, h, 3));
  EXPECT_EQ(get_version(bytes), 1);
  EXPECT_EQ(bytes[6] | (bytes[7] << 8), kHeaderBytes);
  EXPECT_EQ(bytes.size(), size_t(kHeaderBytes) + 3 * record_size(h, RecordKind::kFd) + 16);
  const auto res = decode(bytes, "v1.trj");
  ASSERT_TRUE(res.complete) << res.error;
  EXPECT_FALSE(res.header.has_bcu());
  EXPECT_THROW(res.header.bcu_format(), StreamError);
}

TEST(StreamV2, EverySingleByteCorruptionIsDetected) {
  std::mt19937_64 rng(17);
  const Header h = header_v2();
  const auto recs = mixed_records(rng, h, 6);
  const auto good = encode(h, recs);
  const auto off = offsets(h, recs);
  for (size_t i = 0; i < good.size(); ++i) {
    // the record the byte belongs to (recs.size(): the end record; -1: header)
    long owner = -1;
    for (size_t k = 0; k + 1 < off.size(); ++k)
      if (i >= off[k] && i < off[k + 1]) owner = static_cast<long>(k);
    if (i >= off.back()) owner = static_cast<long>(recs.size());
    for (uint8_t flip : {0x01, 0x02, 0x80, 0xFF}) {
      auto bad = good;
      bad[i] ^= flip;
      const auto res = decode(bad, "link");
      ASSERT_FALSE(res.complete) << "byte " << i << " flip " << int(flip) << " not detected";
      ASSERT_NE(res.error.find("link: byte "), std::string::npos) << res.error;
      if (owner < 0) continue;
      // every record wholly before the damaged one is accepted, unchanged
      ASSERT_GE(res.records.size(), static_cast<size_t>(owner)) << "byte " << i << ": " << res.error;
      for (long k = 0; k < owner; ++k) {
        ASSERT_EQ(res.records[k].kind, recs[k].kind);
        ASSERT_EQ(res.records[k].regs, recs[k].regs);
      }
      // a damaged segment record is named: its index and its first byte
      if (owner < static_cast<long>(recs.size())) {
        const std::string want = "link: byte " + std::to_string(off[owner]);
        const std::string seg = "segment " + std::to_string(owner) + ": ";
        ASSERT_NE(res.error.find(seg), std::string::npos) << "byte " << i << ": " << res.error;
        ASSERT_EQ(res.records.size(), static_cast<size_t>(owner)) << res.error;
        ASSERT_NE(res.error.find("byte " + std::to_string(off[owner])), std::string::npos)
            << "byte " << i << ": " << res.error;
      }
    }
  }
}

TEST(StreamV2, EveryTruncationIsReported) {
  std::mt19937_64 rng(18);
  const Header h = header_v2();
  const auto recs = mixed_records(rng, h, 5);
  const auto good = encode(h, recs);
  const auto off = offsets(h, recs);
  for (size_t n = 0; n < good.size(); ++n) {
    std::vector<uint8_t> cut(good.begin(), good.begin() + n);
    const auto res = decode(cut, "file.trj");
    ASSERT_FALSE(res.complete) << "length " << n;
    ASSERT_NE(res.error.find("file.trj: byte "), std::string::npos) << res.error;
    // every record wholly inside the cut is kept
    size_t whole = 0;
    while (whole < recs.size() && off[whole + 1] <= n) ++whole;
    ASSERT_EQ(res.records.size(), whole) << "length " << n << ": " << res.error;
  }
}

namespace {
// Re-seal a record's CRC after editing its content (to reach the content checks).
void reseal(std::vector<uint8_t>& b, size_t off, size_t rb) {
  const uint32_t c = static_cast<uint32_t>(crc32(crc32(0L, Z_NULL, 0), &b[off], static_cast<uInt>(rb - 4)));
  for (int i = 0; i < 4; ++i) b[off + rb - 4 + i] = static_cast<uint8_t>(c >> (8 * i));
}
}  // namespace

TEST(StreamV2, BcuContentChecksNameTheField) {
  std::mt19937_64 rng(19);
  const Header h = header_v2();
  auto recs = mixed_records(rng, h, 3);  // FD, BCU, BCU
  ASSERT_TRUE(recs[1].is_bcu());
  const auto good = encode(h, recs);
  const auto off = offsets(h, recs);
  const size_t rb = record_size(h, RecordKind::kBcu);
  {  // K = 100: not a power of two
    auto bad = good;
    bad[off[1] + 4] = 100;
    bad[off[1] + 5] = bad[off[1] + 6] = bad[off[1] + 7] = 0;
    reseal(bad, off[1], rb);
    const auto res = decode(bad, "f.trj");
    EXPECT_EQ(res.error, "f.trj: byte " + std::to_string(off[1] + 4) +
                             ": segment 1: BCU K=100 is not 2^d with d <= MaxDepth 12");
    EXPECT_EQ(res.records.size(), 1u);
  }
  {  // K = 2^13 > 2^MaxDepth
    auto bad = good;
    bad[off[1] + 4] = 0;
    bad[off[1] + 5] = 0x20;
    bad[off[1] + 6] = bad[off[1] + 7] = 0;
    reseal(bad, off[1], rb);
    EXPECT_NE(decode(bad, "f").error.find("segment 1: BCU K=8192 is not 2^d with d <= MaxDepth 12"),
              std::string::npos);
  }
  // A value beyond CtrlWidth: with CtrlWidth 36 a 5-byte field can hold more.
  Header n = h;
  n.bcu_ctrl_width = 36;  // 5 bytes per value, 36 bits allowed
  auto recs36 = recs;
  for (auto& r : recs36)
    if (r.is_bcu())
      for (auto& ax : r.regs)
        for (auto& x : ax) x >>= 4;  // within 36 bits
  const auto good36 = encode(n, recs36);
  const auto off36 = offsets(n, recs36);
  auto bad = good36;
  const size_t p = off36[1] + 8 + (1 * 4 + 2) * 5;
  bad[p + 4] = 0x10;  // bit 36 set, sign bit of 40 clear: 2^36 + ... does not fit 36 bits
  reseal(bad, off36[1], record_size(n, RecordKind::kBcu));
  const auto res = decode(bad, "f.trj");
  EXPECT_EQ(res.error.rfind("f.trj: byte " + std::to_string(p) + ": segment 1: axis 1 control value c2 = ", 0), 0u)
      << res.error;
  EXPECT_NE(res.error.find("does not fit CtrlWidth 36 bits"), std::string::npos) << res.error;
  EXPECT_EQ(res.records.size(), 1u);
}

TEST(StreamV2, BcuRecordNeedsVersionTwo) {
  // A type-2 record in a version-1 stream (sealed, so only the type check can catch it).
  std::mt19937_64 rng(20);
  const Header h2 = header_v2();
  const auto recs = mixed_records(rng, h2, 3);
  Header h1 = h2;
  h1.bcu_ctrl_width = 0;
  auto bytes = encode_header(h1);
  const auto fd0 = encode_record(h1, recs[0]);
  bytes.insert(bytes.end(), fd0.begin(), fd0.end());
  const auto bc = encode_record(h2, recs[1]);
  bytes.insert(bytes.end(), bc.begin(), bc.end());
  const auto e = encode_end(2, recs[0].ticks + recs[1].ticks);
  bytes.insert(bytes.end(), e.begin(), e.end());
  const auto res = decode(bytes, "old.trj");
  EXPECT_EQ(res.error, "old.trj: byte " + std::to_string(kHeaderBytes + fd0.size()) +
                           ": segment 1: record type 2 (BCU segment) in a version-1 stream, whose header has no "
                           "BCU format");
  EXPECT_EQ(res.records.size(), 1u);
}

TEST(StreamV2, BadBcuHeaderIsRefused) {
  Header h = header_v2();
  h.bcu_out_width = 40;  // a valid BCU width, but not the FD sample width 32
  EXPECT_THROW(encode_header(h), StreamError);
  h = header_v2();
  h.bcu_ctrl_width = 200;
  EXPECT_THROW(encode_header(h), StreamError);
  // sealed v2 headers with a bad BCU field: named at the field's byte
  auto sealed = [](size_t at, uint8_t v) {
    auto bytes = encode(header_v2(), {});
    bytes[at] = v;
    const uint32_t c = static_cast<uint32_t>(crc32(crc32(0L, Z_NULL, 0), bytes.data(), 60));
    for (int i = 0; i < 4; ++i) bytes[60 + i] = static_cast<uint8_t>(c >> (8 * i));
    return decode(bytes, "h.trj").error;
  };
  EXPECT_EQ(sealed(50, 40), "h.trj: byte 50: header: BCU OutWidth 40 differs from the FD sample width 32 (width - "
                            "guard bits): one sample port");
  EXPECT_EQ(sealed(50, 30), "h.trj: byte 50: header: BCU format: traj::bcu: Format.out_width = 30 out of range 32..64");
  EXPECT_EQ(sealed(48, 31), "h.trj: byte 48: header: BCU format: traj::bcu: Format.max_depth = 31 out of range 1..30");
  EXPECT_EQ(sealed(46, 39), "h.trj: byte 46: header: BCU format: traj::bcu: Format.guard_bits = 39 out of range 0..38");
  EXPECT_EQ(sealed(44, 0), "h.trj: byte 44: header: version 2 without a BCU format (CtrlWidth 0)");
}

TEST(StreamV2, RefusesToWriteBadBcuContent) {
  const Header h = header_v2();
  Record r;
  r.kind = RecordKind::kBcu;
  r.ticks = 6;  // not 2^d
  r.regs.assign(3, std::vector<mpz_class>(4, 0));
  EXPECT_THROW(encode_record(h, r), StreamError);
  r.ticks = 1u << 13;  // d > MaxDepth
  EXPECT_THROW(encode_record(h, r), StreamError);
  r.ticks = 1;  // d = 0 is fine
  EXPECT_NO_THROW(encode_record(h, r));
  r.regs[2][1] = mpz_class(1) << 39;  // beyond 40-bit two's complement
  EXPECT_THROW(encode_record(h, r), StreamError);
  r.regs[2][1] = 0;
  EXPECT_THROW(encode_record(header(), r), StreamError);  // no BCU format in the header
}

TEST(StreamV2, WriterAndFileReadMixed) {
  std::mt19937_64 rng(21);
  const Header h = header_v2();
  const auto recs = mixed_records(rng, h, 7);
  const std::string path = ::testing::TempDir() + "/trajcore_stream_v2.trj";
  {
    StreamWriter w(path, h);
    for (const auto& r : recs) w.add(r);
    w.finish();
  }
  const auto res = read_file(path);
  ASSERT_TRUE(res.complete) << res.error;
  ASSERT_EQ(res.records.size(), recs.size());
  for (size_t i = 0; i < recs.size(); ++i) EXPECT_EQ(res.records[i].regs, recs[i].regs);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}
