// SPDX-License-Identifier: Apache-2.0
#include "geometry/json_io.hpp"

#include <climits>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <algorithm>
#include <vector>

#include "geometry/error.hpp"

namespace traj::geo {

namespace {
[[noreturn]] void fail(const std::string& where, const std::string& what) { throw GeometryError(where + ": " + what); }

// nlohmann's what() without its "[json.exception.<kind>.<id>] " tag and without the
// "parse error at line L, column C: " prefix (the caller states the place itself).
std::string nlohmann_problem(const char* what) {
  std::string m(what);
  if (m.rfind("[json.exception.", 0) == 0) {
    const auto e = m.find("] ");
    if (e != std::string::npos) m.erase(0, e + 2);
  }
  if (m.rfind("parse error", 0) == 0) {
    const auto e = m.find(": ");
    if (e != std::string::npos) m.erase(0, e + 2);
  }
  return m;
}

// At most kMaxEcho characters of a text the input controls (a field path 2 million levels deep, a
// token of megabytes) go into a message: the head and the tail with the size in between.
constexpr std::size_t kMaxEcho = 160;
std::string clip(const std::string& t) {
  if (t.size() <= kMaxEcho) return t;
  return t.substr(0, kMaxEcho / 2) + " ... (" + std::to_string(t.size()) + " characters) ... " +
         t.substr(t.size() - kMaxEcho / 2);
}

// "<name>:<line>:<column>" of byte `at` of `text` (1-based; lines counted from `first_line`).
std::string place(const std::string& name, const std::string& text, std::size_t at, std::size_t first_line) {
  std::size_t line = first_line, line_start = 0;
  for (std::size_t i = 0; i < at && i < text.size(); ++i)
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  return name + ":" + std::to_string(line) + ":" + std::to_string(at - line_start + 1);
}

// SAX handler: builds the document with nlohmann's own DOM builder and keeps the path of the value
// being read, so that a parse error can name the field.
class PathSax {
 public:
  using json = nlohmann::json;
  PathSax(json& root, const std::string& text, const std::string& name, std::size_t first_line = 1)
      : dom_(root, true), text_(text), name_(name), first_line_(first_line) {}

  bool null() { return value(), dom_.null(); }
  bool boolean(bool v) { return value(), dom_.boolean(v); }
  bool number_integer(json::number_integer_t v) { return value(), dom_.number_integer(v); }
  bool number_unsigned(json::number_unsigned_t v) { return value(), dom_.number_unsigned(v); }
  bool number_float(json::number_float_t v, const json::string_t& s) { return value(), dom_.number_float(v, s); }
  bool string(json::string_t& v) { return value(), dom_.string(v); }
  bool binary(json::binary_t& v) { return value(), dom_.binary(v); }
  bool start_object(std::size_t n) {
    stack_.push_back({false, 0, {}, false});
    return dom_.start_object(n);
  }
  bool key(json::string_t& k) {
    stack_.back().key = k;
    stack_.back().in_value = true;
    return dom_.key(k);
  }
  bool end_object() {
    stack_.pop_back();
    leave();
    return dom_.end_object();
  }
  bool start_array(std::size_t n) {
    stack_.push_back({true, 0, {}, false});
    return dom_.start_array(n);
  }
  bool end_array() {
    stack_.pop_back();
    leave();
    return dom_.end_array();
  }
  // Called by the parser for syntax errors and for numbers outside the double range (out_of_range
  // 406), with the byte offset at which it stopped and the offending token.
  bool parse_error(std::size_t offset, const std::string& token, const nlohmann::detail::exception& ex) {
    // offset: characters read, the offending token's last one included (reading the end of the input
    // counts one more). For a number the token is the number's text, so its first character is found;
    // otherwise nlohmann's token text may include earlier characters, and the place is the character
    // the parser stopped at (the last one read, as nlohmann's own messages count it).
    const std::size_t end = std::min(offset, text_.size());
    std::size_t at = end > 0 ? end - 1 : 0;
    if (ex.id == 406 && token.size() <= end) at = end - token.size();
    std::string problem = clip(nlohmann_problem(ex.what()));
    if (ex.id == 406) problem += " (beyond the double range)";
    const std::string f = clip(path());
    throw GeometryError(place(name_, text_, at, first_line_) + ": " + (f.empty() ? "" : f + ": ") + problem);
  }
  // Path of the value being read: object keys joined by '.', array indices in brackets.
  std::string path() const {
    std::string p;
    for (const Frame& f : stack_) {
      if (f.array) {
        p += "[" + std::to_string(f.count) + "]";  // the element being read (or expected next)
      } else {
        if (!f.in_value) break;  // between members: the object itself is the place
        p += (p.empty() ? "" : ".") + f.key;
      }
    }
    return p;
  }

