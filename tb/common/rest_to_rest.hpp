// SPDX-License-Identifier: Apache-2.0
// The least time of a straight move from rest to rest, in closed form: a reference for tests of the
// planner's moves between stops that does not use the planner's code.
#pragma once

#include <cmath>

namespace traj::test {

// Rest-to-rest time of a straight move of length len at speed V, acceleration
// A and jerk J (continuous time, the S-curve's closed form; the peak speed by
// bisection where the move is too short for V): the least time any motion
// within these limits takes.
inline double rest_to_rest_time(double len, double V, double A, double J) {
  auto ramp = [&](double v) { return v >= A * A / J ? v / A + A / J : 2 * std::sqrt(v / J); };
  if (V * ramp(V) <= len) return ramp(V) + len / V;
  double lo = 0, hi = V;
  for (int it = 0; it < 200; ++it) ((0.5 * (lo + hi)) * ramp(0.5 * (lo + hi)) <= len ? lo : hi) = 0.5 * (lo + hi);
  return 2 * ramp(lo);
}

}  // namespace traj::test
