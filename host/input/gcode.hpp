// SPDX-License-Identifier: Apache-2.0
// G-code reader: the RS274NGC subset CAM post-processors emit, with LinuxCNC's
// semantics (checked against LinuxCNC's own interpreter, rs274, by the test
// input.crosscheck.linuxcnc_examples; see host/input/README.md).
//
// Acted on: G0 G1 G2 G3 (centre I J K or R, helical, P turns, planes
// G17/G18/G19; the further axes A B C U V W of GcodeOptions::axes move
// linearly with lines and arcs), G5 G5.1 G5.2/G5.3, G20/G21, G90/G91, G90.1/G91.1,
// G61/G61.1/G64 P, F (units per minute; G93 inverse time: each G1 G2 G3 takes
// 1/F minutes, F on every one; G93 and G94 set the feed to 0, as in LinuxCNC),
// G73/G81/G82/G83 drilling cycles with G98/G99, R, Q, P, L and G80 (in G17,
// expanded into rapids and feeds as rs274 expands them), G4 P (the move
// before it ends in a stop and rests P seconds: Move::dwell), G28/G30 (to
// the machine origin:
// LinuxCNC's parameters 5161-5166 and 5181-5186 at their default 0), G43 H
// (with a tool table; the moves are then of the tool's holder, the
// program's Z plus the length) and G49, G53 with G0/G1 (machine
// coordinates: the holder's, G54 being zero), T with M6 (the tool G43
// without H takes), comments, N, '/', '%', M2/M30; parameters (#n, #<name>)
// and expressions ([ ], operators, functions) as LinuxCNC reads them
// (gcode_lexer.hpp); O-words: subroutines, conditions and loops as LinuxCNC
// runs them (gcode_flow.hpp).
// Accepted with a note: S, M3/M4/M5, M7/M8/M9, T, M6, G40, G54, G80,
// G64 Q, M1 (the optional stop: the move before it ends in an exact stop and
// the program goes on, as LinuxCNC with its optional-stop switch off; CAM
// posts write it between operations). Everything else is refused with one InputError
// "<file>:<line>: <word>: <why>".
//
// The program starts at X0 Y0 Z0 (as rs274 does) and ends at M2, M30 or the
// closing '%'; a file without one of them is refused (as LinuxCNC does).
// Moves of zero length produce no Move.
#pragma once
#include <istream>
#include <map>
#include <optional>
#include <memory>
#include <string>
#include <vector>

#include "input/toolpath.hpp"

namespace traj::input {

// The machine's tool table, LinuxCNC's format: one tool a line,
// "T<n> P<pocket> Z<length> D<diameter> ;comment" (words in any order; T and
// P required). Only Z length offsets are taken (a non-zero X, Y, A, B, C, U,
// V or W offset is refused); lengths in mm, the machine's units.
struct ToolTable {
  std::string file;
  std::map<int, double> z;  // tool number -> Z length offset, mm
};
// Throws InputError "<file>:<line>: <word>: <why>" for a malformed line.
ToolTable read_tool_table(const std::string& file);

// The machine's axes: "XYZ" and then up to five of A B C U V W, each once, in
// the order the curves carry them (e.g. "XYZA", "XYZBC"). A B C are rotary
// (degrees, whatever G20/G21 says), U V W linear. Throws InputError naming
// what is wrong.
void check_axes(const std::string& axes);

struct GcodeOptions {
  // The machine's axes (check_axes): words of other axes are refused.
  std::string axes = "XYZ";
  // LinuxCNC's block-delete switch: when on, lines starting with '/' are
  // skipped; when off (LinuxCNC's default, and rs274's) they run.
  bool block_delete = false;
  // G43 takes its length from here; without a table G43 is refused (a
  // length taken as 0 would move a real tool's tip by its length).
  std::optional<ToolTable> tools;
  // M0 and M60 (program pause) taken as exact stops, as M1 is: the motion
  // goes on at once, with no operator to resume it. Off (the default), they
  // are refused: a program that pauses for a manual tool change would run on
  // with the wrong tool.
  bool pauses_as_stops = false;
  // M0 and M60 as program pauses (Move::pause): exact stops where the
  // stream holds a pause record, at which `trajcore upload` waits for the
  // operator. Not with pauses_as_stops.
  bool pauses_wait = false;
};

// The moves one at a time, as the program is read (a line at a time): memory
// does not grow with the program. Errors as read_gcode's, thrown by next()
// when the line that has them is reached.
class GcodeReader {
 public:
  explicit GcodeReader(const std::string& file, const GcodeOptions& options = {});
  GcodeReader(std::istream& in, const std::string& name, const GcodeOptions& options = {});
  ~GcodeReader();
  // The next move; false at the program's end.
  bool next(Move& m);
  // Notes so far (words accepted and not acted on).
  const std::vector<std::string>& notes() const;
  // The axes the moves' curves carry (GcodeOptions::axes).
  int axes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

Toolpath read_gcode(const std::string& file, const GcodeOptions& options = {});
// The same from a stream; `name` is used in messages and Move::where.
Toolpath read_gcode(std::istream& in, const std::string& name, const GcodeOptions& options = {});

}  // namespace traj::input
