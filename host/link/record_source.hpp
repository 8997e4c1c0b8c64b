// Reads a segment stream (a file, or "-" for standard input) record by record
// in bounded memory, as opaque bytes for the link: the header is checked by
// the stream reader; each FD record's CRC, type and sequence number (u32 at
// offset 8, stream version 3) are checked here before it is sent.
#pragma once
#include <cstdint>
#include <cstdio>
#include <string>

#include "link/frame.hpp"
#include "stream/segment_stream.hpp"

namespace traj::link {

class RecordSource {
 public:
  // Opens and reads the header; throws LinkError naming the file and what is wrong.
  explicit RecordSource(const std::string& path);
  ~RecordSource();
  RecordSource(const RecordSource&) = delete;
  RecordSource& operator=(const RecordSource&) = delete;

  const stream::Header& header() const { return header_; }
  size_t record_bytes() const { return record_bytes_; }
  // The next record's bytes; false after the end record (its count checked).
  // Throws LinkError naming the byte and the segment of a damaged record.
  bool next(Bytes& rec);
  uint64_t records() const { return count_; }
  bool at_end() const { return ended_; }

 private:
  bool read_exact(uint8_t* p, size_t n);
  [[noreturn]] void fail(const std::string& what) const;
  std::string name_;
  FILE* f_ = nullptr;
  bool own_ = false, ended_ = false;
  stream::Header header_;
  size_t record_bytes_ = 0;
  uint64_t offset_ = 0, count_ = 0;
};

}  // namespace traj::link
