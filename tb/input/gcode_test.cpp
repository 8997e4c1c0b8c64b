// SPDX-License-Identifier: Apache-2.0
// read_gcode: each word, each refusal (its message), arcs in all planes, helices, inches, relative
// mode, splines. Geometry is checked by evaluating the curves (geo::Curve).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "geometry/curve.hpp"
#include "input/gcode.hpp"
#include "tmp_file.hpp"
#include "input/gcode_curves.hpp"

using traj::input::InputError;
using traj::input::Move;
using traj::input::Toolpath;

namespace {

constexpr double kPi = 3.14159265358979323846;

Toolpath read(const std::string& program, traj::input::GcodeOptions opt = {}) {
  std::istringstream in(program);
  return traj::input::read_gcode(in, "t.ngc", opt);
}

std::string refusal(const std::string& program, const traj::input::GcodeOptions& opt = {}) {
  try {
    read(program, opt);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

Eigen::Vector3d at(const Move& m, double f) {
  traj::geo::Curve c(m.curve);
  const double u = m.curve.u_begin() + (m.curve.u_end() - m.curve.u_begin()) * f;
  return c.eval(u, 0).col(0);
}

Eigen::Vector3d end_of(const Move& m) { return m.curve.ctrl.row(m.curve.n_ctrl() - 1).transpose(); }
Eigen::Vector4d end_of4(const Move& m) { return m.curve.ctrl.row(m.curve.n_ctrl() - 1).transpose(); }

// Largest distance of samples from the circle (centre c in the plane of axes a, b) and the swept angle.
std::pair<double, double> circle_fit(const Move& m, int a, int b, double ca, double cb, double r, int n = 720) {
  double worst = 0, swept = 0;
  Eigen::Vector3d p0 = at(m, 0);
  double prev = std::atan2(p0[b] - cb, p0[a] - ca);
  for (int k = 1; k <= n; ++k) {
    const Eigen::Vector3d p = at(m, static_cast<double>(k) / n);
    worst = std::max(worst, std::abs(std::hypot(p[a] - ca, p[b] - cb) - r));
    const double ang = std::atan2(p[b] - cb, p[a] - ca);
    double d = ang - prev;
    if (d > kPi) d -= 2 * kPi;
    if (d < -kPi) d += 2 * kPi;
    swept += d;
    prev = ang;
  }
  return {worst, swept};
}

}  // namespace

TEST(Gcode, LinesRapidsFeedUnitsPerMinute) {
  const Toolpath t = read("G21 G90\nF600\nG0 X1 Y2\nG1 X10 Y2 Z-1\nM2\n");
  ASSERT_EQ(t.moves.size(), 2u);
  EXPECT_EQ(t.moves[0].kind, Move::Kind::kRapid);
  EXPECT_TRUE(t.moves[0].exact_stop);
  EXPECT_EQ(t.moves[1].kind, Move::Kind::kFeed);
  EXPECT_DOUBLE_EQ(t.moves[1].feed, 10.0);  // 600 mm/min
  EXPECT_TRUE(at(t.moves[0], 0).isZero());  // the program starts at X0 Y0 Z0
  EXPECT_TRUE(end_of(t.moves[1]).isApprox(Eigen::Vector3d(10, 2, -1)));
  EXPECT_EQ(t.moves[1].where, "t.ngc:4");
  EXPECT_EQ(t.axes, 3);
}

TEST(Gcode, LexicalRules) {
  // case, blanks inside numbers, comments, N, '%', ';'
  const Toolpath t = read("%\n(header)\nn10 g1 f 1 2 0 x 1 . 5 y-.5 (c) ; tail\n\n/G1 X3\nm30\n%\nG1 X99\n");
  ASSERT_EQ(t.moves.size(), 2u);
  EXPECT_TRUE(end_of(t.moves[0]).isApprox(Eigen::Vector3d(1.5, -0.5, 0)));
  EXPECT_DOUBLE_EQ(t.moves[0].feed, 2.0);
  EXPECT_DOUBLE_EQ(end_of(t.moves[1])[0], 3.0);  // block delete off (LinuxCNC's default): the line runs
  traj::input::GcodeOptions skip;
  skip.block_delete = true;
  EXPECT_EQ(read("G1 F60 X1\n/G1 X3\nM2\n", skip).moves.size(), 1u);
}

TEST(Gcode, InchesAndRelative) {
  const Toolpath t = read("G20 G91 F10\nG1 X1 Y1\nX1\nG21 G1 X10\nG90 G1 X0 Y0\nM2\n");
  ASSERT_EQ(t.moves.size(), 4u);
  EXPECT_TRUE(end_of(t.moves[0]).isApprox(Eigen::Vector3d(25.4, 25.4, 0)));
  EXPECT_TRUE(end_of(t.moves[1]).isApprox(Eigen::Vector3d(50.8, 25.4, 0)));
  EXPECT_NEAR(t.moves[0].feed, 10 * 25.4 / 60, 1e-12);
  EXPECT_NEAR(t.moves[2].feed, 10.0 / 60, 1e-12);  // F is a number in the units of the move (as LinuxCNC)
  EXPECT_TRUE(end_of(t.moves[2]).isApprox(Eigen::Vector3d(60.8, 25.4, 0)));
}

TEST(Gcode, ArcCentreAndRadiusFormsAllPlanes) {
  // XY: G2 half circle by I J, G3 by R
  Toolpath t = read("F100\nG1 X10\nG2 X30 Y0 I10 J0\nG3 X10 Y0 R10\nM2\n");
  ASSERT_EQ(t.moves.size(), 3u);
  auto [err, swept] = circle_fit(t.moves[1], 0, 1, 20, 0, 10);
  EXPECT_LT(err, 1e-12);
  EXPECT_NEAR(swept, -kPi, 1e-12);
  std::tie(err, swept) = circle_fit(t.moves[2], 0, 1, 20, 0, 10);
  EXPECT_LT(err, 1e-12);
  EXPECT_NEAR(swept, kPi, 1e-12);
  // XZ (G18): first axis Z, second X, centre words K, I
  t = read("F100\nG18\nG1 X10\nG3 X0 Z10 I-10 K0\nM2\n");
  std::tie(err, swept) = circle_fit(t.moves[1], 2, 0, 0, 0, 10);
  EXPECT_LT(err, 1e-12);
  EXPECT_NEAR(swept, 1.5 * kPi, 1e-12);  // positive from Z towards X: from angle 90 deg (X+) to 0 (Z+)
  // YZ (G19): first Y, second Z, centre words J, K
  t = read("F100\nG19\nG1 Y10\nG3 Y0 Z10 J-10 K0\nM2\n");
  std::tie(err, swept) = circle_fit(t.moves[1], 1, 2, 0, 0, 10);
  EXPECT_LT(err, 1e-12);
  EXPECT_NEAR(swept, kPi / 2, 1e-12);
  // Absolute centre (G90.1)
  t = read("F100\nG90.1\nG1 X10\nG2 X30 I20 J0\nM2\n");
  std::tie(err, swept) = circle_fit(t.moves[1], 0, 1, 20, 0, 10);
  EXPECT_LT(err, 1e-12);
}

TEST(Gcode, FullCircleWithTurns) {
  const Toolpath t = read("F100\nG1 X10\nG3 X10 Y0 I-10 J0 P3\nG2 I-10 J0\nM2\n");
  ASSERT_EQ(t.moves.size(), 3u);
  auto [err, swept] = circle_fit(t.moves[1], 0, 1, 0, 0, 10, 3000);
  EXPECT_LT(err, 1e-12);
  EXPECT_NEAR(swept, 6 * kPi, 1e-11);
  EXPECT_EQ(t.moves[1].curve.degree, 2);
  EXPECT_EQ(t.moves[1].curve.n_ctrl(), 2 * 12 + 1);  // 12 quarter circles
  std::tie(err, swept) = circle_fit(t.moves[2], 0, 1, 0, 0, 10);
  EXPECT_NEAR(swept, -2 * kPi, 1e-12);  // I J K without end words: a full circle (LinuxCNC)
}

TEST(Gcode, HelixWithinBound) {
  const Toolpath t = read("F100\nG1 X10\nG3 X10 Y0 Z-3 I-10 J0 P3\nM2\n");
  const Move& m = t.moves[1];
  EXPECT_EQ(m.curve.degree, traj::input::gcode::kHelixTaylorDegree + 1);
  EXPECT_FALSE(m.curve.rational());
  // Every sample on the helix: radius 10, z linear in the swept angle.
  traj::geo::Curve c(m.curve);
  double worst = 0, swept = 0, prev = 0;
  const int n = 6000;
  for (int k = 1; k <= n; ++k) {
    const Eigen::Vector3d p = at(m, static_cast<double>(k) / n);
    const double ang = std::atan2(p[1], p[0]);
    double d = ang - prev;
    if (d < -kPi) d += 2 * kPi;
    swept += d;
    prev = ang;
    worst = std::max(worst, std::abs(std::hypot(p[0], p[1]) - 10));
    worst = std::max(worst, std::abs(p[2] - (-3 * swept / (6 * kPi))));
  }
  EXPECT_NEAR(swept, 6 * kPi, 1e-11);
  EXPECT_LT(worst, 1e-11);  // truncation bound 1e-12 plus rounding
  EXPECT_TRUE(end_of(m).isApprox(Eigen::Vector3d(10, 0, -3)));
  EXPECT_LT(traj::input::gcode::helix_piece_bound(10000, kPi / 8), 1e-6);  // the bound formula itself
}

TEST(Gcode, Splines) {
  const Toolpath t = read(
      "F100\nG5.1 X10 Y0 I5 J5\nG5 I2 J2 P-2 Q2 X20 Y0\nG5 P-2 Q-2 X30 Y0\n"
      "G5.2 X31 Y2 P1 L4\nX34 Y4 P2\nX37 Y2 P1\nX40 Y0 P1\nG5.3\nM2\n");
  ASSERT_EQ(t.moves.size(), 4u);
  EXPECT_EQ(t.moves[0].curve.degree, 2);
  EXPECT_TRUE(at(t.moves[0], 0.5).isApprox(Eigen::Vector3d(5, 2.5, 0)));  // quadratic Bezier midpoint
  EXPECT_EQ(t.moves[1].curve.degree, 3);
  EXPECT_TRUE(t.moves[2].curve.ctrl.row(1).transpose().isApprox(Eigen::Vector3d(22, -2, 0)));  // continues -P -Q
  const Move& nurbs = t.moves[3];
  EXPECT_EQ(nurbs.curve.degree, 3);   // order L4
  EXPECT_EQ(nurbs.curve.n_ctrl(), 5); // the start point and four
  EXPECT_TRUE(nurbs.curve.rational());
  EXPECT_DOUBLE_EQ(nurbs.curve.knots[4], 1.0);  // 0 0 0 0 1 2 2 2 2
  EXPECT_DOUBLE_EQ(nurbs.curve.u_end(), 2.0);
  EXPECT_TRUE(end_of(nurbs).isApprox(Eigen::Vector3d(40, 0, 0)));
}

TEST(Gcode, PathControlAndNotes) {
  const Toolpath t = read(
      "S1000 M3 M8 T1 M6\nG40 G49 G54 G80 G94 G17\nG64 P0.01 Q0.02 F100\nG1 X1\nG61\nG1 X2\nG61.1 G1 X3\n"
      "G64 G1 X4\nM5 M9\nM2\n");
  ASSERT_EQ(t.moves.size(), 4u);
  EXPECT_DOUBLE_EQ(t.moves[0].tolerance, 0.01);
  EXPECT_FALSE(t.moves[0].exact_stop);
  EXPECT_TRUE(t.moves[1].exact_stop);
  EXPECT_TRUE(t.moves[2].exact_stop);
  EXPECT_FALSE(t.moves[3].exact_stop);
  EXPECT_LT(t.moves[3].tolerance, 0);
  std::string all;
  for (const auto& n : t.notes) all += n + "\n";
  for (const char* kind : {"S1000", "M3", "M8", "T1", "M6", "G40", "G54", "Q0.02"})
    EXPECT_NE(all.find(std::string(": ") + kind + ":"), std::string::npos) << kind << "\n" << all;
  EXPECT_EQ(t.notes.size(), 8u);  // G49 is acted on (no tool length offset to take off here)  // once per kind (M5, M9 are not noted again)
}

TEST(Gcode, Refusals) {
  const std::pair<const char*, const char*> cases[] = {
      {"O100 sub\nM2\n", "t.ngc:1: O100 sub: no endsub before the end of the file"},
      {"G41\nM2\n", "t.ngc:1: G41: cutter radius compensation is not supported"},
      {"G43 H1\nM2\n",
       "t.ngc:1: G43: a tool length offset needs the machine's tool table (trajcore --tool-table FILE, LinuxCNC's format)"},
      {"G43.1 Z1\nM2\n", "t.ngc:1: G43.1: dynamic tool length offsets (G43.1/G43.2) are not supported"},
      {"G28.1\nM2\n", "t.ngc:1: G28.1: storing the reference point (G28.1/G30.1) is not supported"},
      {"G0 G28 X1\nM2\n", "t.ngc:1: G28: two G codes that both use the axis words (G0)"},
      {"G55\nM2\n", "t.ngc:1: G55: work offsets are not supported (only G54, the default work offset)"},
      {"G92 X0\nM2\n", "t.ngc:1: G92: coordinate offsets (G92) are not supported"},
      {"G93\nG1 X1\nM2\n", "t.ngc:2: G1: F word missing: in inverse-time mode (G93) every feed move needs its own F"},
      {"G93 G1 X1 F0\nM2\n", "t.ngc:1: F0: in inverse-time mode (G93) F must be positive (the move takes 1/F minutes)"},
      {"F600\nG94\nG1 X1\nM2\n", "t.ngc:3: G1: no feed rate: program F (units per minute) before the first feed move"},
      {"G93 G5 X1 Y1 I0 J1 P0 Q1 F2\nM2\n", "t.ngc:1: G5: splines (G5, G5.1) in inverse-time mode (G93) are not supported"},
      {"G95\nM2\n", "t.ngc:1: G95: feed per revolution is not supported (only G93 inverse time and G94 units per minute)"},
      {"G85 X1 Y1 Z-1 R1 F10\nM2\n", "t.ngc:1: G85: canned cycles other than G73, G81, G82 and G83 are not supported (feed-out, tapping, boring)"},
      {"F10 G81 X1 Y1 Z-1\nM2\n", "t.ngc:1: G81: R word missing (the retract plane of the cycle)"},
      {"F10 G83 X1 Y1 Z-1 R1\nM2\n", "t.ngc:1: G83: Q word missing (the peck depth)"},
      {"F10 G81 X1 Y1 Z-1 R1\nG0 X3\nG81 X2\nM2\n", "t.ngc:3: G81: R word missing (the retract plane of the cycle)"},
      {"F10 G83 X1 Y1 Z-1 R1 Q1\nG73 X2 R1\nM2\n", "t.ngc:2: G73: Z word missing (the bottom of the hole)"},
      {"F10 G81 X1 Y1 Z1 R-1\nM2\n", "t.ngc:1: G81: the bottom of the hole (Z) is above the retract plane (R)"},
      {"F10 G83 X1 Y1 Z-1000000 R1 Q1\nM2\n", "t.ngc:1: G83: the peck depth Q and the repeats L make more than 100000 pecks in one block"},
      // 999 pecks a hole: 100 holes of them are one block (GcodeCycles.PeckBudget), 101 too many
      {"F10 G91 G83 X1 Y1 Z-999 R1 Q1 L101\nM2\n", "t.ngc:1: G83: the peck depth Q and the repeats L make more than 100000 pecks in one block"},
      {"F10 G81 X1 Y1 Z-1 R1 L0\nM2\n", "t.ngc:1: L0: the repeat count L must be a whole number from 1 to 10000"},
      {"F10 G18 G81 X1 Y1 Z-1 R1\nM2\n", "t.ngc:1: G81: canned cycles are supported in the XY plane (G17) only"},
      {"F100\nG2 X20.029 Y0 I10 J0\nM2\n",
       "t.ngc:2: G2: radius to the end differs from radius to the start: 10 and 10.029 (more than 0.0282843 and 0.1%)"},
      {"F100\nG2 X1 Y1\nM2\n", "t.ngc:2: G2: arc with neither a centre (I J K) nor a radius (R)"},
      {"F100\nG1 X1.2.3\nM2\n", "t.ngc:2: X1.2.3: malformed number"},
      {"F100\nG1 X-\nM2\n", "t.ngc:2: X-: malformed number"},
      {"G1 X1\nM2\n", "t.ngc:1: G1: no feed rate: program F (units per minute) before the first feed move"},
      {"G22\nM2\n", "t.ngc:1: G22: unknown or unsupported G code"},
      {"F1\nG1 X1 A3\nM2\n", "t.ngc:2: A3: the machine has no A axis (its axes: XYZ; name them with trajcore --axes, e.g. --axes XYZA)"},
      {"E1\nM2\n", "t.ngc:1: E1: unknown word"},
      {"F1\nG1 X1\n", "t.ngc:2: end of file: the program has no M2, M30 or closing '%'"},
      // a file of subroutine definitions only (LinuxCNC's increment.ngc): the end is its last line, not line 0
      {"O<inc> sub\nG91 G0 X#1\nO<inc> endsub\n", "t.ngc:3: end of file: the program has no M2, M30 or closing '%'"},
      {"F1\nG0 X1 G1 Y2\nM2\n", "t.ngc:2: G1: two G codes from the same modal group (G0)"},
      {"F1\nG1 X1 R2\nM2\n", "t.ngc:2: R2: no G code in this block uses it"},
      {"F1\nG2 X0 Y0 I10 J0 P0\nM2\n", "t.ngc:2: P0: the number of turns must be 1 or more"},
      // found by the fuzzer: the count overflowed int (undefined behaviour)
      {"F1\nG2 X0 Y0 I10 J0 P1000000000000\nM2\n", "t.ngc:2: P1000000000000: the number of turns must be at most 10000"},
      // found by the fuzzer: a helix of radius 1e70 asked for 7.6 GB of pieces
      {"F1\nG3 X0 Y0 Z-5 I-10000000000000000000000000000000000000000000000000000000000000000000000\nM2\n",
       "t.ngc:2: G3: helical arc of radius 1e+70: too large to follow within 1e-12 in at most 10000 pieces"},
      {"F1\nG2 X1 Y0 R0.2\nM2\n", "t.ngc:2: R0.2: the radius is too small to reach the end point"},
      {"F1\nG2 X0.0019 I0.001 J0\nM2\n", "t.ngc:2: G2: zero-radius arc (start radius 0.001, end radius 0.0009)"},
      {"F1\nG5.2 X1 Y0 P1\nX2 Y2 P1\nG1 X5\nM2\n", "t.ngc:4: G1: G5.2 NURBS not closed with G5.3"},
      // found by the fuzzer: the order overflowed int (undefined behaviour)
      {"F1\nG5.2 X1 Y0 P1 L4111111111111111111111\nX2 Y2 P1\nG5.3\nM2\n",
       "t.ngc:2: L4111111111111111111111: the NURBS order must be an integer from 3 to 16"},
      {"F1\nG5.2 X1 Y0 P1 L17\nX2 Y2 P1\nG5.3\nM2\n", "t.ngc:2: L17: the NURBS order must be an integer from 3 to 16"},
      {"F1\nG18 G5 X1 I1 J0 P0 Q1\nM2\n", "t.ngc:2: G5: splines must be in the XY plane (G17)"},
      {"M0\nM2\n", "t.ngc:1: M0: program pause (M0/M60) is not supported without --pause-wait (a pause at which "
                   "`trajcore upload` waits for the operator) or --pause-as-stop (an exact stop: the machine goes on "
                   "without waiting); M1, the optional stop, is taken as an exact stop"},
      {"F1\nG1 X1\nM60\nM2\n", "t.ngc:3: M60: program pause (M0/M60) is not supported without --pause-wait (a pause "
                               "at which `trajcore upload` waits for the operator) or --pause-as-stop (an exact stop: "
                               "the machine goes on without waiting); M1, the optional stop, is taken as an exact stop"},
      {"F1\nG1 X1 M1 M2\n", "t.ngc:2: M2: two M codes from the same modal group (M1)"},
      {"G1 X#100\nM2\n", "t.ngc:1: X#100: the parameter is not set by the program (trajcore reads no parameter file; "
                          "LinuxCNC would take it from its .var file)"},
      {"G1 X#<nope>\nM2\n", "t.ngc:1: X#<NOPE>: the named parameter is not set"},
      {"G1 X#<_y>\nM2\n", "t.ngc:1: X#<_Y>: predefined parameters (#<_...>, the machine's state) are not supported, and "
                           "the program has not set this one"},
      {"G1 X#5220\nM2\n", "t.ngc:1: X#5220: parameters 5000 and above (the machine's state) are not supported"},
      {"#5300 = 1\nM2\n", "t.ngc:1: #5300: parameters 5000 and above (the machine's state) are not supported"},
      {"G1 X[1/0]\nM2\n", "t.ngc:1: X[1/0: division by zero"},
      {"G1 X[1+2\nM2\n", "t.ngc:1: X[1+2: expected an operator or ']'"},
      {"G1 X[FOO[1]]\nM2\n", "t.ngc:1: X[FOO: a letter without a number (or an unknown function)"},
      {"#1 5\nM2\n", "t.ngc:1: #15: expected '=' (a parameter setting: #n = value)"},
      {"G1 X[ATAN[1]]\nM2\n", "t.ngc:1: X[ATAN[1]]: ATAN needs a second argument: ATAN[y]/[x]"},
      {"G1 X[-1 ** 0.5]\nM2\n", "t.ngc:1: X[-1**0.5: a negative number raised to a non-integer power"},
      {"G1 X[5 MOD 0]\nM2\n", "t.ngc:1: X[5MOD0]: the value is not a finite number"},
      {"G1 X#0\nM2\n", "t.ngc:1: X#0: parameter numbers run from 1 to 5601"},
      {"G1 X#1.5\nM2\n", "t.ngc:1: X#1.5: a parameter number must be a whole number"},
      {"G91 G53 G0 Z20\nM2\n", "t.ngc:1: G53: G53 in incremental distance mode (G91): machine coordinates are absolute"},
      {"F1 G53 G2 X1 Y1 R1\nM2\n", "t.ngc:1: G53: G53 needs G0 or G1 (as in LinuxCNC)"},
      {"G53 G28 Z1\nM2\n", "t.ngc:1: G28: two G codes from the same modal group (G53)"},
      {"F1\nG5.2 X1 Y0 P1\nX2 Y2 P1 M1\nG5.3\nM2\n", "t.ngc:3: M1: G5.2 NURBS not closed with G5.3"},
      {"F1 G1 X1\n%\nM2\n", "t.ngc:2: %: '%' only on the first line, or to close a program opened with '%'"},
      {"F1 (open\nM2\n", "t.ngc:1: (: comment not closed on its line"},
      {"G0 X1\nG80\nX2\nM2\n", "t.ngc:3: X2: axis word with no motion mode (G0, G1, G2, G3, G5, ...) in effect"},
      {"F1\nG3 X1 Y1 K1 I1\nM2\n", "t.ngc:2: K1: K word given for an arc in this plane"},
      // polar coordinates (@ ^): where rs274 refuses them, and where trajcore does
      {"G0 X1 Y1\nG1 F1 X2 @1\nM2\n", "t.ngc:2: @1: X or Y words with polar coordinates (@ ^)"},
      {"F1 G1 @5\nM2\n", "t.ngc:1: @5: a polar distance (@) at the origin needs an angle (^)"},
      {"F1 G91 G1 ^5\nM2\n", "t.ngc:1: ^5: incremental polar coordinates (G91 @ ^) at the origin have no direction"},
      {"F1 G0 X1\nG91 G1 @-1 ^5\nM2\n",
       "t.ngc:2: @-1: incremental polar coordinates (G91 @ ^) at the origin have no direction"},
      {"F1 G0 X1\nG2 @2 ^90 R2\nM2\n", "t.ngc:2: @2: polar coordinates (@ ^) are supported with G0, G1 and the canned cycles only"},
      {"G0 X1\nG28 ^90\nM2\n", "t.ngc:2: ^90: polar coordinates (@ ^) are supported with G0, G1 and the canned cycles only"},
      {"G0 X1\nG53 G0 ^90\nM2\n", "t.ngc:2: ^90: polar coordinates (@ ^) with G53 are not supported"},
      {"G0 X1\nG80\n^90\nM2\n", "t.ngc:3: ^90: axis word with no motion mode (G0, G1, G2, G3, G5, ...) in effect"},
  };
  for (const auto& [program, message] : cases) EXPECT_EQ(refusal(program), message) << program;
  // nesting is bounded (recursion for any input), and a long text is cut in the message
  EXPECT_EQ(refusal("G1 X[" + std::string(120, '[') + "1" + std::string(120, ']') + "]\nM2\n"),
            "t.ngc:1: X" + std::string(47, '[') + "...: expression nested too deeply");
  EXPECT_EQ(refusal("G1 X1 (" + std::string(250, 'a') + ")\nM2\n"),
            "t.ngc:1: G1 X1 (aaaaaaaaa...: the line is too long (258 characters; LinuxCNC reads at most 253)");
}

// G28/G30 as LinuxCNC with its reference parameters at 0: a rapid to the
// point the axis words give (in the block's distance mode), then for the
// axes named (all without axis words) a rapid to the machine origin.
// A move of 1e-9 mm or less (X[0.1+0.2] then X0.3: 5.6e-17 in binary) is left out, and the next
// move starts where the last one kept ends: the planner refuses such a move ("zero-length curve").
TEST(Gcode, NegligibleMoveLeftOut) {
  const Toolpath tp = read("G21 G90 F600\nG1 X10 Y0\nG1 X[0.1+0.2] Y0\nG1 X0.3 Y0\nG1 X0.3 Y5\nM2\n");
  ASSERT_EQ(tp.moves.size(), 3u);
  EXPECT_EQ(end_of(tp.moves[1]), Eigen::Vector3d(0.1 + 0.2, 0, 0));
  EXPECT_EQ(tp.moves[2].curve.ctrl.row(0), tp.moves[1].curve.ctrl.row(tp.moves[1].curve.n_ctrl() - 1));
  EXPECT_EQ(end_of(tp.moves[2]), Eigen::Vector3d(0.3, 5, 0));
  EXPECT_NE(0.1 + 0.2, 0.3);  // the premise: the move left out has a length
}

// LinuxCNC's polar coordinates (@ distance, ^ angle in degrees, about the
// XY origin): end points worked out by hand. rs274 agrees on
// tb/input/gcode/polar_moves.ngc and LinuxCNC's spiral.ngc (the cross-check).
TEST(Gcode, PolarCoordinates) {
  const Toolpath tp = read("G21 G90 F60\nG1 @10 ^90\nG91 ^90\n@5\nG90 ^0\n@2\nG20 @1 ^180\nG21 G91 G0 @1 ^-90\nM2\n");
  const std::vector<Eigen::Vector3d> ends = {{0, 10, 0},  {-10, 0, 0}, {-15, 0, 0},  {15, 0, 0},
                                             {2, 0, 0},   {-25.4, 0, 0}, {0, 26.4, 0}};
  ASSERT_EQ(tp.moves.size(), ends.size());
  for (size_t i = 0; i < ends.size(); ++i)
    EXPECT_LT((end_of(tp.moves[i]) - ends[i]).norm(), 1e-12) << "move " << i << " ends at " << end_of(tp.moves[i]).transpose();
  EXPECT_EQ(tp.moves.back().kind, Move::Kind::kRapid);
}

// Polar coordinates in a canned cycle (LinuxCNC's hole-circle.ngc): G91 ^60 L6 drills six holes on the
// circle through the current point about the origin, each 60 degrees on from the last; G90 @ ^ drills
// at that point. The feeds down are the holes (rs274 agrees move for move: input.crosscheck).
TEST(Gcode, PolarCoordinatesInCannedCycles) {
  const Toolpath tp = read("G21 G90 G0 X10 Y0 Z1\nG91 G81 R.1 Z-.5 ^60 L6 F10\nG90 G81 @4 ^-90 R1 Z0\nM2\n");
  std::vector<Eigen::Vector3d> holes;
  for (const auto& m : tp.moves)
    if (m.kind == Move::Kind::kFeed) holes.push_back(end_of(m));
  ASSERT_EQ(holes.size(), 7u);
  for (int k = 0; k < 6; ++k) {
    const double th = (k + 1) * kPi / 3;
    EXPECT_LT((holes[k] - Eigen::Vector3d(10 * std::cos(th), 10 * std::sin(th), 0.6)).norm(), 1e-12) << k;
  }
  EXPECT_LT((holes[6] - Eigen::Vector3d(0, -4, 0)).norm(), 1e-12);
}

TEST(Gcode, ReferenceMoves) {
  const Toolpath tp = read("G0 X5 Y6 Z7\nG28 G91 Z2\nG90 G30 X1\nG0 X4 Y4 Z4\nG28\nM2\n");
  ASSERT_EQ(tp.moves.size(), 7u);
  for (const Move& m : tp.moves) EXPECT_EQ(m.kind, Move::Kind::kRapid);
  EXPECT_EQ(end_of(tp.moves[1]), Eigen::Vector3d(5, 6, 9));  // G91 Z2: up 2 from Z7
  EXPECT_EQ(end_of(tp.moves[2]), Eigen::Vector3d(5, 6, 0));  // Z only to the origin
  EXPECT_EQ(end_of(tp.moves[3]), Eigen::Vector3d(1, 6, 0));  // G30 X1 (G90 again)
  EXPECT_EQ(end_of(tp.moves[4]), Eigen::Vector3d(0, 6, 0));
  EXPECT_EQ(end_of(tp.moves[5]), Eigen::Vector3d(4, 4, 4));
  EXPECT_EQ(end_of(tp.moves[6]), Eigen::Vector3d(0, 0, 0));  // G28 alone: every axis
}

// G43 (or G49) in the same block as M6, as rs274 runs it (LinuxCNC's
// skeleton.ngc, cross-checked): the program's Z is kept through the tool
// change, so the next move takes the holder by the length, with or without
// a Z word; a G43 in a block of its own leaves the holder where it is.
TEST(Gcode, ToolLengthSetWithTheToolChangeKeepsTheProgramZ) {
  traj::input::GcodeOptions opt;
  opt.tools = traj::input::ToolTable{"tools.tbl", {{1, 40.5}, {2, -3.25}}};
  const Toolpath tp = read("G0 Z0\nT1 M6 G43 H1\nG0 X1\nG0 X2\nT2 M6\nG43\nG0 X3\nT1 M6 G43 H1\nG91 G0 Z1\nM2\n", opt);
  ASSERT_EQ(tp.moves.size(), 4u);  // G0 Z0 from the origin is no move
  EXPECT_EQ(end_of(tp.moves[0]), Eigen::Vector3d(1, 0, 40.5));  // program Z 0, the holder up by the length
  EXPECT_EQ(end_of(tp.moves[1]), Eigen::Vector3d(2, 0, 40.5));  // once only
  EXPECT_EQ(end_of(tp.moves[2]), Eigen::Vector3d(3, 0, 40.5));  // G43 alone: the holder stays
  EXPECT_EQ(end_of(tp.moves[3]), Eigen::Vector3d(3, 0, 40.5 + 43.75 + 1));  // G91 Z1 from the kept program Z
}

// G43 moves the tool's holder: Z targets get the tool's length from the
// table (the machine does not move at the G43 itself); G43 without H takes
// the tool of the last M6; H0 and G49 take the length off.
TEST(Gcode, ToolLengthOffsetsFromTheTable) {
  traj::input::GcodeOptions opt;
  opt.tools = traj::input::ToolTable{"tools.tbl", {{1, 40.5}, {2, -3.25}}};
  const Toolpath tp = read("G0 Z10\nG43 H1\nG0 Z5\nT2 M6\nG43\nG0 Z5\nG43 H0\nG0 Z6\nG43 H1\nG49 G0 Z7\nM2\n", opt);
  ASSERT_EQ(tp.moves.size(), 5u);
  EXPECT_EQ(end_of(tp.moves[0]).z(), 10);
  EXPECT_EQ(end_of(tp.moves[1]).z(), 45.5);
  EXPECT_EQ(end_of(tp.moves[2]).z(), 1.75);
  EXPECT_EQ(end_of(tp.moves[3]).z(), 6);
  EXPECT_EQ(end_of(tp.moves[4]).z(), 7);
  auto refused = [&](const std::string& program) { return refusal(program, opt); };
  EXPECT_EQ(refused("G43 H7\nM2\n"), "t.ngc:1: H7: tool 7 is not in the tool table tools.tbl");
  EXPECT_EQ(refused("G43\nM2\n"), "t.ngc:1: G43: no H word and no tool loaded (T with M6) to take the length of");
  EXPECT_EQ(refused("G43 H1.5\nM2\n"), "t.ngc:1: H1.5: the tool number must be a whole number from 0 to 1000000000");
  // found by the fuzzer: T beyond int (UBSan at the conversion)
  const std::string big = "1" + std::string(114, '0');  // 1e114
  // the word's text cut to 48 characters in the message
  EXPECT_EQ(refused("T" + big + " M6\nM2\n"),
            "t.ngc:1: " + ("T" + big).substr(0, 48) + "...: the tool number must be a whole number from 0 to 1000000000");
  EXPECT_EQ(refused("G43 H3000000000\nM2\n"), "t.ngc:1: H3000000000: the tool number must be a whole number from 0 to 1000000000");
  EXPECT_EQ(refused("G0 X1 H1\nM2\n"), "t.ngc:1: H1: no G code in this block uses it");
}

TEST(Gcode, ToolTableFile) {
  const traj::test::TmpFile file("tools.tbl");
  auto table = [&](const std::string& text) {
    file.write(text);
    return file.path;
  };
  const std::string ok = table("; LinuxCNC tool table\nT1 P1 Z12.5 D6.0 ;end mill\n\nt2 p5 d3 x0\n");
  const auto t = traj::input::read_tool_table(ok);
  ASSERT_EQ(t.z.size(), 2u);
  EXPECT_EQ(t.z.at(1), 12.5);
  EXPECT_EQ(t.z.at(2), 0.0);
  auto refused = [&](const std::string& text) {
    const std::string f = table(text);
    try {
      traj::input::read_tool_table(f);
    } catch (const InputError& e) {
      return std::string(e.what()).substr(f.size());
    }
    return std::string("(accepted)");
  };
  EXPECT_EQ(refused("T1 P1 Z1\nT1 P2 Z2\n"), ":2: T: tool 1 listed twice");
  EXPECT_EQ(refused("T1 P1 X0.5 Z1\n"), ":1: X0.5: only Z tool length offsets are supported");
  EXPECT_EQ(refused("T1 Z1\n"), ":1: P: the pocket number is missing");
  EXPECT_EQ(refused("P1 Z1\n"), ":1: T: the tool number is missing");
  EXPECT_EQ(refused("T1 P1 Zx\n"), ":1: Zx: not a letter and a number");
  EXPECT_EQ(refused("T1 P1 E4\n"), ":1: E4: unknown word");
  EXPECT_EQ(refused("T0 P1\n"), ":1: T: the tool number must be a whole number from 1 to 1000000000");
  EXPECT_EQ(refused("T1e114 P1\n"), ":1: T: the tool number must be a whole number from 1 to 1000000000");
  EXPECT_EQ(refused("T1 P1 Z1e999\n"), ":1: Z1e999: not a letter and a number");
}

// The further axes (GcodeOptions::axes): their words, units, moves along
// lines and arcs, the feed LinuxCNC's way, and the refusals. The LinuxCNC
// cross-check (input.crosscheck.linuxcnc_examples, tb/input/gcode/rotary_abc.ngc)
// compares A B C with rs274; rs274 standalone has no U V W, so they are
// checked here by hand.
TEST(Gcode, FurtherAxesMoveWithLinesAndArcs) {
  traj::input::GcodeOptions opt;
  opt.axes = "XYZAUW";
  const Toolpath tp = read(
      "G21 G90 F600\n"
      "G1 X30 Y40 A90\n"          // X Y and A: F measures X Y Z (50 mm)
      "G1 A180 F3600\n"           // A alone: F in degrees/min
      "G1 U3 W4 A270 F60\n"       // U W and A: F measures U V W (5 mm)
      "G20 G1 A0 U0 W0 F60\n"     // inches: A stays in degrees, U and W in inches
      "G21 G2 X50 Y40 I10 J0 A90 F600\n"  // an arc with A: helix form, A linear in the angle
      "M2\n",
      opt);
  ASSERT_EQ(tp.axes, 6);
  ASSERT_EQ(tp.moves.size(), 5u);
  const Move& m0 = tp.moves[0];
  EXPECT_EQ(m0.curve.ctrl.cols(), 6);
  EXPECT_EQ(m0.curve.ctrl(1, 3), 90.0);
  EXPECT_NEAR(m0.feed_scale, std::hypot(50.0, 90.0) / 50, 1e-15);
  EXPECT_NEAR(m0.feed, 10 * m0.feed_scale, 1e-12);  // 600 mm/min over X Y at 10 mm/s
  EXPECT_NEAR(tp.moves[1].feed, 60.0, 1e-12);          // 3600 degrees/min
  EXPECT_NEAR(tp.moves[1].feed_scale, 1.0, 1e-15);
  const Move& m2 = tp.moves[2];
  EXPECT_EQ(m2.curve.ctrl(1, 4), 3.0);
  EXPECT_EQ(m2.curve.ctrl(1, 5), 4.0);
  EXPECT_NEAR(m2.feed_scale, std::hypot(5.0, 90.0) / 5, 1e-14);
  const Move& m3 = tp.moves[3];
  EXPECT_EQ(m3.curve.ctrl(1, 3), 0.0);
  EXPECT_NEAR(m3.feed / m3.feed_scale, 25.4, 1e-12);  // 60 inch/min of U W
  // the arc: every sample's A on the line from 0 to 90 degrees in the swept angle
  const Move& arc = tp.moves[4];
  traj::geo::Curve c(arc.curve);
  for (int k = 0; k <= 64; ++k) {
    const double u = arc.curve.u_begin() + (arc.curve.u_end() - arc.curve.u_begin()) * k / 64.0;
    const Eigen::VectorXd p = c.eval(u, 0).col(0);
    const double angle = std::atan2(p[1] - 40, p[0] - 40);  // from pi (start, X30) clockwise to 0
    const double swept = kPi - (angle < 0 ? angle + 2 * kPi : angle);
    EXPECT_NEAR(p[3], 90 * std::min(swept, kPi) / kPi, 1e-9) << k;
    EXPECT_NEAR(std::hypot(p[0] - 40, p[1] - 40), 10, 1e-9) << k;
  }
  EXPECT_NEAR(arc.feed_scale, std::hypot(10 * kPi, 90.0) / (10 * kPi), 1e-12);
}

TEST(Gcode, FurtherAxesRefusals) {
  EXPECT_THROW(traj::input::check_axes("XYA"), InputError);
  EXPECT_THROW(traj::input::check_axes("XYZAA"), InputError);
  EXPECT_THROW(traj::input::check_axes("XYZABCUVW"), InputError);  // 9: the core takes 8
  EXPECT_THROW(traj::input::check_axes("XYZQ"), InputError);
  traj::input::check_axes("XYZABCUV");
  traj::input::GcodeOptions opt;
  opt.axes = "XYZA";
  auto refused = [&](const std::string& program) { return refusal(program, opt); };
  EXPECT_EQ(refused("F60\nG1 B3\nM2\n"),
            "t.ngc:2: B3: the machine has no B axis (its axes: XYZA; name them with trajcore --axes, e.g. --axes XYZAB)");
  EXPECT_EQ(refused("F60\nG5 X1 Y1 P0 Q0 I0 J1 A3\nM2\n"), "t.ngc:2: A3: splines (G5, G5.1) may not move A");
  EXPECT_EQ(refused("G80\nA3\nM2\n"), "t.ngc:2: A3: axis word with no motion mode (G0, G1, G2, G3, G5, ...) in effect");
  // G28 takes A home too; with A named only A
  const Toolpath tp = read("G0 X1 A10\nG28\nG0 X2 A20\nG28 A5\nM2\n", opt);
  ASSERT_EQ(tp.moves.size(), 5u);
  EXPECT_EQ(end_of4(tp.moves[1]), Eigen::Vector4d(0, 0, 0, 0));
  EXPECT_EQ(end_of4(tp.moves[3]), Eigen::Vector4d(2, 0, 0, 5));   // to A5 first
  EXPECT_EQ(end_of4(tp.moves[4]), Eigen::Vector4d(2, 0, 0, 0));   // then A home, X stays
}

// G93, inverse time: each feed move takes 60 / F s, whatever its length and
// axes (the feed it gives is its measured length over that time, as rs274
// prints it); G93 and G94 set the feed rate to 0, as in LinuxCNC.
TEST(Gcode, InverseTimeFeeds) {
  traj::input::GcodeOptions opt;
  opt.axes = "XYZA";
  const Toolpath tp = read(
      "G21 G90 F600\n"
      "G93 G1 X30 Y40 A90 F2\n"     // 50 mm of X Y in 30 s
      "G2 X50 Y40 I10 J0 F6\n"      // a half circle of 10 mm radius in 10 s
      "G1 A180 F4\n"                // A alone: 90 degrees in 15 s
      "G0 X0\n"
      "G94 G1 X5 F300\n"            // back to units per minute
      "M2\n",
      opt);
  ASSERT_EQ(tp.moves.size(), 5u);
  const double l0 = std::sqrt(50.0 * 50 + 90.0 * 90);
  EXPECT_NEAR(tp.moves[0].feed, l0 / 30, 1e-12);  // the path (all axes) in 30 s
  EXPECT_NEAR(tp.moves[0].feed / tp.moves[0].feed_scale * 60, 100, 1e-9);  // rs274: 50 mm / 0.5 min
  EXPECT_NEAR(tp.moves[1].feed, 10 * kPi / 10, 1e-9);
  EXPECT_NEAR(tp.moves[2].feed, 90.0 / 15, 1e-12);
  EXPECT_EQ(tp.moves[3].kind, Move::Kind::kRapid);
  EXPECT_NEAR(tp.moves[4].feed, 5.0, 1e-12);
}

// Parameters and expressions: the expected values are rs274's (LinuxCNC 2.9)
// for the same lines (tb/input/gcode/parameters.ngc has them all, cross-checked).
TEST(Gcode, ParametersAndExpressions) {
  const Toolpath tp = read(
      "#1 = 2\n#2 = 3 #1 = 7 #3 = #1\nG21 F100\nG1 X#1 Y#3\n"        // settings read the values before their line
      "#<a> = [1 + 2 * 3 ** 2 - 8 / 4 MOD 3]\nG1 X#<a> Y[5 MOD -3] Z[-5 MOD 3]\n"
      "G1 X[1 EQ 1.00005] Y[1 EQ 1.0002] Z[2 GT 1 AND 0 OR 1 XOR 1]\n"
      "G1 X[ROUND[-2.5]] Y[FIX[-2.5]] Z[FUP[-2.5]]\n"
      "G1 X[ATAN[1]/[-1]] Y[SIN[30]] Z[EXISTS[#<a>] + EXISTS[#<b>]]\n"
      "G1 X-#1 Y-[2] Z+#1\n#4 = [2 ** 3 ** 2]\nG1 X#4 Y[-2 ** 2] Z[ABS[-3]]\n"
      "G1 X[1 NE 1.00005] Y[5 MOD 0 NE 1] Z[5 MOD 0 AND 1]\nM2\n");
  const double want[][3] = {{7, 2, 0},    {17, 2, 1}, {1, 0, 0},  {-3, -3, -2}, {135, 0.5, 1},
                            {-7, -2, 7},  {64, 4, 3}, {0, 0, 1}};
  ASSERT_EQ(tp.moves.size(), 8u);
  for (size_t i = 0; i < 8; ++i)
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(at(tp.moves[i], 1)[a], want[i][a], 1e-12) << tp.moves[i].where;
}

// Subroutines, conditions and loops; every expected point is from rs274's
// output for the same program (LinuxCNC 2.9).
TEST(Gcode, SubroutinesAndControlFlow) {
  const auto ends = [](const Toolpath& tp) {
    std::vector<Eigen::Vector3d> e;
    for (const Move& m : tp.moves) e.push_back(end_of(m));
    return e;
  };
  const auto expect_points = [&](const Toolpath& tp, const std::vector<Eigen::Vector3d>& want) {
    const auto got = ends(tp);
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < want.size(); ++i) EXPECT_LT((got[i] - want[i]).norm(), 1e-12) << tp.moves[i].where;
  };
  // arguments (#3 not passed: 0), globals seen, a caller's local hidden and kept, endsub's value,
  // repeat, do-while, if/elseif/else (rs274: the repeat's second move has zero length, dropped here)
  expect_points(read("#<g> = 5\no<foo> sub\ng1 x#1 y#2 z#3 f100\n#<loc> = 7\n#<_glob> = 9\n"
                     "o<foo> endsub [#1*2]\no<foo> call [3] [4]\ng1 x#<_value> y#<_value_returned> z#<_glob>\n"
                     "o<foo> call\ng1 x#<_value> y#<_value_returned> z#<g>\no200 repeat [2]\ng1 x1 y2\n"
                     "o200 endrepeat\no300 do\ng1 x5\no300 while [0]\no400 if [1 GT 2]\ng1 x7\n"
                     "o400 elseif [1]\ng1 x8\no400 else\ng1 x9\no400 endif\nm2\n"),
                {{3, 4, 0}, {6, 1, 9}, {0, 0, 0}, {0, 1, 5}, {1, 2, 5}, {5, 2, 5}, {8, 2, 5}});
  // return from inside an if, while with continue and break
  expect_points(read("o<foo> sub\no10 if [#1 GT 2]\no<foo> return [#1]\no10 endif\ng1 x#1 f100\n"
                     "o<foo> endsub\no<foo> call [1]\no<foo> call [5]\ng1 y#<_value>\n#<_n> = #<_value>\n"
                     "o20 while [#<_n> GT 0]\n#<_n> = [#<_n> - 1]\no21 if [#<_n> EQ 2]\no20 continue\n"
                     "o21 endif\no22 if [#<_n> EQ 1]\no20 break\no22 endif\ng1 z#<_n>\no20 endwhile\nm2\n"),
                {{1, 0, 0}, {1, 5, 0}, {1, 5, 4}, {1, 5, 3}});
  // recursion (LinuxCNC's factorial.ngc, whose body calls itself)
  expect_points(read("o<factorial> sub\no<factorialif> if [[#1] EQ 0]\no<factorial> return [1]\n"
                     "o<factorialif> else\no<factorial> call [[#1] - 1]\no<factorial> return [#<_value> * #1]\n"
                     "o<factorialif> endif\no<factorial> endsub\no<factorial> call [5]\nG1 X#<_value> F100\nM2\n"),
                {{120, 0, 0}});
}

TEST(Gcode, ControlFlowRefusals) {
  std::string deep = "o<r> sub\no1 if [#1 GT 0]\no<r> call [#1 - 1]\no1 endif\nG1 X#1 F100\no<r> endsub\n";
  const std::pair<std::string, const char*> cases[] = {
      {"O1 endif\nM2\n", "t.ngc:1: O1 ENDIF: no opening line of its kind (if) before it"},
      {"O1 if [0]\nG1 X1 F100\nM2\n",
       "t.ngc:1: O1: its closing line (endif, endwhile, endrepeat, while) is missing before the end of the file"},
      {"O<x> call\nM2\n", "t.ngc:1: O<X> CALL: the subroutine is not defined before the call (subroutine files are not read)"},
      {"O1 if [1]\nO1 endif\nO1 if [1]\nO1 endif\nM2\n", "t.ngc:3: O1 IF: the label is used again (first in line 1)"},
      {"O2 repeat [2]\nO2 break\nO2 endrepeat\nM2\n",
       "t.ngc:2: O2 BREAK: the label O2 is another construct's (line 1), not of the kind: while or do loop"},
      {"O1 while [1]\nO1 endwhile\nM2\n", "t.ngc:2: O1 ENDWHILE: the loop turned more than 1 000 000 times"},
      {"O1 sub\nO1 sub\nM2\n", "t.ngc:2: O1 SUB: subroutines cannot be nested (O1 is open)"},
      {"O1 return\nM2\n", "t.ngc:1: O1 RETURN: outside a subroutine"},
      {"O1 if [1] G1 X1\nM2\n", "t.ngc:1: G1X1: an O-word's line carries nothing but its values ([expression] ...)"},
      // rs274: call [8] nests 9 calls and runs, call [9] is "Too many subroutine levels"
      {deep + "o<r> call [9]\nM2\n", "t.ngc:3: O<R> CALL: calls nested more than 9 deep (LinuxCNC's limit)"},
  };
  for (const auto& [program, want] : cases) EXPECT_EQ(refusal(program), want) << program;
  // rs274 prints 9 moves; the innermost, G1 X0 from X0, has zero length (no move here)
  EXPECT_EQ(read(deep + "o<r> call [8]\nM2\n").moves.size(), 8u);
}

// Block delete skips a line's settings with its words.
TEST(Gcode, BlockDeleteSkipsSettings) {
  traj::input::GcodeOptions opt;
  opt.block_delete = true;
  const Toolpath tp = read("#1 = 1\n/#1 = 5\nG21 F100 G1 X#1\nM2\n", opt);
  ASSERT_EQ(tp.moves.size(), 1u);
  EXPECT_NEAR(at(tp.moves[0], 1)[0], 1, 1e-12);
}

// G53: the block's axis words are machine coordinates, the moves' own: the
// tool length offset (10 mm here) is left out of that block only.
TEST(Gcode, MachineCoordinates) {
  traj::input::GcodeOptions opt;
  opt.tools = traj::input::ToolTable{"t.tbl", {{1, 10.0}}};
  const Toolpath tp = read("T1 M6 G43\nG21 G90 F100\nG1 Z5\nG53 G0 Z20\nG53 X7\nG1 Z5\nM2\n", opt);
  ASSERT_EQ(tp.moves.size(), 4u);
  EXPECT_NEAR(at(tp.moves[0], 1)[2], 15, 1e-12);
  EXPECT_EQ(tp.moves[1].kind, Move::Kind::kRapid);
  EXPECT_NEAR(at(tp.moves[1], 1)[2], 20, 1e-12);
  EXPECT_EQ(tp.moves[2].kind, Move::Kind::kRapid);  // G0 stays modal
  EXPECT_NEAR(at(tp.moves[2], 1)[0], 7, 1e-12);
  EXPECT_NEAR(at(tp.moves[2], 1)[2], 20, 1e-12);
  EXPECT_NEAR(at(tp.moves[3], 1)[2], 15, 1e-12);  // the offset is back
}

// M1 after the block's motion (LinuxCNC's order): the move before it ends in
// an exact stop, the program goes on (the optional-stop switch off), noted.
TEST(Gcode, OptionalStopIsAnExactStop) {
  const Toolpath tp = read("G64 P0.01\nM1\nF600\nG1 X10\nG1 X10 Y10 M1\nG1 X20\nM1\nG1 X30 Y5\nM2\n");
  ASSERT_EQ(tp.moves.size(), 4u);
  const bool expected[4] = {false, true, true, false};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(tp.moves[i].exact_stop, expected[i]) << tp.moves[i].where;
    EXPECT_EQ(tp.moves[i].dwell, 0.0);
  }
  ASSERT_EQ(tp.notes.size(), 1u);  // one note per kind, at its first use (before any move: nothing to stop)
  EXPECT_NE(tp.notes[0].find("t.ngc:2: M1: optional stop taken as an exact stop"), std::string::npos) << tp.notes[0];
}

