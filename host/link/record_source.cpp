#include "link/record_source.hpp"

#include <cerrno>
#include <cstring>
#include <iostream>

namespace traj::link {

RecordSource::RecordSource(const std::string& path, double max_engine_tick) {
  std::istream* in = &std::cin;
  std::string name = "standard input";
  if (path != "-") {
    file_.open(path, std::ios::binary);
    if (!file_) throw LinkError(path + ": " + std::strerror(errno));
    in = &file_;
    name = path;
  }
  name_ = name;
  reader_ = std::make_unique<stream::StreamReader>(*in, name);
  if (!reader_->error().empty()) throw LinkError(reader_->error());
  if (reader_->header().has_bcu()) throw LinkError(name + ": a stream for traj_core (FD and BCU): the board plays FD "
                                                          "segments (traj_fd_engine)");
  record_bytes_ = stream::record_size(reader_->header(), stream::RecordKind::kFd);
  if (const uint32_t n = stream::engine_ticks_per_tick(reader_->header().period, max_engine_tick); n > 1)
    retick_ = std::make_unique<stream::Reticker>(reader_->header(), n);
}

bool RecordSource::read_coarse() {
  if (!reader_->next(rec_)) {
    if (!reader_->complete()) throw LinkError(reader_->error());
    return false;
  }
  if (rec_.is_bcu()) throw LinkError("segment " + std::to_string(rec_.seq) + " is a BCU segment: the board plays FD");
  return true;
}

bool RecordSource::next(Bytes& rec) {
  pause_.reset();
  if (!retick_) {
    if (!read_coarse()) return false;
    rec = reader_->raw();
    pause_ = reader_->pause();
    return true;
  }
  while (pending_next_ == pending_.size()) {
    if (!read_coarse()) return false;
    pending_.clear();
    pending_next_ = 0;
    try {
      retick_->add(rec_, pending_);
    } catch (const stream::StreamError& e) {
      throw LinkError(name_ + ": " + e.what());
    }
    coarse_pause_ = reader_->pause();
  }
  if (pending_next_ == 0) pause_ = coarse_pause_;  // before the first fine record of the paused one
  rec = stream::encode_record(retick_->header(), pending_[pending_next_++]);
  ++given_;
  return true;
}

}  // namespace traj::link
