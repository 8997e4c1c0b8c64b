// SPDX-License-Identifier: Apache-2.0
// trajcore host: the forward-difference recurrence in double precision, the
// reference form of the algorithm (the engine runs the same recurrence on
// fixed-point registers).
//
// With y_k = p(t0 + k h) and registers r_i = Delta^i y_0 (i = 0..N):
//     one tick:  r_i <- r_i + r_{i+1}  for i = 0..N-1 (old values; ascending
//                order in place uses r_{i+1} before it is updated), r_N fixed,
//     output:    y_k = r_0 before the k-th update.
// Proof: Delta^i y_{k+1} = Delta^i y_k + Delta^{i+1} y_k by the definition of
// Delta; Delta^N y is constant for degree N.
// [FD] (sec. 3.2-3.3) prints r_{i+1} <- r_{i+1} + r_i with the output in
// r_N. That keeps y_0 = r_0 constant and sums it into the higher registers:
// it does not reproduce p (tb/fd/fd_recurrence_test.cpp shows both).
#pragma once
#include <vector>

namespace traj::fd {

inline double horner(const std::vector<double>& c, double t) {
  double v = 0;
  for (size_t j = c.size(); j-- > 0;) v = v * t + c[j];
  return v;
}

// r_i = Delta^i p(t0), from N+1 Horner samples.
inline std::vector<double> fd_init(const std::vector<double>& c, double t0, double h, int n) {
  std::vector<double> y(n + 1);
  for (int m = 0; m <= n; ++m) y[m] = horner(c, t0 + m * h);
  std::vector<double> r(n + 1);
  r[0] = y[0];
  for (int i = 1; i <= n; ++i) {
    for (int m = 0; m + i <= n; ++m) y[m] = y[m + 1] - y[m];
    r[i] = y[0];
  }
  return r;
}

inline void fd_step(std::vector<double>& r) {
  for (size_t i = 0; i + 1 < r.size(); ++i) r[i] += r[i + 1];
}

// [FD]'s printed update (kept to show that it fails).
inline void fd_step_printed(std::vector<double>& r) {
  for (size_t i = 0; i + 1 < r.size(); ++i) r[i + 1] += r[i];
}

}  // namespace traj::fd
