// SPDX-License-Identifier: Apache-2.0
// Segment stream format version 4 (FD records; BCU records when the header
// carries a BCU format; every record numbered): round trip, every corruption
// or truncation reported with its place (byte offset and segment) while every
// record before it stays accepted, and every record that is out of order,
// repeated, beyond the format's bounds, with nonzero reserved bits, or that
// does not start where the previous one ends, refused with its place.
// The test streams are chained by the test itself (the FD end by running the
// difference recurrence tick by tick; the kind hand-offs from bcu/chain.hpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <limits>
#include <random>

#include "stream/segment_stream.hpp"
#include "tmp_file.hpp"
#include "util/atomic_file.hpp"

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

// Where the engine is after a record: FD r0 after K ticks of the difference
// recurrence; BCU c_D.
std::vector<mpz_class> end_of(const Record& r) {
  std::vector<mpz_class> e;
  for (auto x : r.regs) {
    if (r.is_bcu()) {
      e.push_back(x[3]);
      continue;
    }
    for (uint32_t k = 0; k < r.ticks; ++k)
      for (size_t i = 0; i + 1 < x.size(); ++i) x[i] += x[i + 1];
    e.push_back(x[0]);
  }
  return e;
}

mpz_class floor_shift(const mpz_class& v, int e) {  // floor(v 2^e)
  mpz_class r;
  if (e >= 0) return v * (mpz_class(1) << e);
  mpz_fdiv_q_2exp(r.get_mpz_t(), v.get_mpz_t(), static_cast<mp_bitcnt_t>(-e));
  return r;
}

// The start the record after `prev` must have (bcu/chain.hpp's hand-offs).
mpz_class start_after(const Header& h, const Record& prev, const mpz_class& end, RecordKind next) {
  const int gf = h.guard_bits, gb = h.bcu_guard_bits;
  if (next == RecordKind::kFd) return prev.is_bcu() ? floor_shift(end, gf - gb) + (mpz_class(1) << (gf - 1)) : end;
  return prev.is_bcu() ? end : floor_shift(end, gb - gf) - (gb > 0 ? mpz_class(1) << (gb - 1) : mpz_class(0));
}

mpz_class signed_random(std::mt19937_64& rng, int bits) {
  mpz_class x = mpz_class(static_cast<unsigned long>(rng() >> (64 - bits)));
  return (rng() & 1) ? mpz_class(-x) : x;
}

// Records of the given kinds ('F' FD, 'B' BCU), numbered 0, 1, ..., each
// starting where the previous one ends.
std::vector<Record> chained(std::mt19937_64& rng, const Header& h, const std::string& kinds) {
  std::vector<Record> v;
  for (size_t s = 0; s < kinds.size(); ++s) {
    Record r;
    r.seq = static_cast<uint32_t>(s);
    if (kinds[s] == 'B') {
      r.kind = RecordKind::kBcu;
      r.ticks = 1u << (rng() % (h.bcu_max_depth + 1));
      r.regs.assign(h.axes, std::vector<mpz_class>(4));
      for (auto& ax : r.regs)
        for (auto& x : ax) x = signed_random(rng, h.bcu_ctrl_width - 3);
    } else {
      r.ticks = 1 + rng() % 1000;
      r.regs.assign(h.axes, std::vector<mpz_class>(h.degree + 1));
      for (auto& ax : r.regs) {
        ax[0] = signed_random(rng, h.width - 4);
        for (int i = 1; i <= h.degree; ++i) ax[i] = signed_random(rng, 20);
      }
    }
    if (s > 0) {
      const auto e = end_of(v.back());
      for (int a = 0; a < h.axes; ++a) r.regs[a][0] = start_after(h, v.back(), e[a], r.kind);
    }
    v.push_back(r);
  }
  return v;
}

