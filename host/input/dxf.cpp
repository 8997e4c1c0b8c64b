// SPDX-License-Identifier: Apache-2.0
#include "input/dxf.hpp"

#include <dl_creationadapter.h>
#include <dl_dxf.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <optional>

#include "input/cuts.hpp"
#include "util/format.hpp"

namespace traj::input {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kJoinTolerance = 1e-6;  // mm: end points closer than this are one joint

// One entity's curves (3-D, drawing units), each starting where the previous ends.
struct Entity {
  std::vector<geo::BSpline> pieces;
  std::string where;
};

// DXF's arbitrary axis algorithm: the object coordinate system's axes (columns) for extrusion n.
Eigen::Matrix3d ocs_axes(const double* dir) {
  Eigen::Vector3d n(dir[0], dir[1], dir[2]);
  if (n.norm() == 0) n = Eigen::Vector3d::UnitZ();
  n.normalize();
  const Eigen::Vector3d ax = (std::abs(n.x()) < 1.0 / 64 && std::abs(n.y()) < 1.0 / 64)
                                 ? Eigen::Vector3d::UnitY().cross(n).normalized()
                                 : Eigen::Vector3d::UnitZ().cross(n).normalized();
  Eigen::Matrix3d m;
  m.col(0) = ax;
  m.col(1) = n.cross(ax);
  m.col(2) = n;
  return m;
}

// A planar 2-D curve at height z of the object coordinate system, in world coordinates.
geo::BSpline lift(const geo::BSpline& c2, double z, const Eigen::Matrix3d& ocs) {
  geo::BSpline c = c2;
  c.ctrl.resize(c2.n_ctrl(), 3);
  for (int i = 0; i < c2.n_ctrl(); ++i)
    c.ctrl.row(i) = (ocs * Eigen::Vector3d(c2.ctrl(i, 0), c2.ctrl(i, 1), z)).transpose();
  return c;
}

// The arc of a polyline segment from p0 to p1 with bulge b (2-D, object coordinates): included
// angle 4 atan(b), counter-clockwise for b > 0; the centre lies c (1 - b^2) / (4 b) to the left of
// the chord's midpoint (c the chord length). End points exactly p0 and p1.
geo::BSpline bulge_arc(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1, double b) {
  const Eigen::Vector2d d = p1 - p0;
  const double chord = d.norm();
  const Eigen::Vector2d left(-d.y() / chord, d.x() / chord);
  const Eigen::Vector2d centre = (p0 + p1) / 2 + left * (chord * (1 - b * b) / (4 * b));
  const double r = chord * (1 + b * b) / (4 * std::abs(b));
  const double a0 = std::atan2(p0.y() - centre.y(), p0.x() - centre.x());
  geo::BSpline arc = geo::make_arc(centre, r, a0, a0 + 4 * std::atan(b));
  arc.ctrl.row(0) = p0.transpose();
  arc.ctrl.row(arc.n_ctrl() - 1) = p1.transpose();
  return arc;
}

struct PendingPolyline {
  int flags = 0;
  double elevation = 0;
  Eigen::Matrix3d ocs = Eigen::Matrix3d::Identity();
  std::vector<DL_VertexData> vertices;
};

struct PendingSpline {
  DL_SplineData data{0, 0, 0, 0, 0};
  std::vector<double> knots;
  std::vector<DL_ControlPointData> ctrl;
  std::size_t fit_points = 0;
};

// A spline written as a chain of Bezier pieces: every interior knot of
// multiplicity degree + 1, each piece starting at the point the last one
// ended on (the dxf library's issue50.dxf: 7 cubic pieces, knots 0 0 0 0
// 0.125 0.125 0.125 0.125 ...). The pieces are independent, so where the two
// points at a break coincide (to 1e-9 of the drawing's size) one knot and one
// of the two points go: the same curve, C0 there. A rational piece keeps its
// shape when all its weights are scaled, so the pieces after the break are
// scaled to carry the first piece's end weight on. A break whose points
// differ is left to geo::validate, which refuses it.
void join_bezier_pieces(geo::BSpline& c) {
  const int p = c.degree;
  const bool rational = c.weights.size() > 0;
  double scale = 1;
  for (Eigen::Index i = 0; i < c.ctrl.rows(); ++i) scale = std::max(scale, c.ctrl.row(i).cwiseAbs().maxCoeff());
  for (Eigen::Index i = c.knots.size() - p - 2; i > p; --i) {
    // a run of p + 1 equal knots U_i .. U_{i+p} strictly inside the knot vector
    Eigen::Index j = i;
    while (j + 1 < c.knots.size() && c.knots[j + 1] == c.knots[i]) ++j;
    if (c.knots[i - 1] == c.knots[i] || j - i != p || j + 1 >= c.knots.size() - p) continue;
    const Eigen::Index n = c.ctrl.rows();
    if (i >= n || (c.ctrl.row(i) - c.ctrl.row(i - 1)).norm() > 1e-9 * scale) continue;
    if (rational) c.weights.tail(n - i) *= c.weights[i - 1] / c.weights[i];
    auto drop = [](auto& m, Eigen::Index k) {  // remove row k (of the points, the weights, the knots)
      const Eigen::Index rows = m.rows() - k - 1;
      m.middleRows(k, rows) = m.bottomRows(rows).eval();
      m.conservativeResize(m.rows() - 1, Eigen::NoChange);
    };
    drop(c.ctrl, i);
    if (rational) drop(c.weights, i);
    drop(c.knots, i);
  }
}

// Collects the entities dxflib reports; polylines and splines arrive in parts and are completed
// when the next entity starts (or at the end).
class Collector : public DL_CreationAdapter {
 public:
  explicit Collector(std::string file) : file_(std::move(file)) {}

