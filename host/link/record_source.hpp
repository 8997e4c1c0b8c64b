// A segment stream (a file, or "-" for standard input) read record by record
// in bounded memory for the link: the stream's own reader checks everything
// (header, CRC, sequence numbers, K, continuity), and each accepted record's
// exact bytes are what a SEGMENT frame carries.
#pragma once
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>

#include "link/frame.hpp"
#include "stream/segment_stream.hpp"

namespace traj::link {

class RecordSource {
 public:
  // Opens and reads the header; throws LinkError naming the file and what is wrong.
  explicit RecordSource(const std::string& path);

  const stream::Header& header() const { return reader_->header(); }
  size_t record_bytes() const { return record_bytes_; }
  // The next FD record's bytes; false after the end record. Throws LinkError
  // (the reader's message: byte and segment) for a damaged or refused record.
  bool next(Bytes& rec);
  uint64_t records() const { return reader_->records(); }

 private:
  std::ifstream file_;
  std::unique_ptr<stream::StreamReader> reader_;
  stream::Record rec_;
  size_t record_bytes_ = 0;
};

}  // namespace traj::link
