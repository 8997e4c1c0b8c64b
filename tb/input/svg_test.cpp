// SPDX-License-Identifier: Apache-2.0
// SVG reader: path data syntax, arcs against the ellipse equation, shapes, transforms and units
// against hand-computed coordinates, the toolpath's structure, error messages.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "geometry/curve.hpp"
#include "input/cuts.hpp"
#include "input/svg.hpp"
#include "input/svg_path.hpp"

namespace {

using traj::geo::BSpline;
using traj::geo::Curve;
using traj::input::InputError;
using traj::input::Move;
using traj::input::Toolpath;
namespace svg = traj::input::svg;

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector2d first(const BSpline& c) { return c.ctrl.row(0).transpose(); }
Eigen::Vector2d last(const BSpline& c) { return c.ctrl.row(c.n_ctrl() - 1).transpose(); }

std::vector<Eigen::Vector2d> samples(const BSpline& b, int n = 200) {
  const Curve c(b);
  std::vector<Eigen::Vector2d> out;
  for (int i = 0; i <= n; ++i) {
    const double u = b.u_begin() + (b.u_end() - b.u_begin()) * i / n;
    out.push_back(c.point(u).head<2>());
  }
  return out;
}

// A document 100 mm square with 1 user unit = 1 mm (y flipped: y_mm = 100 - y).
std::string doc(const std::string& body, const std::string& root = R"~(width="100mm" height="100mm" viewBox="0 0 100 100")~") {
  return R"~(<?xml version="1.0"?><svg xmlns="http://www.w3.org/2000/svg" )~" + root + ">" + body + "</svg>";
}

std::vector<const Move*> feeds(const Toolpath& tp) {
  std::vector<const Move*> f;
  for (const Move& m : tp.moves)
    if (m.kind == Move::Kind::kFeed) f.push_back(&m);
  return f;
}

std::string error_of(const std::string& text) {
  try {
    traj::input::parse_svg(text, "t.svg");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SvgPathData, NumberSyntax) {
  // "1.5.5" is 1.5 and .5; "-.5"; "1e-1"; "10-5" is 10 and -5
  const auto sp = svg::parse_path_data("M1.5.5L-.5,1e-1 10-5");
  ASSERT_EQ(sp.size(), 1u);
  ASSERT_EQ(sp[0].segments.size(), 2u);
  EXPECT_EQ(first(sp[0].segments[0]), Eigen::Vector2d(1.5, 0.5));
  EXPECT_EQ(last(sp[0].segments[0]), Eigen::Vector2d(-0.5, 0.1));
  EXPECT_EQ(last(sp[0].segments[1]), Eigen::Vector2d(10, -5));
  const auto e = svg::parse_path_data("M+1E2,2e+1 l.5e1-0");
  EXPECT_EQ(first(e[0].segments[0]), Eigen::Vector2d(100, 20));
  EXPECT_EQ(last(e[0].segments[0]), Eigen::Vector2d(105, 20));
}

TEST(SvgPathData, ImplicitRepetitionAndRelative) {
  // extra pairs after M are L, after m are l
  auto sp = svg::parse_path_data("M0 0 10 0 10 10");
  ASSERT_EQ(sp[0].segments.size(), 2u);
  EXPECT_EQ(last(sp[0].segments[1]), Eigen::Vector2d(10, 10));
  sp = svg::parse_path_data("m1 1 2 0 0 3");
  EXPECT_EQ(first(sp[0].segments[0]), Eigen::Vector2d(1, 1));
  EXPECT_EQ(last(sp[0].segments[1]), Eigen::Vector2d(3, 4));
  // H V h v, repeated
  sp = svg::parse_path_data("M1 2 H5 6 V7 h-1 v-2 -1");
  ASSERT_EQ(sp[0].segments.size(), 6u);
  EXPECT_EQ(last(sp[0].segments[1]), Eigen::Vector2d(6, 2));
  EXPECT_EQ(last(sp[0].segments[2]), Eigen::Vector2d(6, 7));
  EXPECT_EQ(last(sp[0].segments[5]), Eigen::Vector2d(5, 4));
}

TEST(SvgPathData, CloseAndSubpaths) {
  // Z closes with a line; a command after Z starts a new subpath at the closed one's start
  const auto sp = svg::parse_path_data("M0 0 L10 0 L10 10 Z l 5 5 M 20 20 h 1 z m 1 1 h 1");
  ASSERT_EQ(sp.size(), 4u);
  EXPECT_TRUE(sp[0].closed);
  ASSERT_EQ(sp[0].segments.size(), 3u);
  EXPECT_EQ(last(sp[0].segments[2]), Eigen::Vector2d(0, 0));
  EXPECT_EQ(first(sp[1].segments[0]), Eigen::Vector2d(0, 0));
  EXPECT_EQ(last(sp[1].segments[0]), Eigen::Vector2d(5, 5));
  // h 1 z: a line there and back
  EXPECT_EQ(sp[2].segments.size(), 2u);
  // m after z is relative to the closed subpath's start (20, 20)
  EXPECT_EQ(first(sp[3].segments[0]), Eigen::Vector2d(21, 21));
}

TEST(SvgPathData, SmoothCurvesReflectControlPoints) {
  const auto sp = svg::parse_path_data("M0 0 C1 2 3 2 4 0 S7 -2 8 0 Q9 2 10 0 T12 0 t2 0");
  const auto& s = sp[0].segments;
  ASSERT_EQ(s.size(), 5u);
  EXPECT_EQ(s[0].degree, 3);
  EXPECT_EQ(Eigen::Vector2d(s[1].ctrl.row(1)), Eigen::Vector2d(5, -2));  // reflection of (3, 2) about (4, 0)
  EXPECT_EQ(s[2].degree, 2);
  EXPECT_EQ(Eigen::Vector2d(s[3].ctrl.row(1)), Eigen::Vector2d(11, -2));  // reflection of (9, 2) about (10, 0)
  EXPECT_EQ(Eigen::Vector2d(s[4].ctrl.row(1)), Eigen::Vector2d(13, 2));   // reflection of (11, -2) about (12, 0)
  EXPECT_EQ(last(s[4]), Eigen::Vector2d(14, 0));
  // S after a non-curve: first control point = current point
  const auto t = svg::parse_path_data("M0 0 L1 0 S2 1 3 0");
  EXPECT_EQ(Eigen::Vector2d(t[0].segments[1].ctrl.row(1)), Eigen::Vector2d(1, 0));
}

// Centre of the ellipse (rx, ry, phi) through p0 and p1, computed in the frame where it is the unit
// circle: the midpoint of the chord plus or minus the half-chord's normal.
Eigen::Vector2d reference_centre(Eigen::Vector2d p0, Eigen::Vector2d p1, double rx, double ry, double phi,
                                 bool large, bool sweep) {
  const Eigen::Matrix2d R = Eigen::Rotation2Dd(phi).toRotationMatrix();
  const Eigen::Matrix2d to_unit = Eigen::Vector2d(1 / rx, 1 / ry).asDiagonal() * R.transpose();
  const Eigen::Vector2d a = to_unit * p0, b = to_unit * p1;
  const Eigen::Vector2d m = (a + b) / 2, h = (b - a) / 2;
  const double d = std::sqrt(std::max(0.0, 1 - h.squaredNorm()));
  const Eigen::Vector2d n(-h.y() / h.norm(), h.x() / h.norm());
  // sweep = 1: positive angle direction; the centre is left of a->b for the short positive arc
  const Eigen::Vector2d c = m + ((large != sweep) ? 1.0 : -1.0) * d * n;
  return R * Eigen::Vector2d(rx, ry).asDiagonal() * c;
}

TEST(SvgArc, PointsOnTheEllipseAndFlagsChooseTheArc) {
  const Eigen::Vector2d p0(3, 4), p1(20, 11);
  const double rx = 15, ry = 8, deg = 30, phi = deg * kPi / 180;
  const Eigen::Matrix2d R = Eigen::Rotation2Dd(phi).toRotationMatrix();
  for (int large = 0; large < 2; ++large) {
    for (int sweep = 0; sweep < 2; ++sweep) {
      const BSpline a = svg::arc_segment(p0, rx, ry, deg, large, sweep, p1);
      EXPECT_TRUE(a.rational());
      EXPECT_EQ(a.degree, 2);
      EXPECT_EQ(first(a), p0);
      EXPECT_EQ(last(a), p1);
      const Eigen::Vector2d c = reference_centre(p0, p1, rx, ry, phi, large, sweep);
      double turned = 0, prev = 0;
      bool have_prev = false;
      for (const Eigen::Vector2d& p : samples(a)) {
        const Eigen::Vector2d q = R.transpose() * (p - c);
        EXPECT_NEAR(q.x() * q.x() / (rx * rx) + q.y() * q.y() / (ry * ry), 1.0, 1e-12);
        const double ang = std::atan2(q.y() / ry, q.x() / rx);
        if (have_prev) turned += std::remainder(ang - prev, 2 * kPi);
        prev = ang;
        have_prev = true;
      }
      EXPECT_EQ(std::abs(turned) > kPi, large == 1);
      EXPECT_EQ(turned > 0, sweep == 1);
    }
  }
}

TEST(SvgArc, RadiiTooSmallAreScaledUp) {
  // F.6.6: radius 1 cannot span 10: scaled to 5, a half circle about (5, 0)
  const BSpline a = svg::arc_segment({0, 0}, 1, 1, 0, false, true, {10, 0});
  for (const Eigen::Vector2d& p : samples(a)) EXPECT_NEAR((p - Eigen::Vector2d(5, 0)).norm(), 5.0, 1e-12);
  // sweep 1: the positive angle direction, from angle pi to 2 pi: through (5, -5) (clockwise on
  // screen, y down)
  const auto s = samples(a, 2);
  EXPECT_NEAR(s[1].y(), -5.0, 1e-12);
  // ellipse radii 2:1, too small: scaled keeping the ratio
  const BSpline b = svg::arc_segment({0, 0}, 2, 1, 90, false, false, {0, 8});
  for (const Eigen::Vector2d& p : samples(b)) {
    const Eigen::Vector2d q = p - Eigen::Vector2d(0, 4);
    EXPECT_NEAR(q.y() * q.y() / 16 + q.x() * q.x() / 4, 1.0, 1e-12);
  }
}

TEST(SvgArc, DegenerateArcs) {
  EXPECT_EQ(svg::arc_segment({1, 1}, 5, 5, 0, false, true, {1, 1}).n_ctrl(), 0);  // omitted
  const BSpline l = svg::arc_segment({1, 1}, 0, 5, 0, false, true, {4, 5});     // a line
  EXPECT_EQ(l.degree, 1);
  EXPECT_EQ(last(l), Eigen::Vector2d(4, 5));
  // flags written without separators
  const auto sp = svg::parse_path_data("M0 0a5 5 0 1010 0");
  ASSERT_EQ(sp[0].segments.size(), 1u);
  EXPECT_EQ(last(sp[0].segments[0]), Eigen::Vector2d(10, 0));
}

TEST(SvgTransform, ListsComposeLeftToRight) {
  auto apply = [](const std::string& t, Eigen::Vector2d p) {
    const svg::Affine m = svg::parse_transform(t);
    return Eigen::Vector2d((m * Eigen::Vector3d(p.x(), p.y(), 1)).head<2>());
  };
  auto near = [](Eigen::Vector2d a, Eigen::Vector2d b) { return (a - b).norm() < 1e-12; };
  EXPECT_TRUE(near(apply("translate(10,20)", {1, 2}), {11, 22}));
  EXPECT_TRUE(near(apply("translate(10)", {1, 2}), {11, 2}));
  EXPECT_TRUE(near(apply("scale(2)", {1, 2}), {2, 4}));
  EXPECT_TRUE(near(apply("scale(2 3)", {1, 2}), {2, 6}));
  EXPECT_TRUE(near(apply("rotate(90)", {1, 0}), {0, 1}));
  EXPECT_TRUE(near(apply("rotate(90 10 10)", {11, 10}), {10, 11}));
  EXPECT_TRUE(near(apply("skewX(45)", {1, 2}), {3, 2}));
  EXPECT_TRUE(near(apply("skewY(45)", {1, 2}), {1, 3}));
  EXPECT_TRUE(near(apply("matrix(1 2 3 4 5 6)", {1, 1}), {9, 12}));
  // translate then scale: the point is scaled first
  EXPECT_TRUE(near(apply("translate(10,0) scale(2)", {1, 1}), {12, 2}));
  EXPECT_TRUE(near(apply(" scale(2),translate(10 , 0)", {1, 1}), {22, 2}));
  EXPECT_THROW(svg::parse_transform("shear(1)"), svg::PathDataError);
  EXPECT_THROW(svg::parse_transform("rotate(1 2)"), svg::PathDataError);
}

TEST(SvgDocument, TransformedRectCornersByHand) {
  // rect (1,2) 4x3, rotated 90 degrees about the origin, then translated by (10, 20) in user units:
  // (x, y) -> (-y + 10, x + 20); then y_mm = 100 - y.
  const Toolpath tp = traj::input::parse_svg(
      doc(R"~(<g transform="translate(10,20)"><rect id="r" x="1" y="2" width="4" height="3" transform="rotate(90)"/></g>)~"),
      "t.svg");
  EXPECT_EQ(tp.axes, 2);
  const auto f = feeds(tp);
  ASSERT_EQ(f.size(), 4u);
  auto map = [](double x, double y) { return Eigen::Vector2d(-y + 10, 100 - (x + 20)); };
  const Eigen::Vector2d corners[4] = {map(1, 2), map(5, 2), map(5, 5), map(1, 5)};
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT((first(f[i]->curve) - corners[i]).norm(), 1e-12) << i;
    EXPECT_LT((last(f[i]->curve) - corners[(i + 1) % 4]).norm(), 1e-12) << i;
    EXPECT_EQ(f[i]->where, "t.svg: rect r");
  }
}

// <use>: the element again under the use's transform, then translated by its x, y (SVG 1.1 5.6):
// a line from a <defs> (not drawn there), a line drawn and cloned, a <symbol>'s content, and a
// clone of a clone (xlink:href). End points by hand; y_mm = 100 - y.
TEST(SvgDocument, UseDrawsTheElementAgain) {
  const Toolpath tp = traj::input::parse_svg(
      doc(R"~(<defs><line id="d" x1="1" y1="0" x2="3" y2="0"/></defs>)~"
          R"~(<use href="#d" x="10" y="5"/>)~"
          R"~(<line id="l" x1="0" y1="0" x2="0" y2="2"/>)~"
          R"~(<use id="u" href="#l" transform="rotate(90)" x="1" y="0"/>)~"
          R"~(<symbol id="s"><line x1="0" y1="0" x2="4" y2="0"/></symbol><use href="#s" transform="translate(50,50)"/>)~"
          R"~(<use xmlns:xlink="http://www.w3.org/1999/xlink" xlink:href="#u" x="20"/>)~"),
      "t.svg");
  const auto f = feeds(tp);
  auto P = [](double x, double y) { return Eigen::Vector2d(x, 100 - y); };
  // rotate(90) then translate(1, 0): (x, y) -> (-y, x + 1); the outer use adds x = 20 first
  const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> want = {
      {P(11, 5), P(13, 5)}, {P(0, 0), P(0, 2)}, {P(0, 1), P(-2, 1)}, {P(50, 50), P(54, 50)}, {P(20, 1), P(18, 1)}};
  ASSERT_EQ(f.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_LT((first(f[i]->curve) - want[i].first).norm(), 1e-12) << i;
    EXPECT_LT((last(f[i]->curve) - want[i].second).norm(), 1e-12) << i;
  }
  EXPECT_EQ(f[0]->where, "t.svg: line d");
}

// A path closed by relative steps that return to its start only within rounding (the Vanderbilt
// Commodores logo on Wikimedia: 7e-15 off): its 'z' would add a piece of 1e-15 mm, which the planner
// refuses ("zero-length curve"); the negligible piece is left out, the moves still meet exactly.
// 0.1 + 0.2 - 10.3 != 0 exactly in binary; 1 + 10.1 + 0.2 - 10.3 lands 1e-15 away from 1.
TEST(SvgDocument, NearlyClosedPathHasNoNegligiblePiece) {
  const Toolpath tp = traj::input::parse_svg(doc(R"~(<path d="m1 1 l10.1 0.2 0.2 10.3 -10.3 -10.5z"/>)~"), "t.svg");
  const auto f = feeds(tp);
  ASSERT_EQ(f.size(), 3u);
  for (size_t i = 0; i + 1 < f.size(); ++i) EXPECT_EQ(last(f[i]->curve), first(f[i + 1]->curve)) << i;
  EXPECT_LT((last(f[2]->curve) - Eigen::Vector2d(1, 99)).norm(), 1e-12);
  // a negligible piece between two others: the next one starts where the kept one ends
  BSpline a = svg::parse_path_data("M0 0 L5 0").front().segments.front();
  BSpline tiny = svg::parse_path_data("M5 0 L5 1e-12").front().segments.front();
  BSpline b = svg::parse_path_data("M5 1e-12 L5 5").front().segments.front();
  const Toolpath t2 = traj::input::toolpath_from_cuts({{{a, "a"}, {tiny, "tiny"}, {b, "b"}}}, 2);
  ASSERT_EQ(t2.moves.size(), 2u);
  EXPECT_EQ(last(t2.moves[0].curve), first(t2.moves[1].curve));
  EXPECT_EQ(t2.moves[1].where, "b");
}

// A cut that starts where the last one ended, up to rounding: no rapid of
// 1e-15 mm between them (simple-icons' createreactapp.svg: an arc subpath
// after a 'Z', its start computed through other relative steps than the
// closed one's end, 4e-16 mm apart after the transform, refused as a
// zero-length curve). The second cut starts exactly where the first ends.
TEST(SvgDocument, CutStartingWithinRoundingOfTheLastEndNeedsNoRapid) {
  BSpline a = svg::parse_path_data("M0 0 L5 0").front().segments.front();
  BSpline b = svg::parse_path_data("M5 4e-16 L5 5").front().segments.front();
  const Toolpath tp = traj::input::toolpath_from_cuts({{{a, "a"}}, {{b, "b"}}}, 2);
  ASSERT_EQ(tp.moves.size(), 2u);
  EXPECT_EQ(tp.moves[1].kind, Move::Kind::kFeed);
  EXPECT_EQ(last(tp.moves[0].curve), first(tp.moves[1].curve));
  // 1 um apart: a rapid between them, as before
  BSpline c = svg::parse_path_data("M5 0.001 L5 5").front().segments.front();
  const Toolpath t2 = traj::input::toolpath_from_cuts({{{a, "a"}}, {{c, "c"}}}, 2);
  ASSERT_EQ(t2.moves.size(), 3u);
  EXPECT_EQ(t2.moves[1].kind, Move::Kind::kRapid);
}

TEST(SvgDocument, RoundedRectCornersAreQuarterEllipses) {
  const Toolpath tp = traj::input::parse_svg(doc(R"~(<rect x="10" y="10" width="40" height="20" rx="5" ry="3"/>)~"), "t.svg");
  const auto f = feeds(tp);
  ASSERT_EQ(f.size(), 8u);
  // top-right corner (user units): centre (45, 13), from (45, 10) to (50, 13)
  const BSpline& corner = f[1]->curve;
  EXPECT_TRUE(corner.rational());
  for (const Eigen::Vector2d& p : samples(corner)) {
    const Eigen::Vector2d q(p.x() - 45, (100 - p.y()) - 13);
    EXPECT_NEAR(q.x() * q.x() / 25 + q.y() * q.y() / 9, 1.0, 1e-12);
  }
  EXPECT_LT((first(corner) - Eigen::Vector2d(45, 90)).norm(), 1e-12);
  EXPECT_LT((last(corner) - Eigen::Vector2d(50, 87)).norm(), 1e-12);
}

TEST(SvgDocument, CircleEllipseLinePolyline) {
  const Toolpath tp = traj::input::parse_svg(
      doc(R"~(<circle cx="50" cy="50" r="10"/><ellipse cx="20" cy="30" rx="8" ry="4"/>)~"
          R"~(<line x1="1" y1="2" x2="3" y2="4"/><polyline points="0,0 10,0 10,10"/><polygon points="60 60 70 60 70 70"/>)~"),
      "t.svg");
  const auto f = feeds(tp);
  ASSERT_EQ(f.size(), 1u + 1u + 1u + 2u + 3u);
  // circle: starts at (cx + r, cy), closed exactly, every point at distance r
  EXPECT_EQ(first(f[0]->curve), Eigen::Vector2d(60, 50));
  EXPECT_EQ(last(f[0]->curve), first(f[0]->curve));
  for (const Eigen::Vector2d& p : samples(f[0]->curve)) EXPECT_NEAR((p - Eigen::Vector2d(50, 50)).norm(), 10, 1e-12);
  for (const Eigen::Vector2d& p : samples(f[1]->curve)) {
    const Eigen::Vector2d q = p - Eigen::Vector2d(20, 70);
    EXPECT_NEAR(q.x() * q.x() / 64 + q.y() * q.y() / 16, 1.0, 1e-12);
  }
  EXPECT_EQ(first(f[2]->curve), Eigen::Vector2d(1, 98));
  EXPECT_EQ(last(f[2]->curve), Eigen::Vector2d(3, 96));
  EXPECT_EQ(last(f[7]->curve), Eigen::Vector2d(60, 40));  // polygon closed
}

TEST(SvgDocument, UnitsAndViewBox) {
  const std::string line = R"~(<path d="M0 0 L96 0"/>)~";
  auto end_x = [&](const std::string& root) { return last(feeds(traj::input::parse_svg(doc(line, root), "t.svg"))[0]->curve).x(); };
  // no viewBox: user units are px (96 per inch)
  EXPECT_NEAR(end_x(R"~(width="210mm" height="297mm")~"), 25.4, 1e-12);
  EXPECT_NEAR(end_x(""), 25.4, 1e-12);
  // viewBox 96 wide in 1in, 2.54cm, 72pt, 6pc, 25.4mm, 96px: all one inch
  for (const char* w : {"1in", "2.54cm", "72pt", "6pc", "25.4mm", "96px", "96", "101.6Q"})
    EXPECT_NEAR(end_x(std::string("width=\"") + w + "\" height=\"" + w + "\" viewBox=\"0 0 96 96\""), 25.4, 1e-12) << w;
  // viewBox 10 wide in 100 mm: 1 unit = 10 mm
  EXPECT_NEAR(end_x(R"~(width="100mm" height="100mm" viewBox="0 0 10 10")~"), 960, 1e-9);
  // preserveAspectRatio (default xMidYMid meet): viewBox 200 x 100 in 100 mm x 100 mm: scale 0.5,
  // centred vertically (25 mm margin); with "none": x scale 0.5, y scale 1
  const Toolpath tp = traj::input::parse_svg(doc(R"~(<path d="M0 0 L200 100"/>)~", R"~(width="100mm" height="100mm" viewBox="0 0 200 100")~"), "t.svg");
  const BSpline& c = feeds(tp)[0]->curve;
  EXPECT_LT((first(c) - Eigen::Vector2d(0, 75)).norm(), 1e-12);
  EXPECT_LT((last(c) - Eigen::Vector2d(100, 25)).norm(), 1e-12);
  const Toolpath none = traj::input::parse_svg(
      doc(R"~(<path d="M0 0 L200 100"/>)~", R"~(width="100mm" height="100mm" viewBox="0 0 200 100" preserveAspectRatio="none")~"), "t.svg");
  EXPECT_LT((last(feeds(none)[0]->curve) - Eigen::Vector2d(100, 0)).norm(), 1e-12);
  // viewBox with an offset
  const Toolpath off = traj::input::parse_svg(doc(R"~(<path d="M10 20 L11 20"/>)~", R"~(width="10mm" height="10mm" viewBox="10 20 10 10")~"), "t.svg");
  EXPECT_LT((first(feeds(off)[0]->curve) - Eigen::Vector2d(0, 10)).norm(), 1e-12);
  EXPECT_NE(error_of(doc(line, R"~(width="10em" height="10em")~")).find("unknown unit 'em'"), std::string::npos);
}

TEST(SvgDocument, PercentagesOfTheViewport) {
  // viewBox 200 x 100: x/width refer to 200, y/height to 100, r to sqrt((200^2 + 100^2) / 2)
  const Toolpath tp = traj::input::parse_svg(
      doc(R"~(<rect x="10%" y="10%" width="50%" height="50%"/><circle cx="0" cy="0" r="10%"/>)~",
          R"~(width="200mm" height="100mm" viewBox="0 0 200 100")~"),
      "t.svg");
  const auto f = feeds(tp);
  ASSERT_EQ(f.size(), 5u);
  EXPECT_LT((first(f[0]->curve) - Eigen::Vector2d(20, 90)).norm(), 1e-12);
  EXPECT_LT((last(f[0]->curve) - Eigen::Vector2d(120, 90)).norm(), 1e-12);
  EXPECT_LT((last(f[1]->curve) - Eigen::Vector2d(120, 40)).norm(), 1e-12);
  EXPECT_NEAR(first(f[4]->curve).x(), 0.1 * std::sqrt((200.0 * 200 + 100 * 100) / 2), 1e-12);
  EXPECT_NE(error_of(doc(R"~(<rect width="50%" height="1"/>)~", "")).find("rect #1: width: a percentage"), std::string::npos);
}

TEST(SvgDocument, ToolpathStructure) {
  const Toolpath tp = traj::input::parse_svg(doc(R"~(<path id="p" d="M10 90 H20 M30 90 H40"/>)~"), "t.svg");
  ASSERT_EQ(tp.moves.size(), 4u);
  EXPECT_EQ(tp.moves[0].kind, Move::Kind::kRapid);
  EXPECT_TRUE(tp.moves[0].exact_stop);
  EXPECT_EQ(first(tp.moves[0].curve), Eigen::Vector2d(0, 0));
  EXPECT_EQ(last(tp.moves[0].curve), Eigen::Vector2d(10, 10));
  EXPECT_EQ(tp.moves[1].kind, Move::Kind::kFeed);
  EXPECT_EQ(tp.moves[1].feed, 0);
  EXPECT_FALSE(tp.moves[1].exact_stop);
  EXPECT_EQ(tp.moves[1].where, "t.svg: path p");
  EXPECT_EQ(tp.moves[2].kind, Move::Kind::kRapid);
  EXPECT_EQ(first(tp.moves[2].curve), Eigen::Vector2d(20, 10));
  EXPECT_EQ(last(tp.moves[2].curve), Eigen::Vector2d(30, 10));
  // every move starts where the previous one ended
  for (std::size_t i = 1; i < tp.moves.size(); ++i) EXPECT_EQ(first(tp.moves[i].curve), last(tp.moves[i - 1].curve));
}

TEST(SvgDocument, SkippedElementsAndNotes) {
  const Toolpath tp = traj::input::parse_svg(
      doc(R"~(<defs><path d="M0 0 L5 5"/></defs><g style="display:none"><path d="M0 0 L9 9"/></g>)~"
          R"~(<text x="1" y="1">hi</text><sodipodi:namedview xmlns:sodipodi="x"/><svg:path xmlns:svg="http://www.w3.org/2000/svg" d="M1 1 L2 1"/>)~"),
      "t.svg");
  EXPECT_EQ(feeds(tp).size(), 1u);
  ASSERT_EQ(tp.notes.size(), 2u);
  EXPECT_NE(tp.notes[0].find("display:none"), std::string::npos);
  EXPECT_NE(tp.notes[1].find("<text>"), std::string::npos);
}

// Shapes that draw nothing are not cut: neither fill nor stroke (fill is
// black, stroke none unless set; both inherited, also through <use>), or
// visibility:hidden (inherited, a child may set visible). tabler-icons frames
// each of its 5491 outline icons with <path stroke="none" d="M0 0h24v24H0z"
// fill="none"/> under a root of fill="none" stroke="currentColor": that frame
// was cut around every icon. A file with a <style> sheet (not read: it may
// paint or hide by class) has every shape cut.
TEST(SvgDocument, ShapesThatDrawNothingAreNotCut) {
  const std::string body =
      R"~(<path stroke="none" d="M0 0h24v24H0z" fill="none"/><path d="M1 1 L5 1"/>)~"
      R"~(<g visibility="hidden"><path d="M1 2 L5 2"/><path visibility="visible" d="M1 3 L5 3"/></g>)~"
      R"~(<g fill="red"><path stroke="none" d="M1 4 L5 4"/></g>)~"
      R"~(<defs><path id="f" d="M1 5 L5 5" stroke="none"/></defs><use href="#f" fill="none"/><use href="#f" fill="blue" y="1"/>)~";
  const std::string root = R"~(width="100mm" height="100mm" viewBox="0 0 100 100" fill="none" stroke="currentColor")~";
  const Toolpath tp = traj::input::parse_svg(doc(body, root), "t.svg");
  const auto f = feeds(tp);
  ASSERT_EQ(f.size(), 4u);
  // y_mm = 100 - y: the cuts at y = 1, 3, 4 and the clone moved to 6
  const double ys[4] = {99, 97, 96, 94};
  for (int i = 0; i < 4; ++i) EXPECT_EQ(first(f[i]->curve), Eigen::Vector2d(1, ys[i])) << "cut " << i;
  ASSERT_EQ(tp.notes.size(), 2u);
  EXPECT_NE(tp.notes[0].find("neither fill nor stroke (not drawn) skipped, first path #1"), std::string::npos)
      << tp.notes[0];
  EXPECT_NE(tp.notes[1].find("visibility:hidden skipped, first path #3"), std::string::npos) << tp.notes[1];
  const Toolpath styled = traj::input::parse_svg(doc("<style>.a{stroke:red}</style>" + body, root), "t.svg");
  EXPECT_EQ(feeds(styled).size(), 10u);  // the frame's 4 sides and the 6 other shapes
  EXPECT_TRUE(styled.notes.empty());
}

TEST(SvgDocument, Errors) {
  // malformed path data: element named by id, character offset given
  std::string e = error_of(doc(R"~(<path id="bad" d="M 0 0 L 1 x"/>)~"));
  EXPECT_NE(e.find("t.svg: path bad: d: offset 10: expected a number, got 'x'"), std::string::npos) << e;
  e = error_of(doc(R"~(<path d="M0 0"/><path d="L 1 1"/>)~"));
  EXPECT_NE(e.find("t.svg: path #2: d: offset 0: path data must begin with a moveto"), std::string::npos) << e;
  e = error_of(doc(R"~(<path d="M0 0 K 1 1"/>)~"));
  EXPECT_NE(e.find("offset 5: expected a path command"), std::string::npos) << e;
  e = error_of(doc(R"~(<path d="M0 0 A 1 1 0 2 1 5 5"/>)~"));
  EXPECT_NE(e.find("arc flag"), std::string::npos) << e;
  e = error_of(doc(R"~(<circle r="1cm"/><rect width="5em" height="1"/>)~"));
  EXPECT_NE(e.find("t.svg: rect #2: width: unknown unit 'em'"), std::string::npos) << e;
  e = error_of(doc(R"~(<use href="#a"/>)~"));
  EXPECT_NE(e.find("t.svg: use without id: <use> of #a: the file has no element with that id"), std::string::npos) << e;
  e = error_of(doc(R"~(<use href="other.svg#a"/>)~"));
  EXPECT_NE(e.find("<use> of 'other.svg#a': only #id (an element of this file) is followed"), std::string::npos) << e;
  e = error_of(doc(R"~(<g id="g"><path d="M0 0 L1 1"/><use href="#g"/></g>)~"));
  EXPECT_NE(e.find("<use> of #g: it contains the <use> itself"), std::string::npos) << e;
  e = error_of(doc(R"~(<defs><g id="a"><use href="#b"/></g><g id="b"><use href="#a"/></g></defs><use href="#a"/>)~"));
  EXPECT_NE(e.find("the clones refer to each other in a cycle"), std::string::npos) << e;
  e = error_of(doc(R"~(<symbol id="s" viewBox="0 0 1 1"><path d="M0 0 L1 1"/></symbol><use href="#s"/>)~"));
  EXPECT_NE(e.find("<use> of a <symbol> with its own viewBox or size is not supported"), std::string::npos) << e;
  EXPECT_NE(error_of(doc(R"~(<use/>)~")).find("t.svg: use without id: <use> without href"), std::string::npos);
  // clones of clones: 10 levels of 10 clones would be 10^10 lines
  std::string bomb = R"~(<defs><line id="g0" x1="0" y1="0" x2="1" y2="0"/>)~";
  for (int level = 1; level <= 10; ++level) {
    bomb += "<g id=\"g" + std::to_string(level) + "\">";
    for (int i = 0; i < 10; ++i) bomb += "<use href=\"#g" + std::to_string(level - 1) + "\"/>";
    bomb += "</g>";
  }
  e = error_of(doc(bomb + R"~(</defs><use href="#g10"/>)~"));
  EXPECT_NE(e.find("more than 1000000 shapes to draw (clones of clones multiply: <use>)"), std::string::npos) << e;
  e = error_of(doc(R"~(<text>only text</text>)~"));
  EXPECT_NE(e.find("t.svg: no paths: no path, line, polyline, polygon, rect, circle or ellipse with any length; <text> not converted"), std::string::npos) << e;
  EXPECT_NE(error_of(doc(R"~(<svg><path d="M0 0 L1 1"/></svg>)~")).find("nested <svg>"), std::string::npos);
  EXPECT_NE(error_of(doc(R"~(<path d="M0 0"/>)~")).find("t.svg: no paths"), std::string::npos);
  EXPECT_NE(error_of(doc(R"~(<g transform="rotate(1,2)"><path d="M0 0 L1 1"/></g>)~")).find("g without id: transform:"), std::string::npos);
  EXPECT_NE(error_of("<svg><path d=\"M0 0 L1 1\"></svg>").find("t.svg: XML: line 1"), std::string::npos);
  EXPECT_NE(error_of("<html/>").find("not <svg>"), std::string::npos);
  try {
    traj::input::read_svg("/nonexistent/x.svg");
    FAIL();
  } catch (const InputError& err) {
    EXPECT_STREQ(err.what(), "/nonexistent/x.svg: cannot open");
  }
}

TEST(SvgDocument, ReadsAFile) {
  const std::string name = ::testing::TempDir() + "svg_test_file.svg";
  std::ofstream(name) << doc(R"~(<path d="m 10,10 c 10,0 10,10 20,10"/>)~");
  const Toolpath tp = traj::input::read_svg(name);
  ASSERT_EQ(feeds(tp).size(), 1u);
  EXPECT_EQ(feeds(tp)[0]->curve.degree, 3);
  EXPECT_EQ(last(feeds(tp)[0]->curve), Eigen::Vector2d(30, 80));
}

}  // namespace
