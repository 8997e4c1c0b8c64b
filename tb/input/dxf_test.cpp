// SPDX-License-Identifier: Apache-2.0
// DXF reader: small DXF files written here by hand (group code / value lines), read back and checked
// against hand-computed geometry (bulge arcs by the bulge formula, object coordinates, units,
// chaining, splines).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <utility>

#include "geometry/arclength.hpp"
#include "geometry/curve.hpp"
#include "input/dxf.hpp"
#include "tmp_file.hpp"

namespace {

using traj::geo::BSpline;
using traj::geo::Curve;
using traj::input::InputError;
using traj::input::Move;
using traj::input::Toolpath;

constexpr double kPi = 3.14159265358979323846;

using Groups = std::vector<std::pair<int, std::string>>;

struct Dxf {
  int insunits = 4;  // mm; < 0: no $INSUNITS
  std::vector<Groups> entities;
  std::string blocks;  // raw BLOCKS section body

  std::string text() const {
    std::string t = "0\nSECTION\n2\nHEADER\n9\n$ACADVER\n1\nAC1015\n";
    if (insunits >= 0) t += "9\n$INSUNITS\n70\n" + std::to_string(insunits) + "\n";
    t += "0\nENDSEC\n";
    if (!blocks.empty()) t += "0\nSECTION\n2\nBLOCKS\n" + blocks + "0\nENDSEC\n";
    t += "0\nSECTION\n2\nENTITIES\n";
    for (const Groups& g : entities)
      for (const auto& [code, value] : g) t += std::to_string(code) + "\n" + value + "\n";
    return t + "0\nENDSEC\n0\nEOF\n";
  }
  Toolpath read(const std::string& name = "t.dxf") const {
    const traj::test::TmpFile f(name);
    f.write(text());
    return traj::input::read_dxf(f.path);
  }
};

std::string num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

Groups line(double x1, double y1, double x2, double y2, double z1 = 0, double z2 = 0) {
  return {{0, "LINE"}, {8, "0"}, {10, num(x1)}, {20, num(y1)}, {30, num(z1)}, {11, num(x2)}, {21, num(y2)}, {31, num(z2)}};
}
Groups arc(double cx, double cy, double r, double a0, double a1, double nz = 1) {
  return {{0, "ARC"}, {8, "0"}, {10, num(cx)}, {20, num(cy)}, {30, "0"}, {40, num(r)}, {210, "0"}, {220, "0"}, {230, num(nz)},
          {50, num(a0)}, {51, num(a1)}};
}
Groups lwpolyline(const std::vector<std::array<double, 3>>& v, bool closed) {
  Groups g = {{0, "LWPOLYLINE"}, {8, "0"}, {90, std::to_string(v.size())}, {70, closed ? "1" : "0"}};
  for (const auto& p : v) {
    g.push_back({10, num(p[0])});
    g.push_back({20, num(p[1])});
    if (p[2] != 0) g.push_back({42, num(p[2])});
  }
  return g;
}

Eigen::Vector3d first(const BSpline& c) { return c.ctrl.row(0).transpose(); }
Eigen::Vector3d last(const BSpline& c) { return c.ctrl.row(c.n_ctrl() - 1).transpose(); }

std::vector<const Move*> feeds(const Toolpath& tp) {
  std::vector<const Move*> f;
  for (const Move& m : tp.moves)
    if (m.kind == Move::Kind::kFeed) f.push_back(&m);
  return f;
}
int rapids(const Toolpath& tp) {
  int n = 0;
  for (const Move& m : tp.moves) n += m.kind == Move::Kind::kRapid;
  return n;
}

std::vector<Eigen::Vector3d> samples(const BSpline& b, int n = 200) {
  const Curve c(b);
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i <= n; ++i) out.push_back(c.point(b.u_begin() + (b.u_end() - b.u_begin()) * i / n).head<3>());
  return out;
}

