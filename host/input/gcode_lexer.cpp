// SPDX-License-Identifier: Apache-2.0
#include "input/gcode_lexer.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>

#include "input/toolpath.hpp"

namespace traj::input::gcode {
namespace {

constexpr double kPi = 3.14159265358979323846;
// LinuxCNC's tolerances: EQ/NE compare within it; an integer value (a
// parameter's number) may be this far from a whole number.
constexpr double kTolEqual = 0.0001;
constexpr double kTolInteger = 0.0001;
// Numbered parameters LinuxCNC has (RS274NGC_MAX_PARAMETERS); 5000 and above
// hold the machine's state.
constexpr int kMaxParameter = 5602;
constexpr int kFirstSystemParameter = 5000;
// Expressions nest at most this deep (a recursion bound for any input).
constexpr int kMaxDepth = 100;
// Word texts in messages are cut to this many characters.
constexpr size_t kMaxWordText = 48;

[[noreturn]] void fail(const std::string& file, int line, const std::string& word, const std::string& why) {
  throw InputError(file + ":" + std::to_string(line) + ": " + word + ": " + why);
}

std::string cut(const std::string& t) { return t.size() <= kMaxWordText ? t : t.substr(0, kMaxWordText) + "..."; }

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

enum class Op { kPow, kTimes, kDiv, kMod, kPlus, kMinus, kEq, kNe, kGt, kGe, kLt, kLe, kAnd, kOr, kXor };

struct OpName {
  const char* text;
  Op op;
  int precedence;
};
// Longer names first where one starts another ("**" and "*"; "XOR" and "OR" do not share a start).
constexpr OpName kOps[] = {{"**", Op::kPow, 6},  {"*", Op::kTimes, 5}, {"/", Op::kDiv, 5},  {"MOD", Op::kMod, 5},
                           {"+", Op::kPlus, 4},  {"-", Op::kMinus, 4}, {"EQ", Op::kEq, 3},  {"NE", Op::kNe, 3},
                           {"GT", Op::kGt, 3},   {"GE", Op::kGe, 3},   {"LT", Op::kLt, 3},  {"LE", Op::kLe, 3},
                           {"AND", Op::kAnd, 2}, {"OR", Op::kOr, 2},   {"XOR", Op::kXor, 2}};

// One line: its words' values and its parameter settings.
class LineParser {
 public:
  LineParser(std::string s, int line, const std::string& file, const Parameters& params)
      : s_(std::move(s)), line_(line), file_(file), params_(params) {}

  // Values until the end of the text (an O-word's condition or arguments).
  std::vector<double> values() {
    std::vector<double> v;
    while (pos_ < s_.size()) {
      start_ = pos_;
      if (!v.empty() && std::isalpha(static_cast<unsigned char>(s_[pos_])))
        error(cut(s_.substr(pos_)), "an O-word's line carries nothing but its values ([expression] ...)");
      v.push_back(real_value(0));
    }
    return v;
  }

  Block parse() {
    Block b;
    b.line = line_;
    if (!s_.empty() && s_[0] == '%') {
      if (s_.size() > 1) fail(file_, line_, "%", "text after '%' on its line");
      b.percent = true;
      return b;
    }
    if (pos_ < s_.size() && s_[pos_] == '/') {
      b.block_delete = true;
      ++pos_;
    }
    bool first = true;
    while (pos_ < s_.size()) {
      start_ = pos_;
      const char c = s_[pos_];
      if (c == '#') {
        b.settings.push_back(setting());
      } else {
        // @ and ^: LinuxCNC's polar coordinates (distance, angle)
        if (!std::isalpha(static_cast<unsigned char>(c)) && c != '@' && c != '^')
          error(std::string(1, c), "expected a letter");
        if (c == 'O') error("O", "an O-word (subroutine or control flow) must begin its line and stand alone on it");
        ++pos_;
        Word w;
        w.letter = c;
        if (c == 'N') {
          w.value = std::strtod(number().c_str(), nullptr);
          if (!first) error(text(), "a line number must come first on its line");
        } else {
          w.value = real_value(0);
          w.text = text();
          b.words.push_back(w);
        }
      }
      first = false;
    }
    return b;
  }

 private:
  std::string text() const { return cut(s_.substr(start_, pos_ - start_)); }
  [[noreturn]] void error(const std::string& word, const std::string& why) const { fail(file_, line_, word, why); }
  // the text of the word so far, with the character at the error
  [[noreturn]] void error_here(const std::string& why) const {
    error(cut(s_.substr(start_, std::min(s_.size(), pos_ + 1) - start_)), why);
  }
  bool at(const char* t) const { return s_.compare(pos_, std::char_traits<char>::length(t), t) == 0; }
  void expect(char c, const char* why) {
    if (pos_ >= s_.size() || s_[pos_] != c) error_here(why);
    ++pos_;
  }