 private:
  struct Frame {
    bool array;
    std::size_t count;  // arrays: elements completed
    std::string key;    // objects: last key
    bool in_value;      // objects: reading the value of `key`
  };
  void value() { leave(); }
  void leave() {  // a value of the innermost container is complete
    if (stack_.empty()) return;
    if (stack_.back().array) ++stack_.back().count;
    else stack_.back().in_value = false;
  }
  nlohmann::detail::json_sax_dom_parser<json> dom_;
  std::vector<Frame> stack_;
  const std::string& text_;
  const std::string& name_;
  std::size_t first_line_;
};

double number(const nlohmann::json& v, const std::string& where, const std::string& field) {
  if (!v.is_number()) fail(where, field + ": expected a number, got " + std::string(v.type_name()));
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(where, field + ": not a finite number");
  return d;
}
const nlohmann::json& member(const nlohmann::json& doc, const char* key, const std::string& where) {
  auto it = doc.find(key);
  if (it == doc.end()) fail(where, std::string(key) + ": missing");
  return *it;
}
}  // namespace

nlohmann::json load_json_file(const std::string& path, const std::string& name_in) {
  const std::string& name = name_in.empty() ? path : name_in;
  std::ifstream f(path, std::ios::binary);
  if (!f) fail(name, "cannot open file" + (name == path ? std::string() : " " + path));
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) fail(name, "read error");
  return parse_json_text(text, name);
}

nlohmann::json parse_json_text(const std::string& text, const std::string& name, std::size_t first_line) {
  // nlohmann's lexer takes a NUL byte for the end of the input and would accept whatever follows it;
  // JSON text holds no raw NUL anywhere (not even in a string), so one is refused where it stands.
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos)
    throw GeometryError(place(name, text, nul, first_line) + ": NUL byte (JSON text holds none)");
  nlohmann::json doc;
  PathSax sax(doc, text, name, first_line);
  try {
    nlohmann::json::sax_parse(text, &sax);
  } catch (const nlohmann::json::exception& e) {  // not expected: the parser reports through parse_error
    const std::string p = clip(sax.path());
    fail(name, (p.empty() ? "" : p + ": ") + clip(nlohmann_problem(e.what())));
  }
  return doc;
}