  std::vector<Entity> entities;
  std::vector<std::string> notes;
  int insunits = -1;  // -1: not given

  void finish() { flush(); }

  void setVariableInt(const std::string& key, int value, int) override {
    if (key == "$INSUNITS") insunits = value;
  }

  void addBlock(const DL_BlockData& d) override {
    flush();
    in_block_ = true;
    block_ = d.name;
    blocks_[block_].base = Eigen::Vector3d(d.bpx, d.bpy, d.bpz);
  }
  void endBlock() override {
    flush();
    in_block_ = false;
  }

  void addLine(const DL_LineData& d) override {
    begin("LINE");
    add({geo::make_line(Eigen::Vector3d(d.x1, d.y1, d.z1), Eigen::Vector3d(d.x2, d.y2, d.z2))});
  }
  void addArc(const DL_ArcData& d) override {
    begin("ARC");
    const double a0 = d.angle1 * kPi / 180;
    circle_arc(d.cx, d.cy, d.cz, d.radius, a0, ccw_end(a0, d.angle2 * kPi / 180, "ARC"), false);
  }
  void addCircle(const DL_CircleData& d) override {
    begin("CIRCLE");
    circle_arc(d.cx, d.cy, d.cz, d.radius, 0, 2 * kPi, true);
  }
  void addEllipse(const DL_EllipseData& d) override {
    begin("ELLIPSE");
    const Eigen::Vector3d c(d.cx, d.cy, d.cz), major(d.mx, d.my, d.mz);
    const Eigen::Vector3d n = ocs_axes(getExtrusion()->getDirection()).col(2);
    const Eigen::Vector3d minor = d.ratio * n.cross(major);
    const double t1 = ccw_end(d.angle1, d.angle2, "ELLIPSE");
    const bool full = std::abs(t1 - d.angle1 - 2 * kPi) < 1e-12;
    const geo::BSpline unit = geo::make_arc(Eigen::Vector2d(0, 0), 1.0, d.angle1, full ? d.angle1 + 2 * kPi : t1);
    geo::BSpline e = unit;
    e.ctrl.resize(unit.n_ctrl(), 3);
    for (int i = 0; i < unit.n_ctrl(); ++i) e.ctrl.row(i) = (c + unit.ctrl(i, 0) * major + unit.ctrl(i, 1) * minor).transpose();
    if (full) e.ctrl.row(e.n_ctrl() - 1) = e.ctrl.row(0);
    add({e});
  }
  void addPolyline(const DL_PolylineData& d) override {
    begin("POLYLINE");
    if (d.flags & (16 | 64)) {
      fail("polygon meshes and polyface meshes are not supported");
    }
    polyline_ = PendingPolyline{d.flags, d.elevation, ocs_axes(getExtrusion()->getDirection()), {}};
  }
  void addVertex(const DL_VertexData& d) override {
    if (polyline_) polyline_->vertices.push_back(d);
  }
  void endSequence() override { flush(); }
  void addSpline(const DL_SplineData& d) override {
    begin("SPLINE");
    spline_ = PendingSpline{d, {}, {}, 0};
  }
  void addKnot(const DL_KnotData& d) override {
    if (spline_) spline_->knots.push_back(d.k);
  }
  void addControlPoint(const DL_ControlPointData& d) override {
    if (spline_) spline_->ctrl.push_back(d);
  }
  void addFitPoint(const DL_FitPointData&) override {
    if (spline_) ++spline_->fit_points;
  }

