// SPDX-License-Identifier: Apache-2.0
// A file in the system's temporary folder, named per process (ctest runs
// the cases of one test program in parallel), removed when it goes out of
// scope: a test leaves no file behind, also when it fails.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace traj::test {

struct TmpFile {
  std::string path;
  explicit TmpFile(const std::string& stem)
      : path((std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + "_" + stem)).string()) {}
  ~TmpFile() { std::remove(path.c_str()); }
  TmpFile(const TmpFile&) = delete;
  TmpFile& operator=(const TmpFile&) = delete;
  void write(const std::string& text) const {
    std::ofstream o(path, std::ios::binary);
    o << text;
  }
};

}  // namespace traj::test