namespace {
// `field` is kept up to date with the field being read, for the catch in parse_curve.
BSpline parse_curve_fields(const nlohmann::json& doc, const std::string& where, std::string& field) {
  field = "top level";
  if (!doc.is_object()) fail(where, "top level: expected a JSON object");
  BSpline c;
  field = "name";
  if (auto it = doc.find("name"); it != doc.end() && it->is_string()) c.name = it->get<std::string>();
  field = "degree";
  const auto& deg = member(doc, "degree", where);
  if (!deg.is_number_integer()) fail(where, "degree: expected an integer");
  // An unsigned value beyond long long (18446744073709551615) is shown as written, not as its
  // two's complement reading (-1).
  const bool huge = deg.is_number_unsigned() && deg.get<std::uint64_t>() > static_cast<std::uint64_t>(LLONG_MAX);
  const long long p = huge ? LLONG_MAX : deg.get<long long>();

  bool rational = false;
  field = "rational";
  if (auto it = doc.find("rational"); it != doc.end()) {
    if (!it->is_boolean()) fail(where, "rational: expected true or false");
    rational = it->get<bool>();
  }
  field = "degree";
  if (const std::string e = degree_range_error(p, rational, 0, huge ? deg.dump() : std::string()); !e.empty())
    fail(where, e);
  c.degree = static_cast<int>(p);

  field = "control_points";
  const auto& cps = member(doc, "control_points", where);
  if (!cps.is_array() || cps.empty()) fail(where, "control_points: expected a non-empty array of points");
  const size_t n = cps.size();
  if (!cps[0].is_array() || cps[0].empty())
    fail(where, "control_points[0]: expected an array of coordinates");
  const size_t dim = cps[0].size();
  c.ctrl.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(dim));
  for (size_t i = 0; i < n; ++i) {
    const std::string fi = "control_points[" + std::to_string(i) + "]";
    field = fi;
    if (!cps[i].is_array()) fail(where, fi + ": expected an array of coordinates");
    if (cps[i].size() != dim)
      fail(where, fi + ": " + std::to_string(cps[i].size()) + " coordinates, control_points[0] has " +
                      std::to_string(dim) + " (inconsistent dimensions)");
    for (size_t j = 0; j < dim; ++j) {
      field = fi + "[" + std::to_string(j) + "]";
      c.ctrl(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = number(cps[i][j], where, field);
    }
  }

  field = "weights";
  if (auto it = doc.find("weights"); it != doc.end() && !it->is_null()) {
    if (!it->is_array()) fail(where, "weights: expected an array of numbers");
    if (it->size() != n)
      fail(where, "weights: " + std::to_string(it->size()) + " weights for " + std::to_string(n) +
                      " control points");
    Eigen::VectorXd w(static_cast<Eigen::Index>(n));
    for (size_t i = 0; i < n; ++i) {
      field = "weights[" + std::to_string(i) + "]";
      w[static_cast<Eigen::Index>(i)] = number((*it)[i], where, field);
    }
    if (rational) c.weights = w;
    else
      for (size_t i = 0; i < n; ++i)
        if (w[static_cast<Eigen::Index>(i)] != 1.0)
          fail(where, "weights[" + std::to_string(i) + "]: non-unit weight but \"rational\" is false");
  } else if (rational) {
    fail(where, "weights: missing (\"rational\" is true)");
  }

  field = "knots";
  const auto& kn = member(doc, "knots", where);
  if (!kn.is_array()) fail(where, "knots: expected an array of numbers");
  c.knots.resize(static_cast<Eigen::Index>(kn.size()));
  for (size_t i = 0; i < kn.size(); ++i) {
    field = "knots[" + std::to_string(i) + "]";
    c.knots[static_cast<Eigen::Index>(i)] = number(kn[i], where, field);
  }

  field = "curve";
  validate(c, where);
  return c;
}
}  // namespace

BSpline parse_curve(const nlohmann::json& doc, const std::string& where) {
  std::string field;
  try {
    return parse_curve_fields(doc, where, field);
  } catch (const nlohmann::json::exception& e) {  // not expected: every field's type is checked first
    fail(where, field + ": " + nlohmann_problem(e.what()));
  }
}

BSpline load_curve(const std::string& path) {
  const std::string where = path.substr(path.find_last_of('/') == std::string::npos ? 0 : path.find_last_of('/') + 1);
  return parse_curve(load_json_file(path, where), where);
}

nlohmann::json to_json(const BSpline& c, const std::string& units) {
  nlohmann::json j;
  j["name"] = c.name;
  j["units"] = units;
  j["degree"] = c.degree;
  j["rational"] = c.rational();
  j["control_points"] = nlohmann::json::array();
  for (int i = 0; i < c.n_ctrl(); ++i) {
    nlohmann::json p = nlohmann::json::array();
    for (int d = 0; d < c.dim(); ++d) p.push_back(c.ctrl(i, d));
    j["control_points"].push_back(p);
  }
  if (c.rational()) j["weights"] = std::vector<double>(c.weights.data(), c.weights.data() + c.weights.size());
  j["knots"] = std::vector<double>(c.knots.data(), c.knots.data() + c.knots.size());
  return j;
}

}  // namespace traj::geo
