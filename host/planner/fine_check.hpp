// SPDX-License-Identifier: Apache-2.0
// trajcore planner: a segment's sampled tangential and normal quantities
// (sampled.hpp) and chord speeds at every engine tick, bounded per segment,
// with no work per tick. The fit makes its segments on a tick coarser than
// the engine's (job::Machine::fit_ticks); this is how each one is checked at
// the engine's ticks (host/planner/README.md, "Fine ticks").
//
// Method. Let q be a segment's polynomial (per axis, degree <= 5) and h the
// engine tick. The samples' first differences are D1(t) = (q(t+h) - q(t))/h,
// a polynomial of degree 4 in the window's start t (exact coefficients, no
// cancellation: sum_{j>m} c_j C(j,m) h^(j-m-1)); D2, D3 likewise, and
// E1 = D1', E2 = D1''. With s(t) = |D1(t)| (the chord speed), the sampled
//   tangential acceleration (s(t+h) - s(t))/h  = s'(xi),  xi in [t, t+h]
//   tangential jerk  (s(t+2h) - 2 s(t+h) + s(t))/h^2 = s''(xi), xi in [t, t+2h]
// (mean values; s is smooth where D1 != 0), and
//   s' = E1.u,  s'' = E2.u + |E1 - (E1.u) u|^2 / |D1|,  u = D1/|D1|.
// Over an interval of window starts, with u0 the direction of D1 at its
// middle, the Bernstein coefficients of D1.u0 bound |D1| from below
// (sigma) and those of D1 - (D1.u0) u0 bound its normal part (N1), so every
// direction involved (u, and the chord sums the normal checks project out)
// lies within sin = eps = N1/sigma of u0; a vector's part normal to such a
// direction is at most its part normal to u0 plus eps times its part along
// u0. Hence, from Bernstein bounds of the parts of E1, E2, D2, D3 along and
// normal to u0:
//   |a_t| <= |E1.u0| + eps |E1_n|            |a_n| <= |D2_n| + eps |D2.u0|
//   |j_t| <= |E2.u0| + eps |E2_n| + (|E1_n| + eps |E1.u0|)^2 / sigma
//   |j_n| <= |D3_n| + eps |D3.u0|            chord speed <= sqrt(|D1.u0|^2 + N1^2)
// and, with no direction at all (valid always, used where D1 may vanish):
// |a_t|, |a_n| <= |D2|, |j_n| <= |D3|, |j_t| <= 2 |D2| / h. An interval whose
// bounds exceed a limit is halved; one of at most kExactWindows window starts
// (near a stop, where the chord speed vanishes) is evaluated exactly, window
// by window, as fit_segments does at every tick. So are the few windows that
// reach back into the previous segment (its last ticks, `tail`). The chords
// are means of the path speed |q'|, which speed_within bounds.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "planner/planner.hpp"
#include "planner/segments.hpp"

namespace traj::plan {

// Window starts evaluated one by one rather than bounded.
constexpr long long kExactWindows = 8;

struct FineCheckStats {
  size_t intervals = 0;       // intervals of window starts bounded
  size_t exact_windows = 0;   // windows evaluated one by one
};

// True if the samples of `seg` at engine ticks of period h (ticks 0..K of the
// segment; positions relative to tick 0), preceded by `tail` (up to 3 ticks
// before tick 0, relative to tick 0, oldest first), keep, in every tick
// window that holds a tick of the segment after tick 0 and none after tick
// K, the sampled tangential acceleration and jerk and the normal
// acceleration and jerk within L.a_tan, L.j_tan, L.a_cen, L.j_cen, and every
// chord within L.feed h: what fit_segments checks at every tick when the fit
// tick is the engine's. `why`, if given, says which failed first, and
// `fail_tick` the window's start (ticks of the segment; -1 where no one
// window failed).
bool fine_windows_ok(const TimeSegment& seg, int dim, double h, const Limits& L,
                     const std::vector<std::array<double, kMaxAxes>>& tail, std::string* why = nullptr,
                     FineCheckStats* stats = nullptr, long long* fail_tick = nullptr);

// Whether the path speed |q'| of `seg` stays within v_max over [0, T]
// (Bernstein bounds of |q'|^2, halved up to 6 times where they are above).
// Every chord between samples is then within v_max h.
bool speed_within(const TimeSegment& seg, int dim, double T, double v_max);

// Bernstein coefficients b[0..n] on [a, a + w] of the polynomial c[0..n] in
// tau (n <= 5): the polynomial lies within their hull there.
void bernstein_on(const double* c, int n, double a, double w, double* b);
// The coefficients of (p(t + h) - p(t)) / h, degree n - 1, into out[0..n-1].
void forward_difference(const double* p, int n, double h, double* out);

}  // namespace traj::plan
