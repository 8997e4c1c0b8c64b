// SPDX-License-Identifier: Apache-2.0
// A toolpath as the input readers produce it (G-code, SVG, DXF): moves in
// program order, each a curve of the path with how it is to be run.
//
// The planner's path (plan::Path) is a chain of curves; a toolpath adds, per
// move, whether it is a rapid or a feed move, its programmed feed, its path
// tolerance (G64 P) and whether the machine must stop exactly at its end (G61,
// and every rapid). Units are always millimetres here: a reader converts
// inches (G20) and SVG/DXF units when it reads.
#pragma once
#include <stdexcept>
#include <string>
#include <vector>

#include "geometry/bspline.hpp"
#include "planner/program_pause.hpp"

namespace traj::input {

struct Move {
  enum class Kind { kRapid, kFeed };
  Kind kind = Kind::kFeed;
  geo::BSpline curve;      // the move's geometry in mm (line, arc, helix, spline); starts where the previous ended
  double feed = 0;         // speed along the curve in all its axes, units/s; 0 for rapids (they run at the rapid limits)
  // feed / feed_scale is the programmed feed (F / 60, mm/s or degrees/s): as
  // LinuxCNC, F is the speed of X Y Z when they move, else of U V W, else of
  // A B C, and the other axes keep pace; feed_scale is the curve's length in
  // all axes over that (1 for a move of X Y Z alone).
  double feed_scale = 1;
  double tolerance = -1;   // path tolerance for this move, mm (G64 P); < 0: the job's --tol
  bool exact_stop = false; // the machine stops at the end of this move (G61, G61.1, rapids, a dwell, M1)
  double dwell = 0;        // seconds at rest at the end of this move (G4), after its exact stop
  // a program pause follows (M0/M60 with --pause-wait): the machine stops
  // exactly (exact_stop) and waits there for the operator
  plan::ProgramPause pause{};
  std::string where;       // "<file>:<line>" (G-code), "<file>: path <id>" (SVG), "<file>: entity <n>" (DXF)
};

struct Toolpath {
  std::vector<Move> moves;
  int axes = 3;              // axes the curves carry (2 for SVG, 3 for DXF, 3 or more for G-code: GcodeOptions::axes)
  std::vector<std::string> notes;  // words accepted and not acted on (spindle, coolant, tool), one per kind, with where
};

// Reader errors: one clear message "<file>:<line>: <word>: <why>" (G-code) or
// "<file>: <where>: <why>" (SVG, DXF).
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace traj::input
