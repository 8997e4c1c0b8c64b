// SPDX-License-Identifier: Apache-2.0
// trajcore segment stream: the file (or link) format that carries compiled
// segments from the host to the core, version 4: forward-difference segments
// (traj_fd_engine) and, when the header carries a BCU format, BCU segments
// (traj_core: both engines behind one word stream, tuser = kind). Every record
// carries its sequence number; the link (rtl/board/LINK.md) sends the records
// as they are in the file, one per SEGMENT frame. The reader accepts version 4
// only. host/stream/README.md is the reference for every layout.
//
// All integers little-endian. CRC-32 is zlib's (IEEE 802.3 polynomial).
//
//   Header, 64 bytes
//     0  char[4]  magic "TRJS"
//     4  u16      version (3)
//     6  u16      header size in bytes (64)
//     8  u8       axes (1..8), both engines
//     9  u8       FD degree (1..7)
//    10  u16      FD register width in bits (multiple of 8, <= 128)
//    12  u16      chunk width in bits (16, 32, 64): the word width of the
//                 segment stream, for both engines (traj_core has one)
//    14  u16      FD guard bits
//    16  i16      output fraction bits F (1 LSB = 2^-F units), both engines
//    18  u16      reserved (0)
//    20  f64      tick period in seconds
//    28  char[16] units, one of known_units(), NUL-padded (padding all 0)
//    44  u16      BCU CtrlWidth, control value width in bits (2..128-3*MaxDepth);
//                 0: no BCU format (44..51 all 0, no BCU records)
//    46  u16      BCU GuardBits, control bits below the output LSB (0..CtrlWidth-2)
//    48  u16      BCU MaxDepth, largest d (1..30)
//    50  u16      BCU OutWidth, sample width; must equal FD width - FD guard bits
//                 (one sample port)
//    52  u8[8]    reserved (0)
//    60  u32      CRC-32 of bytes 0..59
//   FD segment record, type 1, 16 + axes*(degree+1)*width/8 bytes:
//     0  u8       record type: 1 = forward-difference segment
//     1  u8       flags (0)
//     2  u16      reserved (0)
//     4  u32      K, the tick count, 1..kMaxTicks
//     8  u32      seq, the sequence number: 0 for the first record, +1 per record
//    12  bytes    registers, axis-major, r[0] first, each width/8 bytes, two's complement
//     .  u32      CRC-32 of the record's bytes before it
//   BCU segment record, type 2, 16 + axes*4*ceil(CtrlWidth/8) bytes:
//     0  u8       record type: 2 = BCU segment (cubic Bezier, K = 2^d samples)
//     1  u8       flags (0)
//     2  u16      reserved (0)
//     4  u32      K = 2^d, the tick count, d = 0..MaxDepth
//     8  u32      seq, as for FD records (one count over both kinds)
//    12  bytes    control values c_0..c_3 (A, B, C, D), axis-major, each
//                 ceil(CtrlWidth/8) bytes two's complement, within CtrlWidth
//                 bits; LSB 2^-GuardBits output LSB (the values the generator
//                 gets, before the 8^(MaxDepth-d) pre-scaling of its word
//                 format, which the reader's side applies: traj::bcu::stream_words)
//     .  u32      CRC-32 of the record's bytes before it
//   End record, 16 bytes:
//     0  u8       record type: 0xFF
//     1  u8       flags (0)
//     2  u16      reserved (0)
//     4  u32      total ticks modulo 2^32
//     8  u32      seq = the segment count (the sequence number the next record would have)
//    12  u32      CRC-32 of bytes 0..11
//
// A reader accepts records one by one: a bad record stops the read with an
// error naming its byte offset and segment index, and every record before it
// stays accepted. Refused: a checksum mismatch, a sequence number out of order
// or repeated, nonzero flags or reserved bytes, an unknown record type or
// units, K = 0 or beyond the format's bound (FD: kMaxTicks; BCU: 2^MaxDepth),
// a BCU control value beyond CtrlWidth bits, and a segment that does not start
// exactly where the previous one ends (check_start). A stream without its end
// record is reported as truncated.
#pragma once
#include <gmpxx.h>