  // A decimal number, sign optional; its text.
  std::string number() {
    const size_t begin = pos_;
    if (pos_ < s_.size() && (s_[pos_] == '+' || s_[pos_] == '-')) ++pos_;
    int digits = 0, points = 0;
    while (pos_ < s_.size() && (std::isdigit(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '.')) {
      if (s_[pos_] == '.') ++points; else ++digits;
      ++pos_;
    }
    if (digits == 0 || points > 1) {
      // show what follows, up to the next letter, so the user sees the bad text
      size_t end = pos_;
      while (end < s_.size() && !std::isalpha(static_cast<unsigned char>(s_[end]))) ++end;
      error(cut(s_.substr(start_, end - start_)), "malformed number");
    }
    return s_.substr(begin, pos_ - begin);
  }

  // LinuxCNC's read_real_value: an expression, a parameter, a unary + or -
  // before anything but a digit or '.', a unary function, or a number.
  double real_value(int depth) {
    if (depth > kMaxDepth) error_here("expression nested too deeply");
    if (pos_ >= s_.size()) error_here("a value is missing");
    const char c = s_[pos_];
    const char c1 = pos_ + 1 < s_.size() ? s_[pos_ + 1] : 0;
    double v;
    if (c == '[') {
      v = expression(depth + 1);
    } else if (c == '#') {
      v = parameter(depth + 1);
    } else if ((c == '+' || c == '-') && c1 && !std::isdigit(static_cast<unsigned char>(c1)) && c1 != '.') {
      ++pos_;
      v = real_value(depth + 1);
      if (c == '-') v = -v;
    } else if (std::isalpha(static_cast<unsigned char>(c))) {
      v = unary(depth + 1);
    } else {
      v = std::strtod(number().c_str(), nullptr);
    }
    if (!std::isfinite(v)) error(text(), "the value is not a finite number");
    return v;
  }

  // '[' value (op value)* ']', precedence climbing: left-associative at every level.
  double expression(int depth) {
    expect('[', "expected '['");
    const double v = binary(1, depth);
    expect(']', "expected an operator or ']'");
    return v;
  }

  const OpName* peek_op() const {
    for (const OpName& o : kOps)
      if (at(o.text)) return &o;
    return nullptr;
  }

  double binary(int min_precedence, int depth) {
    double left = real_value(depth);
    for (const OpName* o = peek_op(); o && o->precedence >= min_precedence; o = peek_op()) {
      pos_ += std::char_traits<char>::length(o->text);
      const double right = binary(o->precedence + 1, depth + 1);
      left = apply(o->op, left, right);
    }
    return left;
  }

  double apply(Op op, double a, double b) const {
    switch (op) {
      case Op::kPow:
        if (a < 0 && std::floor(b) != b) error(text(), "a negative number raised to a non-integer power");
        return std::pow(a, b);
      case Op::kTimes: return a * b;
      case Op::kDiv:
        if (b == 0) error(text(), "division by zero");
        return a / b;
      case Op::kMod: {
        // as LinuxCNC: MOD 0 is not a number, refused when it reaches a value
        // (a comparison or a logical operator may take it first)
        const double r = std::fmod(a, b);
        return r < 0 ? r + std::fabs(b) : r;
      }
      case Op::kPlus: return a + b;
      case Op::kMinus: return a - b;
      case Op::kEq: return std::fabs(a - b) < kTolEqual ? 1 : 0;
      case Op::kNe: return std::fabs(a - b) >= kTolEqual ? 1 : 0;
      case Op::kGt: return a > b ? 1 : 0;
      case Op::kGe: return a >= b ? 1 : 0;
      case Op::kLt: return a < b ? 1 : 0;
      case Op::kLe: return a <= b ? 1 : 0;
      case Op::kAnd: return (a == 0 || b == 0) ? 0 : 1;
      case Op::kOr: return (a != 0 || b != 0) ? 1 : 0;
      case Op::kXor: return ((a == 0) != (b == 0)) ? 1 : 0;
    }
    return 0;
  }

  double unary(int depth) {
    static const char* const kNames[] = {"ABS", "ACOS", "ASIN", "ATAN", "COS", "EXISTS", "EXP", "FIX",
                                         "FUP", "LN",   "ROUND", "SIN", "SQRT", "TAN"};
    std::string name;
    for (const char* n : kNames)
      if (at(n) && std::char_traits<char>::length(n) > name.size()) name = n;
    if (name.empty() || pos_ + name.size() >= s_.size() || s_[pos_ + name.size()] != '[') {
      size_t end = pos_;
      while (end < s_.size() && std::isalpha(static_cast<unsigned char>(s_[end]))) ++end;
      error(cut(s_.substr(start_, end - start_)), "a letter without a number (or an unknown function)");
    }
    pos_ += name.size();
    if (name == "EXISTS") {
      expect('[', "expected '['");
      if (!at("#<")) error_here("EXISTS takes a named parameter, #<name>");
      pos_ += 2;
      const std::string n = parameter_name();
      expect(']', "expected ']'");
      return params_.named.count(n) ? 1 : 0;
    }
    const double x = expression(depth);
    if (name == "ATAN") {
      expect('/', "ATAN needs a second argument: ATAN[y]/[x]");
      const double y = x, xx = expression(depth);
      return std::atan2(y, xx) * 180 / kPi;
    }
    if (name == "ABS") return std::fabs(x);
    if (name == "ACOS" || name == "ASIN") {
      if (x < -1 || x > 1) error(text(), name + " of a number outside [-1, 1]");
      return (name == "ACOS" ? std::acos(x) : std::asin(x)) * 180 / kPi;
    }
    if (name == "COS") return std::cos(x * kPi / 180);
    if (name == "SIN") return std::sin(x * kPi / 180);
    if (name == "TAN") return std::tan(x * kPi / 180);
    if (name == "EXP") return std::exp(x);
    if (name == "FIX") return std::floor(x);
    if (name == "FUP") return std::ceil(x);
    if (name == "LN") {
      if (x <= 0) error(text(), "LN of zero or a negative number");
      return std::log(x);
    }
    if (name == "SQRT") {
      if (x < 0) error(text(), "SQRT of a negative number");
      return std::sqrt(x);
    }
    // ROUND: half away from zero, as LinuxCNC does it (through an int: bounded first)
    if (std::fabs(x) > 2e9) error(text(), "ROUND of a number beyond 2e9");
    return static_cast<double>(static_cast<long long>(x + (x < 0 ? -0.5 : 0.5)));
  }

  // after "#<": the name up to '>'
  std::string parameter_name() {
    const size_t close = s_.find('>', pos_);
    if (close == std::string::npos) error_here("a named parameter #<name> not closed with '>'");
    const std::string n = s_.substr(pos_, close - pos_);
    if (n.empty()) error_here("a named parameter needs a name");
    pos_ = close + 1;
    return n;
  }

  // after '#': the number of a numbered parameter (a value within 1e-4 of a whole number)
  int parameter_number(int depth) {
    const double v = real_value(depth);
    const double r = std::round(v);
    if (std::fabs(v - r) > kTolInteger) error(text(), "a parameter number must be a whole number");
    if (r < 1 || r >= kMaxParameter)
      error(text(), "parameter numbers run from 1 to " + std::to_string(kMaxParameter - 1));
    return static_cast<int>(r);
  }

  double parameter(int depth) {
    ++pos_;  // '#'
    if (pos_ < s_.size() && s_[pos_] == '<') {
      ++pos_;
      const std::string n = parameter_name();
      const auto it = params_.named.find(n);
      if (it != params_.named.end()) return it->second;
      if (n[0] == '_')
        error(text(), "predefined parameters (#<_...>, the machine's state) are not supported, and the program has "
                      "not set this one");
      error(text(), "the named parameter is not set");
    }
    const int k = parameter_number(depth);
    const auto it = params_.numbered.find(k);
    if (it != params_.numbered.end()) return it->second;
    if (k >= kFirstSystemParameter)
      error(text(), "parameters 5000 and above (the machine's state) are not supported");
    error(text(), "the parameter is not set by the program (trajcore reads no parameter file; LinuxCNC would take "
                  "it from its .var file)");
  }

  Setting setting() {
    ++pos_;  // '#'
    Setting st;
    if (pos_ < s_.size() && s_[pos_] == '<') {
      ++pos_;
      st.name = parameter_name();
    } else {
      st.number = parameter_number(0);
      if (st.number >= kFirstSystemParameter)
        error(text(), "parameters 5000 and above (the machine's state) are not supported");
    }
    st.text = text();
    expect('=', "expected '=' (a parameter setting: #n = value)");
    st.value = real_value(0);
    return st;
  }

  std::string s_;
  size_t pos_ = 0, start_ = 0;
  int line_;
  const std::string& file_;
  const Parameters& params_;
};

}  // namespace

void Parameters::apply(const std::vector<Setting>& settings) {
  for (const Setting& s : settings) {
    if (s.name.empty())
      numbered[s.number] = s.value;
    else
      named[s.name] = s.value;
  }
}

std::optional<OLine> o_line(const std::string& text, int line, const std::string& file) {
  // cheap test first: most lines are not O-words
  const size_t first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return std::nullopt;
  const char c0 = static_cast<char>(std::toupper(static_cast<unsigned char>(text[first])));
  if (c0 != 'O' && c0 != 'N') return std::nullopt;
  const std::string s = strip(text, line, file);
  size_t pos = 0;
  if (pos < s.size() && s[pos] == 'N') {  // a line number first
    ++pos;
    while (pos < s.size() && (std::isdigit(static_cast<unsigned char>(s[pos])) || s[pos] == '.')) ++pos;
  }
  if (pos >= s.size() || s[pos] != 'O') return std::nullopt;
  ++pos;
  OLine o;
  if (pos < s.size() && s[pos] == '<') {
    const size_t close = s.find('>', pos);
    if (close == std::string::npos || close == pos + 1) fail(file, line, cut(s), "an O-word's name <...> is not closed or empty");
    o.label = s.substr(pos, close + 1 - pos);
    pos = close + 1;
  } else {
    const size_t begin = pos;
    while (pos < s.size() && std::isdigit(static_cast<unsigned char>(s[pos]))) ++pos;
    if (pos == begin) fail(file, line, cut(s), "an O-word needs a number or a <name>");
    o.label = s.substr(begin, pos - begin);
    o.label.erase(0, std::min(o.label.find_first_not_of('0'), o.label.size() - 1));
  }
  // longer keywords before those they start with (ELSEIF, ELSE; ENDSUB ... before nothing shorter)
  static const std::pair<const char*, OKeyword> kKeywords[] = {
      {"ENDSUB", OKeyword::kEndsub},     {"ENDWHILE", OKeyword::kEndwhile}, {"ENDREPEAT", OKeyword::kEndrepeat},
      {"ENDIF", OKeyword::kEndif},       {"ELSEIF", OKeyword::kElseif},     {"ELSE", OKeyword::kElse},
      {"SUB", OKeyword::kSub},           {"CALL", OKeyword::kCall},         {"RETURN", OKeyword::kReturn},
      {"IF", OKeyword::kIf},             {"WHILE", OKeyword::kWhile},       {"DO", OKeyword::kDo},
      {"REPEAT", OKeyword::kRepeat},     {"BREAK", OKeyword::kBreak},       {"CONTINUE", OKeyword::kContinue}};
  for (const auto& [name, kw] : kKeywords) {
    if (s.compare(pos, std::char_traits<char>::length(name), name) != 0) continue;
    o.keyword = kw;
    o.text = "O" + o.label + " " + name;
    o.values = s.substr(pos + std::char_traits<char>::length(name));
    return o;
  }
  fail(file, line, cut(s), "an O-word needs a keyword: sub endsub call return if elseif else endif while endwhile "
                            "do repeat endrepeat break continue");
}

std::vector<double> o_values(const OLine& o, int line, const std::string& file, const Parameters& params) {
  return LineParser(o.values, line, file, params).values();
}

// LinuxCNC's operator message: a comment whose text, after blanks, starts
// with "MSG," (any case); the message is the rest, blanks at its ends
// removed and control characters (tabs) made blanks. Of several on a line,
// the last.
std::string message_of(const std::string& text) {
  std::string msg;
  for (size_t i = 0; i < text.size() && text[i] != ';'; ++i) {
    if (text[i] != '(') continue;
    const size_t close = text.find(')', i);  // there is one: strip() refuses an open comment
    const size_t b = text.find_first_not_of(" \t", i + 1);
    std::string head = b + 4 <= close ? text.substr(b, 4) : "";
    for (char& c : head) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (head == "msg,") {
      msg = text.substr(b + 4, close - b - 4);
      for (char& c : msg)  // a terminal shows it: no control bytes
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) c = ' ';
      const size_t first = msg.find_first_not_of(' ');
      msg = first == std::string::npos ? "" : msg.substr(first, msg.find_last_not_of(' ') - first + 1);
    }
    i = close;
  }
  return msg;
}

Block lex_line(const std::string& text, int line, const std::string& file, const Parameters& params) {
  Block b = LineParser(strip(text, line, file), line, file, params).parse();
  b.message = message_of(text);
  return b;
}

}  // namespace traj::input::gcode
