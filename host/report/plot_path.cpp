// SPDX-License-Identifier: Apache-2.0
// path_feed.svg (plot_svg.hpp, path_svg): the path of the core's output
// samples at equal scale, axes in units, coloured by the output feed (chord
// speed of consecutive samples) on a labelled colour bar from 0 to the
// commanded feed, or for a toolpath to its fastest feed move (so that the
// rapid speed does not squeeze the feed moves into a few colours); a
// toolpath's rapid moves (by the plan: at any speed, so that a connecting
// move never looks like a cut) or, without a plan, steps faster than the
// scale's top within the feed limit in grey, steps above the
// feed limit in a colour of their own; start, end and direction of travel
// marked. A feed move's output runs above its planned feed by the fit's feed
// error (about 0.2 %, or --feed-accuracy): steps up to kFeedSlack (or that
// accuracy, if larger) above the scale's top keep the top colour, so that a
// feed move is never drawn as a rapid.
//
// A 2-D path, or a 3-D one whose z range is negligible (at most 1e-6 of its
// x-y extent), is drawn as one x-y plot. A 3-D path is drawn in three
// projections laid out as an engineering drawing (third-angle): top (x-y)
// above front (x-z), side (y-z) to the right of front, all at one scale, so
// that x lines up between top and front and z between front and side. Each
// panel is simplified in its own pixels within an equal share of 40,000
// points, so the file stays small whatever the length of the run.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "planner/sampled.hpp"
#include "report/plot_svg.hpp"

