// SPDX-License-Identifier: Apache-2.0
// The one validity rule (and message) for a servo tick period, shared by every
// layer that takes one: the job's machine description, the planner, the
// compiler, the stream header.
#pragma once
#include <cmath>
#include <string>

#include "util/format.hpp"

namespace traj::util {

// Empty if `h` (seconds) is a valid tick period, otherwise the message.
inline std::string tick_period_problem(double h) {
  if (std::isfinite(h) && h > 0) return {};
  return "tick period " + shortest(h) + " s must be positive and finite";
}

}  // namespace traj::util
