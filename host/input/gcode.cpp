// SPDX-License-Identifier: Apache-2.0
#include "input/gcode.hpp"

#include <cmath>
#include <deque>
#include <fstream>
#include <memory>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "input/cuts.hpp"
#include "input/gcode_curves.hpp"
#include "input/gcode_flow.hpp"
#include "input/gcode_lexer.hpp"

namespace traj::input {

namespace {

using gcode::Block;
using gcode::Word;
using Eigen::Vector3d;

// What the refusal of M0/M60 offers.
constexpr const char* kPauseOptions =
    "--pause-wait (a pause at which `trajcore upload` waits for the operator) or --pause-as-stop (an exact stop: "
    "the machine goes on without waiting); M1, the optional stop, is taken as an exact stop";

constexpr double kPi = 3.14159265358979323846;
constexpr double kInch = 25.4;

// LinuxCNC's arc tolerances (interp_internal.hh), in inches and mm. An
// I J K arc is refused when its end radius differs from its start radius by
// more than the absolute tolerance and, at the same time, by more than the
// relative one (rs274 2.9 accepts r 10 -> 10.015 mm and 100 -> 100.09 mm,
// refuses 10 -> 10.029 mm: checked with it).
constexpr double kRadiusTolInch = 0.00005, kRadiusTolMm = kRadiusTolInch * kInch;
// Full turns of one G2/G3 (P word): each is four arc pieces; more is no toolpath, and P beyond int
// would overflow the count.
constexpr int kMaxTurns = 10000;
constexpr double kSpiralAbsInch = 2 * 0.001 * 1.41421356237309504880;
constexpr double kSpiralAbsMm = 2 * 0.01 * 1.41421356237309504880;
constexpr double kSpiralRel = 0.001;

enum class Motion { kNone, kRapid, kLine, kCw, kCcw, kCubic, kQuadratic, kNurbs, kDrill, kDrillDwell, kPeck, kChipBreak };

// LinuxCNC's clearance of G83/G73 above the last peck's depth: 0.010 inch,
// 0.254 mm (rs274 2.9 rapids to 0.254 mm above it in mm programs too).
constexpr double kPeckClearanceMm = 0.254;
// Repeats of one canned-cycle block (L), and pecks of one block (G73, G83:
// holes times pecks a hole): more is no toolpath, and the moves of one block
// are held until taken (at most about 4 a peck).
constexpr int kMaxCycleRepeats = 10000;
constexpr double kMaxPecks = 100000;

// LinuxCNC's longest line (its buffer of 255 with the newline and the
// terminating NUL; rs274 refuses longer ones: "Command too long").
constexpr size_t kMaxLineChars = 253;

// Tool numbers (T, H, a tool table's T) are held as int: checked before the conversion.
constexpr double kMaxTool = 1e9;
constexpr const char* kToolNumber = "the tool number must be a whole number from 0 to 1000000000";

// G codes as integers in tenths (G5.2 -> 52, G1 -> 10).
int tenths(double v) { return static_cast<int>(std::lround(v * 10)); }

// Modal group of an accepted G code, or -1.
int g_group(int g) {
  switch (g) {
    case 0: case 10: case 20: case 30: case 50: case 51: case 52: case 53: case 800: case 730: case 810: case 820: case 830:
      return 1;
    case 980: case 990: return 10;
    case 170: case 180: case 190: return 2;
    case 900: case 910: return 3;
    case 901: case 911: return 4;
    case 930: case 940: return 5;
    case 200: case 210: return 6;
    case 400: return 7;
    case 430: case 490: return 8;
    case 40: case 280: case 300: case 530: return 0;  // non-modal
    case 540: return 12;
    case 610: case 611: case 640: return 13;
    default: return -1;
  }
}

// Why a G code is refused.
std::string g_refusal(int g) {
  if (g == 410 || g == 420 || g == 411 || g == 421) return "cutter radius compensation is not supported";
  if (g == 431 || g == 432) return "dynamic tool length offsets (G43.1/G43.2) are not supported";
  if ((g >= 550 && g <= 593) || g == 100 || g == 520)
    return "work offsets are not supported (only G54, the default work offset)";
  if (g >= 920 && g <= 923) return "coordinate offsets (G92) are not supported";
  if (g == 950) return "feed per revolution is not supported (only G93 inverse time and G94 units per minute)";
  if ((g >= 840 && g <= 890) || g == 740 || g == 760)
    return "canned cycles other than G73, G81, G82 and G83 are not supported (feed-out, tapping, boring)";
  if (g == 281 || g == 301) return "storing the reference point (G28.1/G30.1) is not supported";
  if (g >= 330 && g <= 331) return "spindle-synchronised motion is not supported";
  if (g >= 380 && g <= 385) return "probing is not supported";
  if (g == 70 || g == 80) return "lathe diameter/radius mode is not supported";
  if (g == 171 || g == 181 || g == 191) return "arcs in the U V W planes are not supported";
  return "unknown or unsupported G code";
}

std::string fmt_num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

class Interpreter {
 public:
  Interpreter(std::string name, GcodeOptions opt)
      : name_(std::move(name)), opt_(opt), further_(opt_.axes.substr(3)),
        ext_(Eigen::VectorXd::Zero(static_cast<Eigen::Index>(further_.size()))), ext_end_(ext_) {}

  // Reads lines until two moves are pending (a G4 after the first adds its
  // dwell to it) or the program has ended; false once the program has ended
  // and every move was taken.
  bool read_more(std::istream& in) {
    if (!flow_) flow_ = std::make_unique<gcode::GcodeFlow>(in, name_, params_);
    while (out_.moves.size() < 2 && !ended_) {
      if (!flow_->next(text_, line_no_)) {
        finish(line_no_, false);
        break;
      }
      if (text_.size() > kMaxLineChars) {
        line_ = line_no_;
        fail(text_.substr(0, 16) + "...", "the line is too long (" + std::to_string(text_.size()) +
                                              " characters; LinuxCNC reads at most " + std::to_string(kMaxLineChars) + ")");
      }
      const Block b = gcode::lex_line(text_, line_no_, name_, params_);
      if (b.percent) {
        if (in_percent_) {
          finish(line_no_, true);
          break;
        }
        line_ = line_no_;
        if (seen_content_) fail("%", "'%' only on the first line, or to close a program opened with '%'");
        in_percent_ = true;
        seen_content_ = true;
        continue;
      }
      if (text_.find_first_not_of(" \t") != std::string::npos) seen_content_ = true;
      if (b.block_delete && opt_.block_delete) continue;
      params_.apply(b.settings);  // after the line is read, before it runs (as LinuxCNC)
      if (!b.message.empty()) message_ = b.message;  // shown before the line's motion (as LinuxCNC)
      if (b.words.empty()) continue;
      if (execute(b)) finish(line_no_, true);
    }
    return !out_.moves.empty();
  }

  // The moves produced and not yet taken (in program order), and the notes.
  std::deque<Move>& pending() { return out_.moves; }
  const std::vector<std::string>& notes() const { return out_.notes; }
  const std::string& axes() const { return opt_.axes; }

