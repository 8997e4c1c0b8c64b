// SPDX-License-Identifier: Apache-2.0
// SVG plots of a job (report.hpp, write_plots).
//
//   path_feed.svg  the path of the core's output samples (plot_path.cpp).
//   profile.svg    against time, the whole motion, one panel each: path speed,
//                  tangential acceleration and jerk, acceleration and jerk of
//                  each axis, centripetal acceleration and jerk; the plan and
//                  the output, with the limits dashed.
//
// Output quantities are the report's (make_report, sampled.hpp): differences of
// the samples over 1, 2, 3 ticks, each drawn at the centre of its ticks. Where a
// pixel column holds more than one sample, a series is drawn as its min/max
// envelope over the column (a band), so no extreme is lost to decimation. The
// y range always covers the data and the limits: nothing is clamped. The
// profile stays small whatever the length of the run (a few points per pixel
// column and series).
//
// Both files are written to temporaries (util::AtomicFile) in `dir`, then renamed into place;
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
#include "report/plot_svg.hpp"
#include "report/profile_svg.hpp"
#include "report/report.hpp"
#include "util/atomic_file.hpp"

namespace traj::report {

using namespace plan;
using job::JobConfig;
using job::JobResult;
using namespace svg;

namespace {

// Profile page layout (pixels).
constexpr double kPageW = 1000, kLeft = 84, kRight = 22, kPlotW = kPageW - kLeft - kRight;

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

}  // namespace

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

namespace {


// Writes every file to its temporary, then renames them all into place; on any
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

void write_plot_pages(const std::string& dir, const PlotSource& src, const JobConfig& cfg) {
  {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw PlanError("cannot write plots: cannot create directory " + dir + ": " + ec.message());
  }
  const int d = std::clamp(src.axes, 1, kMaxAxes);
  const double h = cfg.machine.period;
  const double lsb = src.lsb;
  const auto& L = cfg.limits;
  const std::string& u = cfg.machine.units;
  const bool jerk = src.jerk_claimed;
  const size_t n = src.count;
  const std::vector<TickSample> no_ticks;
  const std::vector<TickSample>& ticks = src.plan ? *src.plan : no_ticks;
  auto X = [&](size_t k) {
    const Sample v = src.sample(k);
    std::array<double, kMaxAxes> q;
    for (int a = 0; a < kMaxAxes; ++a) q[a] = static_cast<double>(v[a]) * lsb;
    return q;
  };
  const double sd = std::sqrt(static_cast<double>(d));
  const double allow_v = src.allowance.v, allow_a = src.allowance.a, allow_j = src.allowance.j;
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
    return out("output", h, n2, [&, a](size_t k) { return (X(k + 2)[a] - 2 * X(k + 1)[a] + X(k)[a]) / (h * h); });
  };
  auto out_ja = [&](int a) {
    return out("output", 1.5 * h, n3, [&, a](size_t k) {
      return (X(k + 3)[a] - 3 * X(k + 2)[a] + 3 * X(k + 1)[a] - X(k)[a]) / (h * h * h);
    });
  };
  // plan: the planner's values at the ticks its checks run on; where the
  // fit tick is coarser than the engine's, every fit_ticks-th of the plan's
  // engine-tick samples (as report.txt's plan column: between fit ticks the
  // plan is not held to its bounds, the output is)
  const size_t every = ticks.size() == n ? static_cast<size_t>(cfg.machine.fit_ticks()) : 1;
  auto plan = [&](const std::string& label, std::function<double(const TickSample&)> f) {
    Series q;
    q.label = label, q.colour = kPlanColour, q.t0 = ticks.empty() ? 0 : ticks.front().t, q.dt = every * h;
    q.count = ticks.empty() ? 0 : (ticks.size() - 1) / every + 1;
    q.y = [&ticks, f, every](size_t k) { return f(ticks[k * every]); };
    q.width = 2.6, q.opacity = 0.85, q.band = Band::kFill, q.fill = 0.35;
    return q;
  };
  auto member = [&](const std::string& label, double TickSample::*m) {
    return plan(label, [m](const TickSample& t) { return t.*m; });
  };