#include <cstdint>
#include <cstdio>
#include <iosfwd>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bcu/bcu_format.hpp"
#include "fd/fd_format.hpp"
#include "util/atomic_file.hpp"

namespace traj::stream {

class StreamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Header {
  int axes = 3, degree = 3, width = 64, chunk_width = 16, guard_bits = 32, frac_bits = 16;
  double period = 1e-3;
  std::string units = "mm";  // one of known_units()
  // BCU generator format. bcu_ctrl_width == 0: no BCU engine, the stream
  // cannot hold BCU records (the fields are written as 0).
  int bcu_ctrl_width = 0, bcu_guard_bits = 0, bcu_max_depth = 0, bcu_out_width = 0;
  // Time scaling (host/timescale): the largest s the plan was made for
  // (0: none; a multiple of 1/4096, at most 2) and the ramp bounds of s that
  // keep every per-axis limit, |ds/dt| <= scale_rate (1/s) and
  // |d2s/dt2| <= scale_accel (1/s^2), both positive when scale_max is.
  double scale_max = 0;
  float scale_rate = 0, scale_accel = 0;

  bool has_bcu() const { return bcu_ctrl_width != 0; }
  bool has_time_scaling() const { return scale_max != 0; }
  fd::Format format() const;
  bcu::Format bcu_format() const;  // axes, chunk width and F from the shared fields
  static Header from(const fd::Format& f, double period, const std::string& units);
  // Both engines (traj_core).
  static Header from(const fd::Format& f, const bcu::Format& b, double period, const std::string& units);
};

// The units a header may name.
const std::vector<std::string>& known_units();

enum class RecordKind : uint8_t { kFd = 1, kBcu = 2 };  // the record type byte

struct Record {
  uint32_t ticks = 0;                        // K (BCU: 2^d)
  std::vector<std::vector<mpz_class>> regs;  // [axis][i], signed: FD r[0..degree]; BCU c_0..c_3
  RecordKind kind = RecordKind::kFd;
  uint32_t seq = 0;                          // sequence number (read: as in the stream; the writers number
                                             // the records they write 0, 1, 2, ... whatever it holds)

  bool is_bcu() const { return kind == RecordKind::kBcu; }
  int depth() const;                         // BCU: d with K = 2^d (-1 if K is not a power of two)
};

constexpr int kVersion = 4;       // the version written and read
constexpr int kScaleMaxUnit = 4096;  // the header's s_max is a multiple of 1/4096 (written rounded down)
constexpr int kHeaderBytes = 64;
constexpr int kEndBytes = 16;
// The pause record: the end record's 16 bytes, type 0xFE, and the pause's
// text (its length at offset 2) before the CRC.
constexpr int kPauseBytes = 16;
constexpr uint8_t kPauseType = 0xFE;
// The longest pause text, bytes (a G-code line holds at most 256 characters).
constexpr size_t kMaxPauseText = 255;

// A program pause (G-code M0/M60 read with --pause-wait): the machine rests
// after segment `before` - 1 and waits for the operator before segment
// `before` (`trajcore upload`). Not a segment: it takes no sequence number
// and changes no register. Written only where the plan is at rest.
struct Pause {
  uint64_t before = 0;  // the number of segments before it (> 0)
  uint32_t line = 0;    // the program's line, 0 if none
  std::string text{};   // what the operator is to do (G-code "(MSG, ...)"): printable, at most kMaxPauseText bytes
};
// "" if `text` can stand in a pause record, else why not.
std::string pause_text_problem(const std::string& text);
// The FD record's K bound: the compiler's longest segment (fd::Format::max_ticks).
constexpr uint32_t kMaxTicks = uint32_t(1) << 20;

// Size of a record of either kind under header h.
size_t record_size(const Header& h, RecordKind kind);

std::vector<uint8_t> encode_header(const Header& h);
// One record's exact bytes as they stand in the stream (with r.seq): what a
// link SEGMENT frame carries. Throws StreamError for content the format cannot
// hold (K out of bounds, a value beyond its width, the wrong shape).
std::vector<uint8_t> encode_record(const Header& h, const Record& r);
std::vector<uint8_t> encode_end(uint32_t segments, uint64_t total_ticks);
// Throws StreamError for a text pause_text_problem refuses.
std::vector<uint8_t> encode_pause(const Pause& p);

// Continuity: each segment starts exactly where the exact prediction of the
// previous one ends. FD -> FD: r[0] = the previous r[0] after K ticks
// (sum C(K,i) r[i]); BCU -> BCU: c_A = the previous c_D; across kinds the
// integer maps of bcu/chain.hpp (the first sample of the new segment is the
// end sample of the previous one, bit for bit).
class Continuity {
 public:
  explicit Continuity(const Header& h) : h_(h) {}
  // "" if r starts where the previous record ended (or is the first), else
  // what is wrong; `axis` is set to the first axis that jumps.
  std::string check(const Record& r, int& axis) const;
  // r is accepted: the next record must start where r ends.
  void advance(const Record& r);