 private:
  std::string name_;
  GcodeOptions opt_;
  struct {
    std::deque<Move> moves;
    std::vector<std::string> notes;
  } out_;
  std::set<std::string> noted_;
  std::string text_;  // the line being read
  int line_no_ = 0;
  std::unique_ptr<gcode::GcodeFlow> flow_;  // the lines in the order the program runs them (O-words)
  bool seen_content_ = false, in_percent_ = false, ended_ = false;

  // Machine state (mm, the program's start X0 Y0 Z0; the further axes at 0).
  Vector3d pos_ = Vector3d::Zero();
  Eigen::RowVectorXd last_end_;  // where the last move emitted ends (all its columns)
  std::string further_;     // the machine's axes after X Y Z (A B C U V W)
  Eigen::VectorXd ext_;     // their positions (mm; degrees for A B C)
  Eigen::VectorXd ext_end_; // their positions at the end of the move being made
  double units_ = 1;  // mm per program unit
  bool absolute_ = true, ijk_absolute_ = false;
  int plane_ = 170;
  Motion motion_ = Motion::kNone;
  std::string motion_text_ = "";
  double feed_ = 0;  // the F number, program units per minute (G93: moves per minute)
  bool inverse_time_ = false;  // G93: each feed move takes 60 / F seconds
  double tolerance_ = -1;
  bool exact_stop_ = false;
  double g5_i_ = 0, g5_j_ = 0;  // a G5 without I J continues the previous one's direction
  // Tool length offset (G43): positions are of the tool's holder, the
  // program's Z plus the length (pos_ holds them so).
  double tlo_ = 0;
  // G43 or G49 in the same block as M6: rs274 re-reads the position after
  // the tool change, after the block's G43, in program coordinates, so the
  // program's Z is kept and the next move takes the holder by the change of
  // the length along Z, with a Z word or without (LinuxCNC's skeleton.ngc:
  // "T1 M06 G43 H1", then "G0 X1.0 Y1.0" runs one tool length higher). A
  // G43 in a block of its own keeps the holder where it is (the program's Z
  // changes). This is that change, until the next move.
  double tlo_pending_ = 0;
  gcode::Parameters params_;
  bool machine_coords_ = false;  // within a G53 block
  // Canned cycles (G73, G81, G83): the retract mode (G98: to the Z before
  // the block, if above R) and the R, Z, Q words kept from block to block,
  // in program units as written (LinuxCNC's cycle_r, cycle_z, cycle_q),
  // only while the same cycle goes on (a block that starts a cycle, after
  // another motion or G80, needs its own: rs274 refuses it otherwise).
  bool retract_old_z_ = false;  // G99 until G98, as rs274 starts
  bool same_cycle_ = true;    // this block continues the cycle in effect before it
  bool cycle_fresh_ = false;  // this block starts cycles after another motion or G80
  std::optional<double> cycle_r_, cycle_z_, cycle_q_, cycle_p_;
  double cycle_level_ = 0;    // the Z where the cycles started (G98's plane; G91's base of R)
  std::optional<int> selected_tool_, loaded_tool_;  // T; T at the last M6

  // An open G5.2 NURBS: control points (mm) and weights, its order and place.
  struct Nurbs {
    Nurbs() {}  // declared: clang sees a nested struct's member initialisers only once the class is complete
    std::vector<Vector3d> points;
    std::vector<double> weights;
    int order = 3;
    int line = 0;
  };
  std::optional<Nurbs> nurbs_;
  // The last operator message ("(MSG, ...)") since the last move: the next pause's text.
  std::string message_;

  // The block being executed.
  int line_ = 0;
  std::map<char, Word> words_;
  std::set<char> used_;

  std::string where(int line) const { return name_ + ":" + std::to_string(line); }
  [[noreturn]] void fail(const std::string& word, const std::string& why) const {
    throw InputError(where(line_) + ": " + word + ": " + why);
  }
  void note(const std::string& kind, const std::string& word, const std::string& what) {
    if (noted_.insert(kind).second) out_.notes.push_back(where(line_) + ": " + word + ": " + what);
  }
  bool has(char c) const { return words_.count(c) > 0; }
  double value(char c) {
    used_.insert(c);
    return words_.at(c).value;
  }
  const std::string& text(char c) const { return words_.at(c).text; }

  void finish(int line, bool ended) {
    line_ = line;
    if (nurbs_) {
      line_ = nurbs_->line;
      fail("G5.2", "NURBS not closed with G5.3 before the end of the program");
    }
    if (!ended) fail("end of file", "the program has no M2, M30 or closing '%'");
    ended_ = true;
  }

