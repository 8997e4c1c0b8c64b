// A segment stream (a file, or "-" for standard input) read record by record
// in bounded memory for the link: the stream's own reader checks everything
// (header, CRC, sequence numbers, K, continuity), and each accepted record's
// exact bytes are what a SEGMENT frame carries.
//
// A stream whose tick is longer than `max_engine_tick` is played at n =
// ceil(tick / max_engine_tick) engine ticks per tick: its records are
// re-compiled on the fly (stream/retick.hpp) and the link carries the fine
// records, numbered 0, 1, 2, ... (deterministic: a --resume reads them again
// the same).
#pragma once
#include <cstdint>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

#include "link/frame.hpp"
#include "stream/retick.hpp"
#include "stream/segment_stream.hpp"

namespace traj::link {

class RecordSource {
 public:
  // Opens and reads the header; throws LinkError naming the file and what is wrong.
  // max_engine_tick <= 0: always the stream's own tick.
  explicit RecordSource(const std::string& path, double max_engine_tick = stream::kMaxStepEngineTick);

  // The header of the records next() gives (the fine one when re-ticked).
  const stream::Header& header() const { return retick_ ? retick_->header() : reader_->header(); }
  // The stream's own tick period and the engine ticks per tick (1: as is).
  double stream_period() const { return reader_->header().period; }
  uint32_t engine_ticks_per_tick() const { return retick_ ? retick_->n() : 1; }
  size_t record_bytes() const { return record_bytes_; }
  // The next FD record's bytes; false after the end record. Throws LinkError
  // (the reader's message: byte and segment) for a damaged or refused record.
  bool next(Bytes& rec);
  uint64_t records() const { return retick_ ? given_ : reader_->records(); }
  // The program pause before the record next() gave last (the stream's pause
  // record; its `before` is the stream's own segment number, not the link's).
  const std::optional<stream::Pause>& pause() const { return pause_; }

 private:
  bool read_coarse();  // the stream's next record into rec_; false at its end
  std::string name_;
  std::ifstream file_;
  std::unique_ptr<stream::StreamReader> reader_;
  stream::Record rec_;
  size_t record_bytes_ = 0;
  std::unique_ptr<stream::Reticker> retick_;
  std::vector<stream::Record> pending_;  // fine records of the last coarse one, not yet given
  size_t pending_next_ = 0;
  uint64_t given_ = 0;
  std::optional<stream::Pause> pause_, coarse_pause_;
};

}  // namespace traj::link
