// SPDX-License-Identifier: Apache-2.0
// The simulated board's step/dir pins against the host's exact prediction.
//
// The prediction is the stream's own: every tick's sample, from the records
// by the exact register recurrence (fd::FdTicker). One step is 2^shift output
// LSB, so after tick n an axis has made floor(s_n / 2^shift) - floor(s_0 /
// 2^shift) steps (the first sample sets the position, no steps). Each
// boundary the generator's path (below) crosses between ticks n-1 and n is
// one expected step, in order and direction; the decoded rising edges of the
// step pin must be exactly these, one for one (no step lost, none extra, none
// reversed), with one exception: the generator nets its steps before it
// pulses them, so a step and the opposite step across the same boundary
// within a pulse and a direction turn (the path touching a boundary) may make
// no edge; such pairs are counted and reported.
//
// The path: the step generator (rtl/traj_step_gen.sv) runs, one tick behind
// the samples, 2^m sub-chords per tick through the quadratic that passes
// the samples n-2, n-1, n (m from the tick period; the first tick a single
// chord from the first sample's step boundary). Its steps are the boundaries
// this path crosses, recomputed here in exact integer arithmetic from the
// samples (not from the RTL), with the time each is crossed; an edge's delay
// from that time is reported (minimum and maximum, µs): a constant latency
// plus the pulse generator's queueing. (How close the path's crossings are
// to the polynomial's: tb/board/bench_step_timing.)
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "board/sim_board.hpp"
#include "stream/segment_stream.hpp"

namespace traj::board {

struct AxisSteps {
  uint64_t expected = 0, decoded = 0;  // steps (edges)
  uint64_t cancelled = 0;  // pairs of predicted steps netted out before their pulse
  int64_t final_expected = 0, final_decoded = 0;  // net position, steps
  double delay_min_us = 0, delay_max_us = 0;
  uint64_t delay_min_tick = 0, delay_max_tick = 0;  // where they are
};

struct StepCheck {
  bool scaled = false;  // check_steps_scaled: against the board's own output samples
  uint64_t ticks_expected = 0, ticks_seen = 0;
  std::vector<AxisSteps> axes;
  uint64_t mismatches = 0;   // expected steps not matched by an edge of the same direction
  uint64_t violations = 0;   // pulse width / direction setup or hold below the configured
  std::string first_problem;
  bool ok() const { return mismatches == 0 && violations == 0 && ticks_seen >= ticks_expected; }
};

StepCheck check_steps(const stream::ReadResult& expected, const std::vector<int>& shifts,
                      const SimulatedBoard& board);

// With time scaling (CONFIG's m != 0) the board's output is the stream's
// trajectory re-timed, so the pins are checked against the path the step
// generator makes through the board's own output samples (kept by
// SimulatedBoard::keep_samples, one per servo tick, timed from each
// sample's cycle), and those samples against the prediction by
// check_on_path.
StepCheck check_steps_scaled(const std::vector<int>& shifts, const SimulatedBoard& board);

// Time-scaled output samples (axis-major, `axes` per sample) against the
// trajectory's engine samples (the same layout): each output lies on the
// polyline through the engine samples within `tol_lsb` per axis, at a
// position (in engine ticks) that never goes back and advances by at most
// `max_advance` per output sample; the last output is the last engine
// sample (nothing lost). Where the path comes back within `tol_lsb` of
// itself (out and back along a line, a stop at a corner) or rests (engine
// samples alike) an output matches more than one place: the check keeps,
// per output, every place that some place of the output before reaches,
// and fails where none is left; its figures are those of one such
// assignment (the latest places, taken from the end back).
struct PathCheck {
  uint64_t samples = 0;
  double worst_lsb = 0;        // largest distance from the polyline, per axis
  double largest_advance = 0;  // engine ticks between consecutive outputs
  bool ends_on_last = false;
  std::string first_problem;
  bool ok() const { return first_problem.empty() && ends_on_last; }
};
PathCheck check_on_path(const std::vector<int64_t>& engine, const std::vector<int64_t>& out, int axes,
                        double tol_lsb, double max_advance);
std::string describe(const PathCheck& c);

// The report's paragraph.
std::string describe(const StepCheck& c);

}  // namespace traj::board