  // Returns true at the program's end (M2, M30).
  bool execute(const Block& b) {
    line_ = b.line;
    words_.clear();
    used_.clear();
    std::vector<std::pair<int, std::string>> gs;
    std::vector<std::pair<int, std::string>> ms;
    for (const Word& w : b.words) {
      // codes beyond 1e6 are refused before any conversion to int (which would overflow)
      if ((w.letter == 'G' || w.letter == 'M') && !(std::abs(w.value) < 1e6))
        fail(w.text, std::string("unknown or unsupported ") + w.letter + " code");
      if (w.letter == 'G') {
        if (std::abs(w.value * 10 - tenths(w.value)) > 1e-6) fail(w.text, "unknown or unsupported G code");
        gs.emplace_back(tenths(w.value), w.text);
      } else if (w.letter == 'M') {
        if (w.value != std::floor(w.value)) fail(w.text, "unknown or unsupported M code");
        ms.emplace_back(static_cast<int>(w.value), w.text);
      } else {
        check_letter(w);
        if (words_.count(w.letter)) fail(w.text, std::string("more than one ") + w.letter + " word in the block");
        words_[w.letter] = w;
      }
    }
    std::map<int, std::string> g_by_group;
    for (const auto& [g, t] : gs) {
      const int grp = g_group(g);
      if (grp < 0) fail(t, g_refusal(g));
      if (g_by_group.count(grp)) fail(t, "two G codes from the same modal group (" + g_by_group[grp] + ")");
      g_by_group[grp] = t;
    }
    std::map<int, std::string> m_by_group;
    std::string optional_stop;  // the M1 word (or M0/M60 taken as a stop), if the block has one
    int stop_m = 1;
    for (const auto& [m, t] : ms) {
      int grp;
      if (m == 2 || m == 30) grp = 4;
      else if (m == 1 || ((m == 0 || m == 60) && (opt_.pauses_as_stops || opt_.pauses_wait))) {
        grp = 4;
        optional_stop = t;
        stop_m = m;
      }
      else if (m == 3 || m == 4 || m == 5) grp = 7;
      else if (m == 7 || m == 8 || m == 9) grp = (m == 9 ? 8 : 80 + m);  // M7 and M8 may share a block
      else if (m == 6) grp = 6;
      else if (m == 0 || m == 60)
        fail(t, std::string("program pause (M0/M60) is not supported without ") + kPauseOptions);
      else fail(t, "unknown or unsupported M code");
      if (grp == 8 && (m_by_group.count(87) || m_by_group.count(88))) fail(t, "M9 with M7 or M8 in the same block");
      if ((grp == 87 || grp == 88) && m_by_group.count(8)) fail(t, "M7 or M8 with M9 in the same block");
      if (m_by_group.count(grp)) fail(t, "two M codes from the same modal group (" + m_by_group[grp] + ")");
      m_by_group[grp] = t;
    }
    auto g_in = [&](int grp) -> std::optional<int> {
      for (const auto& [g, t] : gs)
        if (g_group(g) == grp) return g;
      return std::nullopt;
    };
    auto g_text = [&](int g) {
      for (const auto& [gg, t] : gs)
        if (gg == g) return t;
      return std::string();
    };

    // LinuxCNC's order of execution within a block.
    // G93/G94 set the mode and, as in LinuxCNC, the feed rate to 0 (F after
    // them in the same block sets it)
    if (auto g = g_in(5)) {
      inverse_time_ = *g == 930;
      feed_ = 0;
    }
    if (has('F')) {
      const double f = value('F');
      if (f < 0) fail(text('F'), "negative feed rate");
      feed_ = f;
    }
    if (has('S')) {
      value('S');
      note("S", text('S'), "spindle speed accepted and not acted on");
    }
    if (has('T')) {
      const double t = value('T');
      if (!(t >= 0 && t <= kMaxTool) || t != std::floor(t)) fail(text('T'), kToolNumber);
      selected_tool_ = static_cast<int>(t);
      note("T", text('T'), "tool selection accepted (no motion; G43 without H takes the tool of the last M6)");
    }
    for (const auto& [m, t] : ms) {
      if (m == 6) {
        loaded_tool_ = selected_tool_;
        note("M6", t, "tool change accepted (no motion)");
      }
      if (m >= 3 && m <= 5) note("M3/M4/M5", t, "spindle control accepted and not acted on");
      if (m >= 7 && m <= 9) note("M7/M8/M9", t, "coolant control accepted and not acted on");
    }
    if (auto g = g_in(2)) plane_ = *g;
    if (auto g = g_in(6)) set_units(*g == 200 ? kInch : 1.0);
    if (g_in(7)) note("G40", g_text(400), "cutter compensation off (none is applied) accepted");
    if (auto g = g_in(8)) tool_length(*g, g_text(*g), m_by_group.count(6) > 0);
    if (g_in(12)) note("G54", g_text(540), "work offset G54 (the default, zero) accepted");
    if (auto g = g_in(13)) path_control(*g, g_text(*g));
    if (auto g = g_in(3)) absolute_ = *g == 900;
    if (auto g = g_in(4)) ijk_absolute_ = *g == 901;
    if (auto g = g_in(10)) retract_old_z_ = *g == 980;
    same_cycle_ = true;
    cycle_fresh_ = false;
    const std::optional<int> mg = g_in(1);
    if (mg) set_motion(*mg, g_text(*mg));
    const std::optional<int> g0 = g_in(0);
    if (g0 && *g0 == 530) {
      machine_move(g_text(530), mg.has_value());
    } else if (g0 && *g0 != 40) {
      if (mg && any_axis()) fail(g_text(*g0), "two G codes that both use the axis words (" + g_text(*mg) + ")");
      reference_move(*g0, g_text(*g0));
    } else {
      if (g0) dwell(g_text(40));  // before the block's motion, as in LinuxCNC
      motion(mg.has_value());
    }
    check_unused();
    if (!optional_stop.empty()) stop_after_motion(optional_stop, stop_m);
    return m_by_group.count(4) > 0 && optional_stop.empty();
  }

  void check_letter(const Word& w) const {
    switch (w.letter) {
      case 'X': case 'Y': case 'Z': case 'I': case 'J': case 'K': case 'R': case 'P': case 'Q': case 'L':
      case 'F': case 'S': case 'T': case 'H': case '@': case '^':
        return;
      case 'A': case 'B': case 'C': case 'U': case 'V': case 'W':
        if (further_.find(w.letter) != std::string::npos) return;
        fail(w.text, std::string("the machine has no ") + w.letter + " axis (its axes: " + opt_.axes +
                         "; name them with trajcore --axes, e.g. --axes " + opt_.axes + w.letter + ")");
      case 'D': fail(w.text, "cutter radius compensation (D) is not supported");
      default: fail(w.text, "unknown word");
    }
  }

  // G43 (H, or the tool of the last M6) and G49.
  void tool_length(int g, const std::string& t, bool with_tool_change) {
    if (g == 490) {
      set_tool_length(0, with_tool_change);
      return;
    }
    if (!opt_.tools)
      fail(t, "a tool length offset needs the machine's tool table (trajcore --tool-table FILE, LinuxCNC's format)");
    int tool;
    std::string word = t;
    if (has('H')) {
      const double h = value('H');
      if (!(h >= 0 && h <= kMaxTool) || h != std::floor(h)) fail(text('H'), kToolNumber);
      tool = static_cast<int>(h);
      word = text('H');
    } else if (loaded_tool_) {
      tool = *loaded_tool_;
    } else {
      fail(t, "no H word and no tool loaded (T with M6) to take the length of");
    }
    if (tool == 0) {  // LinuxCNC: tool 0 is no tool, of no length
      set_tool_length(0, with_tool_change);
      return;
    }
    const auto it = opt_.tools->z.find(tool);
    if (it == opt_.tools->z.end()) fail(word, "tool " + std::to_string(tool) + " is not in the tool table " + opt_.tools->file);
    set_tool_length(it->second, with_tool_change);
  }

  void set_tool_length(double z, bool keep_program_z) {
    if (keep_program_z) tlo_pending_ += z - tlo_;
    tlo_ = z;
  }

  // G28/G30: with axis words a rapid to that point, then for the axes named
  // (all without axis words) a rapid to the machine origin, as LinuxCNC does
  // with its reference parameters at their default 0. The motion mode stays.
  void reference_move(int g, const std::string& t) {
    if (nurbs_) fail(t, "G5.2 NURBS not closed with G5.3");
    note("G28/G30", t, "reference-point move to the machine origin X0 Y0 Z0, further axes at 0 (LinuxCNC's parameters 5161-5166 and "
                       "5181-5186 at their default 0)");
    if (polar()) refuse_polar();
    const bool named = any_axis();
    const Vector3d mid = named ? end_point() : pos_;
    if (named) ext_end_ = further_end_point();
    rapid_to(mid);
    const char letters[3] = {'X', 'Y', 'Z'};
    Vector3d home = pos_;
    for (int i = 0; i < 3; ++i)
      if (!named || has(letters[i])) home[i] = 0;
    for (size_t i = 0; i < further_.size(); ++i)
      if (!named || has(further_[i])) ext_end_[static_cast<Eigen::Index>(i)] = 0;
    rapid_to(home);
    (void)g;
  }

  void set_units(double u) {
    units_ = u;
  }