std::vector<Record> records(std::mt19937_64& rng, const Header& h, int n) {
  return chained(rng, h, std::string(static_cast<size_t>(n), 'F'));
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

Header header_v2();
Header header_v2_fwd() { return header_v2(); }

size_t fd_record_bytes(const Header& h) { return 16 + size_t(h.axes) * (h.degree + 1) * (h.width / 8); }

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
  const size_t rb = fd_record_bytes(h);
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
  bad.units = "furlong";
  EXPECT_THROW(encode_header(bad), StreamError);
  r.ticks = 1u << 20;  // the bound itself is fine
  EXPECT_NO_THROW(encode_record(h, r));
  r.ticks = (1u << 20) + 1;
  EXPECT_THROW(encode_record(h, r), StreamError);
}

TEST(Stream, ExtremeValuesRoundTrip) {
  // One record each (no predecessor to start from): the ends of the ranges.
  Header h = header_v2_fwd();
  Record f;
  f.ticks = 1;
  f.regs.assign(h.axes, std::vector<mpz_class>(h.degree + 1, 0));
  f.regs[0][0] = -(mpz_class(1) << (h.width - 1));
  f.regs[1][3] = (mpz_class(1) << (h.width - 1)) - 1;
  Record b;
  b.kind = RecordKind::kBcu;
  b.ticks = 1u << h.bcu_max_depth;
  const mpz_class lim = mpz_class(1) << (h.bcu_ctrl_width - 1);
  b.regs.assign(h.axes, std::vector<mpz_class>(4, 0));
  b.regs[0][0] = lim - 1;
  b.regs[h.axes - 1][3] = -lim;
  for (const Record& r : {f, b}) {
    const auto res = decode(encode(h, {r}), "mem");
    ASSERT_TRUE(res.complete) << res.error;
    EXPECT_EQ(res.records[0].regs, r.regs);
  }
}

TEST(Stream, WriteFileIsAtomic) {
  std::mt19937_64 rng(8);
  const Header h = header();
  const traj::test::TmpFile tmp("trajcore_stream_test.trj");
  const std::string& path = tmp.path;
  write_file(path, h, records(rng, h, 5));
  auto res = read_file(path);
  EXPECT_TRUE(res.complete) << res.error;
  EXPECT_EQ(res.records.size(), 5u);
  EXPECT_FALSE(std::filesystem::exists(traj::util::temporary_path(path)));
  EXPECT_THROW(read_file(path + ".missing"), StreamError);
}

// ---------------------------------------------------------------------------
// BCU records (type 2) mixed with FD records.
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

// FD and BCU records, kinds mixed: FD, BCU, BCU, FD, ... (every pair of neighbouring kinds).
std::vector<Record> mixed_records(std::mt19937_64& rng, const Header& h, int n) {
  std::string kinds;
  for (int s = 0; s < n; ++s) kinds += s % 3 == 0 ? 'F' : 'B';
  return chained(rng, h, kinds);
}

// Byte offset of every record (and of the end record, last).
std::vector<size_t> offsets(const Header& h, const std::vector<Record>& recs) {
  std::vector<size_t> o{static_cast<size_t>(kHeaderBytes)};
  for (const auto& r : recs) o.push_back(o.back() + record_size(h, r.kind));
  return o;
}

}  // namespace

