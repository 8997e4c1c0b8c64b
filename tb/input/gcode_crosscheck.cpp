// SPDX-License-Identifier: Apache-2.0
// Cross-check of read_gcode against LinuxCNC's interpreter (rs274, batch mode),
// through rs274's printed canonical calls only (LinuxCNC is not linked).
//
// usage: gcode_crosscheck <precision shim .so> [--tools TABLE] <file or directory>...
// Every *.ngc under the directories is run through both. A program read_gcode
// refuses must get one well-formed "<file>:<line>: <word>: <why>" message
// (counted by reason). A program both accept must agree move for move: the
// kind, end points, for arcs every sampled point on rs274's circle (centre,
// radius) and the swept angle (direction and turns), the control-point count
// of splines, feed rates, path tolerance and exact-stop mode, to 1e-9 (in mm;
// rs274 prints in the program's units, the shim makes it print all digits),
// and the program pauses (M0/M60, read with --pause-wait) with their texts
// (the last MESSAGE since the move before the pause).
// Programs are read with the axes X Y Z A B C (rs274's, standalone): the
// rotary axes' end points, their progress along arcs (linear in the angle)
// and the feed as programmed (Move::feed / Move::feed_scale) are compared too.
// Exit 0 if no disagreement, 1 otherwise, 77 (skipped) without rs274.
// A program X.ngc with a tool table X.tbl beside it (mm) is read with that
// table, and rs274 gets it in inches (its standalone machine units); rs274
// prints positions in program coordinates and the tool length apart
// (USE_TOOL_LENGTH_OFFSET), read_gcode the tool holder's: the length is
// added to rs274's Z (and to an arc centre's Z) before comparing. --tools
// gives the table for the programs without one of their own (LinuxCNC's
// sample configuration's sim_mm.tbl for its examples).
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "geometry/curve.hpp"
#include "input/gcode.hpp"

namespace fs = std::filesystem;
using traj::input::Move;

