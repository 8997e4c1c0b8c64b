// SPDX-License-Identifier: Apache-2.0
#include "stream/segment_stream.hpp"

#include "util/tick_period.hpp"

#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace traj::stream {
namespace {

uint32_t crc(const uint8_t* p, size_t n) {
  return static_cast<uint32_t>(crc32(crc32(0L, Z_NULL, 0), p, static_cast<uInt>(n)));
}

void put(std::vector<uint8_t>& b, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
uint64_t get(const uint8_t* p, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint64_t(p[i]) << (8 * i);
  return v;
}

// Two's complement of v in `bytes` bytes, little-endian (v must fit).
// No temporaries: the magnitude's bytes (mpz_export, least significant
// first), then the two's complement in place for a negative v.
void put_signed(std::vector<uint8_t>& b, const mpz_class& v, int bytes) {
  const size_t base = b.size();
  b.resize(base + static_cast<size_t>(bytes), 0);
  if (mpz_sizeinbase(v.get_mpz_t(), 256) > static_cast<size_t>(bytes))
    throw StreamError("value does not fit " + std::to_string(bytes) + " bytes");
  size_t count = 0;
  mpz_export(b.data() + base, &count, -1, 1, 0, 0, v.get_mpz_t());
  if (mpz_sgn(v.get_mpz_t()) < 0) {
    unsigned carry = 1;
    for (int i = 0; i < bytes; ++i) {
      const unsigned x = static_cast<uint8_t>(~b[base + i]) + carry;
      b[base + i] = static_cast<uint8_t>(x);
      carry = x >> 8;
    }
  }
}
mpz_class get_signed(const uint8_t* p, int bytes) {
  mpz_class u = 0;
  for (int i = bytes - 1; i >= 0; --i) u = (u << 8) + p[i];
  const mpz_class half = mpz_class(1) << (8 * bytes - 1);
  if (u >= half) u -= mpz_class(1) << (8 * bytes);
  return u;
}
int ctrl_bytes(const Header& h) { return (h.bcu_ctrl_width + 7) / 8; }
// -2^(bits-1) <= v < 2^(bits-1), without temporaries.
bool fits_bits(const mpz_class& v, int bits) {
  const mpz_srcptr z = v.get_mpz_t();
  if (mpz_sgn(z) == 0) return bits >= 1;
  const size_t n = mpz_sizeinbase(z, 2);  // bits of |v|
  if (n <= static_cast<size_t>(bits - 1)) return true;
  // v = -2^(bits-1) exactly
  return mpz_sgn(z) < 0 && n == static_cast<size_t>(bits) && mpz_scan1(z, 0) == static_cast<mp_bitcnt_t>(bits - 1);
}
// d with K = 2^d, or -1.
int log2_exact(uint32_t k) {
  if (k == 0 || (k & (k - 1)) != 0) return -1;
  int d = 0;
  while ((uint32_t(1) << d) != k) ++d;
  return d;
}

std::string at(const std::string& name, size_t off) { return name + ": byte " + std::to_string(off) + ": "; }

}  // namespace

fd::Format Header::format() const { return {axes, degree, width, chunk_width, guard_bits, frac_bits}; }

bcu::Format Header::bcu_format() const {
  if (!has_bcu()) throw StreamError("the stream header has no BCU format (version 1)");
  return {axes, chunk_width, bcu_ctrl_width, bcu_guard_bits, bcu_out_width, bcu_max_depth, frac_bits};
}

int Record::depth() const { return is_bcu() ? log2_exact(ticks) : -1; }

size_t record_size(const Header& h, RecordKind kind) {
  if (kind == RecordKind::kBcu) return 12 + size_t(h.axes) * 4 * ctrl_bytes(h);
  return 12 + size_t(h.axes) * (h.degree + 1) * (h.width / 8);
}

Header Header::from(const fd::Format& f, const bcu::Format& b, double period, const std::string& units) {
  Header h = from(f, period, units);
  if (b.axes != f.axes || b.frac_bits != f.frac_bits || b.chunk_width != f.chunk_width)
    throw StreamError("BCU format (axes " + std::to_string(b.axes) + ", frac_bits " + std::to_string(b.frac_bits) +
                      ", chunk_width " + std::to_string(b.chunk_width) + ") does not share axes, frac_bits and "
                      "chunk_width with the FD format (" + std::to_string(f.axes) + ", " +
                      std::to_string(f.frac_bits) + ", " + std::to_string(f.chunk_width) + ")");
  h.bcu_ctrl_width = b.ctrl_width;
  h.bcu_guard_bits = b.guard_bits;
  h.bcu_max_depth = b.max_depth;
  h.bcu_out_width = b.out_width;
  return h;
}

Header Header::from(const fd::Format& f, double period, const std::string& units) {
  Header h;
  h.axes = f.axes;
  h.degree = f.degree;
  h.width = f.width;
  h.chunk_width = f.chunk_width;
  h.guard_bits = f.guard_bits;
  h.frac_bits = f.frac_bits;
  h.period = period;
  h.units = units;
  return h;
}

namespace {
// The BCU half of a version-2 header: "" if fine, else what is wrong; `off` is
// the byte offset of the field at fault.
std::string bcu_header_problem(const Header& h, size_t& off) {
  const bcu::Format f = h.bcu_format();
  try {
    f.validate();
  } catch (const std::invalid_argument& e) {
    const std::string w = e.what();
    off = w.find("guard_bits") != std::string::npos  ? 46
          : w.find("max_depth") != std::string::npos ? 48
          : w.find("out_width") != std::string::npos ? 50
          : w.find("axes") != std::string::npos      ? 8
          : w.find("chunk_width") != std::string::npos ? 12
          : 44;
    return "BCU format: " + w;
  }
  if (h.bcu_out_width != h.width - h.guard_bits) {
    off = 50;
    return "BCU OutWidth " + std::to_string(h.bcu_out_width) + " differs from the FD sample width " +
           std::to_string(h.width - h.guard_bits) + " (width - guard bits): one sample port";
  }
  return "";
}
}  // namespace

std::vector<uint8_t> encode_header(const Header& h) {
  if (h.units.size() > 15) throw StreamError("units '" + h.units + "' longer than 15 characters");
  if (const std::string m = util::tick_period_problem(h.period); !m.empty()) throw StreamError(m);
  h.format().validate();
  if (h.has_bcu()) {
    size_t off = 0;
    const std::string p = bcu_header_problem(h, off);
    if (!p.empty()) throw StreamError(p);
  }
  const int version = h.version();
  std::vector<uint8_t> b{'T', 'R', 'J', 'S'};
  put(b, version, 2);
  put(b, header_bytes(version), 2);
  put(b, h.axes, 1);
  put(b, h.degree, 1);
  put(b, h.width, 2);
  put(b, h.chunk_width, 2);
  put(b, h.guard_bits, 2);
  put(b, static_cast<uint16_t>(static_cast<int16_t>(h.frac_bits)), 2);
  put(b, 0, 2);
  uint64_t pbits;
  std::memcpy(&pbits, &h.period, 8);
  put(b, pbits, 8);
  for (int i = 0; i < 16; ++i) b.push_back(i < static_cast<int>(h.units.size()) ? h.units[i] : 0);
  if (version >= 2) {
    put(b, h.bcu_ctrl_width, 2);
    put(b, h.bcu_guard_bits, 2);
    put(b, h.bcu_max_depth, 2);
    put(b, h.bcu_out_width, 2);
    put(b, 0, 8);
  }
  put(b, crc(b.data(), b.size()), 4);
  return b;
}

std::vector<uint8_t> encode_record(const Header& h, const Record& r) {
  if (static_cast<int>(r.regs.size()) != h.axes) throw StreamError("segment has the wrong number of axes");
  std::vector<uint8_t> b;
  if (r.is_bcu()) {
    if (!h.has_bcu()) throw StreamError("BCU segment in a stream whose header has no BCU format");
    const int d = r.depth();
    if (d < 0 || d > h.bcu_max_depth)
      throw StreamError("BCU segment with K=" + std::to_string(r.ticks) + " ticks: K must be 2^d with d <= MaxDepth " +
                        std::to_string(h.bcu_max_depth));
    put(b, 2, 1);
    put(b, 0, 1);
    put(b, 0, 2);
    put(b, r.ticks, 4);
    for (const auto& ax : r.regs) {
      if (ax.size() != 4) throw StreamError("BCU segment needs 4 control values per axis");
      for (const auto& v : ax) {
        if (!fits_bits(v, h.bcu_ctrl_width)) throw StreamError("BCU control value does not fit CtrlWidth bits");
        put_signed(b, v, ctrl_bytes(h));
      }
    }
    put(b, crc(b.data(), b.size()), 4);
    return b;
  }
  if (r.ticks < 1) throw StreamError("segment with K=0 ticks");
  put(b, 1, 1);
  put(b, 0, 1);
  put(b, 0, 2);
  put(b, r.ticks, 4);
  for (const auto& ax : r.regs) {
    if (static_cast<int>(ax.size()) != h.degree + 1) throw StreamError("segment has the wrong number of registers");
    for (const auto& v : ax) {
      if (!fits_bits(v, h.width)) throw StreamError("register value does not fit the register width");
      put_signed(b, v, h.width / 8);
    }
  }
  put(b, crc(b.data(), b.size()), 4);
  return b;
}

std::vector<uint8_t> encode_end(uint32_t segments, uint64_t total_ticks) {
  std::vector<uint8_t> b;
  put(b, 0xFF, 1);
  put(b, 0, 3);
  put(b, segments, 4);
  put(b, static_cast<uint32_t>(total_ticks), 4);
  put(b, crc(b.data(), b.size()), 4);
  return b;
}

void write_file(const std::string& path, const Header& h, const std::vector<Record>& recs) {
  std::vector<uint8_t> all = encode_header(h);
  uint64_t ticks = 0;
  for (const auto& r : recs) {
    const auto b = encode_record(h, r);
    all.insert(all.end(), b.begin(), b.end());
    ticks += r.ticks;
  }
  const auto e = encode_end(static_cast<uint32_t>(recs.size()), ticks);
  all.insert(all.end(), e.begin(), e.end());
  try {
    util::AtomicFile f(path, std::ios::binary);
    f.out().write(reinterpret_cast<const char*>(all.data()), static_cast<std::streamsize>(all.size()));
    f.commit();
  } catch (const std::runtime_error& e) {
    throw StreamError(e.what());
  }
}

namespace {
util::AtomicFile open_stream_file(const std::string& path) try {
  return util::AtomicFile(path, std::ios::binary);
} catch (const std::runtime_error& e) {
  throw StreamError(e.what());
}
}  // namespace

StreamWriter::StreamWriter(const std::string& path, const Header& h) : h_(h), file_(open_stream_file(path)) {
  put(encode_header(h));
}

void StreamWriter::put(const std::vector<uint8_t>& bytes) {
  file_.out().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!file_.out()) throw StreamError("write failed: " + file_.tmp_path());
}