  // without a plan (sim of a stream), the output alone
  auto panel = [&](const std::string& id, const std::string& title, const std::string& ylabel, std::vector<Series> sv) {
    Panel P;
    P.id = id, P.title = title, P.ylabel = ylabel;
    for (Series& q : sv)
      if (q.colour != kPlanColour || src.plan) P.series.push_back(std::move(q));
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
    if (src.feed_limited)
      limit_up(P, L.feed, "feed", sd * allow_v);
    else
      P.note = "no feed limit given";
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
    const std::string ax = L.axis(a);
    Panel P = panel("a_" + ax, ax + " acceleration", "a_" + ax + " (" + u2 + ")",
                    {plan("plan", [a](const TickSample& t) { return t.ddx[a]; }), out_aa(a)});
    limit_pm(P, L.a_axis[a], "a_" + ax, allow_a);
    panels.push_back(P);
  }
  for (int a = 0; a < d; ++a) {
    const std::string ax = L.axis(a);
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

  const double T = std::max({n > 1 ? (n - 1) * h : 0.0, ticks.empty() ? 0.0 : ticks.back().t, h});
  const double per_col = T / h / kPlotW;
  const std::string prof = profile_svg(
      std::string("Speed, acceleration and jerk against time: ") + (src.plan ? "plan and output" : "output") +
          ", with the limits",
      std::to_string(n) + " output samples at " + gfmt(h * 1e3) + " ms, " + gfmt(T) + " s. " +
          (src.plan ? (every > 1 ? "plan: the planner at the fit ticks (every " + std::to_string(every) +
                                       " ticks), where it is checked; "
                                 : std::string("plan: the planner at the ticks; "))
                    : std::string()) +
          "output: differences of the core's samples\n"
          "over 1, 2, 3 ticks (as in report.txt), at the centre of their ticks. Dashed: the limits; every y range "
          "covers the data and the limits." +
          (per_col > 1 ? "\nShaded: the min/max of a series over each pixel column (" + gfmt(per_col, 3) +
                             " samples a column), so that no peak is lost."
                       : std::string()),
      panels, 0, T);
  // the path in X Y Z (the further axes: their panels)
  const auto xyz = [&](size_t k) {
    const auto q = X(k);
    return std::array<double, 3>{q[0], q[1], q[2]};
  };
  const std::string path = path_svg(n, xyz, std::min(d, 3), cfg, h, sd * allow_v, src.scale_feed, src.rapid_step);
  write_all({{dir + "/path_feed.svg", path}, {dir + "/profile.svg", prof}});
}

void write_plots(const std::string& dir, const Path& p, const JobConfig& cfg, const JobResult& r, const Samples& s,
                 double scale_feed, const std::vector<char>& rapid_curve) {
  // quantisation allowance on sample differences, as in make_report
  double bound = 0;
  double offset = 0;
  for (const auto& c : r.compiled) {
    bound = std::max(bound, c.bound_lsb);
    offset = std::max(offset, c.offset_lsb);
  }
  PlotSource src;
  src.count = s.v.size();
  src.sample = [&s](size_t k) { return s.v[k]; };
  src.axes = p.dim();
  src.lsb = std::ldexp(1.0, -r.header.frac_bits);
  src.jerk_claimed = r.header.degree != 3;  // cubic segments join C1: no jerk claim
  src.allowance = job::sample_allowance((0.5 + bound) * src.lsb, offset * src.lsb, cfg.machine.period);
  src.plan = &r.ticks;
  src.scale_feed = scale_feed;
  if (!rapid_curve.empty()) {
    // output sample k is tick k's: the step to k + 1 is in the curve of tick k + 1
    src.rapid_step = [&r, &rapid_curve](size_t k) {
      const size_t t = std::min(k + 1, r.ticks.size() - 1);
      const size_t c = r.ticks[t].curve;
      return c < rapid_curve.size() && rapid_curve[c];
    };
  }
  write_plot_pages(dir, src, cfg);
}

}  // namespace traj::report
