// SPDX-License-Identifier: Apache-2.0
// SVG plots of a job (report.hpp, write_plots).
//
//   path_feed.svg  the x-y path of the core's output samples (equal aspect,
//                  axes in units), coloured by the output feed (chord speed of
//                  consecutive samples) on a labelled colour bar from 0 to the
//                  commanded feed; steps above the feed in a colour of their own.
//   profile.svg    against time, the whole motion, one panel each: path speed,
//                  tangential acceleration and jerk, acceleration and jerk of
//                  each axis, centripetal acceleration and jerk; the plan and
//                  the output, with the limits dashed.
//
// Output quantities are the report's (make_report, sampled.hpp): differences of
// the samples over 1, 2, 3 ticks, each drawn at the centre of its ticks. Where a
// pixel column holds more than one sample, a series is drawn as its min/max
// envelope over the column (a band), so no extreme is lost to decimation. The
// y range always covers the data and the limits: nothing is clamped. Both files
// stay small whatever the length of the run (the profile: a few points per
// pixel column and series; the path: at most 40,000 points).
//
// Both files are written to <name>.tmp in `dir`, then renamed into place;
// on failure the temporary files are removed (`trajcore run` also stages the
// whole output in a folder inside out_dir and moves it in place at the end).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include "planner/sampled.hpp"
#include "report/report.hpp"
#include "util/atomic_file.hpp"

namespace traj::report {

using namespace plan;
using job::JobConfig;
using job::JobResult;

namespace {

constexpr const char* kFont = "DejaVu Sans, Helvetica, Arial, sans-serif";
constexpr const char* kLimitColour = "#c0392b";
constexpr const char* kPlanColour = "#f28e2b";
constexpr const char* kOutColour = "#1f4e99";
constexpr const char* kOverColour = "#e7298a";

// Fixed-point text with `dec` decimals, trailing zeros dropped, "-0" -> "0".
std::string num(double v, int dec = 1) {
  if (!std::isfinite(v)) v = 0;
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", std::clamp(dec, 0, 12), v);
  std::string s = b;
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

std::string gfmt(double v, int sig = 4) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*g", sig, v);
  return b;
}

// A measured value: 4 significant digits, no exponent between 1e-4 and 1e7.
std::string vfmt(double v) {
  const double a = std::fabs(v);
  if (a == 0) return "0";
  if (a < 1e-4 || a >= 1e7 || !std::isfinite(a)) return gfmt(v);
  return num(v, std::max(0, 3 - static_cast<int>(std::floor(std::log10(a)))));
}

// Tick label: a typographic minus for negative values.
std::string tick_label(double v, int dec) {
  std::string s = num(v, dec);
  if (!s.empty() && s[0] == '-') s = "\xE2\x88\x92" + s.substr(1);
  return s;
}

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      case '\'': o += "&apos;"; break;
      default: o += c;
    }
  }
  return o;
}

struct Ticks {
  double step = 1;
  int dec = 0;
  std::vector<double> v;
};

