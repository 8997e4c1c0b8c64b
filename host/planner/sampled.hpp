// SPDX-License-Identifier: Apache-2.0
// trajcore planner: kinematics of sampled positions, one definition for the
// fit's checks, the report and the plots.
//
// From positions x_k at ticks k h (units), as a user would measure them on the
// core's output:
//   path speed        s_k  = |x_{k+1} - x_k| / h                     (chord speed)
//   tangential accel  at_k = (s_{k+1} - s_k) / h
//   tangential jerk   jt_k = (s_{k+2} - 2 s_{k+1} + s_k) / h^2
//   normal accel      an_k = |A - (A.T) T|,  A = (x_{k+2} - 2 x_{k+1} + x_k) / h^2,
//                            T = (x_{k+2} - x_k) / |x_{k+2} - x_k|     (centripetal)
//   normal jerk       jn_k = |J - (J.T) T|,  J = third difference / h^3,
//                            T = (x_{k+2} - x_{k+1}) / |...|          (the jerk the
//                            centripetal acceleration implies)
// where a chord is shorter than `min_chord`, the direction T is undefined and
// the normal components count as 0 (the machine is at rest there; the
// per-axis differences still bound every component).
//
// For a smooth trajectory these are the sampled versions of d|v|/dt,
// d^2|v|/dt^2, kappa v^2 and the normal part of x''' (3 kappa v a + kappa_s v^3
// + torsion terms), whose bounds the planner keeps (planner.hpp).
#pragma once
#include <cmath>

namespace traj::plan {

struct SampledWindow {
  double at = 0, jt = 0, an = 0, jn = 0;  // |.| of the quantities above, 0 where undefined
};

// Chord speed between two positions of `dim` coordinates.
inline double chord_speed(const double* a, const double* b, int dim, double h) {
  double c2 = 0;
  for (int i = 0; i < dim; ++i) c2 += (b[i] - a[i]) * (b[i] - a[i]);
  return std::sqrt(c2) / h;
}

// Tangential and normal components over the positions x0..x3 (ticks k..k+3):
// at, an use x0..x2; jt, jn use x0..x3 and are 0 when x3 is null.
inline SampledWindow sampled_window(const double* x0, const double* x1, const double* x2, const double* x3, int dim,
                                    double h, double min_chord) {
  SampledWindow w;
  const double s0 = chord_speed(x0, x1, dim, h), s1 = chord_speed(x1, x2, dim, h);
  w.at = std::fabs(s1 - s0) / h;
  double T[8], A[8], J[8], tn = 0, tn2 = 0, ta = 0, tj = 0;
  for (int i = 0; i < dim; ++i) {
    T[i] = x2[i] - x0[i];
    tn += T[i] * T[i];
    A[i] = (x2[i] - 2 * x1[i] + x0[i]) / (h * h);
  }
  tn = std::sqrt(tn);
  if (tn > 2 * min_chord) {
    double a2 = 0;
    for (int i = 0; i < dim; ++i) ta += A[i] * T[i] / tn;
    for (int i = 0; i < dim; ++i) {
      const double c = A[i] - ta * T[i] / tn;
      a2 += c * c;
    }
    w.an = std::sqrt(a2);
  }
  if (!x3) return w;
  const double s2 = chord_speed(x2, x3, dim, h);
  w.jt = std::fabs(s2 - 2 * s1 + s0) / (h * h);
  for (int i = 0; i < dim; ++i) J[i] = (x3[i] - 3 * x2[i] + 3 * x1[i] - x0[i]) / (h * h * h);
  double M[8];
  for (int i = 0; i < dim; ++i) {
    M[i] = x2[i] - x1[i];
    tn2 += M[i] * M[i];
  }
  tn2 = std::sqrt(tn2);
  if (tn2 > min_chord) {
    double j2 = 0;
    for (int i = 0; i < dim; ++i) tj += J[i] * M[i] / tn2;
    for (int i = 0; i < dim; ++i) {
      const double c = J[i] - tj * M[i] / tn2;
      j2 += c * c;
    }
    w.jn = std::sqrt(j2);
  }
  return w;
}

}  // namespace traj::plan
