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
// parameters #<_...> the program has not set.
//
// O-words (subroutines and control flow, LinuxCNC's "O<label> keyword
// [value]..." lines) are recognised by o_line without evaluating anything
// (a line skipped by a false condition, or a subroutine's body before its
// call, may read parameters that are not set yet) and evaluated by o_values
// when they run; gcode_flow.hpp runs them. lex_line refuses an O-word.
#pragma once
#include <map>
#include <optional>
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
  std::string message;           // the operator message of a "(MSG, ...)" comment (message_of), or ""
};

enum class OKeyword {
  kSub, kEndsub, kCall, kReturn, kIf, kElseif, kElse, kEndif, kWhile, kEndwhile, kDo, kRepeat, kEndrepeat, kBreak,
  kContinue
};

struct OLine {
  std::string label;   // "100" (a number, without leading zeros) or "<NAME>" (upper case, blanks removed)
  OKeyword keyword = OKeyword::kSub;
  std::string text;    // "O100 WHILE", "O<CONE> CALL": for messages
  std::string values;  // the text after the keyword, blanks and comments removed (o_values evaluates it)
};

// The O-word of a line (an optional line number N first, then O<label> and
// its keyword), or nothing for any other line. Throws InputError for an
// O-word line that is malformed (no label, an unknown keyword).
std::optional<OLine> o_line(const std::string& text, int line, const std::string& file);
// The values after an O-word's keyword ("[#1 GT 2]", call arguments "[1] [2+3]"), evaluated with `params`.
std::vector<double> o_values(const OLine& o, int line, const std::string& file, const Parameters& params);

// Splits one line into a block, evaluating its values with `params` (the
// parameters before the line). Throws InputError "<file>:<line>: <word>:
// <why>" for malformed numbers and expressions and refused constructs.
Block lex_line(const std::string& text, int line, const std::string& file, const Parameters& params);

}  // namespace traj::input::gcode