  void path_control(int g, const std::string& t) {
    if (g == 640) {
      exact_stop_ = false;
      tolerance_ = -1;
      if (has('P')) {
        const double p = value('P');
        if (p < 0) fail(text('P'), "negative path tolerance");
        if (p > 0) tolerance_ = p * units_;  // P0: no tolerance given, the job's
      }
      if (has('Q')) {
        value('Q');
        note("G64 Q", text('Q'), "G64 Q (naive CAM tolerance) accepted and ignored");
      }
    } else {
      exact_stop_ = true;
      tolerance_ = -1;  // exact path or stop: no tolerance applies
    }
    (void)t;
  }

  void set_motion(int g, const std::string& t) {
    if (g == 800) {
      if (nurbs_) fail(t, "G5.2 NURBS not closed with G5.3");
      motion_ = Motion::kNone;
      return;
    }
    if (g == 53) {
      close_nurbs(t);
      return;
    }
    if (nurbs_ && g != 52) fail(t, "G5.2 NURBS not closed with G5.3");
    const Motion before = motion_;
    motion_ = g == 0 ? Motion::kRapid : g == 10 ? Motion::kLine : g == 20 ? Motion::kCw : g == 30 ? Motion::kCcw
            : g == 50 ? Motion::kCubic : g == 51 ? Motion::kQuadratic : g == 52 ? Motion::kNurbs
            : g == 810 ? Motion::kDrill : g == 820 ? Motion::kDrillDwell : g == 830 ? Motion::kPeck
            : Motion::kChipBreak;
    same_cycle_ = motion_ == before;
    cycle_fresh_ = is_cycle(motion_) && !is_cycle(before);
    motion_text_ = t;
  }

  bool polar() const { return has('@') || has('^'); }
  std::string polar_word() const { return text(has('@') ? '@' : '^'); }
  // polar coordinates in a block whose motion does not take them
  [[noreturn]] void refuse_polar() const {
    fail(polar_word(), "polar coordinates (@ ^) are supported with G0, G1 and the canned cycles only");
  }
  bool any_axis() const {
    if (has('X') || has('Y') || has('Z') || polar()) return true;
    for (char c : further_)
      if (has(c)) return true;
    return false;
  }
  static bool rotary(char axis) { return axis == 'A' || axis == 'B' || axis == 'C'; }

  // A B C are in degrees whatever the length units; U V W in them.
  Eigen::VectorXd further_end_point() {
    Eigen::VectorXd e = ext_;
    for (size_t i = 0; i < further_.size(); ++i) {
      const char c = further_[i];
      if (!has(c)) continue;
      const double unit = rotary(c) ? 1.0 : units_;
      const auto k = static_cast<Eigen::Index>(i);
      e[k] = value(c) * unit + (absolute_ ? 0.0 : ext_[k]);
    }
    return e;
  }

  void rapid_to(const Vector3d& e) {
    if (e != pos_ || ext_end_ != ext_) emit(Move::Kind::kRapid, gcode::line3(pos_, e), 0);
    pos_ = e;
    tlo_pending_ = 0;
    ext_ = ext_end_;
  }

  Vector3d end_point() {
    Vector3d e = pos_;
    e[2] += tlo_pending_;
    const char letters[3] = {'X', 'Y', 'Z'};
    const double z_offset = machine_coords_ ? 0.0 : tlo_;
    for (int i = 0; i < 3; ++i)
      if (has(letters[i])) e[i] = value(letters[i]) * units_ + (absolute_ ? (i == 2 ? z_offset : 0.0) : e[i]);
    if (polar()) polar_end_point(e);
    return e;
  }

  // LinuxCNC's polar coordinates in X Y (whatever the plane), about the
  // origin of the program's coordinates: @ the distance, ^ the angle in
  // degrees from +X. G90: the word given sets its coordinate, the other is
  // the current point's; G91: @ adds to the current distance, then ^ to the
  // current angle. G0, G1 and the canned cycles (each repeat of a cycle
  // from where the last one drilled: G91 ^60 L6 drills a bolt circle); rs274
  // takes them with arcs too, which are refused here in motion().
  void polar_end_point(Vector3d& e) {
    const std::string word = polar_word();
    if (has('X') || has('Y')) fail(word, "X or Y words with polar coordinates (@ ^)");
    const bool at_origin = pos_[0] == 0 && pos_[1] == 0;
    double r = std::hypot(pos_[1], pos_[0]), theta = std::atan2(pos_[1], pos_[0]);
    if (absolute_) {
      if (has('@') && !has('^') && at_origin) fail(word, "a polar distance (@) at the origin needs an angle (^)");
      if (has('@')) r = value('@') * units_;
      if (has('^')) theta = value('^') * kPi / 180;
    } else {
      if (at_origin) fail(word, "incremental polar coordinates (G91 @ ^) at the origin have no direction");
      if (has('@')) r += value('@') * units_;
      if (has('^') && r == 0) fail(word, "incremental polar coordinates (G91 @ ^) at the origin have no direction");
      if (has('^')) theta += value('^') * kPi / 180;
    }
    e[0] = r * std::cos(theta);
    e[1] = r * std::sin(theta);
  }

  // G53: this block's G0 or G1 goes to machine coordinates, the moves' own
  // (the holder's; G54 is zero here, so only the tool length offset is left
  // out), as in LinuxCNC; absolute only.
  void machine_move(const std::string& t, bool explicit_g) {
    if (motion_ != Motion::kRapid && motion_ != Motion::kLine) fail(t, "G53 needs G0 or G1 (as in LinuxCNC)");
    if (!absolute_) fail(t, "G53 in incremental distance mode (G91): machine coordinates are absolute");
    if (polar()) fail(polar_word(), "polar coordinates (@ ^) with G53 are not supported");
    struct Within {
      bool& flag;
      ~Within() { flag = false; }
    } within{machine_coords_ = true};
    motion(explicit_g);
  }

  // The programmed feed of X Y Z or U V W (mm/s); in G93 its F is checked
  // here and the feed made from the move's length (feed_measure).
  double feed_mm_s(const std::string& word) const {
    if (inverse_time_) {
      if (!has('F')) fail(word, "F word missing: in inverse-time mode (G93) every feed move needs its own F");
      if (feed_ <= 0) fail(text('F'), "in inverse-time mode (G93) F must be positive (the move takes 1/F minutes)");
      return 0;
    }
    if (feed_ <= 0) fail(word, "no feed rate: program F (units per minute) before the first feed move");
    return feed_ * units_ / 60.0;
  }

  // The move's length in all axes over the length its feed measures
  // (Move::feed_scale), and the programmed feed in that measure's units/s:
  // F of X Y Z (length xyz, mm) when they move, else of U V W, else of A B C
  // (degrees a minute, whatever the length units); in G93 that length over
  // the move's time, 60 / F s (rs274 prints this feed too). The further axes
  // move linearly with the move's progress (xyz: the XYZ length of a line,
  // of a circle or a helix; the further axes' share is exact for those).
  std::pair<double, double> feed_measure(double xyz, double feed_mm_s) const {
    double uvw = 0, abc = 0;
    for (size_t i = 0; i < further_.size(); ++i) {
      const double d = ext_end_[static_cast<Eigen::Index>(i)] - ext_[static_cast<Eigen::Index>(i)];
      const char c = further_[i];
      (rotary(c) ? abc : uvw) += d * d;
    }
    const bool angular = xyz == 0 && uvw == 0 && abc > 0;
    const double measured = (xyz > 0 || (uvw == 0 && abc == 0)) ? xyz : uvw > 0 ? std::sqrt(uvw) : std::sqrt(abc);
    const double scale = measured > 0 ? std::sqrt(xyz * xyz + uvw + abc) / measured : 1.0;
    if (inverse_time_) return {scale, measured * feed_ / 60.0};
    return {scale, angular ? feed_ / 60.0 : feed_mm_s};
  }

