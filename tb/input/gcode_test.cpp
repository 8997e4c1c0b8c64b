// SPDX-License-Identifier: Apache-2.0
// read_gcode: each word, each refusal (its message), arcs in all planes, helices, inches, relative
// mode, splines. Geometry is checked by evaluating the curves (geo::Curve).
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "geometry/curve.hpp"
#include "input/gcode.hpp"
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

std::string refusal(const std::string& program) {
  try {
    read(program);
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
      "F100 S1000 M3 M8 T1 M6\nG40 G49 G54 G80 G94 G17\nG64 P0.01 Q0.02\nG1 X1\nG61\nG1 X2\nG61.1 G1 X3\n"
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
  for (const char* kind : {"S1000", "M3", "M8", "T1", "M6", "G40", "G49", "G54", "G80", "G94", "Q0.02"})
    EXPECT_NE(all.find(std::string(": ") + kind + ":"), std::string::npos) << kind << "\n" << all;
  EXPECT_EQ(t.notes.size(), 11u);  // once per kind (M5, M9 are not noted again)
}

TEST(Gcode, Refusals) {
  const std::pair<const char*, const char*> cases[] = {
      {"O100 sub\nM2\n", "t.ngc:1: O: subroutines and control flow (O-words) are not supported"},
      {"G1 X[1+2]\nM2\n", "t.ngc:1: X[: expressions ([ ]) are not supported"},
      {"#1=2\nM2\n", "t.ngc:1: #: parameters (#) are not supported"},
      {"G41\nM2\n", "t.ngc:1: G41: cutter radius compensation is not supported"},
      {"G43\nM2\n", "t.ngc:1: G43: tool length offsets are not supported"},
      {"G55\nM2\n", "t.ngc:1: G55: work offsets are not supported (only G54, the default work offset)"},
      {"G92 X0\nM2\n", "t.ngc:1: G92: coordinate offsets (G92) are not supported"},
      {"G93\nM2\n", "t.ngc:1: G93: inverse-time feed mode is not supported (only G94, units per minute)"},
      {"G95\nM2\n", "t.ngc:1: G95: feed per revolution is not supported (only G94, units per minute)"},
      {"G81 X1 Y1 Z-1 R1 F10\nM2\n", "t.ngc:1: G81: canned cycles are not supported"},
      {"F100\nG2 X20.029 Y0 I10 J0\nM2\n",
       "t.ngc:2: G2: radius to the end differs from radius to the start: 10 and 10.029 (more than 0.0282843 and 0.1%)"},
      {"F100\nG2 X1 Y1\nM2\n", "t.ngc:2: G2: arc with neither a centre (I J K) nor a radius (R)"},
      {"F100\nG1 X1.2.3\nM2\n", "t.ngc:2: X1.2.3: malformed number"},
      {"F100\nG1 X-\nM2\n", "t.ngc:2: X-: malformed number"},
      {"G1 X1\nM2\n", "t.ngc:1: G1: no feed rate: program F (units per minute) before the first feed move"},
      {"G22\nM2\n", "t.ngc:1: G22: unknown or unsupported G code"},
      {"F1\nG1 X1 A3\nM2\n", "t.ngc:2: A3: motion of the A/B/C/U/V/W axes is not supported: the planner carries X, Y and Z only"},
      {"E1\nM2\n", "t.ngc:1: E1: unknown word"},
      {"F1\nG1 X1\n", "t.ngc:2: end of file: the program has no M2, M30 or closing '%'"},
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
      {"F1\nG18 G5 X1 I1 J0 P0 Q1\nM2\n", "t.ngc:2: G5: splines must be in the XY plane (G17)"},
      {"M0\nM2\n", "t.ngc:1: M0: program pause (M0/M1/M60) is not supported"},
      {"F1 G1 X1\n%\nM2\n", "t.ngc:2: %: '%' only on the first line, or to close a program opened with '%'"},
      {"F1 (open\nM2\n", "t.ngc:1: (: comment not closed on its line"},
      {"G0 X1\nG80\nX2\nM2\n", "t.ngc:3: X2: axis word with no motion mode (G0, G1, G2, G3, G5, ...) in effect"},
      {"F1\nG3 X1 Y1 K1 I1\nM2\n", "t.ngc:2: K1: K word given for an arc in this plane"},
  };
  for (const auto& [program, message] : cases) EXPECT_EQ(refusal(program), message) << program;
}