TEST(StreamV2, RoundTripMixedKinds) {
  std::mt19937_64 rng(15);
  const Header h = header_v2();
  const auto recs = mixed_records(rng, h, 24);
  const auto bytes = encode(h, recs);
  EXPECT_EQ(get_version(bytes), 4);
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

TEST(StreamV2, FdOnlyHeaderIsVersionFourWithZeroBcuFields) {
  std::mt19937_64 rng(16);
  const Header h = header();
  const auto bytes = encode(h, records(rng, h, 3));
  EXPECT_EQ(get_version(bytes), 4);
  EXPECT_EQ(bytes[6] | (bytes[7] << 8), 64);
  for (int i = 44; i < 60; ++i) EXPECT_EQ(bytes[i], 0) << i;
  EXPECT_EQ(bytes.size(), 64 + 3 * fd_record_bytes(h) + 16);
  const auto res = decode(bytes, "v3.trj");
  ASSERT_TRUE(res.complete) << res.error;
  EXPECT_FALSE(res.header.has_bcu());
  EXPECT_THROW(res.header.bcu_format(), StreamError);
}

TEST(StreamV2, OlderVersionsAreRefusedByName) {
  for (int v : {1, 2, 3, 5}) {
    auto bytes = encode(header(), {});
    bytes[4] = static_cast<uint8_t>(v);
    EXPECT_EQ(decode(bytes, "old.trj").error,
              "old.trj: byte 4: unsupported version " + std::to_string(v) +
                  " (this reader reads version 4 only: write the stream again with this trajcore)");
  }
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
  const size_t p = off36[1] + 12 + (1 * 4 + 2) * 5;
  bad[p + 4] = 0x10;  // bit 36 set, sign bit of 40 clear: 2^36 + ... does not fit 36 bits
  reseal(bad, off36[1], record_size(n, RecordKind::kBcu));
  const auto res = decode(bad, "f.trj");
  EXPECT_EQ(res.error.rfind("f.trj: byte " + std::to_string(p) + ": segment 1: axis 1 control value c2 = ", 0), 0u)
      << res.error;
  EXPECT_NE(res.error.find("does not fit CtrlWidth 36 bits"), std::string::npos) << res.error;
  EXPECT_EQ(res.records.size(), 1u);
}

TEST(StreamV2, BcuRecordNeedsABcuFormat) {
  // A type-2 record in a stream without a BCU format (sealed, so only the type check can catch it).
  std::mt19937_64 rng(20);
  const Header h2 = header_v2();
  const auto recs = mixed_records(rng, h2, 3);
  Header h1 = h2;
  h1.bcu_ctrl_width = h1.bcu_guard_bits = h1.bcu_max_depth = h1.bcu_out_width = 0;
  auto bytes = encode_header(h1);
  const auto fd0 = encode_record(h1, recs[0]);
  bytes.insert(bytes.end(), fd0.begin(), fd0.end());
  const auto bc = encode_record(h2, recs[1]);
  bytes.insert(bytes.end(), bc.begin(), bc.end());
  const auto e = encode_end(2, recs[0].ticks + recs[1].ticks);
  bytes.insert(bytes.end(), e.begin(), e.end());
  const auto res = decode(bytes, "fd.trj");
  EXPECT_EQ(res.error, "fd.trj: byte " + std::to_string(64 + fd0.size()) +
                           ": segment 1: record type 2 (BCU segment) in a stream whose header has no BCU format");
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
    reseal(bytes, 0, 64);
    return decode(bytes, "h.trj").error;
  };
  EXPECT_EQ(sealed(50, 40), "h.trj: byte 50: header: BCU OutWidth 40 differs from the FD sample width 32 (width - "
                            "guard bits): one sample port");
  EXPECT_EQ(sealed(50, 30), "h.trj: byte 50: header: BCU format: traj::bcu: Format.out_width = 30 out of range 32..64");
  EXPECT_EQ(sealed(48, 31), "h.trj: byte 48: header: BCU format: traj::bcu: Format.max_depth = 31 out of range 1..30");
  EXPECT_EQ(sealed(46, 39), "h.trj: byte 46: header: BCU format: traj::bcu: Format.guard_bits = 39 out of range 0..38");
  EXPECT_EQ(sealed(44, 0), "h.trj: byte 46: header: BCU field nonzero (0x09) with CtrlWidth 0 (no BCU format)");
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
  const traj::test::TmpFile tmp("trajcore_stream_v2.trj");
  const std::string& path = tmp.path;
  {
    StreamWriter w(path, h);
    for (const auto& r : recs) w.add(r);
    w.finish();
  }
  const auto res = read_file(path);
  ASSERT_TRUE(res.complete) << res.error;
  ASSERT_EQ(res.records.size(), recs.size());
  for (size_t i = 0; i < recs.size(); ++i) EXPECT_EQ(res.records[i].regs, recs[i].regs);
  EXPECT_FALSE(std::filesystem::exists(traj::util::temporary_path(path)));
}