namespace {

constexpr double kTol = 1e-9;
constexpr double kPi = 3.14159265358979323846;

using Point = Eigen::Matrix<double, 6, 1>;  // X Y Z (mm) A B C (degrees)

struct Canon {
  enum Kind { kTraverse, kFeed, kArc, kNurbs } kind;
  Point end = Point::Zero();  // mm, degrees
  double c1 = 0, c2 = 0;  // arc centre (mm) in the plane's (first, second)
  int rotation = 0;
  int plane = 0;         // 0 XY, 1 XZ, 2 YZ
  int n_ctrl = 0;        // NURBS_FEED
  double feed = 0;       // mm/min (degrees/min for A B C alone: rs274 prints F as programmed)
  double feed_raw = 0;   // F as programmed
  double dwell = 0;      // DWELLs after it, seconds
  bool dwelled = false;  // a DWELL (even of 0 s) or an M1 follows it: the machine stops there
  bool paused = false;   // a PROGRAM_STOP (M0, M60) follows it: a program pause (--pause-wait)
  std::string pause_text;  // and the last MESSAGE between it and the pause, blanks at its ends removed
  double tolerance = -1; // mm, -1 none
  bool exact = false;
};

struct Rs274 {
  bool ok = false;
  std::string error;
  std::vector<Canon> moves;
};

std::vector<double> numbers(const std::string& args) {
  std::vector<double> v;
  std::string tok;
  std::stringstream ss(args);
  while (std::getline(ss, tok, ',')) v.push_back(std::strtod(tok.c_str(), nullptr));
  return v;
}

// rs274's copy of a tool table (mm) in inches, its standalone machine units.
fs::path inch_tool_table(const traj::input::ToolTable& t, const fs::path& work) {
  const fs::path f = work / "tools_inch.tbl";
  std::ofstream o(f);
  o.precision(17);
  for (const auto& [tool, z] : t.z) o << "T" << tool << " P" << tool << " Z" << z / 25.4 << "\n";
  return f;
}

// MESSAGE("  text ")'s text, tabs made blanks and blanks at its ends removed (read_gcode's pause text).
std::string trimmed_message(const std::string& args) {
  std::string t = args.size() >= 2 && args.front() == '"' && args.back() == '"' ? args.substr(1, args.size() - 2) : args;
  for (char& c : t)
    if (c == '\t') c = ' ';
  const size_t b = t.find_first_not_of(' ');
  return b == std::string::npos ? "" : t.substr(b, t.find_last_not_of(' ') - b + 1);
}

Rs274 run_rs274(const std::string& shim, const fs::path& prog, const fs::path& work,
                const std::optional<traj::input::ToolTable>& tools) {
  Rs274 r;
  const fs::path out = work / "canon.txt", msg = work / "msg.txt";
  fs::remove(out);
  const std::string table = tools ? "-t '" + inch_tool_table(*tools, work).string() + "' " : "";
  const std::string cmd = "cd '" + work.string() + "' && LD_PRELOAD='" + shim + "' timeout 30 rs274 " + table + "-g '" +
                          prog.string() + "' '" + out.string() + "' < /dev/null > '" + msg.string() + "' 2>&1";
  const int st = std::system(cmd.c_str());
  r.ok = WIFEXITED(st) && WEXITSTATUS(st) == 0;
  std::ifstream m(msg);
  std::string line;
  while (std::getline(m, line))
    if (line != "executing" && !line.empty()) r.error += line + " | ";
  std::ifstream in(out);
  static const std::regex call(R"(([A-Z_]+)\((.*)\)\s*$)");
  double unit = 1, feed = 0, tol = -1, tlo = 0;
  std::string message;  // the last MESSAGE since the last motion
  bool exact = false;
  int plane = 0;
  while (std::getline(in, line)) {
    std::smatch mt;
    if (!std::regex_search(line, mt, call)) continue;
    const std::string name = mt[1], args = mt[2];
    if (name == "USE_LENGTH_UNITS") unit = args.find("INCHES") != std::string::npos ? 25.4 : 1.0;
    else if (name == "SET_FEED_RATE") feed = numbers(args)[0];
    else if (name == "DWELL" && !r.moves.empty()) {
      r.moves.back().dwell += numbers(args)[0];
      r.moves.back().dwelled = true;
    }
    else if ((name == "OPTIONAL_PROGRAM_STOP" || name == "PROGRAM_STOP") && !r.moves.empty()) {
      r.moves.back().dwelled = true;  // M1, and M0/M60: a stop
      if (name == "PROGRAM_STOP") {
        r.moves.back().paused = true;
        r.moves.back().pause_text = message;
      }
      message.clear();
    }
    else if (name == "MESSAGE") message = trimmed_message(args);
    else if (name == "USE_TOOL_LENGTH_OFFSET") {
      std::istringstream xyz(args);  // "x y z, ..."
      double x = 0, y = 0, z = 0;
      xyz >> x >> y >> z;
      tlo = z * unit;
    }
    else if (name == "SELECT_PLANE") plane = args.find("XZ") != std::string::npos ? 1 : args.find("YZ") != std::string::npos ? 2 : 0;
    else if (name == "SET_MOTION_CONTROL_MODE") {
      exact = args.find("CONTINUOUS") == std::string::npos;
      const auto comma = args.find(',');
      const double t = comma == std::string::npos ? 0 : std::strtod(args.c_str() + comma + 1, nullptr);
      tol = (!exact && t > 0) ? t * unit : -1;
    } else if (name == "STRAIGHT_TRAVERSE" || name == "STRAIGHT_FEED" || name == "ARC_FEED" || name == "NURBS_FEED") {
      Canon c;
      c.kind = name == "STRAIGHT_TRAVERSE" ? Canon::kTraverse : name == "STRAIGHT_FEED" ? Canon::kFeed
             : name == "ARC_FEED" ? Canon::kArc : Canon::kNurbs;
      c.feed = feed * unit;
      c.feed_raw = feed;
      c.tolerance = tol;
      c.exact = exact;
      c.plane = plane;
      const std::vector<double> v = numbers(args);
      if (c.kind == Canon::kNurbs) {
        c.n_ctrl = static_cast<int>(v[0]);
      } else if (c.kind == Canon::kArc) {
        static const int first[3] = {0, 2, 1}, second[3] = {1, 0, 2}, normal[3] = {2, 1, 0};
        c.end[first[plane]] = v[0] * unit;
        c.end[second[plane]] = v[1] * unit;
        c.end[normal[plane]] = v[5] * unit;
        c.c1 = v[2] * unit + (first[plane] == 2 ? tlo : 0);
        c.c2 = v[3] * unit + (second[plane] == 2 ? tlo : 0);
        c.rotation = static_cast<int>(v[4]);
        c.end[2] += tlo;
        for (int k = 0; k < 3 && 6 + k < static_cast<int>(v.size()); ++k) c.end[3 + k] = v[6 + k];
      } else {
        for (int k = 0; k < 3; ++k) c.end[k] = v[k] * unit;
        for (int k = 3; k < 6 && k < static_cast<int>(v.size()); ++k) c.end[k] = v[k];  // degrees
        c.end[2] += tlo;
      }
      r.moves.push_back(c);
      message.clear();
    }
  }
  return r;
}

bool near(double a, double b) { return std::abs(a - b) <= kTol * std::max(1.0, std::max(std::abs(a), std::abs(b))); }
bool near(const Point& a, const Point& b) {
  for (int k = 0; k < 6; ++k)
    if (!near(a[k], b[k])) return false;
  return true;
}

std::string str(const Point& p) {
  std::ostringstream o;
  o.precision(12);
  o << "(" << p[0] << ", " << p[1] << ", " << p[2] << "; A " << p[3] << ", B " << p[4] << ", C " << p[5] << ")";
  return o.str();
}

// Checks our arc move against rs274's ARC_FEED: every sample on the circle (radius interpolated
// linearly in angle between the start and end radii), the normal axis linear in the angle, and the
// total swept angle.
std::string check_arc(const Move& m, const Canon& c, const Point& start) {
  static const int first[3] = {0, 2, 1}, second[3] = {1, 0, 2}, normal[3] = {2, 1, 0};
  const int f = first[c.plane], s = second[c.plane], n = normal[c.plane];
  const double a0 = std::atan2(start[s] - c.c2, start[f] - c.c1), a1 = std::atan2(c.end[s] - c.c2, c.end[f] - c.c1);
  double sweep = a1 - a0;
  if (c.rotation > 0) {
    while (sweep <= 0) sweep += 2 * kPi;
    sweep += 2 * kPi * (c.rotation - 1);
  } else {
    while (sweep >= 0) sweep -= 2 * kPi;
    sweep -= 2 * kPi * (-c.rotation - 1);
  }
  const double r0 = std::hypot(start[f] - c.c1, start[s] - c.c2), r1 = std::hypot(c.end[f] - c.c1, c.end[s] - c.c2);
  traj::geo::Curve curve(m.curve);
  const int samples = 64 * (std::abs(c.rotation) + 1);
  const double u0 = m.curve.u_begin(), u1 = m.curve.u_end();
  double swept = 0, prev = a0;
  for (int k = 1; k <= samples; ++k) {
    const Eigen::VectorXd p = curve.eval(u0 + (u1 - u0) * k / samples, 0).col(0);
    const double ang = std::atan2(p[s] - c.c2, p[f] - c.c1);
    double d = ang - prev;
    while (d > kPi) d -= 2 * kPi;
    while (d < -kPi) d += 2 * kPi;
    swept += d;
    prev = ang;
    const double frac = swept / sweep;
    const double r = std::hypot(p[f] - c.c1, p[s] - c.c2);
    // A spiral (r0 != r1) is approximated by conics: allowed its radius difference.
    const double rtol = std::abs(r1 - r0) + kTol * std::max(1.0, r0);
    if (std::abs(r - (r0 + (r1 - r0) * frac)) > rtol) return "sample " + std::to_string(k) + " off the circle by " + std::to_string(r - r0);
    const double z = start[n] + (c.end[n] - start[n]) * frac;
    if (!near(p[n], z)) return "sample " + std::to_string(k) + " off the helix in the normal axis";
    for (int r = 3; r < 6; ++r)
      if (!near(p[r], start[r] + (c.end[r] - start[r]) * frac))
        return "sample " + std::to_string(k) + " off the rotary axes' linear progress with the angle";
  }
  if (std::abs(swept - sweep) > kTol * std::max(1.0, std::abs(sweep))) return "swept angle " + std::to_string(swept) + " against " + std::to_string(sweep);
  return "";
}

// A move's stop and dwell against rs274's DWELLs after its canonical call
// (and after the zero-length calls that follow it, which make no Move): a
// dwell stops the machine, so the move ends in an exact stop.
// A PROGRAM_STOP there is a program pause, with the last MESSAGE since the move as its text.
std::string check_dwell(const Move& m, double dwell, bool dwelled, bool exact, const Canon* pause) {
  if (!near(m.dwell, dwell)) return m.where + ": dwell " + std::to_string(m.dwell) + " s, rs274 " + std::to_string(dwell);
  if (m.kind != Move::Kind::kRapid && m.exact_stop != (exact || dwelled)) return m.where + ": exact-stop mode differs";
  if (static_cast<bool>(m.pause) != (pause != nullptr))
    return m.where + ": " + (pause ? "no program pause after it; rs274 has one" : "a program pause rs274 does not have");
  if (pause && m.pause.text != pause->pause_text)
    return m.where + ": pause text \"" + m.pause.text + "\", rs274 \"" + pause->pause_text + "\"";
  return "";
}

std::string compare(const traj::input::Toolpath& tp, const Rs274& r) {
  Point pos = Point::Zero();
  size_t i = 0;
  const Move* last = nullptr;  // the last move matched, with its DWELLs so far
  double dwell = 0;
  bool dwelled = false, exact = false;
  const Canon* pause = nullptr;  // the last PROGRAM_STOP since the last move matched
  for (const Canon& c : r.moves) {
    if (c.kind != Canon::kArc && c.kind != Canon::kNurbs && near(c.end, pos)) {  // zero-length: no Move
      dwell += c.dwell;
      dwelled = dwelled || c.dwelled;
      if (c.paused) pause = &c;
      continue;
    }
    if (last) {
      const std::string why = check_dwell(*last, dwell, dwelled, exact, pause);
      if (!why.empty()) return why;
    }
    if (i >= tp.moves.size()) return "rs274 has more moves than read_gcode (" + std::to_string(tp.moves.size()) + ")";
    const Move& m = tp.moves[i++];
    const std::string at = m.where + ": ";
    const Eigen::VectorXd s = m.curve.ctrl.row(0).transpose();
    const Eigen::VectorXd e = m.curve.ctrl.row(m.curve.n_ctrl() - 1).transpose();
    if (!near(Point(s), pos)) return at + "starts at " + str(s) + ", not at " + str(pos);
    const bool rapid = c.kind == Canon::kTraverse;
    if ((m.kind == Move::Kind::kRapid) != rapid) return at + "kind differs";
    if (c.kind != Canon::kNurbs && !near(Point(e), c.end)) return at + "ends at " + str(e) + ", rs274 " + str(c.end);
    if (c.kind == Canon::kFeed || c.kind == Canon::kTraverse) {
      if (m.curve.degree != 1) return at + "not a line";
    } else if (c.kind == Canon::kArc) {
      const std::string why = check_arc(m, c, pos);
      if (!why.empty()) return at + why;
    } else if (m.curve.n_ctrl() != c.n_ctrl) {
      return at + "spline with " + std::to_string(m.curve.n_ctrl()) + " control points, rs274 " + std::to_string(c.n_ctrl);
    }
    if (!rapid) {
      // F measures X Y Z when they move, else A B C (degrees/min whatever the units)
      const bool rotary_only = c.kind == Canon::kFeed && (c.end.head<3>() - pos.head<3>()).norm() == 0;
      const double f = m.feed / m.feed_scale * 60, rf = rotary_only ? c.feed_raw : c.feed;
      if (!near(f, rf)) return at + "feed " + std::to_string(f) + " as programmed, rs274 " + std::to_string(rf);
      if (!(m.tolerance < 0 && c.tolerance < 0) && !near(m.tolerance, c.tolerance)) return at + "path tolerance differs";
    }
    pos = c.kind == Canon::kNurbs ? Point(e) : c.end;
    last = &m;
    dwell = c.dwell;
    dwelled = c.dwelled;
    exact = c.exact;
    pause = c.paused ? &c : nullptr;
  }
  if (last) {
    const std::string why = check_dwell(*last, dwell, dwelled, exact, pause);
    if (!why.empty()) return why;
  }
  if (i != tp.moves.size()) return "read_gcode has " + std::to_string(tp.moves.size() - i) + " more moves than rs274";
  return "";
}

bool well_formed(const std::string& msg, const fs::path& prog) {
  static const std::regex form(R"(^:[0-9]+: [^:]+: .+$)");
  const std::string p = prog.string();
  return msg.compare(0, p.size(), p) == 0 && std::regex_match(msg.substr(p.size()), form);
}

// The reason of a refusal: the <why> part, cut before its details.
std::string reason(const std::string& msg, const fs::path& prog) {
  std::string rest = msg.substr(prog.string().size());
  const auto colon = rest.find(": ", rest.find(": ") + 2);
  std::string why = colon == std::string::npos ? rest : rest.substr(colon + 2);
  why = why.substr(0, why.find_first_of(":("));
  while (!why.empty() && why.back() == ' ') why.pop_back();
  return why;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: gcode_crosscheck <shim.so> <file or directory>...\n";
    return 2;
  }
  if (std::system("command -v rs274 > /dev/null 2>&1") != 0) {
    std::cout << "SKIPPED: rs274 (Debian package linuxcnc-uspace, installed by scripts/setup.sh) not found\n";
    return 77;
  }
  const std::string shim = fs::absolute(argv[1]).string();
  std::vector<fs::path> progs;
  std::optional<traj::input::ToolTable> default_tools;
  for (int a = 2; a < argc; ++a) {
    if (std::string(argv[a]) == "--tools" && a + 1 < argc) {
      if (fs::exists(argv[a + 1])) default_tools = traj::input::read_tool_table(argv[a + 1]);
      ++a;
      continue;
    }
    const fs::path p(argv[a]);
    if (fs::is_directory(p)) {
      for (const auto& e : fs::recursive_directory_iterator(p))
        if (e.is_regular_file() && e.path().extension() == ".ngc") progs.push_back(fs::absolute(e.path()));
    } else if (fs::exists(p)) {
      progs.push_back(fs::absolute(p));
    }
  }
  std::sort(progs.begin(), progs.end());
  const fs::path work = fs::temp_directory_path() / ("gcode_crosscheck." + std::to_string(getpid()));
  fs::create_directories(work);

