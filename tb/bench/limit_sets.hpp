// The limit sets of bench_toolpaths (its header comment says what each
// stands for), shared with the tests that take a case from it.
#pragma once
#include "job/job.hpp"

namespace traj::bench {

// (i) "fast": a machine quoted with one acceleration and one jerk; feed 100
// mm/s, acceleration 3000 mm/s^2 and jerk 60000 mm/s^3 per axis, along the
// path and across it, tolerance 0.05 mm, 0.5 ms ticks.
inline job::JobConfig fast_machine() {
  job::JobConfig c;
  auto& L = c.limits;
  L.feed = 100;
  for (int a = 0; a < plan::kMaxAxes; ++a) L.v_axis[a] = 100, L.a_axis[a] = 3000, L.j_axis[a] = 60000;
  L.a_tan = L.a_cen = 3000;
  L.j_tan = L.j_cen = 60000;
  L.tol = 0.05;
  c.machine.period = 0.5e-3;
  return c;
}

// (ii) "main job": the main job's limits (the JobConfig defaults), feed 50.
inline job::JobConfig main_job() {
  job::JobConfig c;
  c.limits.feed = 50;
  return c;
}

}  // namespace traj::bench