  // Entities not drawn: counted (for entity numbers) and noted once per type.
  void addPoint(const DL_PointData&) override { skip("POINT"); }
  void addXLine(const DL_XLineData&) override { skip("XLINE"); }
  void addRay(const DL_RayData&) override { skip("RAY"); }
  // INSERT: the block's entities drawn again (block_transform); inside a block, kept for when that
  // block is drawn (blocks may be defined in any order).
  void addInsert(const DL_InsertData& d) override {
    const Eigen::Matrix3d ocs = ocs_axes(getExtrusion()->getDirection());
    begin("INSERT");
    if (in_block_) {
      blocks_[block_].items.push_back({{}, "", std::make_shared<Insert>(Insert{d, ocs})});
      return;
    }
    where_ += " of block " + util::excerpt(d.name);
    expand(Insert{d, ocs}, Affine3::Identity(), where_, 0);
  }
  void addTrace(const DL_TraceData&) override { skip("TRACE"); }
  void add3dFace(const DL_3dFaceData&) override { skip("3DFACE"); }
  void addSolid(const DL_SolidData&) override { skip("SOLID"); }
  void addMText(const DL_MTextData&) override { skip("MTEXT"); }
  void addText(const DL_TextData&) override { skip("TEXT"); }
  void addArcAlignedText(const DL_ArcAlignedTextData&) override { skip("ARCALIGNEDTEXT"); }
  void addAttribute(const DL_AttributeData&) override { skip("ATTRIB"); }
  void addDimAlign(const DL_DimensionData&, const DL_DimAlignedData&) override { skip("DIMENSION"); }
  void addDimLinear(const DL_DimensionData&, const DL_DimLinearData&) override { skip("DIMENSION"); }
  void addDimRadial(const DL_DimensionData&, const DL_DimRadialData&) override { skip("DIMENSION"); }
  void addDimDiametric(const DL_DimensionData&, const DL_DimDiametricData&) override { skip("DIMENSION"); }
  void addDimAngular(const DL_DimensionData&, const DL_DimAngular2LData&) override { skip("DIMENSION"); }
  void addDimAngular3P(const DL_DimensionData&, const DL_DimAngular3PData&) override { skip("DIMENSION"); }
  void addDimOrdinate(const DL_DimensionData&, const DL_DimOrdinateData&) override { skip("DIMENSION"); }
  void addLeader(const DL_LeaderData&) override { skip("LEADER"); }
  void addHatch(const DL_HatchData&) override { skip("HATCH"); }
  void addImage(const DL_ImageData&) override { skip("IMAGE"); }

 private:
  // The end angle of a counter-clockwise sweep from a0 to a1, in (a0, a0 + 2 pi]
  // (a file's angles may be any size: no loop of whole turns).
  double ccw_end(double a0, double a1, const char* type) {
    if (!std::isfinite(a0) || !std::isfinite(a1) || std::abs(a0) > 1e9 || std::abs(a1) > 1e9)
      fail(std::string(type) + " angles " + util::num(a0) + ", " + util::num(a1) + " rad: out of range (not a number, or above 1e9)");
    double span = std::fmod(a1 - a0, 2 * kPi);
    if (span <= 0) span += 2 * kPi;
    return a0 + span;
  }
  // Starts a new entity (inside a block definition its curves go to the block, drawn by the INSERTs
  // of it; where_ is then its type, named after the INSERT's).
  void begin(const char* type) {
    flush();
    if (in_block_) {
      where_ = type;
      return;
    }
    ++count_;
    where_ = file_ + ": entity " + std::to_string(count_) + " (" + type + ")";
  }
  void skip(const std::string& type, const std::string& why = "") {
    begin(type.c_str());
    if (std::find(noted_.begin(), noted_.end(), type) != noted_.end()) return;
    noted_.push_back(type);
    notes.push_back((in_block_ ? file_ + ": block " + util::excerpt(block_) : where_) + ": " + type + " entities skipped" + why);
  }
  [[noreturn]] void fail(const std::string& why) const { throw InputError(where_ + ": " + why); }

