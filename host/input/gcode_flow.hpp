// SPDX-License-Identifier: Apache-2.0
// O-words: subroutines and control flow, run as LinuxCNC's interpreter runs
// them (https://linuxcnc.org/docs/html/gcode/o-code.html; its behaviour
// checked against rs274 by input.crosscheck.control_flow, 300 random
// programs, and input.crosscheck.linuxcnc_examples).
//
// GcodeFlow reads a program's lines and runs its O-words itself; every other
// line is handed on in the order the program runs it:
//   O<name> sub ... O<name> endsub [v]   a subroutine (numbered or named),
//                                        defined before its call, not nested
//   O<name> call [a1] [a2] ...           #1..#30 are the callee's own: the
//                                        arguments, 0 for the rest; the
//                                        caller's named parameters that do
//                                        not start with '_' are hidden from
//                                        it, its own are dropped at return;
//                                        at most 9 calls nested (LinuxCNC's)
//   O<name> return [v], endsub [v]       #<_value> = v, #<_value_returned> = 1
//                                        (both 0 without v); a return belongs
//                                        to its subroutine, whatever its label
//   O<n> if [c] / elseif [c] / else / endif
//   O<n> while [c] / endwhile,  O<n> do / while [c],  O<n> repeat [k] / endrepeat
//   O<n> break, O<n> continue            of a while or do loop
// The model is LinuxCNC's: a label belongs to one construct for the whole
// run (its first line; used again elsewhere it is refused), a false
// condition, a break or a continue skips to the label's next O-word line
// (nothing else runs on the way), a loop's end jumps back to its opening
// line, and there is one if flag, one break flag and one continue flag.
// So the flags' effects outside their own loop are LinuxCNC's too: after a
// break of a while loop the next do loop to end stops there; after a
// continue of a do loop the next skip to an endwhile (a false condition, a
// break) goes back to its while, and one to an endrepeat starts the repeat
// over. Subroutine files (a call of a
// name not defined in the program before the call) are not read: such a
// call is refused.
//
// Memory: the lines are kept only from the start of the loops running
// forward in the main program, the callers' return lines and the
// subroutines' bodies: a program without loops is read a line at a time.
// Bounds for any input: 1 000 000 turns of one run of a loop (LinuxCNC has
// none: a program that loops forever there is refused here).
#pragma once
#include <istream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "input/gcode_lexer.hpp"

namespace traj::input::gcode {

class GcodeFlow {
 public:
  // `params` are the program's parameters (the interpreter's); calls and
  // returns scope them.
  GcodeFlow(std::istream& in, std::string file, Parameters& params);
  ~GcodeFlow();
  // The next line to run (not an O-word) and its line number in the file;
  // false at the end of the file (line: then the file's last line). Throws InputError "<file>:<line>: <word>:
  // <why>" for O-words that do not match or cannot run.
  // At the end of the file a construct still open, or a subroutine not
  // returned from, is refused (a program that ends with M2 inside one is
  // not asked for more lines).
  bool next(std::string& text, int& line);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace traj::input::gcode
