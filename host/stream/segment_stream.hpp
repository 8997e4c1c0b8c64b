// SPDX-License-Identifier: Apache-2.0
// trajcore segment stream: the file (or link) format that carries compiled
// segments from the host to the core. Version 1 carries forward-difference
// segments only (traj_fd_engine); version 2 adds the BCU generator's format to
// the header and BCU segment records (traj_core: both engines behind one word
// stream, tuser = kind). A writer emits version 1 whenever the header has no
// BCU format (so an FD-only stream reads on an FD-only reader), version 2
// otherwise; the reader accepts both.
//
// All integers little-endian. CRC-32 is zlib's (IEEE 802.3 polynomial).
//
//   Header, version 1: 48 bytes; version 2: 64 bytes
//     0  char[4]  magic "TRJS"
//     4  u16      version (1 or 2)
//     6  u16      header size in bytes (48 or 64)
//     8  u8       axes (1..8), both engines
//     9  u8       FD degree (1..7)
//    10  u16      FD register width in bits (multiple of 8, <= 128)
//    12  u16      chunk width in bits (16, 32, 64): the word width of the
//                 segment stream, for both engines (traj_core has one)
//    14  u16      FD guard bits
//    16  i16      output fraction bits F (1 LSB = 2^-F units), both engines
//    18  u16      reserved (0)
//    20  f64      tick period in seconds
//    28  char[16] units, NUL-padded (e.g. "mm")
//   version 1:
//    44  u32      CRC-32 of bytes 0..43
//   version 2 (BCU generator format, traj::bcu::Format):
//    44  u16      BCU CtrlWidth, control value width in bits (2..128-3*MaxDepth)
//    46  u16      BCU GuardBits, control bits below the output LSB (0..CtrlWidth-2)
//    48  u16      BCU MaxDepth, largest d (1..30)
//    50  u16      BCU OutWidth, sample width; must equal FD width - FD guard bits
//                 (one sample port)
//    52  u8[8]    reserved (0)
//    60  u32      CRC-32 of bytes 0..59
//   FD segment record, type 1, 12 + axes*(degree+1)*width/8 bytes:
//     0  u8       record type: 1 = forward-difference segment
//     1  u8       flags (0)
//     2  u16      reserved (0)
//     4  u32      K, the tick count (>= 1)
//     8  bytes    registers, axis-major, r[0] first, each width/8 bytes, two's complement
//     .  u32      CRC-32 of the record's bytes before it
//   BCU segment record, type 2 (version 2 only), 12 + axes*4*ceil(CtrlWidth/8) bytes:
//     0  u8       record type: 2 = BCU segment (cubic Bezier, K = 2^d samples)
//     1  u8       flags (0)
//     2  u16      reserved (0)
//     4  u32      K = 2^d, the tick count, d = 0..MaxDepth
//     8  bytes    control values c_0..c_3 (A, B, C, D), axis-major, each
//                 ceil(CtrlWidth/8) bytes two's complement, within CtrlWidth
//                 bits; LSB 2^-GuardBits output LSB (the values the generator
//                 gets, before the 8^(MaxDepth-d) pre-scaling of its word
//                 format, which the reader's side applies: traj::bcu::stream_words)
//     .  u32      CRC-32 of the record's bytes before it
//   End record, 16 bytes:
//     0  u8       record type: 0xFF
//     1  u8[3]    reserved (0)
//     4  u32      segment count (both kinds)
//     8  u32      total ticks modulo 2^32
//    12  u32      CRC-32 of bytes 0..11
//
// A reader accepts records one by one: a damaged record stops the read with
// an error naming its index and byte offset, and every record before it stays
// accepted. A stream without its end record is reported as truncated. A BCU
// record whose checksum holds but whose content does not fit the header's
// format (K not a power of two up to 2^MaxDepth, a control value beyond
// CtrlWidth bits) is refused the same way, naming the field.
#pragma once
#include <gmpxx.h>

#include <cstdint>
#include <cstdio>
#include <iosfwd>
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
  std::string units = "mm";
  // BCU generator format (version 2). bcu_ctrl_width == 0: no BCU engine, the
  // stream is written as version 1 and cannot hold BCU records.
  int bcu_ctrl_width = 0, bcu_guard_bits = 0, bcu_max_depth = 0, bcu_out_width = 0;

  bool has_bcu() const { return bcu_ctrl_width != 0; }
  int version() const { return has_bcu() ? 2 : 1; }
  fd::Format format() const;
  bcu::Format bcu_format() const;  // axes, chunk width and F from the shared fields
  static Header from(const fd::Format& f, double period, const std::string& units);
  // Both engines (traj_core): version 2.
  static Header from(const fd::Format& f, const bcu::Format& b, double period, const std::string& units);
};

enum class RecordKind : uint8_t { kFd = 1, kBcu = 2 };  // the record type byte

struct Record {
  uint32_t ticks = 0;                        // K (BCU: 2^d)
  std::vector<std::vector<mpz_class>> regs;  // [axis][i], signed: FD r[0..degree]; BCU c_0..c_3
  RecordKind kind = RecordKind::kFd;

  bool is_bcu() const { return kind == RecordKind::kBcu; }
  int depth() const;                         // BCU: d with K = 2^d (-1 if K is not a power of two)
};

constexpr int kVersion = 2;        // highest version written and read
constexpr int kHeaderBytes = 48;   // version 1
constexpr int kHeaderBytesV2 = 64; // version 2

inline int header_bytes(int version) { return version >= 2 ? kHeaderBytesV2 : kHeaderBytes; }
// Size of a record of either kind under header h.
size_t record_size(const Header& h, RecordKind kind);

std::vector<uint8_t> encode_header(const Header& h);
std::vector<uint8_t> encode_record(const Header& h, const Record& r);
std::vector<uint8_t> encode_end(uint32_t segments, uint64_t total_ticks);

// Writes a whole stream to `path` atomically (temporary file, then rename).
void write_file(const std::string& path, const Header& h, const std::vector<Record>& recs);

// Incremental writer for long streams: records go to `path`.tmp as they come;
// finish() appends the end record and renames; a writer destroyed before
// finish() (an error upstream) removes the temporary file, so no half-written
// stream is ever left under the final name.
class StreamWriter {
 public:
  StreamWriter(const std::string& path, const Header& h);
  void add(const Record& r);
  void finish();
  uint64_t records() const { return count_; }
  uint64_t ticks() const { return ticks_; }

 private:
  void put(const std::vector<uint8_t>& bytes);
  Header h_;
  util::AtomicFile file_;
  uint64_t count_ = 0, ticks_ = 0;
};

struct ReadResult {
  Header header;
  std::vector<Record> records;  // every record accepted before any error
  bool complete = false;        // end record seen and consistent
  std::string error;            // empty if complete
};

// Decodes a byte buffer; never throws for damaged data (see ReadResult::error).
ReadResult decode(const std::vector<uint8_t>& bytes, const std::string& name);
// Reads a file; throws StreamError if it cannot be opened.
ReadResult read_file(const std::string& path);

}  // namespace traj::stream