  // A move of X Y Z (`curve`, 3-D) with the further axes from ext_ to
  // ext_end_ appended; `xyz` its XYZ length and `feed` the programmed feed
  // (mm/s) for feed moves.
  void emit(Move::Kind kind, geo::BSpline curve, double feed, double xyz = 0) {
    Move m;
    m.kind = kind;
    m.curve = gcode::with_further_axes(std::move(curve), ext_, ext_end_);
    if (kind == Move::Kind::kFeed) {
      const auto [scale, programmed] = feed_measure(xyz, feed);
      m.feed = programmed * scale;
      m.feed_scale = scale;
    }
    tlo_pending_ = 0;  // the move ends at the holder's Z under the offset in force
    m.tolerance = tolerance_;
    m.exact_stop = exact_stop_ || kind == Move::Kind::kRapid;
    m.where = where(line_);
    message_.clear();  // a message before a move (even one left out below) is not the next pause's
    // A move of 1e-9 mm or less (X[0.1+0.2] after X0.3: 6e-17) is left out, as the drawings' pieces
    // (cuts.hpp); the next move starts where the last one kept ends (it moves by as little).
    if (negligible(m.curve)) return;
    if (last_end_.size() == m.curve.ctrl.cols() && (m.curve.ctrl.row(0) - last_end_).norm() <= kNegligibleMm)
      m.curve.ctrl.row(0) = last_end_;
    last_end_ = m.curve.ctrl.row(m.curve.n_ctrl() - 1);
    out_.moves.push_back(std::move(m));
  }

  void motion(bool explicit_g) {
    const std::string word = explicit_g ? motion_text_ : motion_text_ + " (modal)";
    if (motion_ == Motion::kNurbs) {
      nurbs_point(explicit_g);
      return;
    }
    if (polar() && !(motion_ == Motion::kRapid || motion_ == Motion::kLine || is_cycle(motion_)) &&
        motion_ != Motion::kNone)
      refuse_polar();
    if (is_cycle(motion_)) {
      if (any_axis()) canned_cycle(word);  // a block with an axis word runs it (with R alone rs274 refuses R)
      return;
    }
    const bool arc_mode = motion_ == Motion::kCw || motion_ == Motion::kCcw;
    if (!any_axis()) {
      // LinuxCNC: a centre-format arc without end point words is a full circle back to the start.
      if (explicit_g && arc_mode && (has('I') || has('J') || has('K'))) {
        arc(pos_, word);
        return;
      }
      if (explicit_g && (arc_mode || motion_ == Motion::kCubic || motion_ == Motion::kQuadratic) &&
          (has('R') || has('P') || has('Q')))
        fail(motion_text_, "no end point (X, Y or Z)");
      return;
    }
    if (motion_ == Motion::kNone) {
      char c = has('X') ? 'X' : has('Y') ? 'Y' : has('Z') ? 'Z' : has('@') ? '@' : '^';
      for (char f : further_)
        if (!has(c) && has(f)) c = f;
      fail(text(c), "axis word with no motion mode (G0, G1, G2, G3, G5, ...) in effect");
    }
    const Vector3d e = end_point();
    ext_end_ = further_end_point();
    switch (motion_) {
      case Motion::kRapid:
        rapid_to(e);
        break;
      case Motion::kLine: {
        const double f = feed_mm_s(word);
        if (e != pos_ || ext_end_ != ext_) emit(Move::Kind::kFeed, gcode::line3(pos_, e), f, (e - pos_).norm());
        break;
      }
      case Motion::kCw: case Motion::kCcw: arc(e, word); break;
      case Motion::kCubic: case Motion::kQuadratic: spline(e, word); break;
      default: break;
    }
    pos_ = e;
    tlo_pending_ = 0;
    ext_ = ext_end_;
  }

  static bool is_cycle(Motion m) {
    return m == Motion::kDrill || m == Motion::kDrillDwell || m == Motion::kPeck || m == Motion::kChipBreak;
  }
  static bool is_peck(Motion m) { return m == Motion::kPeck || m == Motion::kChipBreak; }

  // G81 (drill), G82 (drill, resting P seconds at the bottom), G83 (peck:
  // back to R after each peck) and G73 (chip
  // break: a short retract after each), as rs274 expands them (in G17; the
  // rules are its, found by running it on programs written for it, 60 of
  // them random): the cycles keep a level L, the Z where they start after
  // another motion or G80; in G91 R is relative to L and Z to R. A block
  // whose R is above L first rises to R at the tool's X Y. Per hole (L
  // times; in G91 X Y are increments): a rapid to the hole's X Y at the
  // tool's Z (rising to the clear plane on the way when not above R), a
  // rapid down to R, the feed down (in pecks of Q, each after the first
  // begun by a rapid to 0.254 mm above the last depth, G83 from R), and a
  // rapid up to the clear plane (G98: the higher of L and R; G99: R). The
  // moves run in exact-path mode, as in LinuxCNC.
  void canned_cycle(const std::string& word) {
    if (plane_ != 170) fail(word, "canned cycles are supported in the XY plane (G17) only");
    if (inverse_time_) fail(word, "canned cycles in inverse-time mode (G93) are not supported");
    refuse_further_axes("canned cycles");
    const double f = feed_mm_s(word);
    if (!same_cycle_) cycle_r_.reset(), cycle_z_.reset(), cycle_q_.reset(), cycle_p_.reset();
    if (has('R')) cycle_r_ = value('R');
    if (has('Z')) cycle_z_ = value('Z');
    if (!cycle_r_) fail(word, "R word missing (the retract plane of the cycle)");
    if (!cycle_z_) fail(word, "Z word missing (the bottom of the hole)");
    if (is_peck(motion_) && has('Q')) {  // G81 and G82 take no Q (rs274 refuses it)
      const double q = value('Q');
      if (!(q > 0)) fail(text('Q'), "the peck depth Q must be positive");
      cycle_q_ = q;
    }
    if (is_peck(motion_) && !cycle_q_) fail(word, "Q word missing (the peck depth)");
    if (motion_ == Motion::kDrillDwell && has('P')) {
      const double p = value('P');
      if (!(p >= 0)) fail(text('P'), "the dwell time must not be negative");
      cycle_p_ = p;
    }
    if (motion_ == Motion::kDrillDwell && !cycle_p_) fail(word, "P word missing (the dwell at the bottom, seconds)");
    int repeats = 1;
    if (has('L')) {
      const double l = value('L');
      if (l != std::floor(l) || l < 1 || l > kMaxCycleRepeats)
        fail(text('L'), "the repeat count L must be a whole number from 1 to " + std::to_string(kMaxCycleRepeats));
      repeats = static_cast<int>(l);
    }
    if (cycle_fresh_) cycle_level_ = pos_[2] + tlo_pending_;
    const double r = absolute_ ? *cycle_r_ * units_ + tlo_ : cycle_level_ + *cycle_r_ * units_;
    const double bottom = absolute_ ? *cycle_z_ * units_ + tlo_ : r + *cycle_z_ * units_;
    if (bottom > r) fail(word, "the bottom of the hole (Z) is above the retract plane (R)");
    if (is_peck(motion_) && !(std::ceil((r - bottom) / (*cycle_q_ * units_)) * repeats <= kMaxPecks))
      fail(word, "the peck depth Q and the repeats L make more than " + fmt_num(kMaxPecks) + " pecks in one block");
    const double x = has('X') ? value('X') * units_ : 0, y = has('Y') ? value('Y') * units_ : 0;
    const bool exact = exact_stop_;
    const double tol = tolerance_;
    exact_stop_ = true;
    tolerance_ = -1;
    if (cycle_level_ < r) rapid_to({pos_[0], pos_[1], r});
    const double clear = retract_old_z_ ? std::max(cycle_level_, r) : r;
    for (int k = 0; k < repeats; ++k) {
      // to the hole at the tool's Z, or risen to the clear plane when not above R
      const double z = pos_[2] + tlo_pending_;  // the program's Z under a new tool length (end_point)
      Vector3d hole(pos_[0], pos_[1], z <= r ? clear : z);
      if (has('X')) hole[0] = absolute_ ? x : pos_[0] + x;
      if (has('Y')) hole[1] = absolute_ ? y : pos_[1] + y;
      if (polar()) polar_end_point(hole);  // about the origin, from the last hole
      rapid_to(hole);
      rapid_to({hole[0], hole[1], r});
      drill(r, bottom, f);
      rapid_to({hole[0], hole[1], clear});
    }
    exact_stop_ = exact;
    tolerance_ = tol;
  }

