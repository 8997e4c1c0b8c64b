// SPDX-License-Identifier: Apache-2.0
// Atomic file output: nothing half-written is ever left under the final name.
//
// AtomicFile writes to "<path>.<pid>.tmp" and renames it onto `path` in
// commit(); if commit() is never reached (an exception, an early return),
// the destructor removes the temporary file, so the target is either the old
// file, the complete new one, or absent. The parent directory is created.
// The process id keeps two processes that write one name apart (a batch of
// `trajcore plan` runs in one folder, each to the default out/plan.trj):
// with one shared temporary they would write into the same file, and one
// would rename a mix of both into place while the other failed; each writes
// its own and the last rename wins, whole.
// The path "-" is standard output, written as it comes (a pipe's reader sees
// an incomplete stream as truncated).
#pragma once
#include <fstream>
#include <string>

namespace traj::util {

// Installs handlers for SIGINT, SIGTERM, SIGHUP and SIGPIPE that remove the
// temporary files of the AtomicFiles open at that moment, then end the
// process by the same signal. Call once at the start of main (it replaces
// earlier handlers of those signals; a command that catches them itself
// installs its own afterwards). SIGKILL cannot be caught: a killed process
// leaves its "<path>.<pid>.tmp" (never a half-written file under the final name).
void remove_temporaries_on_signals();

// The temporary file an AtomicFile of `path` writes in this process.
std::string temporary_path(const std::string& path);

// Throws std::runtime_error if `path` cannot name an output file: empty, or
// an existing directory. AtomicFile checks it; a command checks it first too,
// so that a bad -o is refused before any work.
void check_output_path(const std::string& path);

class AtomicFile {
 public:
  // Throws std::runtime_error("cannot write <temporary>") if it cannot be opened,
  // and before creating anything if `path` is empty or names a directory.
  // "-" is standard output, written as it comes (no temporary, no rename).
  explicit AtomicFile(const std::string& path, std::ios::openmode mode = std::ios::out);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ofstream& out() { return out_; }
  const std::string& tmp_path() const { return tmp_; }
  // Flushes, closes and renames into place; throws std::runtime_error("write failed: <tmp>") on error.
  void commit();

 private:
  std::string path_, tmp_;
  std::ofstream out_;
  bool done_ = false, to_stdout_ = false;
};

}  // namespace traj::util
