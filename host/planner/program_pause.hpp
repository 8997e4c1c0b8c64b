// SPDX-License-Identifier: Apache-2.0
// A program pause (G-code M0/M60 read with --pause-wait) after a move: the
// machine stops exactly and rests there, and the stream holds a pause record
// at which `trajcore upload` waits for the operator. It travels with the
// move's last curve, through blending and planning, to the segment that
// ends in the rest (job::mark_pauses) and the stream (stream::Pause).
#pragma once
#include <string>

namespace traj::plan {

struct ProgramPause {
  int line = 0;        // the program's line of the M word; 0: no pause
  std::string text{};  // what the operator is to do: the program's "(MSG, ...)" since the move before it, or ""
  explicit operator bool() const { return line > 0; }
};

}  // namespace traj::plan
