// SPDX-License-Identifier: Apache-2.0
// SVG building blocks shared by the plots (plots.cpp, plot_path.cpp): number
// formatting, ticks, the colour map, text, and compact path data.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "job/job.hpp"

namespace traj::report::svg {

constexpr const char* kFont = "DejaVu Sans, Helvetica, Arial, sans-serif";
constexpr const char* kLimitColour = "#c0392b";
constexpr const char* kPlanColour = "#f28e2b";
constexpr const char* kOutColour = "#1f4e99";
constexpr const char* kOverColour = "#e7298a";
constexpr const char* kRapidColour = "#9e9e9e";  // a rapid move (by the plan, or faster than the colour scale)

// Fixed-point text with `dec` decimals, trailing zeros dropped, "-0" -> "0".
inline std::string num(double v, int dec = 1) {
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

inline std::string gfmt(double v, int sig = 4) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*g", sig, v);
  return b;
}

// A measured value: 4 significant digits, no exponent between 1e-4 and 1e7.
inline std::string vfmt(double v) {
  const double a = std::fabs(v);
  if (a == 0) return "0";
  if (a < 1e-4 || a >= 1e7 || !std::isfinite(a)) return gfmt(v);
  return num(v, std::max(0, 3 - static_cast<int>(std::floor(std::log10(a)))));
}

// Tick label: a typographic minus for negative values.
inline std::string tick_label(double v, int dec) {
  std::string s = num(v, dec);
  if (!s.empty() && s[0] == '-') s = "\xE2\x88\x92" + s.substr(1);
  return s;
}

inline std::string esc(const std::string& s) {
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

// Ticks every `step` inside [lo, hi] (at most about 100), with the decimals their labels need.
inline Ticks ticks_at(double lo, double hi, double step) {
  Ticks t;
  t.step = step;
  t.dec = std::max(0, static_cast<int>(-std::floor(std::log10(t.step) + 1e-9)));
  const double first = std::ceil(lo / t.step - 1e-9);
  for (double i = first;; i += 1) {
    const double x = i * t.step;
    if (x > hi + 1e-9 * t.step || t.v.size() > 100) break;
    t.v.push_back(std::fabs(x) < 1e-12 * t.step ? 0.0 : x);
  }
  return t;
}

// 1, 2, 5 x 10^k ticks inside [lo, hi], about `target` of them.
inline Ticks nice_ticks(double lo, double hi, int target) {
  double span = hi - lo;
  if (!(span > 0) || !std::isfinite(span)) span = std::max(1.0, std::fabs(lo));
  const double raw = span / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  return ticks_at(lo, hi, (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * mag);
}

// Perceptually uniform colour map (viridis stops), f in [0, 1].
inline std::string viridis(double f) {
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

inline std::string svg_open(double w, double h) {
  std::ostringstream o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" width=\"" << num(w)
    << "\" height=\"" << num(h) << "\" viewBox=\"0 0 " << num(w) << " " << num(h) << "\" font-family=\"" << kFont
    << "\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  return o.str();
}

inline std::string text(double x, double y, const std::string& s, const char* extra = "") {
  return "<text x=\"" + num(x) + "\" y=\"" + num(y) + "\"" + extra + ">" + esc(s) + "</text>\n";
}

// Approximate width of a label at 11 px (DejaVu Sans averages ~6.3 px a character).
inline double text_w(const std::string& s, double size = 11) {
  size_t chars = 0;
  for (unsigned char c : s)
    if ((c & 0xC0) != 0x80) ++chars;  // count UTF-8 code points
  return chars * size * 0.58;
}

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

// path_feed.svg (plot_path.cpp): the path of the n samples pos(k) (d axes, tick
// h), coloured by the output feed; allow_v: the quantisation allowance on the
// chord speed. The colour scale runs from 0 to scale_feed (a toolpath's
// fastest feed move; 0: the feed limit); rapids are drawn in a colour of
// their own (rapid_step(k): step k -> k+1 is in a rapid move, by the plan;
// without it, steps faster than the scale's top within the feed limit),
// steps above the limit in another. A feed limit <= 0: none given (sim of a
// stream), the colour scale up to scale_feed.
std::string path_svg(size_t n, const std::function<std::array<double, 3>(size_t)>& pos, int d,
                     const job::JobConfig& cfg, double h, double allow_v, double scale_feed = 0,
                     const std::function<bool(size_t)>& rapid_step = {});

}  // namespace traj::report::svg