  // The feed down from R to the bottom, in pecks for G83 and G73.
  void drill(double r, double bottom, double f) {
    auto feed_to = [&](double z) {
      const Vector3d e(pos_[0], pos_[1], z);
      if (e != pos_) emit(Move::Kind::kFeed, gcode::line3(pos_, e), f, (e - pos_).norm());
      pos_ = e;
    };
    if (!is_peck(motion_)) {
      feed_to(bottom);
      if (motion_ == Motion::kDrillDwell && !out_.moves.empty()) {  // G82: rests at the bottom
        out_.moves.back().exact_stop = true;
        out_.moves.back().dwell += *cycle_p_;
      }
      return;
    }
    const double q = *cycle_q_ * units_;
    double depth = std::max(r - q, bottom);
    feed_to(depth);
    while (depth > bottom) {
      if (motion_ == Motion::kPeck) rapid_to({pos_[0], pos_[1], r});
      rapid_to({pos_[0], pos_[1], depth + kPeckClearanceMm});
      depth = std::max(depth - q, bottom);
      feed_to(depth);
    }
  }

  // Plane axes (LinuxCNC's order) and the letters of their centre words.
  struct PlaneAxes {
    int first, second, normal;
    char i1, i2, refused;
  };
  PlaneAxes plane_axes() const {
    if (plane_ == 180) return {2, 0, 1, 'K', 'I', 'J'};
    if (plane_ == 190) return {1, 2, 0, 'J', 'K', 'I'};
    return {0, 1, 2, 'I', 'J', 'K'};
  }

  void arc(const Vector3d& e, const std::string& word) {
    const PlaneAxes pa = plane_axes();
    const char axis_letter[3] = {'X', 'Y', 'Z'};
    if (has('R') && !has(axis_letter[pa.first]) && !has(axis_letter[pa.second]))
      fail(word, std::string(1, axis_letter[pa.first]) + " and " + axis_letter[pa.second] +
                     " words missing for an arc in this plane");
    const double f = feed_mm_s(word);
    int turns = 1;
    if (has('P')) {
      const double p = value('P');
      if (std::abs(p - std::round(p)) > 1e-4) fail(text('P'), "the number of turns must be an integer");
      if (std::round(p) < 1) fail(text('P'), "the number of turns must be 1 or more");
      if (std::round(p) > kMaxTurns)
        fail(text('P'), "the number of turns must be at most " + std::to_string(kMaxTurns));
      turns = static_cast<int>(std::round(p));
    }
    const bool ijk = has('I') || has('J') || has('K');
    const double rtol = units_ == 1 ? kRadiusTolMm : kRadiusTolInch * kInch;
    const double s1 = pos_[pa.first], s2 = pos_[pa.second], e1 = e[pa.first], e2 = e[pa.second];
    double c1, c2;
    if (has('R') && ijk) fail(text('R'), "both a radius (R) and a centre (I J K) given");
    if (has('R')) {
      const double r = value('R') * units_;
      if (e1 == s1 && e2 == s2) fail(text('R'), "a radius arc cannot end where it starts (use I J K for a full circle)");
      const double ar = std::abs(r);
      const double m1 = (e1 + s1) / 2, m2 = (e2 + s2) / 2;
      double half = std::hypot(m1 - e1, m2 - e2);
      if (half - ar > rtol) fail(text('R'), "the radius is too small to reach the end point");
      if (half / ar > 1 - 1e-12) half = ar;
      const bool cw = motion_ == Motion::kCw;
      const double theta = std::atan2(e2 - s2, e1 - s1) + (((cw && r > 0) || (!cw && r < 0)) ? -kPi / 2 : kPi / 2);
      const double offset = ar * std::cos(std::asin(half / ar));
      c1 = m1 + offset * std::cos(theta);
      c2 = m2 + offset * std::sin(theta);
    } else if (ijk) {
      if (has(pa.refused)) fail(text(pa.refused), std::string(1, pa.refused) + " word given for an arc in this plane");
      auto offset = [&](char c) -> double {
        if (has(c)) return value(c) * units_;
        if (ijk_absolute_) fail(word, std::string(1, c) + " word missing in an absolute-centre (G90.1) arc");
        return 0.0;
      };
      const double o1 = offset(pa.i1), o2 = offset(pa.i2);
      // an absolute centre is a program position: on Z, the tool's length added as to end points
      c1 = ijk_absolute_ ? o1 + (pa.first == 2 ? tlo_ : 0.0) : s1 + o1;
      c2 = ijk_absolute_ ? o2 + (pa.second == 2 ? tlo_ : 0.0) : s2 + o2;
      const double r0 = std::hypot(c1 - s1, c2 - s2), r1 = std::hypot(c1 - e1, c2 - e2);
      if (r0 < rtol || r1 < rtol) fail(word, "zero-radius arc (start radius " + fmt_num(r0 / units_) + ", end radius " + fmt_num(r1 / units_) + ")");
      const double abs_err = std::abs(r0 - r1), rel_err = abs_err / std::max(r0, r1);
      const double abs_tol = units_ == 1 ? kSpiralAbsMm : kSpiralAbsInch * kInch;
      if (abs_err > abs_tol && rel_err > kSpiralRel)
        fail(word, "radius to the end differs from radius to the start: " + fmt_num(r0 / units_) + " and " +
                       fmt_num(r1 / units_) + " (more than " + fmt_num(abs_tol / units_) + " and " +
                       fmt_num(kSpiralRel * 100) + "%)");
    } else {
      fail(word, "arc with neither a centre (I J K) nor a radius (R)");
    }
    const double a0 = std::atan2(s2 - c2, s1 - c1), a1 = std::atan2(e2 - c2, e1 - c1);
    double sweep = a1 - a0;
    if (motion_ == Motion::kCcw) {
      while (sweep <= 0) sweep += 2 * kPi;
      sweep += 2 * kPi * (turns - 1);
    } else {
      while (sweep >= 0) sweep -= 2 * kPi;
      sweep -= 2 * kPi * (turns - 1);
    }
    gcode::ArcSpec spec;
    spec.first = pa.first;
    spec.second = pa.second;
    spec.normal = pa.normal;
    spec.start = pos_;
    spec.end = e;
    spec.c1 = c1;
    spec.c2 = c2;
    spec.sweep = sweep;
    spec.helix_form = ext_end_ != ext_;
    if ((spec.start[pa.normal] != spec.end[pa.normal] || spec.helix_form) &&
        gcode::helix_pieces(spec) > gcode::kMaxHelixPieces)
      fail(word, "helical arc of radius " + fmt_num(std::hypot(c1 - s1, c2 - s2) / units_) +
                     ": too large to follow within " + fmt_num(gcode::kHelixBound) + " in at most " +
                     std::to_string(gcode::kMaxHelixPieces) + " pieces");
    // X Y Z length: the mean radius turned through the sweep, with the normal axis's travel
    const double r_mean = (std::hypot(c1 - s1, c2 - s2) + std::hypot(c1 - e1, c2 - e2)) / 2;
    const double xyz = std::hypot(r_mean * sweep, e[pa.normal] - pos_[pa.normal]);
    emit(Move::Kind::kFeed, gcode::arc3(spec), f, xyz);
  }