void StreamWriter::add(const Record& r) {
  put(encode_record(h_, r));
  ++count_;
  ticks_ += r.ticks;
}

void StreamWriter::finish() {
  put(encode_end(static_cast<uint32_t>(count_), ticks_));
  try {
    file_.commit();
  } catch (const std::runtime_error& e) {
    throw StreamError(e.what());
  }
}

ReadResult decode(const std::vector<uint8_t>& b, const std::string& name) {
  ReadResult res;
  auto fail = [&](size_t off, const std::string& what) {
    res.error = at(name, off) + what;
    return res;
  };
  if (b.size() < kHeaderBytes) return fail(0, "truncated header (" + std::to_string(b.size()) + " bytes)");
  if (std::memcmp(b.data(), "TRJS", 4) != 0) return fail(0, "bad magic (not a trajcore segment stream)");
  const int version = static_cast<int>(get(&b[4], 2));
  if (version < 1 || version > kVersion)
    return fail(4, "unsupported version " + std::to_string(version) + " (this reader knows 1.." +
                       std::to_string(kVersion) + ")");
  const size_t hb = header_bytes(version);
  if (get(&b[6], 2) != hb)
    return fail(6, "unexpected header size " + std::to_string(get(&b[6], 2)) + " for version " +
                       std::to_string(version) + " (" + std::to_string(hb) + ")");
  if (b.size() < hb) return fail(0, "truncated header (" + std::to_string(b.size()) + " bytes)");
  if (get(&b[hb - 4], 4) != crc(b.data(), hb - 4)) return fail(hb - 4, "header checksum mismatch");
  Header& h = res.header;
  h.axes = b[8];
  h.degree = b[9];
  h.width = static_cast<int>(get(&b[10], 2));
  h.chunk_width = static_cast<int>(get(&b[12], 2));
  h.guard_bits = static_cast<int>(get(&b[14], 2));
  h.frac_bits = static_cast<int16_t>(get(&b[16], 2));
  const uint64_t pbits = get(&b[20], 8);
  std::memcpy(&h.period, &pbits, 8);
  h.units.assign(reinterpret_cast<const char*>(&b[28]), strnlen(reinterpret_cast<const char*>(&b[28]), 16));
  try {
    h.format().validate();
  } catch (const std::exception& e) {
    return fail(8, std::string("header: ") + e.what());
  }
  if (h.width % 8 != 0) return fail(10, "register width not a multiple of 8");
  if (!(h.period > 0) || !std::isfinite(h.period)) return fail(20, "tick period must be positive and finite");
  if (version >= 2) {
    h.bcu_ctrl_width = static_cast<int>(get(&b[44], 2));
    h.bcu_guard_bits = static_cast<int>(get(&b[46], 2));
    h.bcu_max_depth = static_cast<int>(get(&b[48], 2));
    h.bcu_out_width = static_cast<int>(get(&b[50], 2));
    if (!h.has_bcu()) return fail(44, "header: version 2 without a BCU format (CtrlWidth 0)");
    size_t field = 44;
    const std::string p = bcu_header_problem(h, field);
    if (!p.empty()) return fail(field, "header: " + p);
  }

  size_t off = hb;
  uint64_t ticks = 0;
  while (true) {
    const size_t idx = res.records.size();
    const std::string rec = "segment " + std::to_string(idx) + ": ";
    if (off >= b.size()) return fail(off, "truncated: no end record after " + std::to_string(idx) + " segments");
    if (b[off] == 0xFF) {
      if (b.size() - off < 16) return fail(off, "truncated end record");
      if (get(&b[off + 12], 4) != crc(&b[off], 12)) return fail(off, "end record checksum mismatch");
      if (get(&b[off + 4], 4) != idx)
        return fail(off, "end record counts " + std::to_string(get(&b[off + 4], 4)) + " segments, stream has " +
                             std::to_string(idx));
      if (get(&b[off + 8], 4) != static_cast<uint32_t>(ticks)) return fail(off, "end record tick total mismatch");
      if (off + 16 != b.size()) return fail(off + 16, "trailing bytes after the end record");
      res.complete = true;
      return res;
    }
    if (b[off] == 2 && version < 2)
      return fail(off, rec + "record type 2 (BCU segment) in a version-1 stream, whose header has no BCU format");
    if (b[off] != 1 && b[off] != 2) return fail(off, rec + "unknown record type " + std::to_string(b[off]));
    const RecordKind kind = b[off] == 2 ? RecordKind::kBcu : RecordKind::kFd;
    const size_t rb = record_size(h, kind);
    if (b.size() - off < rb) return fail(off, rec + "truncated record");
    if (get(&b[off + rb - 4], 4) != crc(&b[off], rb - 4)) return fail(off, rec + "checksum mismatch");
    Record r;
    r.kind = kind;
    r.ticks = static_cast<uint32_t>(get(&b[off + 4], 4));
    size_t p = off + 8;
    if (kind == RecordKind::kFd) {
      if (r.ticks == 0) return fail(off + 4, rec + "K=0 ticks");
      r.regs.assign(h.axes, std::vector<mpz_class>(h.degree + 1));
      for (auto& ax : r.regs)
        for (auto& v : ax) {
          v = get_signed(&b[p], h.width / 8);
          p += h.width / 8;
        }
    } else {
      const int d = r.depth();
      if (d < 0 || d > h.bcu_max_depth)
        return fail(off + 4, rec + "BCU K=" + std::to_string(r.ticks) + " is not 2^d with d <= MaxDepth " +
                                 std::to_string(h.bcu_max_depth));
      const int cb = ctrl_bytes(h);
      r.regs.assign(h.axes, std::vector<mpz_class>(4));
      for (int a = 0; a < h.axes; ++a)
        for (int i = 0; i < 4; ++i) {
          mpz_class v = get_signed(&b[p], cb);
          if (!fits_bits(v, h.bcu_ctrl_width))
            return fail(p, rec + "axis " + std::to_string(a) + " control value c" + std::to_string(i) + " = " +
                               v.get_str() + " does not fit CtrlWidth " + std::to_string(h.bcu_ctrl_width) + " bits");
          r.regs[a][i] = v;
          p += cb;
        }
    }
    ticks += r.ticks;
    res.records.push_back(std::move(r));
    off += rb;
  }
}

ReadResult read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw StreamError(path + ": cannot open");
  std::vector<uint8_t> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return decode(b, path);
}

}  // namespace traj::stream
