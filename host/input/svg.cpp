// SPDX-License-Identifier: Apache-2.0
#include "input/svg.hpp"

#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "input/cuts.hpp"
#include "input/svg_path.hpp"
#include "util/format.hpp"

namespace traj::input {
namespace {

using svg::Affine;
using svg::PathDataError;
using svg::Subpath;

// An attribute the reader cannot use (units, sizes); path data errors are PathDataError (with offset).
class BadAttribute : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

constexpr double kPi = 3.14159265358979323846;
constexpr double kMmPerPx = 25.4 / 96.0;
constexpr int kMaxDepth = 200;
constexpr long kMaxShapes = 1000000;  // shapes drawn, clones included (a file of a few lines can clone 10^10)

std::string local_name(const char* name) {
  const std::string n = name;
  const std::size_t colon = n.find(':');
  return colon == std::string::npos ? n : n.substr(colon + 1);
}

bool foreign_namespace(const char* name) {
  const std::string n = name;
  const std::size_t colon = n.find(':');
  return colon != std::string::npos && n.substr(0, colon) != "svg";
}

std::string attr(const tinyxml2::XMLElement* e, const char* name) {
  const char* v = e->Attribute(name);
  return v ? v : "";
}

std::string trim(const std::string& s) {
  const std::size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

// The value of `property` in the element's presentation attribute or style="...; property: v".
std::string property(const tinyxml2::XMLElement* e, const std::string& name) {
  std::string value = trim(attr(e, name.c_str()));
  std::stringstream style(attr(e, "style"));
  std::string decl;
  while (std::getline(style, decl, ';')) {
    const std::size_t colon = decl.find(':');
    if (colon != std::string::npos && trim(decl.substr(0, colon)) == name) value = trim(decl.substr(colon + 1));
  }
  return value;
}

// A length in px (user units of the root without viewBox). Units: none, px, mm, cm, in, pt, pc, Q.
struct Length {
  double value = 0;
  std::string unit;
};

Length split_length(const std::string& text, const std::string& what) {
  try {
    const auto [v, unit] = svg::parse_length(text);
    return {v, unit};
  } catch (const PathDataError&) {
    throw BadAttribute(what + ": '" + util::excerpt(text) + "' is not a length");
  }
}

double px_per_unit(const std::string& unit, const std::string& what) {
  if (unit.empty() || unit == "px") return 1.0;
  if (unit == "mm") return 96.0 / 25.4;
  if (unit == "cm") return 960.0 / 25.4;
  if (unit == "in") return 96.0;
  if (unit == "pt") return 96.0 / 72.0;
  if (unit == "pc") return 16.0;
  if (unit == "Q") return 96.0 / 101.6;
  throw BadAttribute(what + ": unknown unit '" + util::excerpt(unit) + "' (known: mm, cm, in, pt, pc, px, Q)");
}

// The length a percentage of attribute `name` refers to: the viewport's width (x, cx, rx, width, ...),
// height (y, cy, ry, height, ...) or, for r, its normalised diagonal sqrt((w^2 + h^2) / 2), in user
// units; NaN if the viewport is unknown.
double percent_base(const std::string& name, const Eigen::Vector2d& viewport) {
  if (name == "r") return std::sqrt(viewport.squaredNorm() / 2);
  const bool vertical = name.find('y') != std::string::npos || name == "height";
  return vertical ? viewport.y() : viewport.x();
}

// A coordinate attribute of a shape in user units (0 if absent); percentages of the root viewport.
double coordinate(const tinyxml2::XMLElement* e, const char* name, const Eigen::Vector2d& viewport) {
  const char* v = e->Attribute(name);
  if (!v || trim(v).empty()) return 0;
  const Length l = split_length(v, name);
  if (l.unit != "%") return l.value * px_per_unit(l.unit, name);
  const double base = percent_base(name, viewport);
  if (std::isnan(base)) throw BadAttribute(std::string(name) + ": a percentage, but the root has no size or viewBox");
  return l.value / 100 * base;
}

void add_segment(Subpath& sp, geo::BSpline c) {
  if (c.n_ctrl() > 0 && !degenerate(c)) sp.segments.push_back(std::move(c));
}

std::vector<Subpath> polyline(const std::vector<double>& xy, bool close) {
  if (xy.size() % 2 != 0) throw BadAttribute("points: odd number of coordinates");
  Subpath sp;
  const std::size_t n = xy.size() / 2;
  for (std::size_t i = 1; i < n; ++i)
    add_segment(sp, geo::make_line(Eigen::Vector2d(xy[2 * i - 2], xy[2 * i - 1]), Eigen::Vector2d(xy[2 * i], xy[2 * i + 1])));
  if (close && n > 1)
    add_segment(sp, geo::make_line(Eigen::Vector2d(xy[2 * n - 2], xy[2 * n - 1]), Eigen::Vector2d(xy[0], xy[1])));
  sp.closed = close;
  return {sp};
}

// The whole ellipse from parametric angle 0, in the positive angle direction (SVG's shape-to-path
// rule for circle and ellipse), exactly closed.
std::vector<Subpath> ellipse(double cx, double cy, double rx, double ry) {
  if (rx <= 0 || ry <= 0) return {};
  Subpath sp;
  geo::BSpline c = svg::ellipse_arc({cx, cy}, rx, ry, 0, 0, 2 * kPi);
  c.ctrl.row(c.n_ctrl() - 1) = c.ctrl.row(0);
  sp.segments.push_back(std::move(c));
  sp.closed = true;
  return {sp};
}

// SVG 2's rect-to-path rule: from (x + rx, y) clockwise on screen, corners as elliptical arcs.
std::vector<Subpath> rect(const tinyxml2::XMLElement* e, const Eigen::Vector2d& vs) {
  const double x = coordinate(e, "x", vs), y = coordinate(e, "y", vs);
  const double w = coordinate(e, "width", vs), h = coordinate(e, "height", vs);
  if (w < 0 || h < 0) throw BadAttribute("negative width or height");
  if (w == 0 || h == 0) return {};
  const bool has_rx = e->Attribute("rx") != nullptr, has_ry = e->Attribute("ry") != nullptr;
  double rx = coordinate(e, "rx", vs), ry = coordinate(e, "ry", vs);
  if (has_rx && !has_ry) ry = rx;
  if (has_ry && !has_rx) rx = ry;
  rx = std::min(std::abs(rx), w / 2);
  ry = std::min(std::abs(ry), h / 2);
  const bool round = rx > 0 && ry > 0;
  if (!round) rx = ry = 0;
  Subpath sp;
  const Eigen::Vector2d p[8] = {{x + rx, y}, {x + w - rx, y}, {x + w, y + ry}, {x + w, y + h - ry},
                                {x + w - rx, y + h}, {x + rx, y + h}, {x, y + h - ry}, {x, y + ry}};
  for (int i = 0; i < 8; i += 2) {
    add_segment(sp, geo::make_line(p[i], p[i + 1]));
    const Eigen::Vector2d& next = p[(i + 2) % 8];
    if (round) add_segment(sp, svg::arc_segment(p[i + 1], rx, ry, 0, false, true, next));
  }
  sp.closed = true;
  return {sp};
}

// `vs`: the root viewport's size in user units (percentages), NaN where unknown.
std::vector<Subpath> shape_subpaths(const tinyxml2::XMLElement* e, const std::string& tag, const Eigen::Vector2d& vs) {
  if (tag == "path") {
    try {
      return svg::parse_path_data(attr(e, "d"));
    } catch (const PathDataError& err) {
      throw BadAttribute(std::string("d: ") + err.what());
    }
  }
  if (tag == "line")
    return polyline({coordinate(e, "x1", vs), coordinate(e, "y1", vs), coordinate(e, "x2", vs), coordinate(e, "y2", vs)}, false);
  if (tag == "polyline" || tag == "polygon") {
    try {
      return polyline(svg::parse_number_list(attr(e, "points")), tag == "polygon");
    } catch (const PathDataError& err) {
      throw BadAttribute(std::string("points: ") + err.what());
    }
  }
  if (tag == "rect") return rect(e, vs);
  if (tag == "circle") {
    const double r = coordinate(e, "r", vs);
    return ellipse(coordinate(e, "cx", vs), coordinate(e, "cy", vs), r, r);
  }
  // ellipse
  return ellipse(coordinate(e, "cx", vs), coordinate(e, "cy", vs), coordinate(e, "rx", vs), coordinate(e, "ry", vs));
}

const std::set<std::string> kShapes = {"path", "line", "polyline", "polygon", "rect", "circle", "ellipse"};
const std::set<std::string> kGroups = {"g", "a"};
const std::set<std::string> kNotDrawn = {"defs", "symbol", "clipPath", "mask", "marker", "pattern",
                                         "linearGradient", "radialGradient", "style", "title", "desc",
                                         "metadata", "script", "filter", "font", "font-face", "cursor", "view"};

// The inherited painting properties that decide whether a shape is seen:
// fill (initially black), stroke (initially none), visibility. A shape with
// neither fill nor stroke, or hidden, draws nothing (icon sets frame every
// icon with such a path: tabler-icons' <path stroke="none" d="M0 0h24v24H0z"
// fill="none"/>), so it is not cut.
struct Paint {
  bool fill = true, stroke = false, visible = true;
  // `e`'s own values over the inherited ones ("inherit" and absent keep them)
  Paint under(const tinyxml2::XMLElement* e) const {
    Paint p = *this;
    auto paint = [&](const char* name, bool& on) {
      const std::string v = property(e, name);
      if (!v.empty() && v != "inherit") on = v != "none";
    };
    paint("fill", p.fill);
    paint("stroke", p.stroke);
    const std::string vis = property(e, "visibility");
    if (vis == "hidden" || vis == "collapse") p.visible = false;
    if (vis == "visible") p.visible = true;
    return p;
  }
};

// Walks the element tree, collecting one cut per subpath.
class Walker {
 public:
  Walker(std::string name, Affine page, Eigen::Vector2d viewport, const tinyxml2::XMLElement* root)
      : name_(std::move(name)), page_(std::move(page)), viewport_(std::move(viewport)) {
    index_ids(root);
  }

  // `paint`: the properties the children inherit (the parent's own applied)
  void children(const tinyxml2::XMLElement* parent, const Affine& ctm, const Paint& paint, int depth) {
    for (const tinyxml2::XMLElement* e = parent->FirstChildElement(); e; e = e->NextSiblingElement())
      element(e, ctm, paint, depth + 1);
  }

  std::vector<Cut> cuts;
  std::vector<std::string> notes;
  int shapes = 0;

 private:
  [[noreturn]] void fail(const std::string& where, const std::string& why) const {
    throw InputError(name_ + ": " + where + ": " + why);
  }

  // The element named in messages: its tag and id as excerpts (a file's
  // names can be of any length; a message stays one line).
  std::string label(const tinyxml2::XMLElement* e, const std::string& tag, int index) const {
    const char* id = e->Attribute("id");
    const std::string t = util::excerpt(tag);
    if (id) return t + " " + util::excerpt(id);
    return index > 0 ? t + " #" + std::to_string(index) : t + " without id";
  }

  void note_once(const std::string& kind, const std::string& text) {
    if (noted_.insert(kind).second) notes.push_back(name_ + ": " + text);
  }

  // `used`: drawn through a <use> (the element may be in <defs>).
  void element(const tinyxml2::XMLElement* e, const Affine& parent_ctm, const Paint& inherited, int depth,
               bool used = false) {
    if (foreign_namespace(e->Name())) return;
    const std::string tag = local_name(e->Name());
    if (kNotDrawn.count(tag) && !used) return;
    const bool shape = kShapes.count(tag) > 0;
    // shapes are numbered in document order; a clone's shape is named by its own id or the <use>'s
    const std::string where = label(e, tag, shape && !cloning_ ? shapes + 1 : 0);
    if (shape && !cloning_) ++shapes;
    if (shape && ++drawn_ > kMaxShapes)
      fail(where, "more than " + std::to_string(kMaxShapes) + " shapes to draw (clones of clones multiply: <use>)");
    if (depth > kMaxDepth) fail(where, "elements nested deeper than " + std::to_string(kMaxDepth));
    if (property(e, "display") == "none") {
      note_once("hidden", "elements with display:none (hidden layers) skipped, first " + where);
      return;
    }
    const Paint paint = inherited.under(e);
    if (tag == "use") {
      use(e, where, parent_ctm, paint, depth);
      return;
    }
    if (tag == "svg") fail(where, "nested <svg> elements are not supported");
    if (!shape && !kGroups.count(tag)) {
      note_once(tag, "<" + util::excerpt(tag) + "> not converted (first " + where + "; Inkscape: Path > Object to Path)");
      return;
    }
    const Affine ctm = transformed(e, parent_ctm, where);
    if (!shape) {
      children(e, ctm, paint, depth);
      return;
    }
    // a <style> sheet (not read) may paint or hide by class: then every shape is cut
    if (!stylesheet_ && !paint.visible) {
      note_once("invisible", "elements with visibility:hidden skipped, first " + where);
      return;
    }
    if (!stylesheet_ && !paint.fill && !paint.stroke) {
      note_once("unpainted", "shapes with neither fill nor stroke (not drawn) skipped, first " + where);
      return;
    }
    std::vector<Subpath> subpaths;
    try {
      subpaths = shape_subpaths(e, tag, viewport_);
    } catch (const std::runtime_error& err) {  // PathDataError, BadAttribute, geometry errors
      fail(where, err.what());
    }
    const Affine m = page_ * ctm;
    for (Subpath& sp : subpaths) {
      Cut cut;
      for (geo::BSpline& seg : sp.segments) cut.push_back({svg::transformed(seg, m), name_ + ": " + where});
      cuts.push_back(std::move(cut));
    }
  }

  // The element's coordinates: its transform attribute after its parent's.
  Affine transformed(const tinyxml2::XMLElement* e, const Affine& parent_ctm, const std::string& where) const {
    try {
      if (const char* t = e->Attribute("transform")) return parent_ctm * svg::parse_transform(t);
    } catch (const PathDataError& err) {
      fail(where, std::string("transform: ") + err.what());
    }
    return parent_ctm;
  }

  void index_ids(const tinyxml2::XMLElement* parent) {
    for (const tinyxml2::XMLElement* e = parent->FirstChildElement(); e; e = e->NextSiblingElement()) {
      if (const char* id = e->Attribute("id")) ids_.emplace(id, e);  // the first of a repeated id, as browsers
      if (local_name(e->Name()) == "style") stylesheet_ = true;
      index_ids(e);
    }
  }

  // <use href="#id" x y transform>: the element drawn again, in the use's
  // coordinates: its transform, then a translation by (x, y) (SVG 1.1, 5.6).
  // A <symbol> is drawn as a group (width, height and a viewBox of its own
  // are refused); other files (href to another document) are refused.
  void use(const tinyxml2::XMLElement* e, const std::string& where, const Affine& parent_ctm, const Paint& paint,
           int depth) {
    const char* h = e->Attribute("href");
    if (!h) h = e->Attribute("xlink:href");
    if (!h) fail(where, "<use> without href");
    const std::string href = trim(h);
    if (href.empty() || href[0] != '#') fail(where, "<use> of '" + util::excerpt(href) + "': only #id (an element of this file) is followed");
    const auto it = ids_.find(href.substr(1));
    if (it == ids_.end()) fail(where, "<use> of " + util::excerpt(href) + ": the file has no element with that id");
    const tinyxml2::XMLElement* ref = it->second;
    for (const tinyxml2::XMLNode* a = e; a; a = a->Parent())
      if (a == ref) fail(where, "<use> of " + util::excerpt(href) + ": it contains the <use> itself");
    if (!active_.insert(ref).second) fail(where, "<use> of " + util::excerpt(href) + ": the clones refer to each other in a cycle");
    Affine ctm = transformed(e, parent_ctm, where);
    Affine shift = Affine::Identity();
    try {
      shift(0, 2) = coordinate(e, "x", viewport_);
      shift(1, 2) = coordinate(e, "y", viewport_);
    } catch (const std::runtime_error& err) {
      fail(where, err.what());
    }
    ctm = ctm * shift;
    const bool was_cloning = cloning_;
    cloning_ = true;
    if (local_name(ref->Name()) == "symbol") {
      if (ref->Attribute("viewBox") || ref->Attribute("width") || ref->Attribute("height"))
        fail(where, "<use> of a <symbol> with its own viewBox or size is not supported");
      children(ref, ctm, paint.under(ref), depth);
    } else {
      element(ref, ctm, paint, depth + 1, true);
    }
    cloning_ = was_cloning;
    active_.erase(ref);
  }

  std::string name_;
  Affine page_;
  Eigen::Vector2d viewport_;
  std::set<std::string> noted_;
  std::map<std::string, const tinyxml2::XMLElement*> ids_;
  std::set<const tinyxml2::XMLElement*> active_;  // the elements being drawn through <use>, for cycles
  bool cloning_ = false;                          // drawing through a <use>
  bool stylesheet_ = false;                       // the file has a <style> element
  long drawn_ = 0;                                // shapes drawn, clones included
};

struct Viewport {
  Affine user_to_mm = Affine::Identity();  // root user units -> mm, y down
  double height_mm = std::nan("");         // page height, NaN if unknown
  Eigen::Vector2d user_size{std::nan(""), std::nan("")};  // the viewport in user units (percentages)
};

// preserveAspectRatio: the viewBox's scale and alignment in the viewport (px).
Affine viewbox_transform(const std::vector<double>& vb, double w, double h, const std::string& par) {
  std::stringstream ss(par);
  std::string align = "xMidYMid", mode = "meet", word;
  if (ss >> word) {
    if (word == "defer") ss >> word;
    align = word;
    if (ss >> word) mode = word;
  }
  double sx = w / vb[2], sy = h / vb[3];
  if (align != "none") sx = sy = mode == "slice" ? std::max(sx, sy) : std::min(sx, sy);
  double tx = -vb[0] * sx, ty = -vb[1] * sy;
  if (align.find("xMid") != std::string::npos) tx += (w - vb[2] * sx) / 2;
  if (align.find("xMax") != std::string::npos) tx += w - vb[2] * sx;
  if (align.find("YMid") != std::string::npos) ty += (h - vb[3] * sy) / 2;
  if (align.find("YMax") != std::string::npos) ty += h - vb[3] * sy;
  Affine m = Affine::Identity();
  m(0, 0) = sx;
  m(1, 1) = sy;
  m(0, 2) = tx;
  m(1, 2) = ty;
  return m;
}

Viewport viewport(const tinyxml2::XMLElement* root, const std::string& name, std::vector<std::string>& notes) {
  auto size_px = [&](const char* which) -> double {
    const char* v = root->Attribute(which);
    if (!v || trim(v).empty()) return std::nan("");
    const Length l = split_length(v, which);
    if (l.unit == "%") {
      notes.push_back(name + ": svg " + which + "=\"" + util::excerpt(v) + "\": a percentage, taken as the viewBox size");
      return std::nan("");
    }
    if (l.value <= 0) throw BadAttribute(std::string(which) + ": must be positive");
    return l.value * px_per_unit(l.unit, which);
  };
  double w = size_px("width"), h = size_px("height");
  Viewport vp;
  Affine to_px = Affine::Identity();
  vp.user_size = {w, h};
  if (const char* vbs = root->Attribute("viewBox")) {
    std::vector<double> vb;
    try {
      vb = svg::parse_number_list(vbs);
    } catch (const PathDataError& err) {
      throw BadAttribute(std::string("viewBox: ") + err.what());
    }
    if (vb.size() != 4 || vb[2] <= 0 || vb[3] <= 0)
      throw BadAttribute("viewBox: expected four numbers, width and height positive");
    if (std::isnan(w) && std::isnan(h)) {
      w = vb[2];
      h = vb[3];
    } else if (std::isnan(w)) {
      w = h * vb[2] / vb[3];
    } else if (std::isnan(h)) {
      h = w * vb[3] / vb[2];
    }
    to_px = viewbox_transform(vb, w, h, attr(root, "preserveAspectRatio"));
    vp.user_size = {vb[2], vb[3]};
  }
  Affine px_to_mm = Affine::Identity();
  px_to_mm(0, 0) = px_to_mm(1, 1) = kMmPerPx;
  vp.user_to_mm = px_to_mm * to_px;
  vp.height_mm = h * kMmPerPx;
  return vp;
}

Toolpath read_document(tinyxml2::XMLDocument& doc, const std::string& name) {
  if (doc.Error())
    throw InputError(name + ": XML: line " + std::to_string(doc.ErrorLineNum()) + ": " + doc.ErrorName());
  const tinyxml2::XMLElement* root = doc.RootElement();
  if (!root || local_name(root->Name()) != "svg") throw InputError(name + ": the root element is not <svg>");
  std::vector<std::string> notes;
  Viewport vp;
  try {
    vp = viewport(root, name, notes);
  } catch (const std::runtime_error& err) {  // PathDataError, BadAttribute
    throw InputError(name + ": svg: " + err.what());
  }
  // y up: flipped about the page (origin at the bottom-left corner), or about y = 0 if no height
  Affine flip = Affine::Identity();
  flip(1, 1) = -1;
  if (!std::isnan(vp.height_mm)) flip(1, 2) = vp.height_mm;
  Walker walker(name, flip * vp.user_to_mm, vp.user_size, root);
  Affine ctm = Affine::Identity();
  try {
    if (const char* t = root->Attribute("transform")) ctm = svg::parse_transform(t);
  } catch (const PathDataError& err) {
    throw InputError(name + ": svg: transform: " + err.what());
  }
  walker.children(root, ctm, Paint().under(root), 0);
  std::size_t segments = 0;
  for (const Cut& c : walker.cuts) segments += c.size();
  if (segments == 0) {
    // the first few things skipped (a file of unknown elements must not make a page-long error)
    std::string skipped;
    const size_t shown = std::min<size_t>(walker.notes.size(), 3);
    for (size_t i = 0; i < shown; ++i) skipped += "; " + walker.notes[i].substr(name.size() + 2);
    if (walker.notes.size() > shown) skipped += "; and " + std::to_string(walker.notes.size() - shown) + " more";
    throw InputError(name + ": no paths: no path, line, polyline, polygon, rect, circle or ellipse with any length" + skipped);
  }
  Toolpath tp = toolpath_from_cuts(walker.cuts, 2);
  tp.notes = notes;
  tp.notes.insert(tp.notes.end(), walker.notes.begin(), walker.notes.end());
  return tp;
}

}  // namespace

Toolpath parse_svg(const std::string& text, const std::string& name) {
  tinyxml2::XMLDocument doc;
  doc.Parse(text.c_str(), text.size());
  return read_document(doc, name);
}

Toolpath read_svg(const std::string& file) {
  tinyxml2::XMLDocument doc;
  if (doc.LoadFile(file.c_str()) == tinyxml2::XML_ERROR_FILE_NOT_FOUND ||
      doc.ErrorID() == tinyxml2::XML_ERROR_FILE_COULD_NOT_BE_OPENED)
    throw InputError(file + ": cannot open");
  return read_document(doc, file);
}

}  // namespace traj::input