// 1, 2, 5 x 10^k ticks inside [lo, hi], about `target` of them.
Ticks nice_ticks(double lo, double hi, int target) {
  Ticks t;
  double span = hi - lo;
  if (!(span > 0) || !std::isfinite(span)) span = std::max(1.0, std::fabs(lo));
  const double raw = span / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  t.step = (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * mag;
  t.dec = std::max(0, static_cast<int>(-std::floor(std::log10(t.step) + 1e-9)));
  const double first = std::ceil(lo / t.step - 1e-9);
  for (double i = first;; i += 1) {
    const double x = i * t.step;
    if (x > hi + 1e-9 * t.step || t.v.size() > 100) break;
    t.v.push_back(std::fabs(x) < 1e-12 * t.step ? 0.0 : x);
  }
  return t;
}

// Perceptually uniform colour map (viridis stops), f in [0, 1].
std::string viridis(double f) {
  static const double c[11][3] = {{68, 1, 84},    {72, 36, 117},  {65, 68, 135},  {53, 95, 141},
                                  {42, 120, 142}, {33, 145, 140}, {34, 168, 132}, {68, 191, 112},
                                  {122, 209, 81}, {189, 223, 38}, {253, 231, 37}};
  f = std::clamp(f, 0.0, 1.0) * 10;
  const int i = std::min(9, static_cast<int>(f));
  const double w = f - i;
  char s[16];
  std::snprintf(s, sizeof s, "#%02x%02x%02x", static_cast<int>(std::lround(c[i][0] + w * (c[i + 1][0] - c[i][0]))),
                static_cast<int>(std::lround(c[i][1] + w * (c[i + 1][1] - c[i][1]))),
                static_cast<int>(std::lround(c[i][2] + w * (c[i + 1][2] - c[i][2]))));
  return s;
}

std::string svg_open(double w, double h) {
  std::ostringstream o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" width=\"" << num(w)
    << "\" height=\"" << num(h) << "\" viewBox=\"0 0 " << num(w) << " " << num(h) << "\" font-family=\"" << kFont
    << "\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  return o.str();
}

std::string text(double x, double y, const std::string& s, const char* extra = "") {
  return "<text x=\"" + num(x) + "\" y=\"" + num(y) + "\"" + extra + ">" + esc(s) + "</text>\n";
}

// Approximate width of a label at 11 px (DejaVu Sans averages ~6.3 px a character).
double text_w(const std::string& s, double size = 11) {
  size_t chars = 0;
  for (unsigned char c : s)
    if ((c & 0xC0) != 0x80) ++chars;  // count UTF-8 code points
  return chars * size * 0.58;
}

// Profile page layout (pixels).
constexpr double kPageW = 1000, kLeft = 84, kRight = 22, kPlotW = kPageW - kLeft - kRight;

// A series against time: y(k) at t0 + k dt for k < count, computed on demand
// (no copy of the samples, whatever the length of the run).
enum class Band { kFill, kEdges };  // a min/max band: filled, or its outline only
struct Series {
  std::string label, colour;
  double t0 = 0, dt = 1;
  size_t count = 0;
  std::function<double(size_t)> y;
  double width = 1.1, opacity = 1;
  Band band = Band::kEdges;
  double fill = 0.25;  // fill opacity of a kFill band
  // indices with t in [ta, tb], widened by one on each side
  std::pair<size_t, size_t> range(double ta, double tb) const {
    if (!count) return {1, 0};
    const double a = std::floor((ta - t0) / dt) - 1, b = std::ceil((tb - t0) / dt) + 1;
    const double last = static_cast<double>(count - 1);
    return {static_cast<size_t>(std::clamp(a, 0.0, last)), static_cast<size_t>(std::clamp(b, 0.0, last))};
  }
};

struct LimitLine {
  double v;
  std::string colour;
};

struct Panel {
  std::string id, title, ylabel;
  std::vector<Series> series;
  std::string note;               // after the title ("not limited (cubic, C1 joins)")
  std::vector<LimitLine> limits;  // horizontal dashed lines
  std::string limit_label;        // legend entry for the limits ("" = none)
  bool from_zero = false;         // y range starts at 0 (speed, centripetal)
  double limit = 0;               // the limit the peaks are compared with (0: none)
  double allowance = 0;           // quantisation allowance on the output (report.txt)
};

// SVG path data in tenths of a pixel: absolute moves, relative lines of
// rounded differences (no drift), so that a pixel column costs a few characters.
class PathData {
 public:
  void move(double x, double y) {
    X_ = std::lround(x * 10), Y_ = std::lround(y * 10);
    d_ += "M" + t(X_) + " " + t(Y_);
    open_ = false;
  }
  void line(double x, double y) {
    const long nx = std::lround(x * 10), ny = std::lround(y * 10);
    d_ += open_ ? " " : "l";
    d_ += t(nx - X_) + " " + t(ny - Y_);
    X_ = nx, Y_ = ny;
    open_ = true;
  }
  void close() {
    d_ += "Z";
    open_ = false;
  }
  bool empty() const { return d_.empty(); }
  const std::string& str() const { return d_; }

 private:
  static std::string t(long v) {  // tenths -> "12.3", "-0.4", "7"
    std::string s = std::to_string(std::labs(v) / 10);
    if (v % 10) s += "." + std::to_string(std::labs(v) % 10);
    return v < 0 ? "-" + s : s;
  }
  std::string d_;
  long X_ = 0, Y_ = 0;
  bool open_ = false;
};

// Draws one series over [ta, tb] into a plot box: a polyline where a pixel
// column holds at most one sample, else per pixel column the min/max envelope:
// a line where it is thinner than 1.2 px, a band (filled, or its two edges)
// where it is thicker. Every sample's value lies inside what is drawn.
void draw_series(std::ostringstream& o, const Series& s, double ta, double tb, double left, double width,
                 const std::function<double(double)>& Y, const std::string& clip) {
  const auto [k0, k1] = s.range(ta, tb);
  if (k1 < k0) return;
  const double tx = width / (tb - ta);
  auto X = [&](double t) { return left + (t - ta) * tx; };
  const std::string cl = "<path clip-path=\"url(#" + clip + ")\" data-series=\"" + esc(s.label) + "\" ";
  PathData line, band;
  bool open = false;
  auto to = [&](double x, double y) {
    if (open)
      line.line(x, y);
    else
      line.move(x, y);
    open = true;
  };
  if (s.dt * tx >= 1.0) {  // at most one sample per pixel column
    for (size_t k = k0; k <= k1; ++k) {
      const double y = s.y(k);
      if (std::isfinite(y)) to(X(s.t0 + k * s.dt), Y(y));
    }
  } else {
    const int cols = static_cast<int>(std::ceil(width));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::vector<double> mn(cols, nan), mx(cols, nan);
    for (size_t k = k0; k <= k1; ++k) {
      const double t = s.t0 + k * s.dt;
      if (t < ta || t > tb) continue;
      const double y = s.y(k);
      if (!std::isfinite(y)) continue;
      const int c = std::clamp(static_cast<int>((t - ta) * tx), 0, cols - 1);
      if (std::isnan(mn[c]) || y < mn[c]) mn[c] = y;
      if (std::isnan(mx[c]) || y > mx[c]) mx[c] = y;
    }
    auto cx = [&](int i) { return left + i + 0.5; };
    auto mid = [&](int i) { return Y(0.5 * (mn[i] + mx[i])); };
    auto thick = [&](int i) { return !std::isnan(mn[i]) && Y(mn[i]) - Y(mx[i]) > 1.2; };
    for (int c = 0; c < cols;) {
      if (std::isnan(mn[c])) {
        ++c;
        continue;
      }
      if (!thick(c)) {
        to(cx(c), mid(c));
        ++c;
        continue;
      }
      // a band runs on across gaps of up to 4 thin columns (so that it is not
      // cut into slivers where a bang-bang signal dwells on one value)
      int e = c;
      for (;;) {
        int g = e + 1;
        while (g < cols && g <= e + 5 && !std::isnan(mn[g]) && !thick(g)) ++g;
        if (g < cols && g <= e + 5 && thick(g))
          e = g;
        else
          break;
      }
      to(cx(c), mid(c));  // the line runs into the band's first column and out of its last
      if (s.band == Band::kFill) {
        band.move(cx(c), Y(mx[c]));
        for (int i = c + 1; i <= e; ++i) band.line(cx(i), Y(mx[i]));
        for (int i = e; i >= c; --i) band.line(cx(i), Y(mn[i]));
        band.close();
      } else {  // the band's outline: its top edge, then its bottom edge back
        line.move(cx(c), Y(mx[c]));
        for (int i = c + 1; i <= e; ++i) line.line(cx(i), Y(mx[i]));
        for (int i = e; i >= c; --i) line.line(cx(i), Y(mn[i]));
      }
      line.move(cx(e), mid(e));
      open = true;
      c = e + 1;
    }
  }
  if (!band.empty())
    o << cl << "fill=\"" << s.colour << "\" fill-opacity=\"" << num(s.fill, 2) << "\" stroke=\"" << s.colour
      << "\" stroke-width=\"0.7\" stroke-linejoin=\"round\" d=\"" << band.str() << "\"/>\n";
  if (!line.empty())
    o << cl << "fill=\"none\" stroke=\"" << s.colour << "\" stroke-width=\"" << num(s.width, 2)
      << "\" stroke-linejoin=\"round\"" << (s.opacity < 1 ? " stroke-opacity=\"" + num(s.opacity, 2) + "\"" : "")
      << " d=\"" << line.str() << "\"/>\n";
}

// Stacked panels against time over [ta, tb]; every y range covers the data
// and the limits (nothing is clamped).
std::string profile_svg(const std::string& title, const std::string& subtitle, const std::vector<Panel>& panels,
                        double ta, double tb) {
  const double left = kLeft, Wp = kPlotW;
  std::vector<std::string> sub;  // subtitle lines ('\n' between)
  for (size_t a = 0;;) {
    const size_t b = subtitle.find('\n', a);
    sub.push_back(subtitle.substr(a, b == std::string::npos ? std::string::npos : b - a));
    if (b == std::string::npos) break;
    a = b + 1;
  }
  const double head = 44 + 14 * sub.size(), row = 22, PH = 118, foot = 22, gap = 12;
  const double H = head + panels.size() * (row + PH + foot + gap) + 24;
  std::ostringstream o;
  o << svg_open(kPageW, H);
  o << text(left, 22, title, " font-size=\"15\" font-weight=\"bold\"");
  for (size_t i = 0; i < sub.size(); ++i) o << text(left, 40 + 14 * i, sub[i], " fill=\"#444\"");
  const Ticks tt = nice_ticks(ta, tb, 12);
  auto X = [&](double t) { return left + (t - ta) / (tb - ta) * Wp; };
  double top = head;
  int pi = 0;
  for (const Panel& P : panels) {
    const double ptop = top + row;
    // data range and peaks in the window
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    const size_t ns = P.series.size();
    std::vector<double> peak(ns, 0.0), peak_t(ns, 0.0), peak_y(ns, 0.0);
    for (size_t si = 0; si < ns; ++si) {
      const Series& s = P.series[si];
      const auto [k0, k1] = s.range(ta, tb);
      for (size_t k = k0; k <= k1 && k1 >= k0; ++k) {
        const double t = s.t0 + k * s.dt;
        if (t < ta - 1e-12 || t > tb + 1e-12) continue;
        const double y = s.y(k);
        if (!std::isfinite(y)) continue;
        lo = std::min(lo, y);
        hi = std::max(hi, y);
        if (std::fabs(y) > peak[si]) peak[si] = std::fabs(y), peak_t[si] = t, peak_y[si] = y;
      }
    }
    for (const auto& L : P.limits) lo = std::min(lo, L.v), hi = std::max(hi, L.v);
    if (!std::isfinite(lo)) lo = hi = 0;
    if (P.from_zero) lo = std::min(lo, 0.0);
    double pad = 0.06 * (hi - lo);
    if (!(pad > 0)) pad = std::max(1.0, std::fabs(hi));
    hi += pad;
    if (!P.from_zero || lo < 0) lo -= pad;
    if (!P.from_zero && P.limits.size() >= 2) {  // +-limits: a symmetric range if nearly so
      const double m = std::max(std::fabs(lo), std::fabs(hi));
      if (lo < 0 && hi > 0 && std::fabs(lo + hi) < 0.25 * m) lo = -m, hi = m;
    }
    auto Y = [&](double v) { return ptop + PH - (v - lo) / (hi - lo) * PH; };
    const std::string clip = "c" + std::to_string(pi);
    o << "<g id=\"panel-" << P.id << "\" data-ymin=\"" << gfmt(lo, 10) << "\" data-ymax=\"" << gfmt(hi, 10)
      << "\" data-top=\"" << num(ptop, 2) << "\" data-height=\"" << num(PH, 2) << "\"";
    if (P.limit > 0) o << " data-limit=\"" << gfmt(P.limit, 10) << "\"";
    o << ">\n<clipPath id=\"" << clip << "\"><rect x=\"" << num(left) << "\" y=\"" << num(ptop) << "\" width=\""
      << num(Wp) << "\" height=\"" << num(PH) << "\"/></clipPath>\n";
    // grid, zero line, ticks and their labels, the y-axis label
    const Ticks yt = nice_ticks(lo, hi, 5);
    o << "<path stroke=\"#e3e3e3\" d=\"";
    for (double v : yt.v) o << "M" << num(left) << " " << num(Y(v)) << "H" << num(left + Wp);
    for (double t : tt.v) o << "M" << num(X(t)) << " " << num(ptop) << "V" << num(ptop + PH);
    o << "\"/>\n";
    if (lo < 0 && hi > 0)
      o << "<path stroke=\"#999\" stroke-width=\"0.8\" d=\"M" << num(left) << " " << num(Y(0)) << "H"
        << num(left + Wp) << "\"/>\n";
    o << "<path stroke=\"#555\" d=\"";
    for (double v : yt.v) o << "M" << num(left - 3) << " " << num(Y(v)) << "h3";
    for (double t : tt.v) o << "M" << num(X(t)) << " " << num(ptop + PH) << "v3";
    o << "\"/>\n<g font-size=\"10\" fill=\"#333\" text-anchor=\"end\">\n";
    for (double v : yt.v) o << text(left - 5, Y(v) + 3.5, tick_label(v, yt.dec));
    o << "</g>\n<g font-size=\"10\" fill=\"#333\" text-anchor=\"middle\">\n";
    for (double t : tt.v) o << text(X(t), ptop + PH + 13, tick_label(t, tt.dec));
    o << "</g>\n<text transform=\"translate(" << num(left - 56) << " " << num(ptop + PH / 2)
      << ") rotate(-90)\" text-anchor=\"middle\">" << esc(P.ylabel) << "</text>\n";
    // limits (dashed), the data, the frame
    for (const auto& L : P.limits)
      if (L.v >= lo && L.v <= hi)
        o << "<path stroke=\"" << L.colour << "\" stroke-width=\"1.2\" stroke-dasharray=\"6 4\" d=\"M" << num(left)
          << " " << num(Y(L.v)) << "H" << num(left + Wp) << "\"/>\n";
    for (const auto& s : P.series) draw_series(o, s, ta, tb, left, Wp, Y, clip);
    o << "<rect x=\"" << num(left) << "\" y=\"" << num(ptop) << "\" width=\"" << num(Wp) << "\" height=\"" << num(PH)
      << "\" fill=\"none\" stroke=\"#555\"/>\n";
    // title: the quantity, its peaks and the limit; a peak above its limit
    // (beyond the quantisation allowance, as in report.txt) is ringed in red
    std::string peaks;
    bool over = false;
    for (size_t si = 0; si < ns; ++si) {
      peaks += (si ? ", " : "") + P.series[si].label + " " + vfmt(peak[si]);
      const double lim = P.limit;
      if (lim > 0 && peak[si] > lim + P.allowance) {
        over = true;
        o << "<circle cx=\"" << num(X(peak_t[si])) << "\" cy=\"" << num(Y(peak_y[si]))
          << "\" r=\"6\" fill=\"none\" stroke=\"#d7191c\" stroke-width=\"2\"/>\n";
      }
    }
    std::string rest = "\xE2\x80\x94 peaks: " + peaks;
    if (P.limit > 0)
      rest += "; limit " + vfmt(P.limit);
    o << "<text x=\"" << num(left) << "\" y=\"" << num(ptop - 7) << "\"><tspan font-weight=\"bold\" font-size=\"11.5\">"
      << esc(P.title) << "</tspan>";
    if (!P.note.empty()) o << " <tspan fill=\"#8a5a00\" font-style=\"italic\">" << esc(P.note) << "</tspan>";
    o << " <tspan fill=\"#333\">" << esc(rest) << "</tspan>";
    if (over) o << " <tspan fill=\"#d7191c\" font-weight=\"bold\">ABOVE THE LIMIT</tspan>";
    o << "</text>\n";
    // legend, right-aligned in the title row
    {
      struct Item {
        std::string label, colour;
        bool dashed;
      };
      std::vector<Item> items;
      for (const auto& s : P.series) items.push_back({s.label, s.colour, false});
      if (!P.limit_label.empty()) items.push_back({P.limit_label, kLimitColour, true});
      double x = left + Wp;
      o << "<g class=\"legend\">\n";
      for (auto it = items.rbegin(); it != items.rend(); ++it) {
        x -= text_w(it->label, 10.5) + 30;
        o << "<path stroke=\"" << it->colour << "\" stroke-width=\"" << (it->dashed ? "1.2" : "2.5") << "\""
          << (it->dashed ? " stroke-dasharray=\"5 3\"" : "") << " d=\"M" << num(x) << " " << num(ptop - 10)
          << "h20\"/>\n";
        o << text(x + 24, ptop - 6.5, it->label, " font-size=\"10.5\"");
      }
      o << "</g>\n";
    }
    o << "</g>\n";
    top += row + PH + foot + gap;
    ++pi;
  }
  o << text(left + Wp / 2, top - gap + 10, "time (s)", " text-anchor=\"middle\" font-size=\"12\"");
  o << "</svg>\n";
  return o.str();
}

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

// The x-y path of the samples, coloured by the output feed.
std::string path_svg(size_t n, const std::function<std::array<double, 3>(size_t)>& pos, int d, const JobConfig& cfg,
                     double h, double allow_v) {
  const std::string& u = cfg.machine.units;
  const double feed = cfg.limits.feed;
  // data range (x, y), a margin, equal scales on both axes
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  for (size_t k = 0; k < n; ++k) {
    const auto p = pos(k);
    if (k == 0) x0 = x1 = p[0], y0 = y1 = p[1];
    x0 = std::min(x0, p[0]), x1 = std::max(x1, p[0]);
    y0 = std::min(y0, p[1]), y1 = std::max(y1, p[1]);
  }
  const double span = std::max({x1 - x0, y1 - y0, 1e-9});
  const double mxs = std::max(x1 - x0, 0.05 * span), mys = std::max(y1 - y0, 0.05 * span);
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  x0 = cx - 0.54 * mxs, x1 = cx + 0.54 * mxs, y0 = cy - 0.54 * mys, y1 = cy + 0.54 * mys;
  const double sc = std::min(720 / (x1 - x0), 620 / (y1 - y0));
  const double Wp = (x1 - x0) * sc, Hp = (y1 - y0) * sc;
  const double left = 70, top = 74, cbw = 16;
  const double W = left + Wp + 120, H = top + Hp + 52;
  auto PX = [&](const std::array<double, 3>& p) { return std::array<double, 2>{left + (p[0] - x0) * sc, top + Hp - (p[1] - y0) * sc}; };
  // Chord speed of each step in colour bands over [0, feed] (a band changes
  // once the speed is a fifth of a band beyond it: no flicker at a boundary);
  // steps above feed + the quantisation allowance in a band of their own.
  // Consecutive steps are merged into strokes at least `spacing` pixels long
  // (0: every step), each coloured by its mean speed, or as above the feed if
  // any of its steps is. Runs of one band become simplified subpaths (tolerance
  // `tol` px), one <path> per band. Spacing and tolerance grow until at most
  // kMaxPoints points remain, so the file stays small whatever the run length.
  constexpr size_t kMaxPoints = 40000;
  const int nb = 20;
  std::vector<std::string> bands(nb + 1);
  double smin = 0, smax = 0;
  size_t over = 0;
  for (size_t k = 0; k + 1 < n; ++k) {
    const auto a = pos(k), b = pos(k + 1);
    const double s = chord_speed(a.data(), b.data(), d, h);
    smin = k ? std::min(smin, s) : s;
    smax = std::max(smax, s);
    if (s > feed + allow_v) ++over;
  }
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
    std::array<double, 3> prev = n ? pos(0) : std::array<double, 3>{};
    std::array<double, 2> start_px = PX(prev);  // the current stroke's first point
    double len = 0;                              // its length (units) and steps
    size_t steps = 0;
    bool stroke_over = false;
    for (size_t k = 0; k + 1 < n; ++k) {
      const auto next = pos(k + 1);
      const double s = chord_speed(prev.data(), next.data(), d, h);
      len += s * h;
      ++steps;
      stroke_over = stroke_over || s > feed + allow_v;
      prev = next;
      const auto q = PX(next);
      const double px = std::hypot(q[0] - start_px[0], q[1] - start_px[1]);
      if (px < spacing && k + 2 < n) continue;  // the stroke goes on
      int b;
      if (stroke_over) {
        b = nb;
      } else {
        const double f = std::clamp(len / (steps * h) / feed * nb, 0.0, nb - 1e-9);
        b = static_cast<int>(f);
        if (cur >= 0 && cur < nb && f > cur - 0.2 && f < cur + 1.2) b = cur;
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
    if (total <= kMaxPoints) break;
    tol = std::min(1.0, tol * 2);
    spacing = std::max(0.5, spacing * 2);
  }
  std::ostringstream o;
  o << svg_open(W, H);
  o << text(left, 24, "Path (x-y) of the core's output samples, coloured by the output feed",
            " font-size=\"15\" font-weight=\"bold\"");
  o << text(left, 43,
            std::to_string(n) + " samples at " + gfmt(h * 1e3) + " ms; output feed = chord speed |x(k+1) \xE2\x88\x92 x(k)| / h" +
                (d > 2 ? "; projection on x-y" : "") + "; equal scales",
            " fill=\"#444\"");
  o << text(left, 59,
            "output feed " + vfmt(smin) + " \xE2\x80\xA6 " + vfmt(smax) + " " + u + "/s (commanded " + vfmt(feed) + " " +
                u + "/s)" + (over ? "; " + std::to_string(over) + " steps above the feed" : ""),
            over ? " fill=\"#c0392b\" font-weight=\"bold\"" : " fill=\"#444\"");
  // grid and ticks, one step on both axes
  const double step = nice_ticks(0, std::max(x1 - x0, y1 - y0), 8).step;
  const int dec = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  auto ticks = [&](double a, double b) {
    std::vector<double> v;
    for (double i = std::ceil(a / step - 1e-9); i * step <= b + 1e-9 * step; i += 1) v.push_back(i * step);
    return v;
  };
  const auto xt = ticks(x0, x1), yt = ticks(y0, y1);
  auto XP = [&](double v) { return left + (v - x0) * sc; };
  auto YP = [&](double v) { return top + Hp - (v - y0) * sc; };
  o << "<path stroke=\"#ececec\" d=\"";
  for (double v : xt) o << "M" << num(XP(v)) << " " << num(top) << "V" << num(top + Hp);
  for (double v : yt) o << "M" << num(left) << " " << num(YP(v)) << "H" << num(left + Wp);
  o << "\"/>\n<path stroke=\"#555\" d=\"";
  for (double v : xt) o << "M" << num(XP(v)) << " " << num(top + Hp) << "v4";
  for (double v : yt) o << "M" << num(left) << " " << num(YP(v)) << "h-4";
  o << "\"/>\n<g font-size=\"10\" fill=\"#333\" text-anchor=\"middle\">\n";
  for (double v : xt) o << text(XP(v), top + Hp + 16, tick_label(v, dec));
  o << "</g>\n<g font-size=\"10\" fill=\"#333\" text-anchor=\"end\">\n";
  for (double v : yt) o << text(left - 7, YP(v) + 3.5, tick_label(v, dec));
  o << "</g>\n";
  o << text(left + Wp / 2, top + Hp + 36, "x (" + u + ")", " text-anchor=\"middle\" font-size=\"12\"");
  o << "<text transform=\"translate(" << num(left - 48) << " " << num(top + Hp / 2)
    << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"12\">" << esc("y (" + u + ")") << "</text>\n";
  // the path: each colour band's geometry once (<defs>), drawn twice: a thin
  // dark casing under all of it (light colours read on white), then coloured
  o << "<defs>\n";
  for (int b = 0; b <= nb; ++b)
    if (!bands[b].empty()) o << "<path id=\"band" << b << "\" d=\"" << bands[b] << "\"/>\n";
  o << "</defs>\n<g fill=\"none\" stroke-width=\"2.4\" stroke-linecap=\"round\" stroke-linejoin=\"round\">\n";
  o << "<g stroke=\"#333\" stroke-width=\"3.6\" stroke-opacity=\"0.55\">";
  for (int b = 0; b <= nb; ++b)
    if (!bands[b].empty()) o << "<use xlink:href=\"#band" << b << "\"/>";
  o << "</g>\n";
  for (int b = 0; b <= nb; ++b)
    if (!bands[b].empty())
      o << "<use xlink:href=\"#band" << b << "\" stroke=\"" << (b == nb ? kOverColour : viridis((b + 0.5) / nb))
        << "\"/>\n";
  o << "</g>\n<rect x=\"" << num(left) << "\" y=\"" << num(top) << "\" width=\"" << num(Wp) << "\" height=\""
    << num(Hp) << "\" fill=\"none\" stroke=\"#555\"/>\n";
  // start (ring), end (square), direction of travel (arrow)
  if (n) {
    const auto s0 = PX(pos(0)), s1 = PX(pos(n - 1));
    for (size_t k = 1; k < n; k += std::max<size_t>(1, n / 100000)) {
      const auto q = PX(pos(k));
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
      const bool right_side = at[0] < left + Wp - 90;
      o << text(at[0] + (right_side ? 11 : -11), at[1] - 9, s, right_side ? "" : " text-anchor=\"end\"");
    };
    if (std::hypot(s1[0] - s0[0], s1[1] - s0[1]) < 10) {
      label(s0, "start = end");
    } else {
      label(s0, "start");
      label(s1, "end");
    }
  }
  // colour bar, 0 .. commanded feed
  {
    const double bx = left + Wp + 28, bh = std::min(Hp, 360.0), by = top + (Hp - bh) / 2;
    o << "<g id=\"colourbar\" data-vmin=\"0\" data-vmax=\"" << gfmt(feed, 10) << "\">\n";
    for (int b = 0; b < nb; ++b)
      o << "<rect x=\"" << num(bx) << "\" y=\"" << num(by + bh - (b + 1) * bh / nb) << "\" width=\"" << num(cbw)
        << "\" height=\"" << num(bh / nb + 0.3) << "\" fill=\"" << viridis((b + 0.5) / nb) << "\"/>\n";
    o << "<rect x=\"" << num(bx) << "\" y=\"" << num(by) << "\" width=\"" << num(cbw) << "\" height=\"" << num(bh)
      << "\" fill=\"none\" stroke=\"#555\"/>\n";
    const Ticks ct = nice_ticks(0, feed, 5);
    o << "<path stroke=\"#555\" d=\"";
    for (double v : ct.v) o << "M" << num(bx + cbw) << " " << num(by + bh - v / feed * bh) << "h4";
    o << "\"/>\n";
    for (double v : ct.v) o << text(bx + cbw + 7, by + bh - v / feed * bh + 3.5, tick_label(v, ct.dec), " font-size=\"10\"");
    if (over) {
      o << "<rect x=\"" << num(bx) << "\" y=\"" << num(by - 22) << "\" width=\"" << num(cbw)
        << "\" height=\"12\" fill=\"" << kOverColour << "\"/>\n";
      o << text(bx + cbw + 7, by - 12, "> feed", " font-size=\"10\"");
    }
    o << "<text transform=\"translate(" << num(bx + cbw + 52) << " " << num(by + bh / 2)
      << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"12\">" << esc("output feed (" + u + "/s)") << "</text>\n";
    o << "</g>\n";
  }
  o << "</svg>\n";
  return o.str();
}

// Writes every file to <name>.tmp, then renames them all into place; on any
// failure the temporary files are removed and a PlanError names the plot.
void write_all(const std::vector<std::pair<std::string, std::string>>& files) {
  std::vector<std::unique_ptr<util::AtomicFile>> out;
  size_t i = 0;
  try {
    for (; i < files.size(); ++i) {
      out.push_back(std::make_unique<util::AtomicFile>(files[i].first, std::ios::binary));
      out.back()->out() << files[i].second;
    }
    for (i = 0; i < files.size(); ++i) out[i]->commit();
  } catch (const std::exception& e) {
    throw PlanError("cannot write plot " + files[i].first + ": " + e.what());
  }
}

}  // namespace

void write_plots(const std::string& dir, const Path& p, const JobConfig& cfg, const JobResult& r, const Samples& s) {
  {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw PlanError("cannot write plots: cannot create directory " + dir + ": " + ec.message());
  }
  const int d = std::clamp(p.dim(), 1, 3);
  const double h = cfg.machine.period;
  const double lsb = std::ldexp(1.0, -r.header.frac_bits);
  const auto& L = cfg.limits;
  const std::string& u = cfg.machine.units;
  const bool jerk = r.header.degree != 3;  // cubic segments join C1: no jerk claim
  const size_t n = s.v.size();
  auto X = [&](size_t k) {
    std::array<double, 3> q;
    for (int a = 0; a < 3; ++a) q[a] = static_cast<double>(s.v[k][a]) * lsb;
    return q;
  };
  // quantisation allowance on sample differences, as in make_report
  double bound = 0;
  for (const auto& c : r.compiled) bound = std::max(bound, c.bound_lsb);
  const double quant = (0.5 + bound) * lsb, sd = std::sqrt(static_cast<double>(d));
  const double allow_v = 2 * quant / h, allow_a = 4 * quant / (h * h), allow_j = 8 * quant / (h * h * h);
  const std::string u1 = u + "/s", u2 = u + "/s\xC2\xB2", u3 = u + "/s\xC2\xB3";
  const std::string not_limited = "not limited (cubic, C1 joins)";

  // output: differences of the samples (sampled.hpp; per axis as in
  // make_report), each at the centre of the ticks it spans
  auto out = [&](const std::string& label, double t0, size_t count, std::function<double(size_t)> y) {
    Series q;
    q.label = label, q.colour = kOutColour, q.t0 = t0, q.dt = h, q.count = count, q.y = std::move(y);
    return q;
  };
  auto cs = [&](size_t k) {  // chord speed over ticks k, k+1
    const auto a = X(k), b = X(k + 1);
    return chord_speed(a.data(), b.data(), d, h);
  };
  auto win = [&](size_t k) {
    const auto a = X(k), b = X(k + 1), c = X(k + 2);
    if (k + 3 < n) {
      const auto e = X(k + 3);
      return sampled_window(a.data(), b.data(), c.data(), e.data(), d, h, 16 * lsb);
    }
    return sampled_window(a.data(), b.data(), c.data(), nullptr, d, h, 16 * lsb);
  };
  const size_t n1 = n > 0 ? n - 1 : 0, n2 = n > 1 ? n - 2 : 0, n3 = n > 2 ? n - 3 : 0;
  const Series out_v = out("output", 0.5 * h, n1, cs);
  const Series out_at = out("output", h, n2, [&](size_t k) { return (cs(k + 1) - cs(k)) / h; });
  const Series out_jt = out("output", 1.5 * h, n3, [&](size_t k) { return (cs(k + 2) - 2 * cs(k + 1) + cs(k)) / (h * h); });
  const Series out_an = out("output", h, n2, [&](size_t k) { return win(k).an; });
  const Series out_jn = out("output", 1.5 * h, n3, [&](size_t k) { return win(k).jn; });
  auto out_aa = [&](int a) {
    return out("output", h, n2, [&, a](size_t k) {
      return (s.v[k + 2][a] * lsb - 2 * (s.v[k + 1][a] * lsb) + s.v[k][a] * lsb) / (h * h);
    });
  };
  auto out_ja = [&](int a) {
    return out("output", 1.5 * h, n3, [&, a](size_t k) {
      return (s.v[k + 3][a] * lsb - 3 * (s.v[k + 2][a] * lsb) + 3 * (s.v[k + 1][a] * lsb) - s.v[k][a] * lsb) /
             (h * h * h);
    });
  };
  // plan: the planner's values at the ticks
  auto plan = [&](const std::string& label, std::function<double(const TickSample&)> f) {
    Series q;
    q.label = label, q.colour = kPlanColour, q.t0 = r.ticks.empty() ? 0 : r.ticks.front().t, q.dt = h;
    q.count = r.ticks.size(), q.y = [&r, f](size_t k) { return f(r.ticks[k]); };
    q.width = 2.6, q.opacity = 0.85, q.band = Band::kFill, q.fill = 0.35;
    return q;
  };
  auto member = [&](const std::string& label, double TickSample::*m) {
    return plan(label, [m](const TickSample& t) { return t.*m; });
  };

  auto panel = [](const std::string& id, const std::string& title, const std::string& ylabel, std::vector<Series> sv) {
    Panel P;
    P.id = id, P.title = title, P.ylabel = ylabel, P.series = std::move(sv);
    return P;
  };
  auto limit_pm = [&](Panel& P, double lim, const std::string& name, double allowance) {
    P.limits = {{lim, kLimitColour}, {-lim, kLimitColour}};
    P.limit_label = "\xC2\xB1" + name;
    P.limit = lim;
    P.allowance = allowance;
  };
  auto limit_up = [&](Panel& P, double lim, const std::string& name, double allowance) {
    P.limits = {{lim, kLimitColour}};
    P.limit_label = name;
    P.limit = lim;
    P.allowance = allowance;
  };

  std::vector<Panel> panels;
  {
    Panel P = panel("speed", "Path speed (feed)", "speed (" + u1 + ")", {member("plan", &TickSample::v), out_v});
    limit_up(P, L.feed, "feed", sd * allow_v);
    P.from_zero = true;
    panels.push_back(P);
  }
  {
    Panel P = panel("a_tan", "Tangential acceleration", "a_tan (" + u2 + ")", {member("plan", &TickSample::a), out_at});
    limit_pm(P, L.a_tan, "a_tan", sd * allow_a);
    panels.push_back(P);
  }
  {
    Panel P = panel("j_tan", "Tangential jerk", "j_tan (" + u3 + ")", {member("plan", &TickSample::j), out_jt});
    if (jerk)
      limit_pm(P, L.j_tan, "j_tan", sd * allow_j);
    else
      P.note = not_limited;
    panels.push_back(P);
  }
  for (int a = 0; a < d; ++a) {
    const std::string ax(1, "xyz"[a]);
    Panel P = panel("a_" + ax, ax + " acceleration", "a_" + ax + " (" + u2 + ")",
                    {plan("plan", [a](const TickSample& t) { return t.ddx[a]; }), out_aa(a)});
    limit_pm(P, L.a_axis[a], "a_" + ax, allow_a);
    panels.push_back(P);
  }
  for (int a = 0; a < d; ++a) {
    const std::string ax(1, "xyz"[a]);
    Panel P = panel("j_" + ax, ax + " jerk", "j_" + ax + " (" + u3 + ")",
                    {plan("plan", [a](const TickSample& t) { return t.dddx[a]; }), out_ja(a)});
    if (jerk)
      limit_pm(P, L.j_axis[a], "j_" + ax, allow_j);
    else
      P.note = not_limited;
    panels.push_back(P);
  }
  {
    Panel P = panel("a_cen", "Centripetal acceleration", "a_cen (" + u2 + ")",
                    {member("plan", &TickSample::a_cen), out_an});
    limit_up(P, L.a_cen, "a_cen", sd * allow_a);
    P.from_zero = true;
    panels.push_back(P);
  }
  {
    Panel P = panel("j_cen", "Centripetal jerk", "j_cen (" + u3 + ")",
                    {member("plan (bound)", &TickSample::j_cen_geo), out_jn});
    P.from_zero = true;
    if (jerk)
      limit_up(P, L.j_cen, "j_cen", sd * allow_j);
    else
      P.note = not_limited;
    panels.push_back(P);
  }

  const double T = std::max({n > 1 ? (n - 1) * h : 0.0, r.ticks.empty() ? 0.0 : r.ticks.back().t, h});
  const double per_col = T / h / kPlotW;
  const std::string prof = profile_svg(
      "Speed, acceleration and jerk against time: plan and output, with the limits",
      std::to_string(n) + " output samples at " + gfmt(h * 1e3) + " ms, " + gfmt(T) +
          " s. plan: the planner at the ticks; output: differences of the core's samples\n"
          "over 1, 2, 3 ticks (as in report.txt), at the centre of their ticks. Dashed: the limits; every y range "
          "covers the data and the limits." +
          (per_col > 1 ? "\nShaded: the min/max of a series over each pixel column (" + gfmt(per_col, 3) +
                             " samples a column), so that no peak is lost."
                       : std::string()),
      panels, 0, T);
  const std::string path = path_svg(n, X, d, cfg, h, sd * allow_v);
  write_all({{dir + "/path_feed.svg", path}, {dir + "/profile.svg", prof}});
}

}  // namespace traj::report
