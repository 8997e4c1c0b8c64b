// SPDX-License-Identifier: Apache-2.0
#include "util/atomic_file.hpp"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace traj::util {

namespace {

// The temporary files open at this moment, for the signal handler: a fixed
// table of C strings (a handler may only read memory and call async-signal-safe
// functions such as unlink and _exit). Slots are claimed and released by the
// main thread; a file beyond the table is still removed on every normal exit.
constexpr int kSlots = 16;
constexpr size_t kPathMax = 4096;
char g_tmp[kSlots][kPathMax];
volatile std::sig_atomic_t g_used[kSlots];

void register_temporary(const std::string& tmp) {
  if (tmp.size() >= kPathMax) return;
  for (int i = 0; i < kSlots; ++i)
    if (!g_used[i]) {
      std::memcpy(g_tmp[i], tmp.c_str(), tmp.size() + 1);
      g_used[i] = 1;
      return;
    }
}

void unregister_temporary(const std::string& tmp) {
  for (int i = 0; i < kSlots; ++i)
    if (g_used[i] && tmp == g_tmp[i]) {
      g_used[i] = 0;
      return;
    }
}

extern "C" void remove_temporaries_and_exit(int sig) {
  for (int i = 0; i < kSlots; ++i)
    if (g_used[i]) ::unlink(g_tmp[i]);
  ::signal(sig, SIG_DFL);  // die by the same signal (the shell sees 128 + sig)
  ::raise(sig);
}

}  // namespace

void remove_temporaries_on_signals() {
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) {
    struct sigaction sa {};
    sa.sa_handler = remove_temporaries_and_exit;
    sigemptyset(&sa.sa_mask);
    sigaction(sig, &sa, nullptr);
  }
}

void check_output_path(const std::string& path) {
  if (path.empty()) throw std::runtime_error("no output file given (an empty name)");
  std::error_code ec;
  if (path != "-" && std::filesystem::is_directory(path, ec))
    throw std::runtime_error("cannot write " + path + ": it is a directory");
}

std::string temporary_path(const std::string& path) { return path + "." + std::to_string(::getpid()) + ".tmp"; }

AtomicFile::AtomicFile(const std::string& path, std::ios::openmode mode) : path_(path), tmp_(temporary_path(path)) {
  if (path == "-") {  // a pipe: written as it comes, nothing to rename or remove
    tmp_ = "/dev/stdout";
    to_stdout_ = true;
    out_.open(tmp_, mode | std::ios::out);
    if (!out_) throw std::runtime_error("cannot write to standard output");
    return;
  }
  check_output_path(path);
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
  register_temporary(tmp_);
  errno = 0;
  out_.open(tmp_, mode | std::ios::out | std::ios::trunc);
  if (!out_) throw std::runtime_error("cannot write " + tmp_ + (errno ? std::string(": ") + std::strerror(errno) : ""));
}

AtomicFile::~AtomicFile() {
  if (done_ || to_stdout_) return;
  out_.close();
  std::remove(tmp_.c_str());
  unregister_temporary(tmp_);
}

void AtomicFile::commit() {
  out_.close();
  if (!out_) throw std::runtime_error("write failed: " + tmp_);
  done_ = to_stdout_;
  if (done_) return;
  std::error_code ec;
  std::filesystem::rename(tmp_, path_, ec);
  if (ec) throw std::runtime_error("cannot move " + tmp_ + " to " + path_ + ": " + ec.message());
  done_ = true;
  unregister_temporary(tmp_);
}

}  // namespace traj::util
