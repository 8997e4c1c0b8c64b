#include "util/atomic_file.hpp"

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace traj::util {

AtomicFile::AtomicFile(const std::string& path, std::ios::openmode mode) : path_(path), tmp_(path + ".tmp") {
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
  out_.open(tmp_, mode | std::ios::out | std::ios::trunc);
  if (!out_) throw std::runtime_error("cannot write " + tmp_);
}

AtomicFile::~AtomicFile() {
  if (done_) return;
  out_.close();
  std::remove(tmp_.c_str());
}

void AtomicFile::commit() {
  out_.close();
  if (!out_) throw std::runtime_error("write failed: " + tmp_);
  std::filesystem::rename(tmp_, path_);
  done_ = true;
}

}  // namespace traj::util