// ---------------------------------------------------------------------------
// Integrity: order, bounds, reserved fields, codes, continuity.
// ---------------------------------------------------------------------------
namespace {

void put32(std::vector<uint8_t>& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<uint8_t>(v >> (8 * i));
}

// The stream of `recs` as they are (their seq fields), with a consistent end record.
std::vector<uint8_t> as_given(const Header& h, const std::vector<Record>& recs) { return encode(h, recs); }

struct Fixture {
  Header h = header();
  std::vector<Record> recs;
  std::vector<uint8_t> good;
  size_t rb = 0;
  Fixture() {
    std::mt19937_64 rng(30);
    recs = records(rng, h, 5);
    good = encode(h, recs);
    rb = fd_record_bytes(h);
  }
  size_t off(size_t i) const { return 64 + i * rb; }
  // Edit record i's bytes, re-seal its checksum, decode.
  ReadResult edited(size_t i, const std::function<void(std::vector<uint8_t>&, size_t)>& edit) const {
    auto b = good;
    edit(b, off(i));
    reseal(b, off(i), rb);
    return decode(b, "plan.trj");
  }
};

}  // namespace

TEST(StreamIntegrity, SwappedRecordsAreRefused) {
  Fixture f;
  auto recs = f.recs;
  std::swap(recs[1], recs[2]);
  const auto res = decode(as_given(f.h, recs), "plan.trj");
  EXPECT_EQ(res.error, "plan.trj: byte " + std::to_string(f.off(1) + 8) + ": segment 1: sequence number 2, expected 1");
  ASSERT_EQ(res.records.size(), 1u);
  EXPECT_EQ(res.records[0].regs, f.recs[0].regs);
}

TEST(StreamIntegrity, DuplicatedRecordIsRefused) {
  // the end record counts the duplicate (encode() recomputes it), every CRC holds
  Fixture f;
  auto recs = f.recs;
  recs.insert(recs.begin() + 2, recs[1]);
  const auto res = decode(as_given(f.h, recs), "plan.trj");
  EXPECT_EQ(res.error, "plan.trj: byte " + std::to_string(f.off(2) + 8) + ": segment 2: sequence number 1, expected 2");
  EXPECT_EQ(res.records.size(), 2u);
  // the first record must be 0
  auto late = f.recs;
  for (auto& r : late) r.seq += 7;
  EXPECT_EQ(decode(as_given(f.h, late), "plan.trj").error,
            "plan.trj: byte " + std::to_string(f.off(0) + 8) + ": segment 0: sequence number 7, expected 0");
}

TEST(StreamIntegrity, KBeyondTheBoundIsRefusedAtOnce) {
  Fixture f;
  for (uint32_t k : {0xFFFFFFFFu, 1u << 26, (1u << 20) + 1}) {
    const auto res = f.edited(3, [&](std::vector<uint8_t>& b, size_t o) { put32(b, o + 4, k); });
    EXPECT_EQ(res.error, "plan.trj: byte " + std::to_string(f.off(3) + 4) + ": segment 3: K=" + std::to_string(k) +
                             " ticks, beyond the format's bound 2^20 = 1048576");
    EXPECT_EQ(res.records.size(), 3u);
  }
  const auto zero = f.edited(3, [&](std::vector<uint8_t>& b, size_t o) { put32(b, o + 4, 0); });
  EXPECT_EQ(zero.error, "plan.trj: byte " + std::to_string(f.off(3) + 4) + ": segment 3: K=0 ticks");
}