 private:
  Header h_;
  bool have_ = false;
  RecordKind kind_ = RecordKind::kFd;
  std::vector<mpz_class> end_;  // the previous record's exact end: FD r0 after K; BCU c_D
};

// Writes a whole stream to `path` atomically (temporary file, then rename),
// the records numbered 0, 1, 2, ...; content the format cannot hold and a
// stream that would jump are refused (StreamError) before anything is written.
// Pauses (in order, each after at least one segment and before the last
// segment ends) go between the records they name.
void write_file(const std::string& path, const Header& h, const std::vector<Record>& recs,
                const std::vector<Pause>& pauses = {});

// Incremental writer for long streams: records go to a temporary (util::AtomicFile) as they come;
// finish() appends the end record and renames; a writer destroyed before
// finish() (an error upstream) removes the temporary file, so no half-written
// stream is ever left under the final name.
class StreamWriter {
 public:
  StreamWriter(const std::string& path, const Header& h);
  void add(const Record& r);
  // A program pause after the records added so far: written before the next
  // record (none after the last one: there is nothing left to wait for).
  // The text is checked here (StreamError).
  void pause(uint32_t line, const std::string& text = "");
  void finish();
  uint64_t records() const { return count_; }
  uint64_t ticks() const { return ticks_; }

 private:
  void put(const std::vector<uint8_t>& bytes);
  Header h_;
  util::AtomicFile file_;
  Continuity chain_;
  uint64_t count_ = 0, ticks_ = 0;
  std::optional<Pause> pause_;
};

// Incremental reader (bounded memory): the header on construction, then one
// record per next(). Every check of the format is made here; nothing it
// accepts can be refused later for its content.
class StreamReader {
 public:
  StreamReader(std::istream& in, std::string name);
  const Header& header() const { return h_; }
  // true: r holds the next record, accepted. false: the end record was
  // accepted (complete()) or the stream is bad (error()).
  bool next(Record& r);
  bool complete() const { return complete_; }
  const std::string& error() const { return error_; }
  // The pause record just before the record last accepted by next(), if any.
  const std::optional<Pause>& pause() const { return pause_; }
  // The exact bytes of the record last accepted by next() (a link frame's payload).
  const std::vector<uint8_t>& raw() const { return raw_; }
  uint64_t records() const { return count_; }

 private:
  bool fail(uint64_t off, const std::string& what);
  std::string header_problem(const std::vector<uint8_t>& b, size_t n, uint64_t& at);
  std::string record_problem(Record& r, uint64_t& at);
  bool read_end();
  bool read_pause();
  std::istream& in_;
  std::string name_;
  Header h_;
  Continuity chain_{Header{}};
  std::vector<uint8_t> raw_;
  uint64_t off_ = 0, count_ = 0, ticks_ = 0;
  bool complete_ = false, done_ = false;
  std::string error_;
  std::optional<Pause> pause_, pending_pause_;
};

struct ReadResult {
  Header header;
  std::vector<Record> records;  // every record accepted before any error
  std::vector<Pause> pauses;    // the pause records before them
  bool complete = false;        // end record seen and consistent
  std::string error;            // empty if complete
};

// Decodes a byte buffer; never throws for damaged data (see ReadResult::error).
ReadResult decode(const std::vector<uint8_t>& bytes, const std::string& name);
// Reads a file; throws StreamError if it cannot be opened.
ReadResult read_file(const std::string& path);

}  // namespace traj::stream
