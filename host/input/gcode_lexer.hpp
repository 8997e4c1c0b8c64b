// SPDX-License-Identifier: Apache-2.0
// G-code lines -> blocks of words, with LinuxCNC's (RS274NGC) lexical rules:
// case-insensitive letters, blanks allowed anywhere outside comments (also
// inside numbers: "X 1 . 5"), comments "( ... )" and "; ...", a leading '/'
// (block delete), a leading line number N, '%' lines. Numbers are decimal
// without exponent ("1", "-.5", "+2.", "0.25").
//
// Constructs of the full language the reader does not implement (parameters
// '#', expressions '[ ]', O-words) are refused here, where the text is at hand.
#pragma once
#include <string>
#include <vector>

namespace traj::input::gcode {

struct Word {
  char letter = 0;    // upper case
  double value = 0;
  std::string text;   // as written, blanks removed ("G2", "X-1.5"), for messages
};

struct Block {
  int line = 0;                  // 1-based line number in the file
  bool percent = false;          // a '%' line
  bool block_delete = false;     // the line starts with '/'
  std::vector<Word> words;       // without the line number N
};

// Splits one line into a block. Throws InputError "<file>:<line>: <word>: <why>"
// for malformed numbers and refused constructs.
Block lex_line(const std::string& text, int line, const std::string& file);

}  // namespace traj::input::gcode
