// trajcore planner: SVG plots of a job (see pipeline.hpp, write_plots).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "planner/pipeline.hpp"

namespace traj::plan {

namespace {

std::string colour(double f) {  // blue -> green -> yellow -> red
  f = std::clamp(f, 0.0, 1.0);
  const double r = std::clamp(2 * f - 0.5, 0.0, 1.0) * 255, g = std::clamp(f < 0.75 ? 2 * f : 4 * (1 - f), 0.0, 1.0) * 255,
               b = std::clamp(1 - 2 * f, 0.0, 1.0) * 255;
  char s[16];
  std::snprintf(s, sizeof s, "#%02x%02x%02x", int(r), int(g), int(b));
  return s;
}

void write_atomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream o(tmp);
    if (!o) throw PlanError("cannot write " + tmp);
    o << text;
    o.close();
    if (!o) throw PlanError("write failed: " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace

void write_plots(const std::string& dir, const Path& p, const JobConfig& cfg, const JobResult& r, const Samples& s) {
  std::filesystem::create_directories(dir);
  const double lsb = std::ldexp(1.0, -r.header.frac_bits);
  const double h = cfg.plan.period;
  const size_t n = s.v.size();
  // --- path coloured by feed (output feed from consecutive samples) ---
  {
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (const auto& v : s.v) {
      x0 = std::min(x0, v[0] * lsb);
      x1 = std::max(x1, v[0] * lsb);
      y0 = std::min(y0, v[1] * lsb);
      y1 = std::max(y1, v[1] * lsb);
    }
    const double W = 800, H = 800 * std::max(0.2, (y1 - y0) / std::max(1e-12, x1 - x0)), m = 40;
    const double sc = (W - 2 * m) / std::max(1e-12, x1 - x0);
    std::ostringstream o;
    o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H + 60 << "' font-family='sans-serif' font-size='12'>\n";
    o << "<rect width='100%' height='100%' fill='white'/>\n";
    o << "<text x='" << m << "' y='20'>path coloured by output feed (x-y), 0 to " << cfg.limits.feed << " " << cfg.units
      << "/s</text>\n";
    const size_t stride = std::max<size_t>(1, n / 20000);
    for (size_t k = 0; k + stride < n; k += stride) {
      double c2 = 0;
      for (int a = 0; a < p.dim(); ++a) {
        const double dd = (s.v[k + stride][a] - s.v[k][a]) * lsb;
        c2 += dd * dd;
      }
      const double feed = std::sqrt(c2) / (stride * h);
      auto X = [&](const std::array<long long, 3>& v) { return m + (v[0] * lsb - x0) * sc; };
      auto Y = [&](const std::array<long long, 3>& v) { return 30 + H - m - (v[1] * lsb - y0) * sc; };
      o << "<line x1='" << X(s.v[k]) << "' y1='" << Y(s.v[k]) << "' x2='" << X(s.v[k + stride]) << "' y2='"
        << Y(s.v[k + stride]) << "' stroke='" << colour(feed / cfg.limits.feed) << "' stroke-width='2'/>\n";
    }
    for (int i = 0; i <= 10; ++i)
      o << "<rect x='" << m + i * 30 << "' y='" << H + 30 << "' width='30' height='12' fill='" << colour(i / 10.0)
        << "'/>\n";
    o << "<text x='" << m + 340 << "' y='" << H + 41 << "'>feed / commanded feed, 0 .. 1</text>\n";
    o << "</svg>\n";
    write_atomic(dir + "/path_feed.svg", o.str());
  }
  // --- feed, acceleration, jerk against time ---
  {
    const double W = 900, PH = 200, m = 60;
    const double T = r.ticks.empty() ? 1 : r.ticks.back().t;
    std::ostringstream o;
    o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << 3 * (PH + 40) + 20
      << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n";
    struct Panel {
      const char* title;
      double lim;
      std::function<double(size_t)> plan;
    };
    const auto& L = cfg.limits;
    Panel panels[3] = {{"feed (plan, and output chord/h in red)", L.feed, [&](size_t k) { return r.ticks[k].v; }},
                       {"tangential acceleration (plan)", L.a_tan, [&](size_t k) { return r.ticks[k].a; }},
                       {"tangential jerk (plan)", L.j_tan, [&](size_t k) { return r.ticks[k].j; }}};
    const size_t stride = std::max<size_t>(1, r.ticks.size() / 4000);
    for (int pi = 0; pi < 3; ++pi) {
      const double top = 20 + pi * (PH + 40) + 20;
      const double lim = panels[pi].lim;
      const double lo = pi == 0 ? 0 : -lim * 1.1, hi = lim * 1.1;
      auto Y = [&](double v) { return top + PH - (std::clamp(v, lo, hi) - lo) / (hi - lo) * PH; };
      auto X = [&](double t) { return m + t / T * (W - 2 * m); };
      o << "<text x='" << m << "' y='" << top - 6 << "'>" << panels[pi].title << ", limit " << lim << "</text>\n";
      o << "<rect x='" << m << "' y='" << top << "' width='" << W - 2 * m << "' height='" << PH
        << "' fill='none' stroke='#888'/>\n";
      o << "<line x1='" << m << "' x2='" << W - m << "' y1='" << Y(lim) << "' y2='" << Y(lim)
        << "' stroke='#c00' stroke-dasharray='4'/>\n";
      if (pi > 0)
        o << "<line x1='" << m << "' x2='" << W - m << "' y1='" << Y(-lim) << "' y2='" << Y(-lim)
          << "' stroke='#c00' stroke-dasharray='4'/>\n";
      o << "<polyline fill='none' stroke='#036' stroke-width='1' points='";
      for (size_t k = 0; k < r.ticks.size(); k += stride) o << X(r.ticks[k].t) << "," << Y(panels[pi].plan(k)) << " ";
      o << "'/>\n";
      if (pi == 0) {
        o << "<polyline fill='none' stroke='#c33' stroke-width='0.7' points='";
        for (size_t k = 0; k + 1 < n; k += stride) {
          double c2 = 0;
          for (int a = 0; a < 3; ++a) {
            const double dd = (s.v[k + 1][a] - s.v[k][a]) * lsb;
            c2 += dd * dd;
          }
          o << X(k * h) << "," << Y(std::sqrt(c2) / h) << " ";
        }
        o << "'/>\n";
      }
      o << "<text x='" << W - m << "' y='" << top + PH + 14 << "' text-anchor='end'>" << T << " s</text>\n";
    }
    o << "</svg>\n";
    write_atomic(dir + "/profile.svg", o.str());
  }
}

}  // namespace traj::plan
