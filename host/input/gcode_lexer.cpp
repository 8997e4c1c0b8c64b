// SPDX-License-Identifier: Apache-2.0
#include "input/gcode_lexer.hpp"

#include <cctype>
#include <cstdlib>

#include "input/toolpath.hpp"

namespace traj::input::gcode {
namespace {

[[noreturn]] void fail(const std::string& file, int line, const std::string& word, const std::string& why) {
  throw InputError(file + ":" + std::to_string(line) + ": " + word + ": " + why);
}

// The line without comments and blanks, letters upper-cased. A '(' comment
// ends at the first ')' (LinuxCNC does not nest them); ';' ends the line.
std::string strip(const std::string& text, int line, const std::string& file) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '(') {
      const size_t close = text.find(')', i);
      if (close == std::string::npos) fail(file, line, "(", "comment not closed on its line");
      i = close;
    } else if (c == ';') {
      break;
    } else if (c == ')') {
      fail(file, line, ")", "')' without '('");
    } else if (!std::isspace(static_cast<unsigned char>(c))) {
      out += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
  }
  return out;
}

// Reads the number after a letter at s[pos]; returns its text and advances pos.
std::string read_number(const std::string& s, size_t& pos, const std::string& word_so_far, int line,
                        const std::string& file) {
  const size_t start = pos;
  if (pos < s.size() && (s[pos] == '+' || s[pos] == '-')) ++pos;
  int digits = 0, points = 0;
  while (pos < s.size() && (std::isdigit(static_cast<unsigned char>(s[pos])) || s[pos] == '.')) {
    if (s[pos] == '.') ++points; else ++digits;
    ++pos;
  }
  const std::string num = s.substr(start, pos - start);
  if (pos < s.size() && (s[pos] == '#' || s[pos] == '['))
    fail(file, line, word_so_far + num + s[pos],
         s[pos] == '#' ? "parameters (#) are not supported" : "expressions ([ ]) are not supported");
  if (digits == 0 || points > 1) {
    // Show what follows, up to the next letter, so the user sees the bad text.
    size_t end = pos;
    while (end < s.size() && !std::isalpha(static_cast<unsigned char>(s[end]))) ++end;
    fail(file, line, word_so_far + s.substr(start, end - start), "malformed number");
  }
  return num;
}

}  // namespace

Block lex_line(const std::string& text, int line, const std::string& file) {
  Block b;
  b.line = line;
  std::string s = strip(text, line, file);
  size_t pos = 0;
  if (!s.empty() && s[0] == '%') {
    if (s.size() > 1) fail(file, line, "%", "text after '%' on its line");
    b.percent = true;
    return b;
  }
  if (pos < s.size() && s[pos] == '/') {
    b.block_delete = true;
    ++pos;
  }
  bool first = true;
  while (pos < s.size()) {
    const char c = s[pos];
    if (c == '#') fail(file, line, "#", "parameters (#) are not supported");
    if (c == '[') fail(file, line, "[", "expressions ([ ]) are not supported");
    if (!std::isalpha(static_cast<unsigned char>(c))) fail(file, line, std::string(1, c), "expected a letter");
    if (c == 'O') fail(file, line, "O", "subroutines and control flow (O-words) are not supported");
    ++pos;
    if (pos < s.size() && std::isalpha(static_cast<unsigned char>(s[pos]))) {
      // Two letters in a row: a named function or a missing number ("G", "ABS[...]").
      size_t end = pos;
      while (end < s.size() && std::isalpha(static_cast<unsigned char>(s[end]))) ++end;
      fail(file, line, s.substr(pos - 1, end - pos + 1), "a letter without a number (or an unsupported function)");
    }
    Word w;
    w.letter = c;
    const std::string num = read_number(s, pos, std::string(1, c), line, file);
    w.text = std::string(1, c) + num;
    w.value = std::strtod(num.c_str(), nullptr);
    if (c == 'N') {
      if (!first) fail(file, line, w.text, "a line number must come first on its line");
    } else {
      b.words.push_back(w);
    }
    first = false;
  }
  return b;
}

}  // namespace traj::input::gcode
