// SPDX-License-Identifier: Apache-2.0
// A file or a folder in the system's temporary folder, named per process
// (ctest runs the cases of one test program in parallel), removed when it
// goes out of scope: a test leaves nothing behind, also when it fails.
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

// A folder of files, removed with them (a static one: at exit).
struct TmpDir {
  std::filesystem::path path;
  explicit TmpDir(const std::string& stem)
      : path(std::filesystem::temp_directory_path() / (stem + "_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path);
  }
  ~TmpDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TmpDir(const TmpDir&) = delete;
  TmpDir& operator=(const TmpDir&) = delete;
  // Writes `text` to the file `name` in the folder; returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    const std::string file = (path / name).string();
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }
};

}  // namespace traj::test