  void add(std::vector<geo::BSpline> pieces) {
    std::vector<geo::BSpline> kept;
    for (geo::BSpline& p : pieces)
      if (!degenerate(p)) kept.push_back(std::move(p));
    if (kept.empty()) return;
    if (in_block_) blocks_[block_].items.push_back({std::move(kept), where_, nullptr});
    else entities.push_back({std::move(kept), where_});
  }

  using Affine3 = Eigen::Matrix4d;
  struct Insert {
    DL_InsertData data;
    Eigen::Matrix3d ocs;
  };
  // A block's entity (its curves in block coordinates, its type) or an INSERT in it.
  struct BlockItem {
    std::vector<geo::BSpline> pieces;
    std::string type;
    std::shared_ptr<Insert> insert;
  };
  struct Block {
    Eigen::Vector3d base = Eigen::Vector3d::Zero();
    std::vector<BlockItem> items;
  };
  static constexpr int kMaxInsertDepth = 16;
  static constexpr long kMaxInserted = 100000;  // entities and array cells drawn by INSERTs (they multiply)

  // The block's entities through `parent` and the INSERT's own placement, per array cell: world =
  // parent * ocs * translate(insertion point) * rotate(angle) * translate(cell) * scale * translate(-base).
  void expand(const Insert& ins, const Affine3& parent, const std::string& where, int depth) {
    const DL_InsertData& d = ins.data;
    const auto it = blocks_.find(d.name);
    if (it == blocks_.end()) fail("the file has no block " + util::excerpt(d.name));
    if (depth >= kMaxInsertDepth)
      fail("blocks inserted in one another deeper than " + std::to_string(kMaxInsertDepth) + " (a block that inserts itself?)");
    if (!(d.cols >= 1 && d.rows >= 1) || double(d.cols) * d.rows > kMaxInserted)
      fail("INSERT array of " + std::to_string(d.cols) + " x " + std::to_string(d.rows) + ": out of range");
    // each cell counts too: blocks of nothing but INSERTs multiply without drawing
    if ((inserted_ += long(d.cols) * d.rows) > kMaxInserted)
      fail("more than " + std::to_string(kMaxInserted) + " entities drawn by INSERTs (arrays of blocks multiply)");
    const Block& b = it->second;
    Affine3 ocs = Affine3::Identity(), rot = Affine3::Identity(), scale = Affine3::Identity(), base = Affine3::Identity();
    ocs.topLeftCorner<3, 3>() = ins.ocs;
    const double a = d.angle * kPi / 180;
    rot.topLeftCorner<2, 2>() << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
    rot.topRightCorner<3, 1>() = Eigen::Vector3d(d.ipx, d.ipy, d.ipz);
    scale.diagonal().head<3>() = Eigen::Vector3d(d.sx, d.sy, d.sz);
    base.topRightCorner<3, 1>() = -b.base;
    for (int r = 0; r < d.rows; ++r)
      for (int c = 0; c < d.cols; ++c) {
        Affine3 cell = Affine3::Identity();
        cell.topRightCorner<3, 1>() = Eigen::Vector3d(c * d.colSp, r * d.rowSp, 0);
        const Affine3 m = parent * ocs * rot * cell * scale * base;
        for (const BlockItem& item : b.items) {
          if (item.insert) {
            expand(*item.insert, m, where, depth + 1);
            continue;
          }
          if (++inserted_ > kMaxInserted)
            fail("more than " + std::to_string(kMaxInserted) + " entities drawn by INSERTs (arrays of blocks multiply)");
          std::vector<geo::BSpline> pieces = item.pieces;
          for (geo::BSpline& p : pieces)
            for (int i = 0; i < p.n_ctrl(); ++i) {
              const Eigen::Vector4d q = m * Eigen::Vector4d(p.ctrl(i, 0), p.ctrl(i, 1), p.ctrl(i, 2), 1);
              p.ctrl.row(i) = q.head<3>().transpose();
            }
          entities.push_back({std::move(pieces), where + ", its " + item.type});
        }
      }
  }

  void circle_arc(double cx, double cy, double cz, double r, double a0, double a1, bool closed) {
    if (!(r > 0)) return;
    const Eigen::Matrix3d ocs = ocs_axes(getExtrusion()->getDirection());
    geo::BSpline arc = lift(geo::make_arc(Eigen::Vector2d(cx, cy), r, a0, a1), cz, ocs);
    if (closed) arc.ctrl.row(arc.n_ctrl() - 1) = arc.ctrl.row(0);
    add({arc});
  }

