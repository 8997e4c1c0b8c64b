// SPDX-License-Identifier: Apache-2.0
#include "stream/segment_stream.hpp"

#include "fd/fd_compiler.hpp"
#include "util/tick_period.hpp"

#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace traj::stream {

static_assert(kMaxTicks == fd::Format{}.max_ticks, "the stream's K bound is the FD compiler's longest segment");

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
std::string hex2(unsigned v) {
  char b[8];
  std::snprintf(b, sizeof b, "0x%02X", v & 0xFF);
  return b;
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
// Bits of the shortest two's complement form of v.
size_t signed_bits(const mpz_class& v) {
  for (size_t b = mpz_sizeinbase(v.get_mpz_t(), 2);; ++b)
    if (fits_bits(v, static_cast<int>(b))) return b;
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
  if (!has_bcu()) throw StreamError("the stream header has no BCU format (CtrlWidth 0)");
  return {axes, chunk_width, bcu_ctrl_width, bcu_guard_bits, bcu_out_width, bcu_max_depth, frac_bits};
}

int Record::depth() const { return is_bcu() ? log2_exact(ticks) : -1; }

size_t record_size(const Header& h, RecordKind kind) {
  if (kind == RecordKind::kBcu) return 16 + size_t(h.axes) * 4 * ctrl_bytes(h);
  return 16 + size_t(h.axes) * (h.degree + 1) * (h.width / 8);
}

const std::vector<std::string>& known_units() {
  static const std::vector<std::string> u = {"mm", "um", "m", "in", "deg", "rad"};
  return u;
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
// The BCU half of a header with a BCU format: "" if fine, else what is wrong; `off` is
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

namespace {
bool is_known_units(const std::string& u) {
  for (const auto& k : known_units())
    if (u == k) return true;
  return false;
}
std::string units_list() {
  std::string s;
  for (const auto& k : known_units()) s += (s.empty() ? "" : ", ") + k;
  return s;
}
}  // namespace

namespace {
// The header byte of the FD format field a fd::Format::validate() message names ("format: <field>=...").
size_t fd_field_offset(const std::string& message) {
  static const std::pair<const char*, size_t> kFields[] = {
      {"axes", 8}, {"degree", 9}, {"width", 10}, {"chunk_width", 12}, {"guard_bits", 14}, {"frac_bits", 16}};
  const std::string prefix = "format: ";
  const size_t b = message.rfind(prefix, 0) == 0 ? prefix.size() : 0;
  const size_t e = message.find_first_of("= ", b);
  const std::string field = message.substr(b, e == std::string::npos ? std::string::npos : e - b);
  for (const auto& [name, off] : kFields)
    if (field == name) return off;
  return 8;
}
// The time-scaling fields: none (all zero), or s_max in (0, 2] with both
// ramp bounds finite and positive.
std::string time_scaling_problem(const Header& h) {
  if (h.scale_max == 0) {
    if (h.scale_rate != 0 || h.scale_accel != 0) return "time-scaling ramp bounds without s_max (bytes 18-19 are 0)";
    return "";
  }
  char buf[160];
  if (!(h.scale_max * kScaleMaxUnit >= 1 - 1e-9 && h.scale_max <= 2)) {
    std::snprintf(buf, sizeof buf, "time-scaling s_max %g: must be in [1/4096, 2]", h.scale_max);
    return buf;
  }
  if (!(std::isfinite(h.scale_rate) && h.scale_rate > 0) || !(std::isfinite(h.scale_accel) && h.scale_accel > 0)) {
    std::snprintf(buf, sizeof buf, "time-scaling ramp bounds |ds/dt| <= %g, |d2s/dt2| <= %g: must be finite and positive",
                  static_cast<double>(h.scale_rate), static_cast<double>(h.scale_accel));
    return buf;
  }
  return "";
}

}  // namespace

std::vector<uint8_t> encode_header(const Header& h) {
  if (!is_known_units(h.units)) throw StreamError("units '" + h.units + "' unknown (known: " + units_list() + ")");
  if (const std::string m = util::tick_period_problem(h.period); !m.empty()) throw StreamError(m);
  h.format().validate();
  if (h.has_bcu()) {
    size_t off = 0;
    const std::string p = bcu_header_problem(h, off);
    if (!p.empty()) throw StreamError(p);
  }
  if (const std::string p = time_scaling_problem(h); !p.empty()) throw StreamError(p);
  std::vector<uint8_t> b{'T', 'R', 'J', 'S'};
  put(b, kVersion, 2);
  put(b, kHeaderBytes, 2);
  put(b, h.axes, 1);
  put(b, h.degree, 1);
  put(b, h.width, 2);
  put(b, h.chunk_width, 2);
  put(b, h.guard_bits, 2);
  put(b, static_cast<uint16_t>(static_cast<int16_t>(h.frac_bits)), 2);
  put(b, static_cast<uint16_t>(std::floor(h.scale_max * kScaleMaxUnit + 1e-9)), 2);
  uint64_t pbits;
  std::memcpy(&pbits, &h.period, 8);
  put(b, pbits, 8);
  for (int i = 0; i < 16; ++i) b.push_back(i < static_cast<int>(h.units.size()) ? h.units[i] : 0);
  put(b, h.bcu_ctrl_width, 2);
  put(b, h.bcu_guard_bits, 2);
  put(b, h.bcu_max_depth, 2);
  put(b, h.bcu_out_width, 2);
  uint32_t fbits = 0;  // no time scaling: all 0 (not the bits of -0)
  if (h.has_time_scaling()) std::memcpy(&fbits, &h.scale_rate, 4);
  put(b, fbits, 4);
  if (h.has_time_scaling()) std::memcpy(&fbits, &h.scale_accel, 4);
  put(b, fbits, 4);
  put(b, crc(b.data(), b.size()), 4);
  return b;
}

namespace {
// type, flags, reserved, K, seq: the first 12 bytes of every record.
void put_record_head(std::vector<uint8_t>& b, int type, uint32_t ticks, uint32_t seq) {
  put(b, type, 1);
  put(b, 0, 1);
  put(b, 0, 2);
  put(b, ticks, 4);
  put(b, seq, 4);
}
}  // namespace

namespace {
std::vector<uint8_t> encode_numbered(const Header& h, const Record& r, uint32_t seq) {
  if (static_cast<int>(r.regs.size()) != h.axes) throw StreamError("segment has the wrong number of axes");
  std::vector<uint8_t> b;
  b.reserve(record_size(h, r.kind));
  if (r.is_bcu()) {
    if (!h.has_bcu()) throw StreamError("BCU segment in a stream whose header has no BCU format");
    const int d = r.depth();
    if (d < 0 || d > h.bcu_max_depth)
      throw StreamError("BCU segment with K=" + std::to_string(r.ticks) + " ticks: K must be 2^d with d <= MaxDepth " +
                        std::to_string(h.bcu_max_depth));
    put_record_head(b, 2, r.ticks, seq);
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
  if (r.ticks > kMaxTicks)
    throw StreamError("segment with K=" + std::to_string(r.ticks) + " ticks, beyond the format's bound 2^20 = " +
                      std::to_string(kMaxTicks));
  put_record_head(b, 1, r.ticks, seq);
  for (size_t a = 0; a < r.regs.size(); ++a) {
    const auto& ax = r.regs[a];
    if (static_cast<int>(ax.size()) != h.degree + 1) throw StreamError("segment has the wrong number of registers");
    for (size_t i = 0; i < ax.size(); ++i) {
      if (!fits_bits(ax[i], h.width))
        throw StreamError("segment " + std::to_string(seq) + ": axis " + std::to_string(a) + ": r[" + std::to_string(i) +
                          "] = " + ax[i].get_str() + " needs " + std::to_string(signed_bits(ax[i])) +
                          " bits, the register width is " + std::to_string(h.width));
      put_signed(b, ax[i], h.width / 8);
    }
  }
  put(b, crc(b.data(), b.size()), 4);
  return b;
}
}  // namespace

std::vector<uint8_t> encode_record(const Header& h, const Record& r) { return encode_numbered(h, r, r.seq); }

std::vector<uint8_t> encode_end(uint32_t segments, uint64_t total_ticks) {
  std::vector<uint8_t> b;
  put_record_head(b, 0xFF, static_cast<uint32_t>(total_ticks), segments);
  put(b, crc(b.data(), b.size()), 4);
  return b;
}

std::string pause_text_problem(const std::string& text) {
  if (text.size() > kMaxPauseText)
    return "text of " + std::to_string(text.size()) + " bytes, at most " + std::to_string(kMaxPauseText);
  // no control bytes: the text is printed to the operator's terminal as it is
  for (size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<uint8_t>(text[i]);
    if (c < 0x20 || c == 0x7F) return "control byte " + hex2(c) + " at " + std::to_string(i) + " of its text";
  }
  return "";
}

std::vector<uint8_t> encode_pause(const Pause& p) {
  if (const std::string why = pause_text_problem(p.text); !why.empty())
    throw StreamError("pause at line " + std::to_string(p.line) + ": " + why);
  std::vector<uint8_t> b;
  put_record_head(b, kPauseType, p.line, static_cast<uint32_t>(p.before));
  b[2] = static_cast<uint8_t>(p.text.size());
  b.insert(b.end(), p.text.begin(), p.text.end());
  put(b, crc(b.data(), b.size()), 4);
  return b;
}

// ---------------------------------------------------------------------------
// Continuity
// ---------------------------------------------------------------------------
namespace {
// floor(v 2^e), exact for any sign of e.
mpz_class shift_floor(const mpz_class& v, int e) {
  mpz_class r;
  if (e >= 0)
    mpz_mul_2exp(r.get_mpz_t(), v.get_mpz_t(), static_cast<mp_bitcnt_t>(e));
  else
    mpz_fdiv_q_2exp(r.get_mpz_t(), v.get_mpz_t(), static_cast<mp_bitcnt_t>(-e));
  return r;
}
mpz_class half_of(int g) { return g > 0 ? mpz_class(1) << (g - 1) : mpz_class(0); }
const char* start_name(RecordKind k) { return k == RecordKind::kBcu ? "c_A" : "r[0]"; }
}  // namespace

std::string Continuity::check(const Record& r, int& axis) const {
  if (!have_) return "";
  const int gf = h_.guard_bits, gb = h_.bcu_guard_bits;
  for (int a = 0; a < h_.axes; ++a) {
    const mpz_class& e = end_[a];
    mpz_class want;
    if (r.is_bcu())
      want = kind_ == RecordKind::kBcu ? e : shift_floor(e, gb - gf) - half_of(gb);
    else
      want = kind_ == RecordKind::kFd ? e : shift_floor(e, gf - gb) + half_of(gf);
    if (r.regs[a][0] == want) continue;
    axis = a;
    const mpz_class jump = r.regs[a][0] - want;
    std::ostringstream m;
    m << "axis " << a << " starts at " << start_name(r.kind) << " = " << r.regs[a][0].get_str()
      << ", not where the previous segment ends (" << want.get_str() << "): a jump of "
      << std::ldexp(jump.get_d(), -(r.is_bcu() ? gb : gf)) << " output LSB";
    return m.str();
  }
  return "";
}

void Continuity::advance(const Record& r) {
  have_ = true;
  kind_ = r.kind;
  end_.resize(h_.axes);
  if (r.is_bcu()) {
    for (int a = 0; a < h_.axes; ++a) end_[a] = r.regs[a][3];
    return;
  }
  fd::Compiled c;
  c.ticks = r.ticks;
  c.regs = r.regs;
  for (int a = 0; a < h_.axes; ++a) end_[a] = fd::Compiler::state_at(c, a, r.ticks, h_.width);
}

// ---------------------------------------------------------------------------
// Writers
// ---------------------------------------------------------------------------
namespace {
// The record as the writers number it, refused if it would jump.
std::vector<uint8_t> numbered(const Header& h, const Record& r, uint64_t seq, Continuity& chain) {
  std::vector<uint8_t> b = encode_numbered(h, r, static_cast<uint32_t>(seq));
  int axis = 0;
  const std::string jump = chain.check(r, axis);
  if (!jump.empty()) throw StreamError("segment " + std::to_string(seq) + ": " + jump);
  chain.advance(r);
  return b;
}
}  // namespace

void write_file(const std::string& path, const Header& h, const std::vector<Record>& recs,
                const std::vector<Pause>& pauses) {
  std::vector<uint8_t> all = encode_header(h);
  Continuity chain(h);
  uint64_t ticks = 0;
  size_t next_pause = 0;
  for (size_t i = 0; i < recs.size(); ++i) {
    if (next_pause < pauses.size() && pauses[next_pause].before <= i) {
      const Pause& p = pauses[next_pause++];
      if (p.before != i || i == 0 || (next_pause < pauses.size() && pauses[next_pause].before == i))
        throw StreamError(path + ": pause before segment " + std::to_string(p.before) +
                          " out of order, repeated, or before the first segment");
      const auto b = encode_pause(p);
      all.insert(all.end(), b.begin(), b.end());
    }
    const auto b = numbered(h, recs[i], i, chain);
    all.insert(all.end(), b.begin(), b.end());
    ticks += recs[i].ticks;
  }
  if (next_pause < pauses.size())
    throw StreamError(path + ": pause before segment " + std::to_string(pauses[next_pause].before) + " of " +
                      std::to_string(recs.size()) + ": nothing follows it");
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

StreamWriter::StreamWriter(const std::string& path, const Header& h)
    : h_(h), file_(open_stream_file(path)), chain_(h) {
  put(encode_header(h));
}

void StreamWriter::put(const std::vector<uint8_t>& bytes) {
  file_.out().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!file_.out()) throw StreamError("write failed: " + file_.tmp_path());
}

void StreamWriter::pause(uint32_t line, const std::string& text) {
  if (count_ == 0) return;
  if (const std::string why = pause_text_problem(text); !why.empty())
    throw StreamError(file_.tmp_path() + ": pause at line " + std::to_string(line) + ": " + why);
  pause_ = Pause{count_, line, text};
}

void StreamWriter::add(const Record& r) {
  if (pause_) put(encode_pause(*pause_));
  pause_.reset();
  put(numbered(h_, r, count_, chain_));
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

// ---------------------------------------------------------------------------
// Reader
// ---------------------------------------------------------------------------
namespace {
size_t read_some(std::istream& in, uint8_t* p, size_t n) {
  in.read(reinterpret_cast<char*>(p), static_cast<std::streamsize>(n));
  return static_cast<size_t>(in.gcount());
}
// Offset of the first nonzero byte in b[from, to), or `to`.
size_t first_nonzero(const std::vector<uint8_t>& b, size_t from, size_t to) {
  while (from < to && b[from] == 0) ++from;
  return from;
}
}  // namespace

bool StreamReader::fail(uint64_t off, const std::string& what) {
  error_ = at(name_, off) + what;
  done_ = true;
  return false;
}

StreamReader::StreamReader(std::istream& in, std::string name) : in_(in), name_(std::move(name)) {
  std::vector<uint8_t> b(kHeaderBytes);
  const size_t n = read_some(in_, b.data(), b.size());
  uint64_t where = 0;
  const std::string p = header_problem(b, n, where);
  if (!p.empty()) {
    fail(where, p);
    return;
  }
  chain_ = Continuity(h_);
  off_ = kHeaderBytes;
}

std::string StreamReader::header_problem(const std::vector<uint8_t>& b, size_t n, uint64_t& at) {
  const std::string truncated = "truncated header (" + std::to_string(n) + " bytes)";
  if (n < 4) return truncated;
  if (std::memcmp(b.data(), "TRJS", 4) != 0) return "bad magic (not a trajcore segment stream)";
  if (n < 6) return truncated;
  const int version = static_cast<int>(get(&b[4], 2));
  if (version != kVersion) {
    at = 4;
    return "unsupported version " + std::to_string(version) + " (this reader reads version " +
           std::to_string(kVersion) + " only: write the stream again with this trajcore)";
  }
  if (n < 8) return truncated;
  if (get(&b[6], 2) != kHeaderBytes) {
    at = 6;
    return "unexpected header size " + std::to_string(get(&b[6], 2)) + " for version " + std::to_string(kVersion) +
           " (" + std::to_string(kHeaderBytes) + ")";
  }
  if (n < size_t(kHeaderBytes)) return truncated;
  at = kHeaderBytes - 4;
  if (get(&b[kHeaderBytes - 4], 4) != crc(b.data(), kHeaderBytes - 4)) return "header checksum mismatch";
  Header& h = h_;
  h.axes = b[8];
  h.degree = b[9];
  h.width = static_cast<int>(get(&b[10], 2));
  h.chunk_width = static_cast<int>(get(&b[12], 2));
  h.guard_bits = static_cast<int>(get(&b[14], 2));
  h.frac_bits = static_cast<int16_t>(get(&b[16], 2));
  const uint64_t pbits = get(&b[20], 8);
  std::memcpy(&h.period, &pbits, 8);
  h.units.assign(reinterpret_cast<const char*>(&b[28]), strnlen(reinterpret_cast<const char*>(&b[28]), 16));
  h.bcu_ctrl_width = static_cast<int>(get(&b[44], 2));
  h.bcu_guard_bits = static_cast<int>(get(&b[46], 2));
  h.bcu_max_depth = static_cast<int>(get(&b[48], 2));
  h.bcu_out_width = static_cast<int>(get(&b[50], 2));
  h.scale_max = static_cast<double>(get(&b[18], 2)) / kScaleMaxUnit;
  if (h.scale_max == 0) {
    if ((at = first_nonzero(b, 52, 60)) < 60) return "header: time-scaling ramp bounds without s_max (bytes 18-19 are 0)";
  } else {
    uint32_t fbits = static_cast<uint32_t>(get(&b[52], 4));
    std::memcpy(&h.scale_rate, &fbits, 4);
    fbits = static_cast<uint32_t>(get(&b[56], 4));
    std::memcpy(&h.scale_accel, &fbits, 4);
    if (const std::string p = time_scaling_problem(h); !p.empty()) {
      at = h.scale_max > 2 ? 18 : (std::isfinite(h.scale_rate) && h.scale_rate > 0 ? 56 : 52);
      return "header: " + p;
    }
  }
  try {
    h.format().validate();
  } catch (const std::exception& e) {
    at = fd_field_offset(e.what());
    return std::string("header: ") + e.what();
  }
  at = 10;
  if (h.width % 8 != 0) return "register width not a multiple of 8";
  at = 20;
  if (const std::string m = util::tick_period_problem(h.period); !m.empty()) return "header: " + m;
  at = 28;
  if (!is_known_units(h.units)) return "header: units '" + h.units + "' unknown (known: " + units_list() + ")";
  if ((at = first_nonzero(b, 28 + h.units.size(), 44)) < 44)
    return "header: units padding byte " + hex2(b[at]) + ", must be 0";
  if (!h.has_bcu()) {
    at = first_nonzero(b, 44, 52);
    if (at < 52) return "header: BCU field nonzero (" + hex2(b[at]) + ") with CtrlWidth 0 (no BCU format)";
    return "";
  }
  size_t field = 44;
  const std::string p = bcu_header_problem(h, field);
  at = field;
  return p.empty() ? "" : "header: " + p;
}

std::string StreamReader::record_problem(Record& r, uint64_t& at) {
  const std::vector<uint8_t>& b = raw_;
  const size_t rb = b.size();
  at = off_;
  if (get(&b[rb - 4], 4) != crc(b.data(), rb - 4)) return "checksum mismatch";
  at = off_ + 1;
  if (b[1] != 0) return "flags " + hex2(b[1]) + ", must be 0";
  if ((at = off_ + first_nonzero(b, 2, 4)) < off_ + 4) return "reserved byte " + hex2(b[at - off_]) + ", must be 0";
  at = off_ + 8;
  r.seq = static_cast<uint32_t>(get(&b[8], 4));
  if (r.seq != static_cast<uint32_t>(count_))
    return "sequence number " + std::to_string(r.seq) + ", expected " + std::to_string(static_cast<uint32_t>(count_));
  at = off_ + 4;
  r.ticks = static_cast<uint32_t>(get(&b[4], 4));
  size_t p = 12;
  if (r.kind == RecordKind::kFd) {
    if (r.ticks == 0) return "K=0 ticks";
    if (r.ticks > kMaxTicks)
      return "K=" + std::to_string(r.ticks) + " ticks, beyond the format's bound 2^20 = " + std::to_string(kMaxTicks);
    const int wb = h_.width / 8;
    r.regs.resize(h_.axes);
    for (auto& ax : r.regs) {
      ax.resize(h_.degree + 1);
      for (auto& v : ax) {
        v = get_signed(&b[p], wb);
        p += wb;
      }
    }
  } else {
    const int d = r.depth();
    if (d < 0 || d > h_.bcu_max_depth)
      return "BCU K=" + std::to_string(r.ticks) + " is not 2^d with d <= MaxDepth " + std::to_string(h_.bcu_max_depth);
    const int cb = ctrl_bytes(h_);
    r.regs.resize(h_.axes);
    for (int a = 0; a < h_.axes; ++a) {
      r.regs[a].resize(4);
      for (int i = 0; i < 4; ++i) {
        mpz_class& v = r.regs[a][i];
        v = get_signed(&b[p], cb);
        if (!fits_bits(v, h_.bcu_ctrl_width)) {
          at = off_ + p;
          return "axis " + std::to_string(a) + " control value c" + std::to_string(i) + " = " + v.get_str() +
                 " does not fit CtrlWidth " + std::to_string(h_.bcu_ctrl_width) + " bits";
        }
        p += cb;
      }
    }
  }
  int axis = 0;
  const std::string jump = chain_.check(r, axis);
  if (!jump.empty()) {
    const size_t per_axis = r.is_bcu() ? 4 * size_t(ctrl_bytes(h_)) : size_t(h_.degree + 1) * (h_.width / 8);
    at = off_ + 12 + per_axis * axis;
    return jump;
  }
  return "";
}

bool StreamReader::read_end() {
  raw_.resize(kEndBytes);
  raw_[0] = 0xFF;
  if (pending_pause_) return fail(off_, "segment " + std::to_string(count_) + ": pause record after the last segment (nothing follows it)");
  if (read_some(in_, raw_.data() + 1, kEndBytes - 1) != size_t(kEndBytes - 1)) return fail(off_, "truncated end record");
  const auto& b = raw_;
  if (get(&b[12], 4) != crc(b.data(), 12)) return fail(off_, "end record checksum mismatch");
  if (b[1] != 0) return fail(off_ + 1, "end record: flags " + hex2(b[1]) + ", must be 0");
  if (const size_t z = first_nonzero(b, 2, 4); z < 4) return fail(off_ + z, "end record: reserved byte " + hex2(b[z]) + ", must be 0");
  if (get(&b[8], 4) != count_)
    return fail(off_ + 8, "end record counts " + std::to_string(get(&b[8], 4)) + " segments, stream has " +
                              std::to_string(count_));
  if (get(&b[4], 4) != static_cast<uint32_t>(ticks_)) return fail(off_ + 4, "end record tick total mismatch");
  if (in_.peek() != std::char_traits<char>::eof()) return fail(off_ + kEndBytes, "trailing bytes after the end record");
  complete_ = true;
  done_ = true;
  return false;
}

// A pause record: checked as the end record is, and it must follow a
// segment (not the start, not another pause).
bool StreamReader::read_pause() {
  const std::string rec = "segment " + std::to_string(count_) + ": pause record";
  raw_.resize(12);
  raw_[0] = kPauseType;
  const std::string truncated = "segment " + std::to_string(count_) + ": truncated pause record";
  if (read_some(in_, raw_.data() + 1, 11) != 11) return fail(off_, truncated);
  const size_t n = get(&raw_[2], 2);
  if (n > kMaxPauseText)  // before reading it: a damaged length would read up to 64 KiB
    return fail(off_ + 2, rec + ": text of " + std::to_string(n) + " bytes, at most " + std::to_string(kMaxPauseText));
  raw_.resize(kPauseBytes + n);
  if (read_some(in_, raw_.data() + 12, n + 4) != n + 4) return fail(off_, truncated);
  const auto& b = raw_;
  if (get(&b[12 + n], 4) != crc(b.data(), 12 + n)) return fail(off_, rec + " checksum mismatch");
  if (b[1] != 0) return fail(off_ + 1, rec + ": flags " + hex2(b[1]) + ", must be 0");
  const std::string text(b.begin() + 12, b.begin() + 12 + static_cast<std::ptrdiff_t>(n));
  if (const std::string why = pause_text_problem(text); !why.empty()) return fail(off_ + 12, rec + ": " + why);
  if (get(&b[8], 4) != static_cast<uint32_t>(count_))
    return fail(off_ + 8, rec + " before segment " + std::to_string(get(&b[8], 4)) + ", but " +
                              std::to_string(count_) + " segments precede it");
  if (count_ == 0) return fail(off_, rec + " before the first segment");
  if (pending_pause_) return fail(off_, rec + " after another one");
  pending_pause_ = Pause{count_, static_cast<uint32_t>(get(&b[4], 4)), text};
  off_ += kPauseBytes + n;
  return true;
}

bool StreamReader::next(Record& r) {
  if (done_) return false;
  pause_.reset();
  uint8_t type = 0;
  for (;;) {
    if (read_some(in_, &type, 1) != 1)
      return fail(off_, "truncated: no end record after " + std::to_string(count_) + " segments");
    if (type != kPauseType) break;
    if (!read_pause()) return false;
  }
  const std::string rec = "segment " + std::to_string(count_) + ": ";
  if (type == 0xFF) return read_end();
  if (type == 2 && !h_.has_bcu())
    return fail(off_, rec + "record type 2 (BCU segment) in a stream whose header has no BCU format");
  if (type != 1 && type != 2) return fail(off_, rec + "unknown record type " + hex2(type));
  r.kind = static_cast<RecordKind>(type);
  const size_t rb = record_size(h_, r.kind);
  raw_.resize(rb);
  raw_[0] = type;
  if (read_some(in_, raw_.data() + 1, rb - 1) != rb - 1) return fail(off_, rec + "truncated record");
  uint64_t where = off_;
  const std::string p = record_problem(r, where);
  if (!p.empty()) return fail(where, rec + p);
  chain_.advance(r);
  ++count_;
  ticks_ += r.ticks;
  off_ += rb;
  pause_ = pending_pause_;
  pending_pause_.reset();
  return true;
}

namespace {
ReadResult read_all(std::istream& in, const std::string& name) {
  StreamReader rd(in, name);
  ReadResult res;
  res.header = rd.header();
  Record r;
  while (rd.next(r)) {
    if (rd.pause()) res.pauses.push_back(*rd.pause());
    res.records.push_back(r);
  }
  res.complete = rd.complete();
  res.error = rd.error();
  return res;
}
}  // namespace

ReadResult decode(const std::vector<uint8_t>& bytes, const std::string& name) {
  std::istringstream in(std::string(bytes.begin(), bytes.end()), std::ios::binary);
  return read_all(in, name);
}

ReadResult read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw StreamError(path + ": cannot open");
  return read_all(in, path);
}

}  // namespace traj::stream