std::string error_of(const Dxf& d) {
  try {
    d.read("err.dxf");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(DxfReader, ChainsLineArcLineReversingWhereNeeded) {
  Dxf d;
  // square-ish loop: line (0,0)-(10,0); arc centre (10,5) r 5 from -90 to 90 degrees (ends at (10,10));
  // line given from (0,10) to (10,10): run backwards
  d.entities = {line(0, 0, 10, 0), arc(10, 5, 5, -90, 90), line(0, 10, 10, 10)};
  const Toolpath tp = d.read();
  EXPECT_EQ(tp.axes, 3);
  EXPECT_EQ(rapids(tp), 0);  // starts at the origin
  const auto f = feeds(tp);
  ASSERT_EQ(f.size(), 3u);
  EXPECT_TRUE(f[1]->curve.rational());
  EXPECT_LT((last(f[1]->curve) - Eigen::Vector3d(10, 10, 0)).norm(), 1e-12);
  EXPECT_EQ(first(f[2]->curve), last(f[1]->curve));
  EXPECT_EQ(last(f[2]->curve), Eigen::Vector3d(0, 10, 0));
  EXPECT_NE(f[2]->where.find("entity 3 (LINE)"), std::string::npos) << f[2]->where;
  for (const Eigen::Vector3d& p : samples(f[1]->curve)) {
    EXPECT_NEAR((p - Eigen::Vector3d(10, 5, 0)).norm(), 5, 1e-12);
    EXPECT_GE(p.x(), 10 - 1e-12);  // the right half: counter-clockwise from -90 to 90
  }
  EXPECT_TRUE(tp.notes.empty());
}

TEST(DxfReader, ChainsOnlyWithinTolerance) {
  Dxf d;
  d.entities = {line(0, 0, 10, 0), line(10 + 5e-7, 0, 20, 0), line(20 + 1e-5, 0, 30, 0)};
  const Toolpath tp = d.read();
  ASSERT_EQ(tp.moves.size(), 4u);  // two feeds, a rapid, a feed
  EXPECT_EQ(tp.moves[1].kind, Move::Kind::kFeed);
  EXPECT_EQ(first(tp.moves[1].curve), Eigen::Vector3d(10, 0, 0));  // joint closed exactly
  EXPECT_EQ(tp.moves[2].kind, Move::Kind::kRapid);
  EXPECT_TRUE(tp.moves[2].exact_stop);
  EXPECT_EQ(first(tp.moves[2].curve), Eigen::Vector3d(20, 0, 0));
  EXPECT_EQ(last(tp.moves[2].curve), Eigen::Vector3d(20 + 1e-5, 0, 0));
  // a chain is also extended backwards from its first entity
  Dxf b;
  b.entities = {line(10, 0, 20, 0), line(50, 0, 60, 0), line(0, 0, 10, 0)};
  const Toolpath read_back = b.read();
  const auto f = feeds(read_back);
  ASSERT_EQ(f.size(), 3u);
  EXPECT_EQ(first(f[0]->curve), Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(last(f[1]->curve), Eigen::Vector3d(20, 0, 0));
  EXPECT_EQ(first(f[2]->curve), Eigen::Vector3d(50, 0, 0));
}

TEST(DxfReader, BulgeArcMidpointByTheBulgeFormula) {
  // From p0 to p1 with bulge b: the arc's midpoint lies b * c / 2 (the sagitta, c the chord) to the
  // right of the chord's midpoint; the radius is c (1 + b^2) / (4 |b|).
  for (double b : {0.5, -0.5, 2.0, -0.3, 1.0}) {
    const Eigen::Vector2d p0(1, 2), p1(9, 8);
    Dxf d;
    d.entities = {lwpolyline({{{p0.x(), p0.y(), b}}, {{p1.x(), p1.y(), 0}}}, false)};
    const Toolpath read_back = d.read();
  const auto f = feeds(read_back);
    ASSERT_EQ(f.size(), 1u);
    const BSpline& a = f[0]->curve;
    EXPECT_EQ(first(a), Eigen::Vector3d(1, 2, 0));
    EXPECT_EQ(last(a), Eigen::Vector3d(9, 8, 0));
    const double c = (p1 - p0).norm();
    const Eigen::Vector2d right = Eigen::Vector2d((p1 - p0).y(), -(p1 - p0).x()) / c;
    const Eigen::Vector2d mid = (p0 + p1) / 2 + right * (b * c / 2);
    const double r = c * (1 + b * b) / (4 * std::abs(b));
    // centre: on the chord's bisector, r from the midpoint of the arc, towards the chord
    const Eigen::Vector2d centre = mid - right * (b > 0 ? r : -r);
    double closest = 1e9;
    for (const Eigen::Vector3d& p : samples(a, 4000)) {
      EXPECT_NEAR((p.head<2>() - centre).norm(), r, 1e-12);
      closest = std::min(closest, (p.head<2>() - mid).norm());
    }
    EXPECT_LT(closest, 2 * kPi * r / 4000) << "bulge " << b;
    // the arc's length by its included angle 4 atan(b)
    EXPECT_NEAR(std::abs(4 * std::atan(b)) * r, [&] {
      double len = 0;
      const auto s = samples(a, 20000);
      for (std::size_t i = 1; i < s.size(); ++i) len += (s[i] - s[i - 1]).norm();
      return len;
    }(), 1e-6 * r);
  }
}

TEST(DxfReader, ClosedPolylineWithArcs) {
  // a slot: two half circles (bulge 1) and two lines, closed; elevation 3
  Dxf d;
  Groups g = lwpolyline({{{0, 0, 0}}, {{10, 0, 1}}, {{10, 4, 0}}, {{0, 4, 1}}}, true);
  g.push_back({38, "3"});
  d.entities = {g};
  const Toolpath read_back = d.read();
  const auto f = feeds(read_back);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(last(f[3]->curve), Eigen::Vector3d(0, 0, 3));
  for (const Eigen::Vector3d& p : samples(f[1]->curve)) {
    EXPECT_NEAR((p - Eigen::Vector3d(10, 2, 3)).norm(), 2, 1e-12);
    EXPECT_GE(p.x(), 10 - 1e-12);  // counter-clockwise from (10,0) to (10,4): bulging right
  }
}

TEST(DxfReader, ObjectCoordinatesOfAMirroredArc) {
  // extrusion (0,0,-1): the object x axis is world -x. Arc centre (5,0), r 5, 0..90 degrees:
  // from object (10,0) = world (-10,0) to object (5,5) = world (-5,5)
  Dxf d;
  d.entities = {arc(5, 0, 5, 0, 90, -1)};
  const Toolpath read_back = d.read();
  const auto f = feeds(read_back);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_LT((first(f[0]->curve) - Eigen::Vector3d(-10, 0, 0)).norm(), 1e-12);
  EXPECT_LT((last(f[0]->curve) - Eigen::Vector3d(-5, 5, 0)).norm(), 1e-12);
  for (const Eigen::Vector3d& p : samples(f[0]->curve)) EXPECT_NEAR((p - Eigen::Vector3d(-5, 0, 0)).norm(), 5, 1e-12);
}

TEST(DxfReader, CircleAndEllipse) {
  Dxf d;
  d.entities = {{{0, "CIRCLE"}, {8, "0"}, {10, "1"}, {20, "2"}, {30, "4"}, {40, "3"}},
                {{0, "ELLIPSE"}, {8, "0"}, {10, "20"}, {20, "0"}, {30, "0"}, {11, "0"}, {21, "6"}, {31, "0"},
                 {40, "0.5"}, {41, "0"}, {42, num(2 * kPi)}}};
  const Toolpath read_back = d.read();
  const auto f = feeds(read_back);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(first(f[0]->curve), last(f[0]->curve));
  EXPECT_EQ(first(f[0]->curve), Eigen::Vector3d(4, 2, 4));
  for (const Eigen::Vector3d& p : samples(f[0]->curve)) EXPECT_NEAR((p - Eigen::Vector3d(1, 2, 4)).norm(), 3, 1e-12);
  // ellipse: major axis 6 along y, minor 3 along -x (z cross major)
  EXPECT_EQ(first(f[1]->curve), last(f[1]->curve));
  for (const Eigen::Vector3d& p : samples(f[1]->curve)) {
    const Eigen::Vector3d q = p - Eigen::Vector3d(20, 0, 0);
    EXPECT_NEAR(q.y() * q.y() / 36 + q.x() * q.x() / 9, 1.0, 1e-12);
  }
}

TEST(DxfReader, RationalSplineQuarterCircle) {
  // degree 2, knots 0 0 0 1 1 1, control points (1,0) (1,1) (0,1), weights 1 sqrt(1/2) 1, in cm
  Dxf d;
  d.insunits = 5;
  d.entities = {{{0, "SPLINE"}, {8, "0"}, {70, "12"}, {71, "2"}, {72, "6"}, {73, "3"}, {74, "0"},
                 {40, "0"}, {40, "0"}, {40, "0"}, {40, "1"}, {40, "1"}, {40, "1"},
                 {10, "1"}, {20, "0"}, {30, "0"}, {41, "1"},
                 {10, "1"}, {20, "1"}, {30, "0"}, {41, num(std::sqrt(0.5))},
                 {10, "0"}, {20, "1"}, {30, "0"}, {41, "1"}}};
  const Toolpath read_back = d.read();
  const auto f = feeds(read_back);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_TRUE(f[0]->curve.rational());
  for (const Eigen::Vector3d& p : samples(f[0]->curve)) EXPECT_NEAR(p.norm(), 10, 1e-12);
}

// A SPLINE written as a chain of Bezier pieces (every interior knot of
// multiplicity degree + 1; the dxf library's issue50.dxf has 7 cubic ones) is
// one curve, C0 at the joins: here a cubic piece and a rational one whose
// weights start at 2 where the first ends at 1, against both pieces evaluated
// by de Casteljau here. Pieces that do not meet are refused.
TEST(DxfReader, SplineOfBezierPieces) {
  const std::array<Eigen::Vector2d, 8> P = {Eigen::Vector2d(0, 0), {1, 2}, {3, 2}, {4, 0},
                                            Eigen::Vector2d(4, 0), {5, -2}, {7, -1}, {8, 1}};
  const std::array<double, 8> W = {1, 1, 1, 1, 2, 3, 1, 2};
  auto spline = [&](double gap) {
    Groups g = {{0, "SPLINE"}, {8, "0"}, {70, "12"}, {71, "3"}, {72, "12"}, {73, "8"}, {74, "0"}};
    for (double k : {0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2}) g.push_back({40, num(k)});
    for (int i = 0; i < 8; ++i) {
      g.push_back({10, num(P[i].x() + (i == 4 ? gap : 0))});
      g.push_back({20, num(P[i].y())});
      g.push_back({30, "0"});
      g.push_back({41, num(W[i])});
    }
    return g;
  };
  // rational de Casteljau of the piece starting at control point k, at t in [0, 1]
  auto piece = [&](int k, double t) {
    std::array<Eigen::Vector3d, 4> h;
    for (int i = 0; i < 4; ++i) h[i] << W[k + i] * P[k + i], W[k + i];
    for (int r = 1; r < 4; ++r)
      for (int i = 0; i < 4 - r; ++i) h[i] = (1 - t) * h[i] + t * h[i + 1];
    return Eigen::Vector2d(h[0].head<2>() / h[0][2]);
  };
  Dxf d;
  d.insunits = 4;
  d.entities = {spline(0)};
  const Toolpath tp = d.read();
  const auto f = feeds(tp);
  ASSERT_EQ(f.size(), 1u);
  const BSpline& c = f[0]->curve;
  EXPECT_EQ(c.n_ctrl(), 7);
  const Curve cv(c);
  for (int i = 0; i <= 40; ++i) {
    const double u = 2.0 * i / 40;
    const Eigen::Vector2d want = u <= 1 ? piece(0, u) : piece(4, u - 1);
    EXPECT_LT((cv.point(u).head<2>() - want).norm(), 1e-12) << "u = " << u;
  }
  d.entities = {spline(1e-3)};
  const std::string e = error_of(d);
  EXPECT_NE(e.find("err.dxf: entity 1 (SPLINE): "), std::string::npos) << e;
  EXPECT_NE(e.find("multiplicity"), std::string::npos) << e;
}

TEST(DxfReader, UnitsAnd3D) {
  Dxf d;
  d.insunits = 1;
  d.entities = {line(1, 2, 3, 4, 5, 6)};
  Toolpath tp = d.read();
  ASSERT_EQ(tp.moves.size(), 2u);
  EXPECT_EQ(last(tp.moves[0].curve), Eigen::Vector3d(25.4, 50.8, 127));
  EXPECT_LT((last(tp.moves[1].curve) - Eigen::Vector3d(3, 4, 6) * 25.4).norm(), 1e-12);
  ASSERT_EQ(tp.notes.size(), 1u);
  EXPECT_NE(tp.notes[0].find("$INSUNITS 1: drawn in inches, 1 unit = 25.4 mm"), std::string::npos) << tp.notes[0];
  d.insunits = 6;
  tp = d.read();
  EXPECT_EQ(last(tp.moves[0].curve), Eigen::Vector3d(1000, 2000, 5000));
  EXPECT_NE(tp.notes.at(0).find("drawn in metres, 1 unit = 1000 mm"), std::string::npos);
  d.insunits = 0;
  tp = d.read();
  EXPECT_EQ(last(tp.moves[0].curve), Eigen::Vector3d(1, 2, 5));
  ASSERT_EQ(tp.notes.size(), 1u);
  EXPECT_NE(tp.notes[0].find("unitless"), std::string::npos);
  d.insunits = -1;
  EXPECT_NE(d.read().notes.at(0).find("missing"), std::string::npos);
  d.insunits = 3;  // miles
  EXPECT_NE(error_of(d).find("$INSUNITS 3 not supported"), std::string::npos);
}

// INSERT draws its block's entities again: minus the block's base point, scaled, rotated by the
// angle (degrees), moved to the insertion point, per cell of a column/row array (spacing along the
// rotated axes); a block inserted in a block goes through both. End points by hand. A block alone
// (no INSERT) is not drawn; a TEXT is skipped with a note.
TEST(DxfReader, InsertDrawsTheBlock) {
  Dxf d;
  // B1: base (1, 0), a line (1,0)-(3,0); B2: base (0,0), an INSERT of B1 at (0, 10)
  d.blocks = "0\nBLOCK\n8\n0\n2\nB1\n70\n0\n10\n1\n20\n0\n30\n0\n3\nB1\n"
             "0\nLINE\n8\n0\n10\n1\n20\n0\n30\n0\n11\n3\n21\n0\n31\n0\n0\nENDBLK\n8\n0\n"
             "0\nBLOCK\n8\n0\n2\nB2\n70\n0\n10\n0\n20\n0\n30\n0\n3\nB2\n"
             "0\nINSERT\n8\n0\n2\nB1\n10\n0\n20\n10\n30\n0\n0\nENDBLK\n8\n0\n";
  d.entities = {
      // B1 at (100, 0), scale 2, rotated 90 degrees: (x, y) -> (100 - 2 y', 2 x'), x' = x - 1
      {{0, "INSERT"}, {8, "0"}, {2, "B1"}, {10, "100"}, {20, "0"}, {30, "0"}, {41, "2"}, {42, "2"}, {43, "1"}, {50, "90"}},
      {{0, "TEXT"}, {8, "0"}, {10, "0"}, {20, "0"}, {30, "0"}, {40, "1"}, {1, "hi"}},
      // B1 in a 2 x 1 array, column spacing 50, at (0, -20)
      {{0, "INSERT"}, {8, "0"}, {2, "B1"}, {10, "0"}, {20, "-20"}, {30, "0"}, {70, "2"}, {71, "1"}, {44, "50"}},
      // B2 at (0, 100): B1 at (0, 110)
      {{0, "INSERT"}, {8, "0"}, {2, "B2"}, {10, "0"}, {20, "100"}, {30, "0"}},
      line(300, 300, 301, 300)};
  const Toolpath tp = d.read();
  const auto f = feeds(tp);
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> want = {
      {{100, 0, 0}, {100, 4, 0}}, {{0, -20, 0}, {2, -20, 0}}, {{50, -20, 0}, {52, -20, 0}}, {{0, 110, 0}, {2, 110, 0}},
      {{300, 300, 0}, {301, 300, 0}}};
  ASSERT_EQ(f.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_LT((first(f[i]->curve) - want[i].first).norm(), 1e-12) << i << ": " << first(f[i]->curve).transpose();
    EXPECT_LT((last(f[i]->curve) - want[i].second).norm(), 1e-12) << i << ": " << last(f[i]->curve).transpose();
  }
  EXPECT_NE(f[0]->where.find("entity 1 (INSERT) of block B1, its LINE"), std::string::npos) << f[0]->where;
  EXPECT_NE(f[4]->where.find("entity 5 (LINE)"), std::string::npos) << f[4]->where;
  ASSERT_EQ(tp.notes.size(), 1u);
  EXPECT_NE(tp.notes[0].find("TEXT"), std::string::npos);
}

TEST(DxfReader, InsertErrors) {
  auto error_of = [](const Dxf& d) {
    try {
      d.read();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  Dxf d;
  d.entities = {{{0, "INSERT"}, {8, "0"}, {2, "NOPE"}, {10, "0"}, {20, "0"}, {30, "0"}}};
  std::string e = error_of(d);
  EXPECT_NE(e.find("entity 1 (INSERT) of block NOPE: the file has no block NOPE"), std::string::npos) << e;
  // a block that inserts itself
  d.blocks = "0\nBLOCK\n8\n0\n2\nS\n70\n0\n10\n0\n20\n0\n30\n0\n3\nS\n"
             "0\nLINE\n8\n0\n10\n0\n20\n0\n30\n0\n11\n1\n21\n0\n31\n0\n"
             "0\nINSERT\n8\n0\n2\nS\n10\n1\n20\n0\n30\n0\n0\nENDBLK\n8\n0\n";
  d.entities = {{{0, "INSERT"}, {8, "0"}, {2, "S"}, {10, "0"}, {20, "0"}, {30, "0"}}};
  e = error_of(d);
  EXPECT_NE(e.find("blocks inserted in one another deeper than 16 (a block that inserts itself?)"), std::string::npos) << e;
  // arrays: 400 x 300 cells; arrays of arrays: 2 x (300 x 300)
  d.blocks = "0\nBLOCK\n8\n0\n2\nB\n70\n0\n10\n0\n20\n0\n30\n0\n3\nB\n"
             "0\nLINE\n8\n0\n10\n0\n20\n0\n30\n0\n11\n1\n21\n0\n31\n0\n0\nENDBLK\n8\n0\n"
             "0\nBLOCK\n8\n0\n2\nC\n70\n0\n10\n0\n20\n0\n30\n0\n3\nC\n"
             "0\nINSERT\n8\n0\n2\nB\n10\n0\n20\n0\n30\n0\n70\n300\n71\n300\n44\n2\n45\n2\n0\nENDBLK\n8\n0\n";
  d.entities = {{{0, "INSERT"}, {8, "0"}, {2, "B"}, {10, "0"}, {20, "0"}, {30, "0"}, {70, "400"}, {71, "300"}, {44, "2"}, {45, "2"}}};
  e = error_of(d);
  EXPECT_NE(e.find("entity 1 (INSERT) of block B: INSERT array of 400 x 300: out of range"), std::string::npos) << e;
  d.entities = {{{0, "INSERT"}, {8, "0"}, {2, "C"}, {10, "0"}, {20, "0"}, {30, "0"}, {70, "2"}, {44, "1000"}}};
  e = error_of(d);
  EXPECT_NE(e.find("more than 100000 entities drawn by INSERTs"), std::string::npos) << e;
  // blocks of nothing but INSERTs, 10 of the one before in each of 15: 10^15 cells, no entity
  d.blocks = "0\nBLOCK\n8\n0\n2\nA0\n70\n0\n10\n0\n20\n0\n30\n0\n3\nA0\n0\nENDBLK\n8\n0\n";
  for (int k = 1; k <= 15; ++k) {
    const std::string n = "A" + std::to_string(k), prev = "A" + std::to_string(k - 1);
    d.blocks += "0\nBLOCK\n8\n0\n2\n" + n + "\n70\n0\n10\n0\n20\n0\n30\n0\n3\n" + n + "\n";
    for (int i = 0; i < 10; ++i) d.blocks += "0\nINSERT\n8\n0\n2\n" + prev + "\n10\n0\n20\n0\n30\n0\n";
    d.blocks += "0\nENDBLK\n8\n0\n";
  }
  d.entities = {{{0, "INSERT"}, {8, "0"}, {2, "A15"}, {10, "0"}, {20, "0"}, {30, "0"}}, line(0, 0, 1, 0)};
  e = error_of(d);
  EXPECT_NE(e.find("more than 100000 entities drawn by INSERTs"), std::string::npos) << e;
}

TEST(DxfReader, Errors) {
  Dxf fit;
  fit.entities = {line(0, 0, 1, 0),
                  {{0, "SPLINE"}, {8, "0"}, {70, "8"}, {71, "3"}, {72, "0"}, {73, "0"}, {74, "4"},
                   {11, "0"}, {21, "0"}, {31, "0"}, {11, "1"}, {21, "1"}, {31, "0"},
                   {11, "2"}, {21, "0"}, {31, "0"}, {11, "3"}, {21, "1"}, {31, "0"}}};
  std::string e = error_of(fit);
  EXPECT_NE(e.find("err.dxf: entity 2 (SPLINE): a spline given by fit points only"), std::string::npos) << e;
  Dxf knots;
  knots.entities = {{{0, "SPLINE"}, {8, "0"}, {70, "8"}, {71, "1"}, {72, "3"}, {73, "2"}, {74, "0"},
                     {40, "0"}, {40, "0"}, {40, "1"},
                     {10, "0"}, {20, "0"}, {30, "0"}, {10, "1"}, {20, "0"}, {30, "0"}}};
  e = error_of(knots);
  EXPECT_NE(e.find("entity 1 (SPLINE): degree 1, 2 control points need 4 knots, got 3"), std::string::npos) << e;
  Dxf empty;
  EXPECT_NE(error_of(empty).find("err.dxf: no curves"), std::string::npos);
  // an arc whose angle is absurd: refused at once (it once looped whole turns for minutes, a fuzz finding)
  Dxf huge;
  huge.entities = {arc(0, 0, 5, 1e300, 0)};
  e = error_of(huge);
  EXPECT_NE(e.find("entity 1 (ARC): ARC angles"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  try {
    traj::input::read_dxf("/nonexistent/x.dxf");
    FAIL();
  } catch (const InputError& err) {
    EXPECT_STREQ(err.what(), "/nonexistent/x.dxf: cannot open");
  }
}

double length(const BSpline& b) {
  const Curve c(b);
  return traj::geo::ArcLength(c).total();
}

TEST(DxfReader, FileFromAnIndependentWriter) {
  // written by ezdxf (data/ezdxf_sample.py): a closed LWPOLYLINE slot 40 x 20 with half-circle ends
  // (bulge 1), LINE-ARC-LINE with the last line backwards, CIRCLE r 5, ELLIPSE, a rational SPLINE
  // quarter circle r 10, a cubic SPLINE, TEXT
  const Toolpath tp = traj::input::read_dxf(TRAJ_INPUT_DATA "/ezdxf_sample.dxf");
  const auto f = feeds(tp);
  ASSERT_EQ(f.size(), 11u);
  EXPECT_EQ(rapids(tp), 5);
  ASSERT_EQ(tp.notes.size(), 1u);
  EXPECT_NE(tp.notes[0].find("TEXT"), std::string::npos);
  double slot = 0, chain = 0;
  for (int i = 0; i < 4; ++i) slot += length(f[i]->curve);
  for (int i = 4; i < 7; ++i) chain += length(f[i]->curve);
  EXPECT_NEAR(slot, 80 + 20 * kPi, 1e-9);
  EXPECT_NEAR(chain, 40 + 10 * kPi, 1e-9);
  EXPECT_EQ(last(f[6]->curve), Eigen::Vector3d(60, 20, 0));
  EXPECT_NEAR(length(f[7]->curve), 10 * kPi, 1e-9);
  EXPECT_NEAR(length(f[9]->curve), 5 * kPi, 1e-9);
  for (const Eigen::Vector3d& p : samples(f[9]->curve)) EXPECT_NEAR((p - Eigen::Vector3d(150, 0, 0)).norm(), 10, 1e-12);
  // every move starts where the previous one ended
  for (std::size_t i = 1; i < tp.moves.size(); ++i) EXPECT_EQ(first(tp.moves[i].curve), last(tp.moves[i - 1].curve));
}

}  // namespace
