// SPDX-License-Identifier: Apache-2.0
// trajcore planner: jerk-limited (S-curve) feed profile along arc length.
//
// The motion along the path is a sequence of constant-jerk pieces in time:
//   s(t) = s0 + v0 tau + a0 tau^2/2 + j tau^3/6,   tau in [0, T]
// with s, v, a continuous. A velocity change v0 -> v1 that starts and ends at
// zero acceleration uses jerk +-J and acceleration up to A:
//   dv = |v1 - v0|;  if dv >= A^2/J:  t_j = A/J, t_a = dv/A - A/J  (jerk, hold, jerk)
//                    else:            t_j = sqrt(dv/J), t_a = 0
//   duration T(dv) = 2 t_j + t_a,  distance = (v0 + v1)/2 * T(dv)
// (the velocity is point-symmetric about the middle of the change, so the
// distance is the mean velocity times the duration).
// Shortest jerk phase tau (0: none): a change whose t_j at J would be
// shorter (dv < J tau^2, or A / J < tau) uses the lower jerk
// J' = min(dv / tau^2, A / tau), so that t_j = tau: it takes 2 tau
// (dv / A + tau where dv > A tau), however small dv is. A change of almost
// nothing then still takes 2 tau and 2 v tau of path, so a block shorter than
// that keeps its speed: passes and peaks only ever lower speeds for it, and
// the jerk stays within J.
//
// Stations along s carry a speed bound; between two stations a block
// accelerates, cruises at v_peak and decelerates. Look-ahead: a backward pass
// makes every station's speed reachable-to-stop from the next one, a forward
// pass makes it reachable from the previous one, so the machine can always
// stop by the end of the planned window.
#pragma once
#include <vector>

namespace traj::plan {

struct Piece {
  double t0 = 0, T = 0;              // start time, duration
  double s0 = 0, v0 = 0, a0 = 0, j = 0;
  bool dwell = false;                // at rest for T (a G4 dwell: PlanOptions::dwells)
  // Starts on a tick (a straight move re-timed on the tick grid, planner.cpp):
  // the fit ends a segment there, so that no segment spans its jerk switch.
  bool on_tick = false;
  double s(double tau) const { return s0 + tau * (v0 + tau * (a0 / 2 + tau * j / 6)); }
  double v(double tau) const { return v0 + tau * (a0 + tau * j / 2); }
  double a(double tau) const { return a0 + tau * j; }
};

// Duration of a zero-to-zero-acceleration velocity change of size dv >= 0.
double change_time(double dv, double A, double J, double tau = 0);
// Distance covered by the change v0 -> v1.
double change_distance(double v0, double v1, double A, double J, double tau = 0);
// Largest v1 >= v0 (<= vmax) reachable from v0 within distance L.
double reachable(double v0, double L, double A, double J, double vmax, double tau = 0);

// Appends the pieces of a velocity change v0 -> v1 (either direction) starting
// at time t, position s. Returns the end time.
double append_change(std::vector<Piece>& out, double t, double s, double v0, double v1, double A, double J,
                     double tau = 0);

struct Station {
  double s = 0;
  double vmax = 0;  // bound at this point
  double v = 0;     // planned speed (after the passes)
};

// Plans speeds at the stations (look-ahead passes) and the pieces between
// them. cap(i) is the cruise cap for block i (between station i and i+1).
// Station speeds are lowered in place so that every block is feasible.
std::vector<Piece> plan_blocks(std::vector<Station>& st, const std::vector<double>& cap, double A, double J,
                               double tau = 0);
// The same with a tangential acceleration per block (A[i] for block i).
std::vector<Piece> plan_blocks(std::vector<Station>& st, const std::vector<double>& cap, const std::vector<double>& A,
                               double J, double tau = 0);

// The same with a memo of the previous call's blocks: a block whose ends,
// end speeds, cap and acceleration are bitwise those of a remembered block reuses its peak
// speed (the one costly step); the result is identical to a call without the
// memo. changed[i] (one per block) tells which blocks were not found.
struct BlockMemo {
  double s0, s1, va, vb, cap, A, vp;
};
std::vector<Piece> plan_blocks(std::vector<Station>& st, const std::vector<double>& cap, const std::vector<double>& A,
                               double J,
                               std::vector<BlockMemo>& memo, std::vector<char>& changed, double tau = 0);

// Evaluation of a profile: index of the piece active at time t (pieces sorted).
int piece_at(const std::vector<Piece>& p, double t, int hint = 0);

}  // namespace traj::plan