namespace traj::report::svg {

namespace {

using Pos = std::function<std::array<double, 3>(size_t)>;
constexpr size_t kMaxPoints = 40000;  // points of the path in the whole file
constexpr int kBands = 20;            // colour bands over [0, scale]; kBands: above the feed; kRapid: between
constexpr int kRapid = kBands + 1;
constexpr double kFeedSlack = 0.01;   // relative: a step this far above the scale's top is still a feed move

// The samples and what colours them.
struct Feed {
  size_t n;
  const Pos& pos;
  int d;
  double h, feed, allow_v;
  double scale;           // top of the colour scale (<= feed)
  double rapid_above;     // steps faster than this (and within the feed) are "rapid": scale plus its slack
  std::string scale_what; // what the scale's top is, when below the feed
  // step k -> k+1 is in a rapid move (a toolpath's plan); empty: not known,
  // a rapid is a step above rapid_above
  const std::function<bool(size_t)>& rapid_step;
  size_t over = 0;        // steps above feed + allow_v
  size_t rapid = 0;       // rapid steps (by the plan, or above rapid_above), within feed + allow_v
  double smin = 0, smax = 0;  // range of the chord speed
};

// One projection of the path on a box of pixels: axis `a` to the right, `b` up.
struct View {
  int a = 0, b = 1;
  std::string id, title;  // "" for the single x-y plot
  double lo_a = 0, hi_a = 0, lo_b = 0, hi_b = 0;  // the data range with its margins (units)
  double left = 0, top = 0, sc = 1;                // the box's corner (px), px per unit
  double w() const { return (hi_a - lo_a) * sc; }
  double h() const { return (hi_b - lo_b) * sc; }
  std::array<double, 2> px(const std::array<double, 3>& p) const {
    return {left + (p[a] - lo_a) * sc, top + h() - (p[b] - lo_b) * sc};
  }
};

// Douglas-Peucker: marks the points of pts to keep so that the polyline stays
// within tol (pixels) of every point; the ends are kept.
void simplify(const std::vector<std::array<double, 2>>& pts, double tol, std::vector<char>& keep) {
  const size_t n = pts.size();
  keep.assign(n, 0);
  if (!n) return;
  keep[0] = keep[n - 1] = 1;
  std::vector<std::pair<size_t, size_t>> stack{{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j <= i + 1) continue;
    const double dx = pts[j][0] - pts[i][0], dy = pts[j][1] - pts[i][1], L = std::hypot(dx, dy);
    double worst = -1;
    size_t wk = i;
    for (size_t k = i + 1; k < j; ++k) {
      const double ex = pts[k][0] - pts[i][0], ey = pts[k][1] - pts[i][1];
      const double e = L > 1e-12 ? std::fabs(ex * dy - ey * dx) / L : std::hypot(ex, ey);
      if (e > worst) worst = e, wk = k;
    }
    if (worst > tol) {
      keep[wk] = 1;
      stack.push_back({i, wk});
      stack.push_back({wk, j});
    }
  }
}

// A step (within the feed) drawn as a rapid: by the plan's move kind where
// the plan is known, else by its speed s.
bool is_rapid(const Feed& F, size_t k, double s) { return F.rapid_step ? F.rapid_step(k) : s > F.rapid_above; }

// Range of the chord speed and the steps above the feed.
void measure_feed(Feed& F) {
  for (size_t k = 0; k + 1 < F.n; ++k) {
    const auto a = F.pos(k), b = F.pos(k + 1);
    const double s = plan::chord_speed(a.data(), b.data(), F.d, F.h);
    F.smin = k ? std::min(F.smin, s) : s;
    F.smax = std::max(F.smax, s);
    if (s > F.feed + F.allow_v) ++F.over;
    else if (is_rapid(F, k, s)) ++F.rapid;
  }
}

// SVG path data of the view's path, one string per colour band.
// Chord speed of each step in colour bands over [0, feed] (a band changes
// once the speed is a fifth of a band beyond it: no flicker at a boundary);
// steps above feed + the quantisation allowance in a band of their own.
// Consecutive steps are merged into strokes at least `spacing` pixels long
// (0: every step), each coloured by its mean speed, or as above the feed if
// any of its steps is. Runs of one band become simplified subpaths (tolerance
// `tol` px), one <path> per band. Spacing and tolerance grow until at most
// max_points points remain.
std::vector<std::string> feed_bands(const Feed& F, const View& v, size_t max_points) {
  const size_t n = F.n;
  const double h = F.h, feed = F.feed, scale = F.scale;
  std::vector<std::string> bands(kRapid + 1);
  double tol = 0.25, spacing = 0;
  for (int attempt = 0; attempt < 64; ++attempt) {
    for (auto& b : bands) b.clear();
    size_t total = 0;
    std::vector<std::array<double, 2>> run;
    std::vector<char> keep;
    int cur = -1;
    auto flush = [&]() {
      if (run.size() < 2) return;
      simplify(run, tol, keep);
      PathData pd;
      bool first = true;
      for (size_t i = 0; i < run.size(); ++i)
        if (keep[i]) {
          if (first)
            pd.move(run[i][0], run[i][1]);
          else
            pd.line(run[i][0], run[i][1]);
          first = false;
          ++total;
        }
      bands[cur] += pd.str();
    };
    std::array<double, 3> prev = n ? F.pos(0) : std::array<double, 3>{};
    std::array<double, 2> start_px = v.px(prev);  // the current stroke's first point
    double len = 0;                                // its length (units) and steps
    size_t steps = 0;
    bool stroke_over = false;
    for (size_t k = 0; k + 1 < n; ++k) {
      const auto next = F.pos(k + 1);
      const double s = plan::chord_speed(prev.data(), next.data(), F.d, h);
      len += s * h;
      ++steps;
      stroke_over = stroke_over || s > feed + F.allow_v;
      prev = next;
      const auto q = v.px(next);
      const double px = std::hypot(q[0] - start_px[0], q[1] - start_px[1]);
      // by the plan, a stroke ends where the move kind changes (so each is one kind)
      const bool kind_changes = F.rapid_step && k + 2 < n && F.rapid_step(k + 1) != F.rapid_step(k);
      if (px < spacing && k + 2 < n && !kind_changes) continue;  // the stroke goes on
      int b;
      if (stroke_over) {
        b = kBands;
      } else if (is_rapid(F, k, len / (steps * h))) {
        b = kRapid;
      } else {
        const double f = std::clamp(len / (steps * h) / scale * kBands, 0.0, kBands - 1e-9);
        b = static_cast<int>(f);
        if (cur >= 0 && cur < kBands && f > cur - 0.2 && f < cur + 1.2) b = cur;
      }
      if (b != cur) {
        flush();
        run.clear();
        run.push_back(start_px);
        cur = b;
      }
      // drop points within 0.1 px of the last one (they cannot change the picture)
      if (run.size() < 2 || std::hypot(q[0] - run.back()[0], q[1] - run.back()[1]) > 0.1 || k + 2 == n)
        run.push_back(q);
      start_px = q;
      len = 0, steps = 0, stroke_over = false;
    }
    flush();
    if (total <= max_points) break;
    tol = std::min(1.0, tol * 2);
    spacing = std::max(0.5, spacing * 2);
  }
  return bands;
}

// The tick step of an axis from `lo` to `hi` drawn at `sc` px per unit: about
// one tick in 70 px, at least two where their labels fit side by side. Each
// axis has its own step: one step for both left a 20 mm-wide, 300 mm-tall
// drawing with a single x label.
double axis_step(double lo, double hi, double sc) {
  const int target = std::clamp(static_cast<int>((hi - lo) * sc / 70), 2, 8);
  double step = nice_ticks(lo, hi, target).step;
  for (int widen = 0; widen < 30; ++widen) {
    const Ticks t = ticks_at(lo, hi, step);
    double widest = 0;
    for (double x : t.v) widest = std::max(widest, text_w(tick_label(x, t.dec), 10));
    if (step * sc >= widest + 8) break;
    const double mag = std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    step = (step / mag < 1.5 ? 2 : step / mag < 3.5 ? 5 : 10) * mag;  // the next of 1, 2, 5, 10
  }
  return step;
}

// Grid, ticks and labels every `step_a` units across and `step_b` up, the axis names in units.
void draw_axes(std::ostringstream& o, const View& v, double step_a, double step_b, const std::string& u) {
  const double left = v.left, top = v.top, Wp = v.w(), Hp = v.h();
  const Ticks xt = ticks_at(v.lo_a, v.hi_a, step_a), yt = ticks_at(v.lo_b, v.hi_b, step_b);
  auto XP = [&](double t) { return left + (t - v.lo_a) * v.sc; };
  auto YP = [&](double t) { return top + Hp - (t - v.lo_b) * v.sc; };
  o << "<path stroke=\"#ececec\" d=\"";
  for (double t : xt.v) o << "M" << num(XP(t)) << " " << num(top) << "V" << num(top + Hp);
  for (double t : yt.v) o << "M" << num(left) << " " << num(YP(t)) << "H" << num(left + Wp);
  o << "\"/>\n<path stroke=\"#555\" d=\"";
  for (double t : xt.v) o << "M" << num(XP(t)) << " " << num(top + Hp) << "v4";
  for (double t : yt.v) o << "M" << num(left) << " " << num(YP(t)) << "h-4";
  o << "\"/>\n<g font-size=\"10\" fill=\"#333\" text-anchor=\"middle\">\n";
  for (double t : xt.v) o << text(XP(t), top + Hp + 16, tick_label(t, xt.dec));
  o << "</g>\n<g font-size=\"10\" fill=\"#333\" text-anchor=\"end\">\n";
  for (double t : yt.v) o << text(left - 7, YP(t) + 3.5, tick_label(t, yt.dec));
  o << "</g>\n";
  const std::string an(1, "xyz"[v.a]), bn(1, "xyz"[v.b]);
  o << text(left + Wp / 2, top + Hp + 36, an + " (" + u + ")", " text-anchor=\"middle\" font-size=\"12\"");
  o << "<text transform=\"translate(" << num(left - 48) << " " << num(top + Hp / 2)
    << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"12\">" << esc(bn + " (" + u + ")") << "</text>\n";
}

// The path: each colour band's geometry once (<defs>, ids `prefix`0..), drawn
// twice: a thin dark casing under all of it (light colours read on white),
// then coloured; the frame over it.
void draw_bands(std::ostringstream& o, const View& v, const std::vector<std::string>& bands, const std::string& prefix) {
  o << "<defs>\n";
  for (int b = 0; b <= kRapid; ++b)
    if (!bands[b].empty()) o << "<path id=\"" << prefix << b << "\" d=\"" << bands[b] << "\"/>\n";
  o << "</defs>\n<g fill=\"none\" stroke-width=\"2.4\" stroke-linecap=\"round\" stroke-linejoin=\"round\">\n";
  o << "<g stroke=\"#333\" stroke-width=\"3.6\" stroke-opacity=\"0.55\">";
  for (int b = 0; b <= kRapid; ++b)
    if (!bands[b].empty()) o << "<use xlink:href=\"#" << prefix << b << "\"/>";
  o << "</g>\n";
  for (int b = 0; b <= kRapid; ++b)
    if (!bands[b].empty())
      o << "<use xlink:href=\"#" << prefix << b << "\" stroke=\""
        << (b == kBands ? kOverColour : b == kRapid ? kRapidColour : viridis((b + 0.5) / kBands)) << "\"/>\n";
  o << "</g>\n<rect x=\"" << num(v.left) << "\" y=\"" << num(v.top) << "\" width=\"" << num(v.w()) << "\" height=\""
    << num(v.h()) << "\" fill=\"none\" stroke=\"#555\"/>\n";
}

// Start (ring), end (square), direction of travel (arrow). Start and end
// that meet in the view are labelled "start = end" where they also meet in
// space, else "start, end" (one above the other in a projection).
void draw_ends(std::ostringstream& o, const Feed& F, const View& v) {
  const size_t n = F.n;
  if (!n) return;
  const auto p0 = F.pos(0), p1 = F.pos(n - 1);
  const auto s0 = v.px(p0), s1 = v.px(p1);
  for (size_t k = 1; k < n; k += std::max<size_t>(1, n / 100000)) {
    const auto q = v.px(F.pos(k));
    const double dx = q[0] - s0[0], dy = q[1] - s0[1], L = std::hypot(dx, dy);
    if (L < 22) continue;
    const double ux = dx / L, uy = dy / L, ax = s0[0] + ux * 30, ay = s0[1] + uy * 30;
    o << "<path fill=\"#222\" d=\"M" << num(ax) << " " << num(ay) << "L" << num(ax - 9 * ux - 4 * uy) << " "
      << num(ay - 9 * uy + 4 * ux) << "L" << num(ax - 9 * ux + 4 * uy) << " " << num(ay - 9 * uy - 4 * ux)
      << "Z\"/>\n";
    break;
  }
  o << "<circle cx=\"" << num(s0[0]) << "\" cy=\"" << num(s0[1])
    << "\" r=\"7\" fill=\"none\" stroke=\"#1a9850\" stroke-width=\"2.5\"/>\n";
  o << "<rect x=\"" << num(s1[0] - 3.5) << "\" y=\"" << num(s1[1] - 3.5)
    << "\" width=\"7\" height=\"7\" fill=\"#d73027\"/>\n";
  auto label = [&](const std::array<double, 2>& at, const std::string& s) {
    const bool right_side = at[0] < v.left + v.w() - 90;
    // in a titled panel, a label that would reach the title row goes under its mark
    const bool under = !v.title.empty() && at[1] - 20 < v.top;
    o << text(at[0] + (right_side ? 11 : -11), at[1] + (under ? 18 : -9), s, right_side ? "" : " text-anchor=\"end\"");
  };
  if (std::hypot(s1[0] - s0[0], s1[1] - s0[1]) < 10) {
    double gap = 0;
    for (int a = 0; a < 3; ++a) gap += (p1[a] - p0[a]) * (p1[a] - p0[a]);
    label(s0, std::sqrt(gap) * v.sc < 10 ? "start = end" : "start, end");
  } else {
    label(s0, "start");
    label(s1, "end");
  }
}

// Colour bar, 0 .. the colour scale's top, at x = bx, centred on [top, top + span].
void draw_colour_bar(std::ostringstream& o, const Feed& F, double bx, double top, double span, const std::string& u) {
  const double cbw = 16, bh = std::min(span, 360.0), by = top + (span - bh) / 2, feed = F.scale;
  o << "<g id=\"colourbar\" data-vmin=\"0\" data-vmax=\"" << gfmt(feed, 10) << "\">\n";
  for (int b = 0; b < kBands; ++b)
    o << "<rect x=\"" << num(bx) << "\" y=\"" << num(by + bh - (b + 1) * bh / kBands) << "\" width=\"" << num(cbw)
      << "\" height=\"" << num(bh / kBands + 0.3) << "\" fill=\"" << viridis((b + 0.5) / kBands) << "\"/>\n";
  o << "<rect x=\"" << num(bx) << "\" y=\"" << num(by) << "\" width=\"" << num(cbw) << "\" height=\"" << num(bh)
    << "\" fill=\"none\" stroke=\"#555\"/>\n";
  const Ticks ct = nice_ticks(0, feed, 5);
  o << "<path stroke=\"#555\" d=\"";
  for (double t : ct.v) o << "M" << num(bx + cbw) << " " << num(by + bh - t / feed * bh) << "h4";
  o << "\"/>\n";
  for (double t : ct.v) o << text(bx + cbw + 7, by + bh - t / feed * bh + 3.5, tick_label(t, ct.dec), " font-size=\"10\"");
  if (F.over) {
    o << "<rect x=\"" << num(bx) << "\" y=\"" << num(by - 22) << "\" width=\"" << num(cbw)
      << "\" height=\"12\" fill=\"" << kOverColour << "\"/>\n";
    o << text(bx + cbw + 7, by - 12, "> feed", " font-size=\"10\"");
  }
  if (F.rapid) {
    const double y = by - (F.over ? 40 : 22);
    o << "<rect x=\"" << num(bx) << "\" y=\"" << num(y) << "\" width=\"" << num(cbw) << "\" height=\"12\" fill=\""
      << kRapidColour << "\"/>\n";
    o << text(bx + cbw + 7, y + 10, "rapid", " font-size=\"10\"");
  }
  o << "<text transform=\"translate(" << num(bx + cbw + 52) << " " << num(by + bh / 2)
    << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"12\">" << esc("output feed (" + u + "/s)") << "</text>\n";
  o << "</g>\n";
}

// Title and the two lines under it.
struct Heading {
  std::string title, how, range;
  bool over = false;  // steps above the feed: the range line in red
  // Width the lines take from their left edge (a tall, narrow drawing's page
  // is made at least this wide, or its title is cut).
  double width() const { return std::max({text_w(title, 15) * 1.08, text_w(how), text_w(range)}); }
};

Heading make_heading(const Feed& F, const std::string& title, const std::string& how, const std::string& u) {
  Heading h;
  h.title = title;
  h.how = std::to_string(F.n) + " samples at " + gfmt(F.h * 1e3) +
          " ms; output feed = chord speed |x(k+1) \xE2\x88\x92 x(k)| / h" + how;
  h.range = "output feed " + vfmt(F.smin) + " \xE2\x80\xA6 " + vfmt(F.smax) + " " + u + "/s (" +
            (std::isfinite(F.feed) ? "feed limit " + vfmt(F.feed) + " " + u + "/s" : "no feed limit given") +
            (F.scale < F.feed ? "; colours up to " + F.scale_what + ", " + vfmt(F.scale) + " " + u + "/s" : "") + ")" +
            (F.over ? "; " + std::to_string(F.over) + " steps above the feed" : "");
  h.over = F.over > 0;
  return h;
}

void draw_heading(std::ostringstream& o, const Heading& h, double left) {
  o << text(left, 24, h.title, " font-size=\"15\" font-weight=\"bold\"");
  o << text(left, 43, h.how, " fill=\"#444\"");
  o << text(left, 59, h.range, h.over ? " fill=\"#c0392b\" font-weight=\"bold\"" : " fill=\"#444\"");
}

// Data range of each axis, widened to at least 5 % of the largest and by a
// margin of 4 % on each side: {lo, hi} per axis.
std::array<std::array<double, 2>, 3> framed_ranges(const Feed& F, int axes) {
  std::array<std::array<double, 2>, 3> r{};
  for (size_t k = 0; k < F.n; ++k) {
    const auto p = F.pos(k);
    for (int a = 0; a < axes; ++a) {
      if (k == 0) r[a] = {p[a], p[a]};
      r[a][0] = std::min(r[a][0], p[a]), r[a][1] = std::max(r[a][1], p[a]);
    }
  }
  double span = 1e-9;
  for (int a = 0; a < axes; ++a) span = std::max(span, r[a][1] - r[a][0]);
  for (int a = 0; a < axes; ++a) {
    const double m = std::max(r[a][1] - r[a][0], 0.05 * span), c = 0.5 * (r[a][0] + r[a][1]);
    r[a] = {c - 0.54 * m, c + 0.54 * m};
  }
  return r;
}

View make_view(int a, int b, const std::array<std::array<double, 2>, 3>& r, double left, double top, double sc) {
  View v;
  v.a = a, v.b = b;
  v.lo_a = r[a][0], v.hi_a = r[a][1], v.lo_b = r[b][0], v.hi_b = r[b][1];
  v.left = left, v.top = top, v.sc = sc;
  return v;
}

// One x-y plot.
std::string flat_svg(const Feed& F, const std::string& u) {
  const auto r = framed_ranges(F, 2);
  const double sc = std::min(720 / (r[0][1] - r[0][0]), 620 / (r[1][1] - r[1][0]));
  const View v = make_view(0, 1, r, 70, 74, sc);
  const Heading hd = make_heading(F, "Path (x-y) of the core's output samples, coloured by the output feed",
                                  std::string(F.d > 2 ? "; projection on x-y" : "") + "; equal scales", u);
  const double W = std::max(v.left + v.w() + 120, v.left + hd.width() + 20), H = v.top + v.h() + 52;
  std::ostringstream o;
  o << svg_open(W, H);
  draw_heading(o, hd, v.left);
  draw_axes(o, v, axis_step(v.lo_a, v.hi_a, v.sc), axis_step(v.lo_b, v.hi_b, v.sc), u);
  draw_bands(o, v, feed_bands(F, v, kMaxPoints), "band");
  draw_ends(o, F, v);
  draw_colour_bar(o, F, v.left + v.w() + 28, v.top, v.h(), u);
  o << "</svg>\n";
  return o.str();
}

// Three projections at one scale: top (x-y) above front (x-z), side (y-z)
// right of front; each panel a <g id="panel-xy|xz|yz"> with its axes.
std::string drawing_svg(const Feed& F, const std::string& u) {
  const auto r = framed_ranges(F, 3);
  const double rx = r[0][1] - r[0][0], ry = r[1][1] - r[1][0], rz = r[2][1] - r[2][0];
  const double sc = std::min(680 / (rx + ry), 600 / (ry + rz));
  const double left = 70, top = 96, gap_h = 90, gap_v = 80;  // gaps: tick labels, axis name, panel title
  View views[3] = {make_view(0, 1, r, left, top, sc), make_view(0, 2, r, left, top + ry * sc + gap_v, sc),
                   make_view(1, 2, r, left + rx * sc + gap_h, top + ry * sc + gap_v, sc)};
  views[0].id = "xy", views[0].title = "top (x-y)";
  views[1].id = "xz", views[1].title = "front (x-z)";
  views[2].id = "yz", views[2].title = "side (y-z)";
  // one tick step per axis, the same in every panel that shows it
  double step[3];
  for (int a = 0; a < 3; ++a) step[a] = axis_step(r[a][0], r[a][1], sc);
  const View& side = views[2];
  const double right = std::max(side.left + side.w(), side.left + text_w(side.title, 12));
  const Heading hd = make_heading(
      F, "Path of the core's output samples in three projections, coloured by the output feed",
      "; third-angle projection, one scale", u);
  const double W = std::max(right + 120, left + hd.width() + 20), H = side.top + side.h() + 52;
  std::ostringstream o;
  o << svg_open(W, H);
  draw_heading(o, hd, left);
  for (const View& v : views) {
    o << "<g id=\"panel-" << v.id << "\" data-axes=\"" << "xyz"[v.a] << " " << "xyz"[v.b] << "\" data-scale=\""
      << gfmt(v.sc, 6) << "\" data-left=\"" << num(v.left, 2) << "\" data-top=\"" << num(v.top, 2)
      << "\" data-width=\"" << num(v.w(), 2) << "\" data-height=\"" << num(v.h(), 2) << "\">\n";
    o << text(v.left, v.top - 9, v.title, " font-size=\"12\" font-weight=\"bold\"");
    draw_axes(o, v, step[v.a], step[v.b], u);
    draw_bands(o, v, feed_bands(F, v, kMaxPoints / 3), v.id + "-band");
    draw_ends(o, F, v);
    o << "</g>\n";
  }
  draw_colour_bar(o, F, right + 28, top, side.top + side.h() - top, u);
  o << "</svg>\n";
  return o.str();
}

// True if the path has 3 axes and its z range is more than 1e-6 of its x-y extent.
bool needs_three_views(const Feed& F) {
  if (F.d < 3 || !F.n) return false;
  double lo[3], hi[3];
  for (size_t k = 0; k < F.n; ++k) {
    const auto p = F.pos(k);
    for (int a = 0; a < 3; ++a) {
      lo[a] = k ? std::min(lo[a], p[a]) : p[a];
      hi[a] = k ? std::max(hi[a], p[a]) : p[a];
    }
  }
  return hi[2] - lo[2] > 1e-6 * std::max(hi[0] - lo[0], hi[1] - lo[1]);
}

}  // namespace

std::string path_svg(size_t n, const std::function<std::array<double, 3>(size_t)>& pos, int d,
                     const job::JobConfig& cfg, double h, double allow_v, double scale_feed,
                     const std::function<bool(size_t)>& rapid_step) {
  // no feed limit (<= 0: sim of a stream without --feed): nothing is "above the feed"
  const double feed = cfg.limits.feed > 0 ? cfg.limits.feed : std::numeric_limits<double>::infinity();
  double scale = scale_feed > 0 ? std::min(scale_feed, feed) : feed;
  std::string scale_what = std::isfinite(feed) ? "the fastest feed move" : "the fastest step";
  if (std::isfinite(feed) && cfg.limits.top_speed(d) < scale) {  // a feed above what the axes allow
    scale = cfg.limits.top_speed(d);
    scale_what = "the axes' top speed";
  }
  const double rapid_above = scale * (1 + std::max(kFeedSlack, cfg.machine.feed_accuracy)) + allow_v;
  Feed F{n, pos, d, h, feed, allow_v, scale, rapid_above, scale_what, rapid_step};
  measure_feed(F);
  return needs_three_views(F) ? drawing_svg(F, cfg.machine.units) : flat_svg(F, cfg.machine.units);
}

}  // namespace traj::report::svg
