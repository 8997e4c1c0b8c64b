// SPDX-License-Identifier: Apache-2.0
#include "util/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace traj::util {

AtomicFile::AtomicFile(const std::string& path, std::ios::openmode mode) : path_(path), tmp_(path + ".tmp") {
  if (path == "-") {  // standard output: written as it comes (a reader sees a truncated stream on an error)
    tmp_ = "standard output";
    out_.open("/dev/stdout", mode | std::ios::out);
    if (!out_) throw std::runtime_error("cannot write to standard output");
    return;
  }
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
  errno = 0;
  out_.open(tmp_, mode | std::ios::out | std::ios::trunc);
  if (!out_) throw std::runtime_error("cannot write " + tmp_ + (errno ? std::string(": ") + std::strerror(errno) : ""));
}

AtomicFile::~AtomicFile() {
  if (done_) return;
  out_.close();
  if (path_ != "-") std::remove(tmp_.c_str());
}

void AtomicFile::commit() {
  out_.close();
  if (!out_) throw std::runtime_error("write failed: " + tmp_);
  if (path_ == "-") {
    done_ = true;
    return;
  }
  std::error_code ec;
  std::filesystem::rename(tmp_, path_, ec);
  if (ec) throw std::runtime_error("cannot move " + tmp_ + " to " + path_ + ": " + ec.message());
  done_ = true;
}

}  // namespace traj::util
