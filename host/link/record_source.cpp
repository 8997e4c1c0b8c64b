#include "link/record_source.hpp"

#include <cerrno>
#include <cstring>
#include <iostream>

namespace traj::link {

RecordSource::RecordSource(const std::string& path) {
  std::istream* in = &std::cin;
  std::string name = "standard input";
  if (path != "-") {
    file_.open(path, std::ios::binary);
    if (!file_) throw LinkError(path + ": " + std::strerror(errno));
    in = &file_;
    name = path;
  }
  reader_ = std::make_unique<stream::StreamReader>(*in, name);
  if (!reader_->error().empty()) throw LinkError(reader_->error());
  if (reader_->header().has_bcu()) throw LinkError(name + ": a stream for traj_core (FD and BCU): the board plays FD "
                                                          "segments (traj_fd_engine)");
  record_bytes_ = stream::record_size(reader_->header(), stream::RecordKind::kFd);
}

bool RecordSource::next(Bytes& rec) {
  if (!reader_->next(rec_)) {
    if (!reader_->complete()) throw LinkError(reader_->error());
    return false;
  }
  if (rec_.is_bcu()) throw LinkError("segment " + std::to_string(rec_.seq) + " is a BCU segment: the board plays FD");
  rec = reader_->raw();
  return true;
}

}  // namespace traj::link