// M0 and M60 with pauses_as_stops, as CAM posts write them before a manual
// tool change (pcb2gcode: "M6 (Tool change.)" then "M0 (Temporary machine
// stop.)"): exact stops like M1, the program goes on, noted once as a pause
// that does not wait. Both in one block are two codes of one modal group.
TEST(Gcode, PauseAsStopIsAnExactStop) {
  traj::input::GcodeOptions opt;
  opt.pauses_as_stops = true;
  const Toolpath tp = read("G21 G90\nM0\nF600\nG1 X10\nT2 M6\nM0 (change the bit)\nG1 X10 Y10\nG1 X20 M60\n"
                           "G1 X30 Y5\nM1\nG1 X40\nM2\n",
                           opt);
  ASSERT_EQ(tp.moves.size(), 5u);
  const bool expected[5] = {true, false, true, true, false};
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(tp.moves[i].exact_stop, expected[i]) << tp.moves[i].where;
    EXPECT_EQ(tp.moves[i].dwell, 0.0);
  }
  int pause_notes = 0;
  for (const std::string& n : tp.notes)
    if (n.find("program pause taken as an exact stop") != std::string::npos) {
      ++pause_notes;
      EXPECT_EQ(n.rfind("t.ngc:2: M0: ", 0), 0u) << n;
      EXPECT_NE(n.find("without waiting for an operator"), std::string::npos) << n;
    }
  EXPECT_EQ(pause_notes, 1);
  EXPECT_EQ(refusal("F1\nG1 X1 M0 M1\nM2\n", opt), "t.ngc:2: M1: two M codes from the same modal group (M0)");
}