  int accepted = 0, agree = 0, refused = 0, malformed = 0, only_here = 0;
  size_t moves = 0, pauses = 0, texts = 0;
  std::map<std::string, int> reasons;
  std::vector<std::string> disagreements;
  for (const fs::path& prog : progs) {
    traj::input::GcodeOptions opt;
    opt.axes = "XYZABC";
    opt.pauses_wait = true;  // M0/M60 as program pauses, with their texts
    fs::path table = prog;
    table.replace_extension(".tbl");
    opt.tools = fs::exists(table) ? traj::input::read_tool_table(table.string()) : default_tools;
    const Rs274 r = run_rs274(shim, prog, work, opt.tools);
    try {
      const traj::input::Toolpath tp = traj::input::read_gcode(prog.string(), opt);
      ++accepted;
      if (!r.ok) {
        ++only_here;
        disagreements.push_back(prog.string() + ": accepted here, refused by rs274: " + r.error);
        continue;
      }
      const std::string why = compare(tp, r);
      if (why.empty()) {
        ++agree;
        moves += tp.moves.size();
        for (const Move& m : tp.moves) {
          pauses += static_cast<bool>(m.pause);
          texts += !m.pause.text.empty();
        }
      } else {
        disagreements.push_back(prog.string() + ": " + why);
      }
    } catch (const traj::input::InputError& e) {
      ++refused;
      const std::string msg = e.what();
      if (!well_formed(msg, prog)) {
        ++malformed;
        disagreements.push_back("malformed refusal: " + msg);
      } else {
        reasons[reason(msg, prog) + (r.ok ? "" : " [rs274 refuses too]")]++;
      }
    }
  }
  fs::remove_all(work);

  std::cout << "G-code cross-check against rs274: " << progs.size() << " programs\n"
            << "  accepted: " << accepted << " (agree move for move: " << agree << ", " << moves << " moves, "
            << pauses << " program pauses, " << texts << " with a message)\n"
            << "  refused:  " << refused << " (malformed messages: " << malformed << ")\n";
  for (const auto& [why, n] : reasons) std::cout << "    " << n << "  " << why << "\n";
  std::cout << "  disagreements: " << disagreements.size() << " (of which accepted here, refused by rs274: "
            << only_here << ")\n";
  for (const std::string& d : disagreements) std::cout << "    " << d << "\n";
  return disagreements.empty() ? 0 : 1;
}
