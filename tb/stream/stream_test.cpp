// Segment stream format v1: round trip, and every corruption or truncation is
// reported with its place while every record before it stays accepted.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "stream/segment_stream.hpp"

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