  // Splines move X and Y only (LinuxCNC's G5, G5.1 and G5.2 do).
  void refuse_further_axes(const std::string& what) const {
    for (char c : further_)
      if (has(c)) fail(text(c), what + " may not move " + std::string(1, c));
  }

  void spline(const Vector3d& e, const std::string& word) {
    if (inverse_time_) fail(word, "splines (G5, G5.1) in inverse-time mode (G93) are not supported");
    if (plane_ != 170) fail(word, "splines must be in the XY plane (G17)");
    if (has('Z')) fail(text('Z'), "splines (G5, G5.1) may not move Z");
    refuse_further_axes("splines (G5, G5.1)");
    const double f = feed_mm_s(word);
    if (motion_ == Motion::kQuadratic) {
      if (!has('I') || !has('J')) fail(word, "G5.1 needs both I and J");
      Eigen::MatrixXd c(3, 3);
      c.row(0) = pos_.transpose();
      c.row(1) = Vector3d(pos_[0] + value('I') * units_, pos_[1] + value('J') * units_, pos_[2]).transpose();
      c.row(2) = e.transpose();
      emit(Move::Kind::kFeed, gcode::bezier3(c), f);
      return;
    }
    double i, j;
    if (has('I') != has('J')) fail(word, "G5 needs both I and J, or neither");
    if (has('I')) {
      i = value('I') * units_;
      j = value('J') * units_;
    } else {
      i = g5_i_;
      j = g5_j_;
    }
    if (!has('P') || !has('Q')) fail(word, "G5 needs both P and Q");
    const double p = value('P') * units_, q = value('Q') * units_;
    Eigen::MatrixXd c(4, 3);
    c.row(0) = pos_.transpose();
    c.row(1) = Vector3d(pos_[0] + i, pos_[1] + j, pos_[2]).transpose();
    c.row(2) = Vector3d(e[0] + p, e[1] + q, pos_[2]).transpose();
    c.row(3) = e.transpose();
    g5_i_ = -p;
    g5_j_ = -q;
    emit(Move::Kind::kFeed, gcode::bezier3(c), f);
  }

  // M1 (after the block's motion, as in LinuxCNC): the machine stops at the
  // end of the move before it and goes on, as LinuxCNC does with its
  // optional-stop switch off; a pause for an operator is not modelled. M0 and
  // M60 (GcodeOptions::pauses_as_stops) likewise.
  void stop_after_motion(const std::string& t, int m) {
    if (nurbs_) fail(t, "G5.2 NURBS not closed with G5.3");
    const bool pause = m != 1 && opt_.pauses_wait;
    if (pause && out_.moves.empty()) {
      note("M0 first", t, "program pause before the first move: no pause record (the stream holds none before its "
                          "first segment); starting the job (`trajcore upload`) is the go-ahead" +
                          (message_.empty() ? std::string() : " (its message: \"" + message_ + "\")"));
      message_.clear();
      return;
    }
    if (m == 1)
      note("M1", t, "optional stop taken as an exact stop, without a pause (LinuxCNC's optional-stop switch off)");
    else if (pause)
      note("M0", t, "program pause: the stream holds a pause record there, at which `trajcore upload` waits for the "
                    "operator (--pause-wait)");
    else
      note("M0", t, "program pause taken as an exact stop: the motion goes on without waiting for an operator "
                    "(--pause-as-stop)");
    if (out_.moves.empty()) return;
    out_.moves.back().exact_stop = true;
    if (!pause) return;
    out_.moves.back().pause = {line_, message_};
    message_.clear();
  }

  // G4 P: the machine stops at the end of the move before it and rests P
  // seconds there (P0: the stop alone, LinuxCNC's way of forcing one).
  void dwell(const std::string& t) {
    if (!has('P')) fail(t, "dwell time P (seconds) missing");
    const double p = value('P');
    if (!(p >= 0)) fail(text('P'), "the dwell time must not be negative");
    if (nurbs_) fail(t, "G5.2 NURBS not closed with G5.3");
    if (out_.moves.empty()) {
      note("G4", t, "dwell before the first move accepted (the machine is at rest there)");
      return;
    }
    out_.moves.back().exact_stop = true;
    out_.moves.back().dwell += p;
  }

