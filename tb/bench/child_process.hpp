// SPDX-License-Identifier: Apache-2.0
// One benchmark case in a child process of its own (its own max RSS, and a
// case that throws or dies does not end the others).
#pragma once
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <exception>

namespace traj::bench {

// Runs f in a child process; false if it failed (an exception is printed
// after `failed`, e.g. "FAILED: ").
template <class F>
bool in_child(F f, const char* failed) {
  std::fflush(stdout);  // nothing buffered is printed twice
  const pid_t pid = fork();
  if (pid == 0) {
    try {
      f();
    } catch (const std::exception& e) {
      std::printf("%s%s\n", failed, e.what());
      std::fflush(stdout);
      _exit(1);
    }
    std::fflush(stdout);
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

}  // namespace traj::bench