  void flush() {
    if (polyline_) finish_polyline();
    if (spline_) finish_spline();
  }

  void finish_polyline() {
    PendingPolyline pl = std::move(*polyline_);
    polyline_.reset();
    const bool closed = pl.flags & 1, three_d = pl.flags & 8;
    const std::size_t n = pl.vertices.size();
    std::vector<geo::BSpline> pieces;
    const std::size_t segments = closed ? n : (n > 0 ? n - 1 : 0);
    for (std::size_t i = 0; i < segments && n > 1; ++i) {
      const DL_VertexData& a = pl.vertices[i];
      const DL_VertexData& b = pl.vertices[(i + 1) % n];
      if (three_d) {
        pieces.push_back(geo::make_line(Eigen::Vector3d(a.x, a.y, a.z), Eigen::Vector3d(b.x, b.y, b.z)));
        continue;
      }
      const Eigen::Vector2d p0(a.x, a.y), p1(b.x, b.y);
      if (p0 == p1) continue;
      const double z = pl.elevation != 0 ? pl.elevation : a.z;
      pieces.push_back(lift(a.bulge == 0 ? geo::make_line(p0, p1) : bulge_arc(p0, p1, a.bulge), z, pl.ocs));
    }
    // consecutive pieces share their vertex exactly (the same doubles through the same map)
    add(std::move(pieces));
  }

  void finish_spline() {
    PendingSpline sp = std::move(*spline_);
    spline_.reset();
    if (sp.ctrl.empty()) {
      if (sp.fit_points > 0)
        fail("a spline given by fit points only (no control points) is not supported: convert it to control points in the CAD program");
      fail("a spline without control points");
    }
    const int p = static_cast<int>(sp.data.degree);
    const std::size_t n = sp.ctrl.size();
    if (sp.knots.size() != n + p + 1)
      fail("degree " + std::to_string(p) + ", " + std::to_string(n) + " control points need " +
           std::to_string(n + p + 1) + " knots, got " + std::to_string(sp.knots.size()));
    geo::BSpline c;
    c.degree = p;
    c.ctrl.resize(static_cast<Eigen::Index>(n), 3);
    c.knots = Eigen::Map<const Eigen::VectorXd>(sp.knots.data(), static_cast<Eigen::Index>(sp.knots.size()));
    bool rational = false;
    Eigen::VectorXd w(static_cast<Eigen::Index>(n));
    for (std::size_t i = 0; i < n; ++i) {
      c.ctrl.row(static_cast<Eigen::Index>(i)) << sp.ctrl[i].x, sp.ctrl[i].y, sp.ctrl[i].z;
      w[static_cast<Eigen::Index>(i)] = sp.ctrl[i].w;
      rational = rational || sp.ctrl[i].w != 1.0;
    }
    if (rational) c.weights = w;
    join_bezier_pieces(c);
    try {
      geo::validate(c, "spline");
      c = geo::clamp(c);
    } catch (const std::exception& e) {
      fail(e.what());
    }
    add({c});
  }