  // A G5.2 block: the first one starts the NURBS at the current point.
  void nurbs_point(bool explicit_g) {
    const std::string word = explicit_g ? motion_text_ : "G5.2 (modal)";
    if (inverse_time_) fail(word, "NURBS (G5.2) in inverse-time mode (G93) are not supported");
    if (plane_ != 170) fail(word, "NURBS (G5.2) must be in the XY plane (G17)");
    if (has('Z')) fail(text('Z'), "NURBS (G5.2) control points are in X and Y only");
    refuse_further_axes("NURBS (G5.2)");
    if (has('X') != has('Y')) fail(word, "a NURBS control point needs both X and Y");
    if (!nurbs_) {
      feed_mm_s(word);
      nurbs_.emplace();
      nurbs_->line = line_;
      nurbs_->points.push_back(pos_);
      nurbs_->weights.push_back(!has('X') && has('P') ? value('P') : 1.0);
      if (!has('X') && has('P') && nurbs_->weights.back() <= 0) fail(text('P'), "weights must be positive");
    } else if (!has('X') && has('P')) {
      fail(text('P'), "a weight without X and Y is allowed only for the first control point");
    }
    if (has('L')) {
      const double l = value('L');
      // the order is held as int: bounded before the conversion (a rational NURBS is checked against
      // its own, lower cap when it is closed)
      if (l != std::floor(l) || l < 3 || l > geo::kMaxDegree + 1)
        fail(text('L'), "the NURBS order must be an integer from 3 to " + std::to_string(geo::kMaxDegree + 1));
      nurbs_->order = static_cast<int>(l);
    }
    if (has('X')) {
      if (!has('P')) fail(word, "every NURBS control point needs a positive weight P");
      const double w = value('P');
      if (w <= 0) fail(text('P'), "weights must be positive");
      // Relative (G91) control points are relative to the NURBS's start, as in LinuxCNC.
      const Vector3d start = nurbs_->points.front();
      Vector3d p = start;
      p[0] = value('X') * units_ + (absolute_ ? 0.0 : start[0]);
      p[1] = value('Y') * units_ + (absolute_ ? 0.0 : start[1]);
      nurbs_->points.push_back(p);
      nurbs_->weights.push_back(w);
    }
  }

  void close_nurbs(const std::string& t) {
    if (!nurbs_) fail(t, "G5.3 without G5.2 first");
    const Nurbs n = *nurbs_;
    nurbs_.reset();
    motion_ = Motion::kNone;
    const int count = static_cast<int>(n.points.size());
    if (count < n.order)
      fail(t, "a NURBS of order " + std::to_string(n.order) + " needs at least " + std::to_string(n.order) +
                  " control points (it has " + std::to_string(count) + ")");
    Eigen::MatrixXd c(count, 3);
    Eigen::VectorXd w(count);
    for (int i = 0; i < count; ++i) {
      c.row(i) = n.points[i].transpose();
      w[i] = n.weights[i];
    }
    geo::BSpline b = gcode::nurbs3(c, w, n.order);
    const std::string err = geo::degree_range_error(b.degree, b.rational());
    if (!err.empty()) fail(t, "NURBS order " + std::to_string(n.order) + ": " + err);
    const int line = line_;
    line_ = n.line;
    emit(Move::Kind::kFeed, std::move(b), feed_mm_s(t));
    line_ = line;
    pos_ = n.points.back();
  }

  void check_unused() const {
    for (const auto& [c, w] : words_)
      if (!used_.count(c)) fail(w.text, "no G code in this block uses it");
  }
};

}  // namespace

struct GcodeReader::Impl {
  Impl(std::string name, GcodeOptions opt) : interp(std::move(name), opt) {}
  std::ifstream file;
  std::istream* in = nullptr;
  Interpreter interp;
};

GcodeReader::GcodeReader(const std::string& file, const GcodeOptions& options)
    : impl_((check_axes(options.axes), std::make_unique<Impl>(file, options))) {
  impl_->file.open(file);
  if (!impl_->file) throw InputError(file + ": cannot open");
  impl_->in = &impl_->file;
}

GcodeReader::GcodeReader(std::istream& in, const std::string& name, const GcodeOptions& options)
    : impl_((check_axes(options.axes), std::make_unique<Impl>(name, options))) {
  impl_->in = &in;
}

GcodeReader::~GcodeReader() = default;

bool GcodeReader::next(Move& m) {
  if (!impl_->interp.read_more(*impl_->in)) return false;
  m = std::move(impl_->interp.pending().front());
  impl_->interp.pending().pop_front();
  return true;
}

const std::vector<std::string>& GcodeReader::notes() const { return impl_->interp.notes(); }

int GcodeReader::axes() const { return static_cast<int>(impl_->interp.axes().size()); }

namespace {
Toolpath read_all(GcodeReader& r) {
  Toolpath tp;
  Move m;
  while (r.next(m)) tp.moves.push_back(std::move(m));
  tp.notes = r.notes();
  tp.axes = r.axes();
  return tp;
}
}  // namespace

void check_axes(const std::string& axes) {
  const std::string why = "--axes " + axes + ": ";
  if (axes.compare(0, 3, "XYZ") != 0) throw InputError(why + "the axes start with X Y Z (e.g. XYZA)");
  if (axes.size() > 8) throw InputError(why + "at most 8 axes (the core's)");
  for (size_t i = 3; i < axes.size(); ++i) {
    if (std::string("ABCUVW").find(axes[i]) == std::string::npos)
      throw InputError(why + std::string(1, axes[i]) + " is not one of A B C U V W");
    if (axes.find(axes[i]) != i) throw InputError(why + std::string(1, axes[i]) + " named twice");
  }
}

ToolTable read_tool_table(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file + ": cannot open");
  ToolTable t;
  t.file = file;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const std::string at = file + ":" + std::to_string(n) + ": ";
    const std::string body = line.substr(0, line.find(';'));
    std::istringstream words(body);
    std::string w;
    std::map<char, double> v;
    while (words >> w) {
      const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])));
      const std::string num = w.substr(1);
      size_t used = 0;
      double x = 0;
      try {
        x = std::stod(num, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (num.empty() || used != num.size() || !std::isfinite(x)) throw InputError(at + w + ": not a letter and a number");
      if (std::string("TPXYZABCUVWDIJQ").find(c) == std::string::npos) throw InputError(at + w + ": unknown word");
      if (v.count(c)) throw InputError(at + w + ": more than one " + std::string(1, c) + " word");
      if (std::string("XYABCUVW").find(c) != std::string::npos && x != 0)
        throw InputError(at + w + ": only Z tool length offsets are supported");
      v[c] = x;
    }
    if (v.empty()) continue;
    if (!v.count('T')) throw InputError(at + "T: the tool number is missing");
    if (!v.count('P')) throw InputError(at + "P: the pocket number is missing");
    const double tool = v['T'];
    if (!(tool >= 1 && tool <= kMaxTool) || tool != std::floor(tool))
      throw InputError(at + "T: the tool number must be a whole number from 1 to 1000000000");
    if (t.z.count(static_cast<int>(tool))) throw InputError(at + "T: tool " + std::to_string(static_cast<int>(tool)) + " listed twice");
    t.z[static_cast<int>(tool)] = v.count('Z') ? v['Z'] : 0.0;
  }
  return t;
}

Toolpath read_gcode(std::istream& in, const std::string& name, const GcodeOptions& options) {
  GcodeReader r(in, name, options);
  return read_all(r);
}

Toolpath read_gcode(const std::string& file, const GcodeOptions& options) {
  GcodeReader r(file, options);
  return read_all(r);
}

}  // namespace traj::input
