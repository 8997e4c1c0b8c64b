// SPDX-License-Identifier: Apache-2.0
#include "input/svg_path.hpp"

#include <charconv>
#include <cmath>
#include <cstring>

#include "util/format.hpp"

namespace traj::input::svg {
namespace {

constexpr double kPi = 3.14159265358979323846;

bool is_wsp(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

// Reads the tokens of SVG's number grammar from an attribute value.
class Scanner {
 public:
  explicit Scanner(const std::string& s) : s_(s) {}
  std::size_t pos() const { return i_; }
  bool done() const { return i_ >= s_.size(); }
  char peek() const { return done() ? '\0' : s_[i_]; }
  void advance() { ++i_; }
  void skip_wsp() {
    while (!done() && is_wsp(s_[i_])) ++i_;
  }
  // wsp* (',' wsp*)?
  void skip_comma_wsp() {
    skip_wsp();
    if (peek() == ',') {
      ++i_;
      skip_wsp();
    }
  }
  bool at_number() const {
    const char c = peek();
    return is_digit(c) || c == '.' || c == '-' || c == '+';
  }
  // sign? (digits ('.' digits?)? | '.' digits) (('e'|'E') sign? digits)?
  double number() {
    const std::size_t begin = i_;
    std::size_t j = i_;
    if (j < s_.size() && (s_[j] == '+' || s_[j] == '-')) ++j;
    const std::size_t mantissa = j;
    while (j < s_.size() && is_digit(s_[j])) ++j;
    bool digits = j > mantissa;
    if (j < s_.size() && s_[j] == '.') {
      const std::size_t frac = ++j;
      while (j < s_.size() && is_digit(s_[j])) ++j;
      digits = digits || j > frac;
    }
    if (!digits) throw PathDataError(begin, describe("expected a number", begin));
    if (j < s_.size() && (s_[j] == 'e' || s_[j] == 'E')) {
      std::size_t k = j + 1;
      if (k < s_.size() && (s_[k] == '+' || s_[k] == '-')) ++k;
      if (k < s_.size() && is_digit(s_[k])) {
        while (k < s_.size() && is_digit(s_[k])) ++k;
        j = k;
      }
    }
    // from_chars takes no leading '+'.
    const std::size_t from = s_[begin] == '+' ? begin + 1 : begin;
    double v = 0;
    const auto r = std::from_chars(s_.data() + from, s_.data() + j, v);
    if (r.ec != std::errc() || r.ptr != s_.data() + j || !std::isfinite(v))
      throw PathDataError(begin, "number '" + util::excerpt(s_.substr(begin, j - begin)) + "' out of range");
    i_ = j;
    return v;
  }
  // An arc flag: a single '0' or '1' (no separator needed after it).
  bool flag() {
    const char c = peek();
    if (c != '0' && c != '1') throw PathDataError(i_, describe("expected an arc flag 0 or 1", i_));
    ++i_;
    return c == '1';
  }
  std::string describe(const std::string& what, std::size_t at) const {
    if (at >= s_.size()) return what + ", got the end of the data";
    return what + ", got '" + s_[at] + "'";
  }

 private:
  const std::string& s_;
  std::size_t i_ = 0;
};

Eigen::Vector2d read_point(Scanner& sc) {
  const double x = sc.number();
  sc.skip_comma_wsp();
  const double y = sc.number();
  return {x, y};
}

// Builds the subpaths of one path data string while the commands are executed.
class PathBuilder {
 public:
  void move_to(const Eigen::Vector2d& p) {
    out_.emplace_back();
    cur_ = start_ = p;
    open_ = true;
  }
  void segment(geo::BSpline c, const Eigen::Vector2d& end) {
    if (!open_) {  // drawing after Z without M: a new subpath at the closed one's start
      out_.emplace_back();
      open_ = true;
    }
    if (c.n_ctrl() > 0 && !is_degenerate(c)) out_.back().segments.push_back(std::move(c));
    cur_ = end;
  }
  void line_to(const Eigen::Vector2d& p) { segment(geo::make_line(cur_, p), p); }
  void close() {
    if (cur_ != start_) line_to(start_);
    if (!out_.empty() && open_) out_.back().closed = true;
    cur_ = start_;
    open_ = false;
  }
  const Eigen::Vector2d& current() const { return cur_; }
  std::vector<Subpath> finish() {
    std::vector<Subpath> r;
    for (Subpath& s : out_)
      if (!s.segments.empty()) r.push_back(std::move(s));
    return r;
  }

 private:
  static bool is_degenerate(const geo::BSpline& c) {
    for (int i = 1; i < c.n_ctrl(); ++i)
      if (c.ctrl.row(i) != c.ctrl.row(0)) return false;
    return true;
  }
  std::vector<Subpath> out_;
  Eigen::Vector2d cur_{0, 0}, start_{0, 0};
  bool open_ = false;
};

geo::BSpline bezier(std::initializer_list<Eigen::Vector2d> pts) {
  Eigen::MatrixXd P(static_cast<Eigen::Index>(pts.size()), 2);
  Eigen::Index i = 0;
  for (const Eigen::Vector2d& p : pts) P.row(i++) = p.transpose();
  return geo::make_bezier(P);
}

// Executes one command with its arguments (one repetition); `rel` for lower-case commands.
struct CommandState {
  char prev = 0;                   // previous command (upper case), for S and T
  Eigen::Vector2d last_ctrl{0, 0}; // its last control point (C/S: second, Q/T: the one)
};

void run_command(char cmd, Scanner& sc, PathBuilder& pb, CommandState& st) {
  const bool rel = cmd >= 'a';
  const char up = static_cast<char>(rel ? cmd - ('a' - 'A') : cmd);
  const Eigen::Vector2d o = rel ? pb.current() : Eigen::Vector2d(0, 0);
  const Eigen::Vector2d cur = pb.current();
  auto reflected = [&](char a, char b) {
    return (st.prev == a || st.prev == b) ? Eigen::Vector2d(2 * cur - st.last_ctrl) : cur;
  };
  switch (up) {
    case 'L': pb.line_to(o + read_point(sc)); break;
    case 'H': pb.line_to({sc.number() + (rel ? cur.x() : 0), cur.y()}); break;
    case 'V': pb.line_to({cur.x(), sc.number() + (rel ? cur.y() : 0)}); break;
    case 'C': case 'S': {
      const Eigen::Vector2d c1 = up == 'C' ? Eigen::Vector2d(o + read_point(sc)) : reflected('C', 'S');
      if (up == 'C') sc.skip_comma_wsp();
      const Eigen::Vector2d c2 = o + read_point(sc);
      sc.skip_comma_wsp();
      const Eigen::Vector2d p = o + read_point(sc);
      pb.segment(bezier({cur, c1, c2, p}), p);
      st.last_ctrl = c2;
      break;
    }
    case 'Q': case 'T': {
      const Eigen::Vector2d c1 = up == 'Q' ? Eigen::Vector2d(o + read_point(sc)) : reflected('Q', 'T');
      if (up == 'Q') sc.skip_comma_wsp();
      const Eigen::Vector2d p = o + read_point(sc);
      pb.segment(bezier({cur, c1, p}), p);
      st.last_ctrl = c1;
      break;
    }
    case 'A': {
      const double rx = sc.number();
      sc.skip_comma_wsp();
      const double ry = sc.number();
      sc.skip_comma_wsp();
      const double rot = sc.number();
      sc.skip_comma_wsp();
      const bool large = sc.flag();
      sc.skip_comma_wsp();
      const bool sweep = sc.flag();
      sc.skip_comma_wsp();
      const Eigen::Vector2d p = o + read_point(sc);
      pb.segment(arc_segment(cur, rx, ry, rot, large, sweep, p), p);
      break;
    }
    default: break;
  }
  st.prev = up;
}

// angle from u to v, signed, in (-pi, pi]
double angle_between(const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
  return std::atan2(u.x() * v.y() - u.y() * v.x(), u.dot(v));
}

Affine rotation_deg(double deg) {
  const double a = deg * kPi / 180.0;
  Affine m = Affine::Identity();
  m(0, 0) = std::cos(a); m(0, 1) = -std::sin(a);
  m(1, 0) = std::sin(a); m(1, 1) = std::cos(a);
  return m;
}

Affine translation(double tx, double ty) {
  Affine m = Affine::Identity();
  m(0, 2) = tx;
  m(1, 2) = ty;
  return m;
}

// One transform function applied to its argument list.
Affine transform_function(const std::string& name, const std::vector<double>& a, std::size_t at) {
  auto need = [&](std::initializer_list<std::size_t> counts) {
    for (std::size_t c : counts)
      if (a.size() == c) return;
    throw PathDataError(at, name + ": wrong number of arguments (" + std::to_string(a.size()) + ")");
  };
  Affine m = Affine::Identity();
  if (name == "matrix") {
    need({6});
    m << a[0], a[2], a[4], a[1], a[3], a[5], 0, 0, 1;
  } else if (name == "translate") {
    need({1, 2});
    m = translation(a[0], a.size() > 1 ? a[1] : 0.0);
  } else if (name == "scale") {
    need({1, 2});
    m(0, 0) = a[0];
    m(1, 1) = a.size() > 1 ? a[1] : a[0];
  } else if (name == "rotate") {
    need({1, 3});
    m = rotation_deg(a[0]);
    if (a.size() == 3) m = translation(a[1], a[2]) * m * translation(-a[1], -a[2]);
  } else if (name == "skewX") {
    need({1});
    m(0, 1) = std::tan(a[0] * kPi / 180.0);
  } else if (name == "skewY") {
    need({1});
    m(1, 0) = std::tan(a[0] * kPi / 180.0);
  } else {
    throw PathDataError(at, "unknown transform '" + util::excerpt(name) + "'");
  }
  return m;
}

}  // namespace

std::vector<Subpath> parse_path_data(const std::string& d) {
  Scanner sc(d);
  PathBuilder pb;
  CommandState st;
  sc.skip_wsp();
  bool first = true;
  while (!sc.done()) {
    const std::size_t at = sc.pos();
    const char cmd = sc.peek();
    if (!std::strchr("MmLlHhVvCcSsQqTtAaZz", cmd) || cmd == '\0')
      throw PathDataError(at, sc.describe("expected a path command (M L H V C S Q T A Z)", at));
    if (first && cmd != 'M' && cmd != 'm')
      throw PathDataError(at, "path data must begin with a moveto (M or m)");
    first = false;
    sc.advance();
    sc.skip_wsp();
    if (cmd == 'Z' || cmd == 'z') {
      pb.close();
      st.prev = 'Z';
      continue;
    }
    char repeat = cmd;
    if (cmd == 'M' || cmd == 'm') {
      const Eigen::Vector2d p = read_point(sc) + (cmd == 'm' ? pb.current() : Eigen::Vector2d(0, 0));
      pb.move_to(p);
      st.prev = 'M';
      repeat = cmd == 'm' ? 'l' : 'L';  // further pairs are line-tos
      sc.skip_comma_wsp();
      if (!sc.at_number()) continue;
    }
    do {
      run_command(repeat, sc, pb, st);
      sc.skip_comma_wsp();
    } while (sc.at_number());
  }
  return pb.finish();
}

geo::BSpline ellipse_arc(const Eigen::Vector2d& c, double rx, double ry, double rotation, double t0,
                         double t1) {
  geo::BSpline u = geo::make_arc(Eigen::Vector2d(0, 0), 1.0, t0, t1);
  Affine m = Affine::Identity();
  m(0, 0) = std::cos(rotation) * rx; m(0, 1) = -std::sin(rotation) * ry;
  m(1, 0) = std::sin(rotation) * rx; m(1, 1) = std::cos(rotation) * ry;
  m(0, 2) = c.x();
  m(1, 2) = c.y();
  return transformed(u, m);
}

geo::BSpline arc_segment(const Eigen::Vector2d& p0, double rx, double ry, double rotation_deg,
                         bool large_arc, bool sweep, const Eigen::Vector2d& p1) {
  if (p0 == p1) return geo::BSpline{};  // F.6.2: the arc is omitted
  rx = std::abs(rx);
  ry = std::abs(ry);
  if (rx == 0 || ry == 0) return geo::make_line(p0, p1);  // F.6.2: a straight line
  const double phi = std::fmod(rotation_deg, 360.0) * kPi / 180.0;
  const double cphi = std::cos(phi), sphi = std::sin(phi);
  // F.6.5.1: (x1', y1')
  const Eigen::Vector2d h = (p0 - p1) / 2;
  const Eigen::Vector2d q(cphi * h.x() + sphi * h.y(), -sphi * h.x() + cphi * h.y());
  // F.6.6.2: radii too small to reach from p0 to p1 are scaled up
  const double lambda = q.x() * q.x() / (rx * rx) + q.y() * q.y() / (ry * ry);
  if (lambda > 1) {
    rx *= std::sqrt(lambda);
    ry *= std::sqrt(lambda);
  }
  // F.6.5.2: (cx', cy')
  const double rx2 = rx * rx, ry2 = ry * ry;
  const double den = rx2 * q.y() * q.y() + ry2 * q.x() * q.x();
  double coef = std::sqrt(std::max(0.0, (rx2 * ry2 - den) / den));
  if (large_arc == sweep) coef = -coef;
  const Eigen::Vector2d cq(coef * rx * q.y() / ry, -coef * ry * q.x() / rx);
  // F.6.5.3: centre
  const Eigen::Vector2d c(cphi * cq.x() - sphi * cq.y() + (p0.x() + p1.x()) / 2,
                          sphi * cq.x() + cphi * cq.y() + (p0.y() + p1.y()) / 2);
  // F.6.5.5-6: start angle and sweep
  const Eigen::Vector2d u((q.x() - cq.x()) / rx, (q.y() - cq.y()) / ry);
  const Eigen::Vector2d v((-q.x() - cq.x()) / rx, (-q.y() - cq.y()) / ry);
  const double theta1 = angle_between(Eigen::Vector2d(1, 0), u);
  double dtheta = angle_between(u, v);
  if (!sweep && dtheta > 0) dtheta -= 2 * kPi;
  if (sweep && dtheta < 0) dtheta += 2 * kPi;
  // A half-ellipse computed as the short way round by rounding of the sign (|dtheta| ~ pi) still
  // has the sweep's sign after the two corrections above; a zero sweep cannot reach p1 != p0.
  geo::BSpline arc = ellipse_arc(c, rx, ry, phi, theta1, theta1 + dtheta);
  arc.ctrl.row(0) = p0.transpose();
  arc.ctrl.row(arc.n_ctrl() - 1) = p1.transpose();
  return arc;
}

geo::BSpline transformed(const geo::BSpline& c, const Affine& m) {
  geo::BSpline r = c;
  const Eigen::Matrix2d lin = m.topLeftCorner<2, 2>();
  const Eigen::Vector2d t = m.topRightCorner<2, 1>();
  for (int i = 0; i < c.n_ctrl(); ++i) r.ctrl.row(i) = (lin * c.ctrl.row(i).transpose() + t).transpose();
  return r;
}

Affine parse_transform(const std::string& s) {
  Scanner sc(s);
  Affine total = Affine::Identity();
  sc.skip_wsp();
  while (!sc.done()) {
    const std::size_t at = sc.pos();
    std::string name;
    while (!sc.done() && std::isalpha(static_cast<unsigned char>(sc.peek()))) {
      name += sc.peek();
      sc.advance();
    }
    if (name.empty()) throw PathDataError(at, sc.describe("expected a transform name", at));
    sc.skip_wsp();
    if (sc.peek() != '(') throw PathDataError(sc.pos(), sc.describe("expected '('", sc.pos()));
    sc.advance();
    sc.skip_wsp();
    std::vector<double> args;
    while (sc.at_number()) {
      args.push_back(sc.number());
      sc.skip_comma_wsp();
    }
    if (sc.peek() != ')') throw PathDataError(sc.pos(), sc.describe("expected ')' or a number", sc.pos()));
    sc.advance();
    total = total * transform_function(name, args, at);
    sc.skip_comma_wsp();
  }
  return total;
}

std::pair<double, std::string> parse_length(const std::string& s) {
  Scanner sc(s);
  sc.skip_wsp();
  const double v = sc.number();
  sc.skip_wsp();
  std::string unit = s.substr(sc.pos());
  unit.erase(unit.find_last_not_of(" \t\r\n\f") + 1);
  return {v, unit};
}

std::vector<double> parse_number_list(const std::string& s) {
  Scanner sc(s);
  std::vector<double> v;
  sc.skip_wsp();
  while (!sc.done()) {
    v.push_back(sc.number());
    sc.skip_comma_wsp();
  }
  return v;
}

}  // namespace traj::input::svg
