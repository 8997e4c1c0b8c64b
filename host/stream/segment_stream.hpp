// trajcore segment stream, format version 1: the file (or link) format that
// carries compiled segments from the host to the core.
//
// All integers little-endian. CRC-32 is zlib's (IEEE 802.3 polynomial).
//
//   Header, 48 bytes:
//     0  char[4]  magic "TRJS"
//     4  u16      version (1)
//     6  u16      header size in bytes (48)
//     8  u8       axes (1..8)
//     9  u8       degree (1..7)
//    10  u16      register width in bits (multiple of 8, <= 128)
//    12  u16      chunk width in bits (16, 32, 64)
//    14  u16      guard bits
//    16  i16      output fraction bits F (1 LSB = 2^-F units)
//    18  u16      reserved (0)
//    20  f64      tick period in seconds
//    28  char[16] units, NUL-padded (e.g. "mm")
//    44  u32      CRC-32 of bytes 0..43
//   Segment record, 12 + axes*(degree+1)*width/8 bytes:
//     0  u8       record type: 1 = forward-difference segment
//     1  u8       flags (0)
//     2  u16      reserved (0)
//     4  u32      K, the tick count (>= 1)
//     8  bytes    registers, axis-major, r[0] first, each width/8 bytes, two's complement
//     .  u32      CRC-32 of the record's bytes before it
//   End record, 16 bytes:
//     0  u8       record type: 0xFF
//     1  u8[3]    reserved (0)
//     4  u32      segment count
//     8  u32      total ticks modulo 2^32
//    12  u32      CRC-32 of bytes 0..11
//
// A reader accepts records one by one: a damaged record stops the read with
// an error naming its index and byte offset, and every record before it stays
// accepted. A stream without its end record is reported as truncated.
#pragma once
#include <cstdint>
#include <cstdio>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

#include "fd/fd_compiler.hpp"

namespace traj::stream {

class StreamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Header {
  int axes = 3, degree = 3, width = 64, chunk_width = 16, guard_bits = 32, frac_bits = 16;
  double period = 1e-3;
  std::string units = "mm";

  fd::Format format() const;
  static Header from(const fd::Format& f, double period, const std::string& units);
};

struct Record {
  uint32_t ticks = 0;
  std::vector<std::vector<mpz_class>> regs;  // [axis][i], signed
};

constexpr int kVersion = 1;
constexpr int kHeaderBytes = 48;

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
  ~StreamWriter();
  StreamWriter(const StreamWriter&) = delete;
  StreamWriter& operator=(const StreamWriter&) = delete;
  void add(const Record& r);
  void finish();
  uint64_t records() const { return count_; }
  uint64_t ticks() const { return ticks_; }

 private:
  std::string path_, tmp_;
  Header h_;
  std::FILE* f_ = nullptr;
  uint64_t count_ = 0, ticks_ = 0;
  bool done_ = false;
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