  std::string file_;
  std::string where_;
  int count_ = 0;
  bool in_block_ = false;
  std::string block_;  // the block being defined
  std::map<std::string, Block> blocks_;
  long inserted_ = 0;
  std::vector<std::string> noted_;
  std::optional<PendingPolyline> polyline_;
  std::optional<PendingSpline> spline_;
};

// mm per drawing unit for $INSUNITS; a note for unitless drawings.
double units_to_mm(int insunits, const std::string& file, std::vector<std::string>& notes) {
  // a drawing in other units than mm says so (a part drawn in metres may land far from the origin)
  auto scaled = [&](double k, const char* name) {
    notes.push_back(file + ": $INSUNITS " + std::to_string(insunits) + ": drawn in " + name + ", 1 unit = " +
                    util::fmt("%g", k) + " mm");
    return k;
  };
  switch (insunits) {
    case 1: return scaled(25.4, "inches");
    case 2: return scaled(304.8, "feet");
    case 4: return 1.0;
    case 5: return scaled(10.0, "centimetres");
    case 6: return scaled(1000.0, "metres");
    case -1:
    case 0:
      notes.push_back(file + ": $INSUNITS " + (insunits < 0 ? "missing" : "0 (unitless)") + ": taken as millimetres");
      return 1.0;
    default:
      throw InputError(file + ": $INSUNITS " + std::to_string(insunits) +
                       " not supported (known: 1 inches, 2 feet, 4 mm, 5 cm, 6 m, 0 unitless)");
  }
}

void scale(Entity& e, double k) {
  for (geo::BSpline& c : e.pieces) c.ctrl *= k;
}

// End points of the entities, sorted by x, to find those within the join tolerance of a point.
class EndIndex {
 public:
  explicit EndIndex(const std::vector<Entity>& es) {
    for (std::size_t i = 0; i < es.size(); ++i) {
      ends_.push_back({start_point(es[i].pieces.front()), i, false});
      ends_.push_back({end_point(es[i].pieces.back()), i, true});
    }
    std::sort(ends_.begin(), ends_.end(), [](const End& a, const End& b) { return a.p.x() < b.p.x(); });
  }
  // The unused entity with the lowest index that has an end at p: (index, that end is its last point).
  std::optional<std::pair<std::size_t, bool>> find(const Eigen::VectorXd& p, const std::vector<bool>& used) const {
    auto it = std::lower_bound(ends_.begin(), ends_.end(), p.x() - kJoinTolerance,
                               [](const End& e, double x) { return e.p.x() < x; });
    std::optional<std::pair<std::size_t, bool>> best;
    for (; it != ends_.end() && it->p.x() <= p.x() + kJoinTolerance; ++it)
      if (!used[it->entity] && (it->p - p).norm() <= kJoinTolerance && (!best || it->entity < best->first))
        best = std::make_pair(it->entity, it->last);
    return best;
  }

 private:
  struct End {
    Eigen::VectorXd p;
    std::size_t entity;
    bool last;
  };
  std::vector<End> ends_;
};

std::vector<CutPiece> pieces_of(const Entity& e, bool backwards) {
  std::vector<CutPiece> out;
  for (const geo::BSpline& c : e.pieces) out.push_back({backwards ? reversed(c) : c, e.where});
  if (backwards) std::reverse(out.begin(), out.end());
  return out;
}

// Chains entities that meet end to end into cuts (see dxf.hpp).
std::vector<Cut> chain(const std::vector<Entity>& es) {
  const EndIndex index(es);
  std::vector<bool> used(es.size(), false);
  std::vector<Cut> cuts;
  for (std::size_t i = 0; i < es.size(); ++i) {
    if (used[i]) continue;
    used[i] = true;
    Cut cut = pieces_of(es[i], false);
    auto closed = [&] { return (end_point(cut.back().curve) - start_point(cut.front().curve)).norm() <= kJoinTolerance; };
    // forward from the end: an entity starting here runs forwards, one ending here backwards
    while (!closed()) {
      const auto next = index.find(end_point(cut.back().curve), used);
      if (!next) break;
      used[next->first] = true;
      for (CutPiece& p : pieces_of(es[next->first], next->second)) cut.push_back(std::move(p));
    }
    // backward from the start
    while (!closed()) {
      const auto prev = index.find(start_point(cut.front().curve), used);
      if (!prev) break;
      used[prev->first] = true;
      std::vector<CutPiece> before = pieces_of(es[prev->first], !prev->second);
      cut.insert(cut.begin(), before.begin(), before.end());
    }
    // close the joints exactly
    for (std::size_t k = 1; k < cut.size(); ++k) cut[k].curve.ctrl.row(0) = cut[k - 1].curve.ctrl.row(cut[k - 1].curve.n_ctrl() - 1);
    cuts.push_back(std::move(cut));
  }
  return cuts;
}

}  // namespace

Toolpath read_dxf(const std::string& file) {
  if (!std::ifstream(file)) throw InputError(file + ": cannot open");
  Collector collector(file);
  DL_Dxf dxf;
  if (!dxf.in(file, &collector)) throw InputError(file + ": cannot open or read as DXF");
  collector.finish();
  std::vector<std::string> notes;
  const double k = units_to_mm(collector.insunits, file, notes);
  if (collector.entities.empty())
    throw InputError(file + ": no curves: no LINE, ARC, CIRCLE, ELLIPSE, LWPOLYLINE, POLYLINE or SPLINE with any length");
  for (Entity& e : collector.entities) scale(e, k);
  Toolpath tp = toolpath_from_cuts(chain(collector.entities), 3);
  tp.notes = notes;
  tp.notes.insert(tp.notes.end(), collector.notes.begin(), collector.notes.end());
  return tp;
}

}  // namespace traj::input