TEST(StreamIntegrity, NonzeroFlagsAndReservedAreRefused) {
  Fixture f;
  EXPECT_EQ(f.edited(2, [](std::vector<uint8_t>& b, size_t o) { b[o + 1] = 0x40; }).error,
            "plan.trj: byte " + std::to_string(f.off(2) + 1) + ": segment 2: flags 0x40, must be 0");
  EXPECT_EQ(f.edited(2, [](std::vector<uint8_t>& b, size_t o) { b[o + 3] = 0x01; }).error,
            "plan.trj: byte " + std::to_string(f.off(2) + 3) + ": segment 2: reserved byte 0x01, must be 0");
  // the end record's reserved byte
  auto b = f.good;
  const size_t e = f.off(f.recs.size());
  b[e + 2] = 0x10;
  reseal(b, e, 16);
  EXPECT_EQ(decode(b, "plan.trj").error, "plan.trj: byte " + std::to_string(e + 2) +
                                             ": end record: reserved byte 0x10, must be 0");
  // the header's time-scaling fields (s_max at 18, the ramp bounds at 52
  // and 56): bounds without s_max, s_max without bounds, s_max above 2
  const std::pair<size_t, std::string> bad_scale[] = {
      {52, "byte 52: header: time-scaling ramp bounds without s_max (bytes 18-19 are 0)"},
      {59, "byte 59: header: time-scaling ramp bounds without s_max (bytes 18-19 are 0)"},
      {18, "byte 52: header: time-scaling ramp bounds |ds/dt| <= 0, |d2s/dt2| <= 0: must be finite and positive"},
      {19, "byte 18: header: time-scaling s_max 8: must be in [1/4096, 2]"}};
  for (const auto& [at, msg] : bad_scale) {
    auto hb = f.good;
    hb[at] = 0x80;
    reseal(hb, 0, 64);
    const auto res = decode(hb, "plan.trj");
    EXPECT_EQ(res.error, "plan.trj: " + msg);
    EXPECT_TRUE(res.records.empty());
  }
}

TEST(StreamIntegrity, TimeScalingFieldsRoundTrip) {
  Header h = header();
  h.scale_max = 1.2;  // written rounded down to 4915/4096
  h.scale_rate = 5.125f;
  h.scale_accel = 196.5f;
  const auto res = decode(encode(h, {}), "ts.trj");
  ASSERT_TRUE(res.complete) << res.error;
  EXPECT_EQ(res.header.scale_max, 4915.0 / 4096);
  EXPECT_EQ(res.header.scale_rate, 5.125f);
  EXPECT_EQ(res.header.scale_accel, 196.5f);
  h.scale_accel = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(encode(h, {}), StreamError);
  h.scale_accel = 1;
  h.scale_max = 2.5;
  EXPECT_THROW(encode(h, {}), StreamError);
}

TEST(StreamIntegrity, UnknownUnitsAndRecordTypeAreRefused) {
  Fixture f;
  auto b = f.good;
  b[28] = 'x';  // "xm"
  reseal(b, 0, 64);
  EXPECT_EQ(decode(b, "plan.trj").error,
            "plan.trj: byte 28: header: units 'xm' unknown (known: mm, um, m, in, deg, rad)");
  b = f.good;
  b[40] = 'z';  // after the NUL of "mm"
  reseal(b, 0, 64);
  EXPECT_EQ(decode(b, "plan.trj").error, "plan.trj: byte 40: header: units padding byte 0x7A, must be 0");
  for (uint8_t type : {0x00, 0x03, 0x7E}) {
    const auto res = f.edited(2, [&](std::vector<uint8_t>& bb, size_t o) { bb[o] = type; });
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02X", type);
    EXPECT_EQ(res.error, "plan.trj: byte " + std::to_string(f.off(2)) + ": segment 2: unknown record type " + hex);
    EXPECT_EQ(res.records.size(), 2u);
  }
}

TEST(StreamIntegrity, AJumpInPositionIsRefused) {
  Fixture f;
  const size_t per_axis = size_t(f.h.degree + 1) * (f.h.width / 8);
  // axis 1's r[0] of segment 3, one register LSB off (CRC re-sealed)
  const auto res = f.edited(3, [&](std::vector<uint8_t>& b, size_t o) { b[o + 12 + per_axis] ^= 1; });
  const std::string want = "plan.trj: byte " + std::to_string(f.off(3) + 12 + per_axis) +
                           ": segment 3: axis 1 starts at r[0] = ";
  EXPECT_EQ(res.error.rfind(want, 0), 0u) << res.error;
  EXPECT_NE(res.error.find("not where the previous segment ends (" + end_of(f.recs[2])[1].get_str() + ")"),
            std::string::npos)
      << res.error;
  EXPECT_EQ(res.records.size(), 3u);
  // the writers refuse it before writing
  auto recs = f.recs;
  recs[3].regs[0][0] += 1;
  const std::string path = ::testing::TempDir() + "/trajcore_jump.trj";
  std::filesystem::remove(path);
  EXPECT_THROW(write_file(path, f.h, recs), StreamError);
  EXPECT_FALSE(std::filesystem::exists(path));
  // a BCU segment's c_A too
  std::mt19937_64 rng(31);
  const Header h2 = header_v2();
  auto mixed = mixed_records(rng, h2, 4);  // F B B F
  mixed[2].regs[2][0] -= 1;
  const auto off = offsets(h2, mixed);
  const size_t cb = (h2.bcu_ctrl_width + 7) / 8;
  const auto r2 = decode(encode(h2, mixed), "m.trj");
  EXPECT_EQ(r2.error.rfind("m.trj: byte " + std::to_string(off[2] + 12 + 2 * 4 * cb) + ": segment 2: axis 2 starts at c_A = ", 0), 0u)
      << r2.error;
  EXPECT_EQ(r2.records.size(), 2u);
}