// --pause-wait: M0 and M60 are exact stops with a pause (the line of the M
// word) on the move before them; M1 stays a plain exact stop; an M0 before
// any move has nothing to stop and is noted.
TEST(Gcode, PauseWaitMarksThePauseOnTheMoveBefore) {
  traj::input::GcodeOptions opt;
  opt.pauses_wait = true;
  const Toolpath tp = read("G21 G90\n(MSG, Load tool 1)\nM0\nF600\nG1 X10\nT2 M6\nM0 (change the bit)\nG1 X10 Y10\nG1 X20 M60\n"
                           "G1 X30 Y5\nM1\nG1 X40\nM2\n",
                           opt);
  ASSERT_EQ(tp.moves.size(), 5u);
  const bool stop[5] = {true, false, true, true, false};
  const int pause[5] = {7, 0, 9, 0, 0};
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(tp.moves[i].exact_stop, stop[i]) << tp.moves[i].where;
    EXPECT_EQ(tp.moves[i].pause.line, pause[i]) << tp.moves[i].where;
  }
  int pause_notes = 0, first_notes = 0;
  for (const std::string& n : tp.notes) {
    if (n.find("`trajcore upload` waits for the operator") != std::string::npos) {
      ++pause_notes;
      EXPECT_EQ(n.rfind("t.ngc:7: M0: ", 0), 0u) << n;
    }
    if (n.find("program pause before the first move: no pause record") != std::string::npos) {
      ++first_notes;
      EXPECT_EQ(n.rfind("t.ngc:3: M0: ", 0), 0u) << n;
      EXPECT_NE(n.find("(its message: \"Load tool 1\")"), std::string::npos) << n;  // shown where it is planned
    }
  }
  EXPECT_EQ(pause_notes, 1);
  EXPECT_EQ(first_notes, 1);
  const std::string refused = refusal("F1\nG1 X1\nM0\nM2\n");
  EXPECT_NE(refused.find("without --pause-wait (a pause at which `trajcore upload` waits"), std::string::npos)
      << refused;
}

