// SPDX-License-Identifier: Apache-2.0
// G-code lines -> blocks of words, with LinuxCNC's (RS274NGC) lexical rules:
// case-insensitive letters, blanks allowed anywhere outside comments (also
// inside numbers: "X 1 . 5"), comments "( ... )" and "; ...", a leading '/'
// (block delete), a leading line number N, '%' lines. Numbers are decimal
// without exponent ("1", "-.5", "+2.", "0.25").
//
// Parameters and expressions, as LinuxCNC reads them (interp_read.cc): a
// word's value may be a number, a parameter (#5, ##1, #[2+3], #<name>), an
// expression in brackets with the binary operators ** (highest), * / MOD,
// + -, EQ NE GT GE LT LE, AND OR XOR (lowest), left-associative, or a unary
// function ABS ACOS ASIN ATAN[y]/[x] COS EXP EXISTS[#<name>] FIX FUP LN ROUND
// SIN SQRT TAN (angles in degrees), each of them after any number of unary +
// or -. A line's parameter settings (#n = value, #<name> = value) read the
// values before the line and take effect after it, in order (Block::settings,
// applied by the reader). Names are case-insensitive and blanks in them
// ignored. A numbered parameter the program has not set is refused (LinuxCNC
// takes it from its parameter file, which trajcore does not read), as are
// numbers 5000 and above (the machine's state) and the predefined named
// parameters #<_...> the program has not set. O-words (subroutines, control
// flow) are refused here, where the text is at hand.
#pragma once
#include <map>
#include <string>
#include <vector>

namespace traj::input::gcode {

struct Word {
  char letter = 0;    // upper case
  double value = 0;
  std::string text;   // as written, blanks removed ("G2", "X-1.5", "X[#<R>*2]"; long ones cut), for messages
};

// A parameter a line sets: numbered (name empty) or named (upper case, no blanks).
struct Setting {
  int number = 0;
  std::string name;
  double value = 0;
  std::string text;  // "#5", "#<R>", for messages
};

// The program's parameters.
struct Parameters {
  std::map<int, double> numbered;
  std::map<std::string, double> named;
  void apply(const std::vector<Setting>& settings);
};

struct Block {
  int line = 0;                  // 1-based line number in the file
  bool percent = false;          // a '%' line
  bool block_delete = false;     // the line starts with '/'
  std::vector<Word> words;       // without the line number N
  std::vector<Setting> settings; // parameter settings, in the order written
};

// Splits one line into a block, evaluating its values with `params` (the
// parameters before the line). Throws InputError "<file>:<line>: <word>:
// <why>" for malformed numbers and expressions and refused constructs.
Block lex_line(const std::string& text, int line, const std::string& file, const Parameters& params);

}  // namespace traj::input::gcode