TEST(StreamIntegrity, RawBytesAreTheRecordsAsWritten) {
  std::mt19937_64 rng(32);
  const Header h = header_v2();
  const auto recs = mixed_records(rng, h, 7);
  const traj::test::TmpFile tmp("trajcore_raw.trj");
  const std::string& path = tmp.path;
  write_file(path, h, recs);
  std::ifstream file(path, std::ios::binary);
  const std::vector<uint8_t> all((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  std::istringstream in(std::string(all.begin(), all.end()));
  StreamReader rd(in, path);
  const auto off = offsets(h, recs);
  Record r;
  size_t i = 0;
  while (rd.next(r)) {
    ASSERT_LT(i, recs.size());
    EXPECT_EQ(r.seq, i);
    const std::vector<uint8_t> slice(all.begin() + off[i], all.begin() + off[i + 1]);
    EXPECT_EQ(rd.raw(), slice) << i;
    EXPECT_EQ(encode_record(h, r), slice) << i;
    ++i;
  }
  EXPECT_TRUE(rd.complete()) << rd.error();
  EXPECT_EQ(i, recs.size());
}

TEST(StreamIntegrity, EndRecordCarriesTheCount) {
  Fixture f;
  auto b = f.good;
  const size_t e = f.off(f.recs.size());
  put32(b, e + 8, 4);
  reseal(b, e, 16);
  EXPECT_EQ(decode(b, "plan.trj").error,
            "plan.trj: byte " + std::to_string(e + 8) + ": end record counts 4 segments, stream has 5");
}

// Pause records (program pauses): written between the records they name by
// both writers, read back in place, and every misplaced or damaged one
// refused with its place. The records and their bytes are those of the
// stream without the pauses.
TEST(StreamPause, WrittenAndReadBackInPlace) {
  Fixture f;
  const std::vector<Pause> pauses = {{2, 17, ""}, {4, 0, ""}};
  traj::test::TmpFile a("pause_a.trj"), b("pause_b.trj");
  write_file(a.path, f.h, f.recs, pauses);
  {
    StreamWriter w(b.path, f.h);
    for (size_t i = 0; i < f.recs.size(); ++i) {
      w.add(f.recs[i]);
      if (i == 1) w.pause(17);
      if (i == 3) w.pause(0);
      if (i == 4) w.pause(99);  // after the last record: nothing to wait for, not written
    }
    w.finish();
  }
  for (const std::string& path : {a.path, b.path}) {
    std::ifstream in(path, std::ios::binary);
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(bytes.size(), f.good.size() + 2 * kPauseBytes) << path;
    const ReadResult r = decode(bytes, "p.trj");
    ASSERT_TRUE(r.complete) << r.error;
    ASSERT_EQ(r.pauses.size(), 2u);
    EXPECT_EQ(r.pauses[0].before, 2u);
    EXPECT_EQ(r.pauses[0].line, 17u);
    EXPECT_EQ(r.pauses[1].before, 4u);
    EXPECT_EQ(r.pauses[1].line, 0u);
    ASSERT_EQ(r.records.size(), f.recs.size());
    for (size_t i = 0; i < f.recs.size(); ++i) EXPECT_EQ(r.records[i].regs, f.recs[i].regs);
    // the pause record's bytes, as LINK.md and the stream README give them
    const size_t at = f.off(2);
    const std::vector<uint8_t> want = {0xFE, 0, 0, 0, 17, 0, 0, 0, 2, 0, 0, 0};
    EXPECT_TRUE(std::equal(want.begin(), want.end(), bytes.begin() + static_cast<long>(at)));
    EXPECT_EQ(uint32_t(bytes[at + 12] | bytes[at + 13] << 8 | bytes[at + 14] << 16 | uint32_t(bytes[at + 15]) << 24),
              uint32_t(crc32(0, bytes.data() + at, 12)));
  }
  EXPECT_THROW(write_file(a.path, f.h, f.recs, {{0, 1, ""}}), StreamError);
  EXPECT_THROW(write_file(a.path, f.h, f.recs, {{3, 1, ""}, {2, 1, ""}}), StreamError);
  EXPECT_THROW(write_file(a.path, f.h, f.recs, {{2, 1, ""}, {2, 1, ""}}), StreamError);
  EXPECT_THROW(write_file(a.path, f.h, f.recs, {{5, 1, ""}}), StreamError);
}

// A pause's text (G-code "(MSG, ...)"): its length at offset 2, its bytes
// from offset 12, the CRC after them; round trip through both writers.
TEST(StreamPause, TextTravelsWithThePause) {
  Fixture f;
  const std::string text = "Change tool bit to mill diameter 1.25000mm";
  traj::test::TmpFile a("pause_ta.trj"), b("pause_tb.trj");
  write_file(a.path, f.h, f.recs, {{2, 19, text}, {3, 20, ""}});
  {
    StreamWriter w(b.path, f.h);
    for (size_t i = 0; i < f.recs.size(); ++i) {
      w.add(f.recs[i]);
      if (i == 1) w.pause(19, text);
      if (i == 2) w.pause(20);
    }
    w.finish();
  }
  for (const std::string& path : {a.path, b.path}) {
    std::ifstream in(path, std::ios::binary);
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(bytes.size(), f.good.size() + 2 * kPauseBytes + text.size()) << path;
    const ReadResult r = decode(bytes, "p.trj");
    ASSERT_TRUE(r.complete) << r.error;
    ASSERT_EQ(r.pauses.size(), 2u);
    EXPECT_EQ(r.pauses[0].text, text);
    EXPECT_EQ(r.pauses[1].text, "");
    EXPECT_EQ(r.pauses[1].line, 20u);
    const size_t at = f.off(2);
    EXPECT_EQ(bytes[at + 2], text.size());
    EXPECT_EQ(bytes[at + 3], 0);
    EXPECT_EQ(std::string(bytes.begin() + static_cast<long>(at + 12), bytes.begin() + static_cast<long>(at + 12 + text.size())),
              text);
    const size_t c = at + 12 + text.size();
    EXPECT_EQ(uint32_t(bytes[c] | bytes[c + 1] << 8 | bytes[c + 2] << 16 | uint32_t(bytes[c + 3]) << 24),
              uint32_t(crc32(0, bytes.data() + at, static_cast<uInt>(c - at))));
  }
  // what a terminal would act on, or the record cannot hold, is refused by both writers
  for (const std::string& bad : {std::string("tool\tbit"), std::string("\x1b[2J"), std::string(256, 'x')}) {
    EXPECT_THROW(write_file(a.path, f.h, f.recs, {{2, 19, bad}}), StreamError) << bad;
    StreamWriter w(b.path, f.h);
    w.add(f.recs[0]);
    EXPECT_THROW(w.pause(19, bad), StreamError) << bad;
  }
  EXPECT_NO_THROW(write_file(a.path, f.h, f.recs, {{2, 19, std::string(255, 'x')}}));
  EXPECT_NO_THROW(write_file(a.path, f.h, f.recs, {{2, 19, "Werkzeug wechseln: Fr\xC3\xA4ser 3 mm"}}));  // UTF-8
}

TEST(StreamPause, DamagedTextIsRefusedWithItsPlace) {
  Fixture f;
  auto with_text = [&](const std::string& text) {
    auto b = f.good;
    const auto p = encode_pause({2, 5, "ok"});
    std::vector<uint8_t> q(p.begin(), p.begin() + 12);
    q[2] = static_cast<uint8_t>(text.size());
    q[3] = static_cast<uint8_t>(text.size() >> 8);
    q.insert(q.end(), text.begin(), text.end());
    const auto sum = uint32_t(crc32(0, q.data(), static_cast<uInt>(q.size())));
    for (int i = 0; i < 4; ++i) q.push_back(static_cast<uint8_t>(sum >> (8 * i)));
    b.insert(b.begin() + static_cast<long>(f.off(2)), q.begin(), q.end());
    return b;
  };
  const ReadResult good = decode(with_text("Load tool 2"), "p.trj");
  ASSERT_TRUE(good.complete) << good.error;
  EXPECT_EQ(good.pauses.at(0).text, "Load tool 2");
  EXPECT_EQ(decode(with_text("a\nb"), "p.trj").error,
            "p.trj: byte " + std::to_string(f.off(2) + 12) + ": segment 2: pause record: control byte 0x0A at 1 of its text");
  EXPECT_EQ(decode(with_text(std::string(300, 'x')), "p.trj").error,
            "p.trj: byte " + std::to_string(f.off(2) + 2) + ": segment 2: pause record: text of 300 bytes, at most 255");
  auto bad = with_text("Load tool 2");
  bad[f.off(2) + 14] ^= 1;  // the text, under the checksum
  EXPECT_EQ(decode(bad, "p.trj").error, "p.trj: byte " + std::to_string(f.off(2)) + ": segment 2: pause record checksum mismatch");
  const auto cut = with_text("Load tool 2");
  EXPECT_EQ(decode(std::vector<uint8_t>(cut.begin(), cut.begin() + static_cast<long>(f.off(2) + 20)), "p.trj").error,
            "p.trj: byte " + std::to_string(f.off(2)) + ": segment 2: truncated pause record");
}

TEST(StreamPause, MisplacedOrDamagedPausesAreRefusedWithTheirPlace) {
  Fixture f;
  // the good stream with a pause record of `before` inserted at record i's place
  auto with_pause = [&](size_t i, uint32_t before, int copies = 1) {
    auto b = f.good;
    for (int c = 0; c < copies; ++c) {
      const auto p = encode_pause({before, 5, ""});
      b.insert(b.begin() + static_cast<long>(f.off(i)), p.begin(), p.end());
    }
    return b;
  };
  EXPECT_EQ(decode(with_pause(2, 2), "p.trj").error, "");
  EXPECT_EQ(decode(with_pause(0, 0), "p.trj").error, "p.trj: byte 64: segment 0: pause record before the first segment");
  EXPECT_EQ(decode(with_pause(2, 3), "p.trj").error,
            "p.trj: byte " + std::to_string(f.off(2) + 8) + ": segment 2: pause record before segment 3, but 2 segments precede it");
  EXPECT_EQ(decode(with_pause(2, 2, 2), "p.trj").error,
            "p.trj: byte " + std::to_string(f.off(2) + kPauseBytes) + ": segment 2: pause record after another one");
  EXPECT_EQ(decode(with_pause(5, 5), "p.trj").error,
            "p.trj: byte " + std::to_string(f.off(5) + kPauseBytes) +
                ": segment 5: pause record after the last segment (nothing follows it)");
  auto bad = with_pause(2, 2);
  bad[f.off(2) + 4] ^= 1;  // the line, under the checksum
  EXPECT_EQ(decode(bad, "p.trj").error, "p.trj: byte " + std::to_string(f.off(2)) + ": segment 2: pause record checksum mismatch");
  const auto cut = with_pause(2, 2);
  const auto truncated = decode(std::vector<uint8_t>(cut.begin(), cut.begin() + static_cast<long>(f.off(2) + 9)), "p.trj");
  EXPECT_EQ(truncated.error, "p.trj: byte " + std::to_string(f.off(2)) + ": segment 2: truncated pause record");
  EXPECT_EQ(truncated.records.size(), 2u);
}