// A pause's text is LinuxCNC's operator message, "(MSG, ...)" (any case,
// blanks after '(' and around the text, tabs), the last one since the move
// before the pause: on the pause's own line too, not one before a move
// (LinuxCNC shows it before that line's motion), not one in a ';' comment.
TEST(Gcode, PauseTextIsTheMessageSinceTheLastMove) {
  traj::input::GcodeOptions opt;
  opt.pauses_wait = true;
  const Toolpath tp = read("G21 G90 F600\n(MSG, before any move)\nG1 X10\n( msg,  Change tool bit to drill 0.8mm )\n"
                           "M6 T1\nM0\n"                       // 6: the message of line 4
                           "G1 Y10\n(MSG, first)\n(Msg,\tsecond\t)\nM0 (Temporary machine stop.)\n"  // 10: the last
                           "G1 X0\nM0 (MSG,on the line)\n"      // 12: its own line's
                           "(MSG, passed)\nG1 Y0 (MSG, with the move)\nM0\n"  // 15: none since the move
                           "G1 X5\nM0 ; (MSG, not a comment that counts)\n"  // 17: none
                           "G1 X6\n(MSG,)\nM60\nG1 X7\nM2\n",  // 20: an empty message
                           opt);
  ASSERT_EQ(tp.moves.size(), 7u);
  const int line[7] = {6, 10, 12, 15, 17, 20, 0};
  const char* text[7] = {"Change tool bit to drill 0.8mm", "second", "on the line", "", "", "", ""};
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(tp.moves[i].pause.line, line[i]) << tp.moves[i].where;
    EXPECT_EQ(tp.moves[i].pause.text, text[i]) << tp.moves[i].where;
  }
}

// One block's pecks are bounded as holes times pecks a hole (its moves are
// held until taken): 100 holes of 999 pecks are read, each peck a feed of Q
// (after the first, from LinuxCNC's clearance of 0.254 mm above the last).
TEST(Gcode, PeckBudgetOfOneBlock) {
  const Toolpath p = read("F10 G91 G83 X1 Y1 Z-999 R1 Q1 L100\nM2\n");
  int feeds = 0;
  for (const Move& m : p.moves)
    if (m.kind == Move::Kind::kFeed) {
      const double peck = (at(m, 1) - at(m, 0)).norm() - (feeds % 999 == 0 ? 0 : 0.254);
      EXPECT_NEAR(peck, 1.0, 1e-9) << "feed " << feeds;
      ++feeds;
    }
  EXPECT_EQ(feeds, 100 * 999);
}

// G4 P: the move before it ends in an exact stop and rests P seconds; G82
// rests at the bottom of each hole (P kept while G82 goes on, as R and Z).
TEST(Gcode, Dwells) {
  const Toolpath tp = read(
      "G21 G90 G64 P0.05 F600\n"
      "G4 P2\n"                  // before any move: nothing to rest after (a note)
      "G1 X10\n"
      "G4 P0.5\n"
      "G4 P0.25\n"               // two dwells add up
      "G1 X20\n"
      "G4 P0\n"                  // a stop without a rest
      "G1 X30\n"
      "G0 Z5\n"
      "G82 X40 Z-2 R1 P0.4\n"
      "X50\n"
      "G80\n"
      "M2\n");
  ASSERT_GE(tp.moves.size(), 4u);
  EXPECT_TRUE(tp.moves[0].exact_stop);
  EXPECT_DOUBLE_EQ(tp.moves[0].dwell, 0.75);
  EXPECT_TRUE(tp.moves[1].exact_stop);
  EXPECT_EQ(tp.moves[1].dwell, 0.0);
  EXPECT_FALSE(tp.moves[2].exact_stop);  // G64: no stop where no dwell is
  int bottoms = 0;
  for (const Move& m : tp.moves)
    if (m.kind == Move::Kind::kFeed && m.curve.ctrl(m.curve.n_ctrl() - 1, 2) == -2) {
      ++bottoms;
      EXPECT_DOUBLE_EQ(m.dwell, 0.4);
    }
  EXPECT_EQ(bottoms, 2);
  bool noted = false;
  for (const auto& n : tp.notes) noted = noted || n.find("t.ngc:2: G4: dwell before the first move") == 0;
  EXPECT_TRUE(noted);
  EXPECT_EQ(refusal("G1 X1 F60\nG4\nM2\n"), "t.ngc:2: G4: dwell time P (seconds) missing");
  EXPECT_EQ(refusal("G1 X1 F60\nG4 P-1\nM2\n"), "t.ngc:2: P-1: the dwell time must not be negative");
  EXPECT_EQ(refusal("F60 G82 X1 Z-1 R1\nM2\n"), "t.ngc:1: G82: P word missing (the dwell at the bottom, seconds)");
}
