// SPDX-License-Identifier: Apache-2.0
// Tests of the SVG plots (host/report/plots.cpp, plot_path.cpp, write_plots):
// well-formed XML, the labels a reader needs, three projections of a 3-D path,
// min/max envelopes that keep a one-sample spike, a bounded file size on long
// runs, and atomic writes that leave no temporary file behind on failure.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "input/path_json.hpp"
#include "report/plot_svg.hpp"
#include "report/report.hpp"
#include "util/atomic_file.hpp"

using namespace traj;
using namespace traj::plan;
using namespace traj::input;
using namespace traj::job;
using namespace traj::report;
namespace fs = std::filesystem;

#ifndef TRAJ_ASSETS
#error "TRAJ_ASSETS must name host/assets"
#endif

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream i(p, std::ios::binary);
  std::ostringstream o;
  o << i.rdbuf();
  return o.str();
}

// Each test writes into <tmp>/trajcore_plots_test_<pid>/<name>, removed at the
// end unless TRAJ_KEEP_PLOTS is set (to look at the plots).
fs::path test_root() { return fs::temp_directory_path() / ("trajcore_plots_test_" + std::to_string(::getpid())); }

class CleanUp : public ::testing::Environment {
 public:
  void TearDown() override {
    if (std::getenv("TRAJ_KEEP_PLOTS")) return;
    std::error_code ec;
    fs::remove_all(test_root(), ec);
  }
};
const auto* const kCleanUp = ::testing::AddGlobalTestEnvironment(new CleanUp);

// A fresh, empty directory for one test.
fs::path fresh_dir(const std::string& name) {
  const fs::path d = test_root() / name;
  std::error_code ec;
  fs::permissions(d, fs::perms::owner_all, fs::perm_options::add, ec);
  fs::remove_all(d, ec);
  fs::create_directories(d);
  return d;
}

bool has_tmp_file(const fs::path& d) {
  for (const auto& e : fs::directory_iterator(d))
    if (e.path().extension() == ".tmp") return true;
  return false;
}

// Minimal XML check: tags nest and balance, attributes are quoted, '<' never
// appears in text or attribute values, every '&' starts a known entity.
// Returns "" when well-formed, else the first problem.
std::string xml_problem(const std::string& s) {
  std::vector<std::string> stack;
  size_t i = 0, roots = 0;
  auto entity_ok = [&](size_t at) {
    static const char* ents[] = {"&amp;", "&lt;", "&gt;", "&quot;", "&apos;"};
    for (const char* e : ents)
      if (s.compare(at, std::strlen(e), e) == 0) return true;
    return false;
  };
  while (i < s.size()) {
    if (s[i] == '&' && !entity_ok(i)) return "bad entity at " + std::to_string(i);
    if (s[i] != '<') {
      if (stack.empty() && !std::isspace(static_cast<unsigned char>(s[i]))) return "text outside the root";
      ++i;
      continue;
    }
    if (s.compare(i, 5, "<?xml") == 0) {
      const size_t e = s.find("?>", i);
      if (e == std::string::npos) return "unterminated <?xml";
      i = e + 2;
      continue;
    }
    if (s.compare(i, 4, "<!--") == 0) {
      const size_t e = s.find("-->", i);
      if (e == std::string::npos) return "unterminated comment";
      i = e + 3;
      continue;
    }
    const bool closing = s[i + 1] == '/';
    size_t j = i + (closing ? 2 : 1);
    const size_t name0 = j;
    while (j < s.size() && (std::isalnum(static_cast<unsigned char>(s[j])) || s[j] == ':' || s[j] == '-' || s[j] == '_'))
      ++j;
    const std::string name = s.substr(name0, j - name0);
    if (name.empty()) return "empty tag name at " + std::to_string(i);
    // attributes: name="value" or name='value'
    char quote = 0;
    for (; j < s.size(); ++j) {
      const char c = s[j];
      if (quote) {
        if (c == quote) quote = 0;
        else if (c == '<') return "'<' in an attribute of <" + name + ">";
        else if (c == '&' && !entity_ok(j)) return "bad entity in an attribute of <" + name + ">";
        continue;
      }
      if (c == '"' || c == '\'') {
        if (s[j - 1] != '=') return "unexpected quote in <" + name + ">";
        quote = c;
      } else if (c == '>' || c == '<') {
        break;
      }
    }
    if (j >= s.size() || s[j] != '>') return "unterminated tag <" + name + ">";
    const bool self_closing = s[j - 1] == '/';
    if (closing) {
      if (stack.empty() || stack.back() != name)
        return "</" + name + "> closes " + (stack.empty() ? std::string("nothing") : "<" + stack.back() + ">");
      stack.pop_back();
    } else if (!self_closing) {
      if (stack.empty()) ++roots;
      stack.push_back(name);
    } else if (stack.empty()) {
      ++roots;
    }
    i = j + 1;
  }
  if (!stack.empty()) return "<" + stack.back() + "> not closed";
  if (roots != 1) return std::to_string(roots) + " root elements";
  return "";
}

// The opening tag that contains `needle` (e.g. id="panel-a_y") and its attributes.
std::map<std::string, std::string> attrs_of(const std::string& svg, const std::string& needle) {
  std::map<std::string, std::string> m;
  const size_t at = svg.find(needle);
  if (at == std::string::npos) return m;
  const size_t b = svg.rfind('<', at), e = svg.find('>', at);
  const std::string tag = svg.substr(b, e - b);
  size_t i = 0;
  while ((i = tag.find("=\"", i)) != std::string::npos) {
    size_t k = i;
    while (k > 0 && tag[k - 1] != ' ') --k;
    const size_t v0 = i + 2, v1 = tag.find('"', v0);
    m[tag.substr(k, i - k)] = tag.substr(v0, v1 - v0);
    i = v1;
  }
  return m;
}

// The text of the element <g id="panel-ID" ...> ... </g> (panels hold nested <g>s).
std::string panel_text(const std::string& svg, const std::string& id) {
  const size_t b = svg.find("<g id=\"panel-" + id + "\"");
  if (b == std::string::npos) return "";
  int depth = 0;
  for (size_t i = b; i < svg.size(); ++i) {
    if (svg.compare(i, 2, "<g") == 0 && (svg[i + 2] == ' ' || svg[i + 2] == '>')) ++depth;
    if (svg.compare(i, 4, "</g>") == 0 && --depth == 0) return svg.substr(b, i + 4 - b);
  }
  return "";
}

// Range of the y coordinates (pixels) of what SVG path data draws (M L H V Z,
// absolute and relative): the ends of its line segments (a bare move draws nothing).
struct YRange {
  double lo = 1e300, hi = -1e300;
  size_t points = 0;
};
void path_y_range(const std::string& d, YRange& r) {
  std::istringstream in(d);
  char cmd = 0;
  double x = 0, y = 0, move_y = 0;
  bool moved = false;
  auto add_y = [&](double v) { r.lo = std::min(r.lo, v), r.hi = std::max(r.hi, v), ++r.points; };
  auto add = [&]() {
    if (cmd == 'M' || cmd == 'm') {  // a move: drawn only if a line follows
      moved = true, move_y = y;
      return;
    }
    if (moved) add_y(move_y), moved = false;
    add_y(y);
  };
  while (true) {
    in >> std::ws;
    const int c = in.peek();
    if (c == EOF) break;
    if (std::isalpha(c)) {
      cmd = static_cast<char>(in.get());
      if (cmd == 'Z' || cmd == 'z') continue;
    }
    double a = 0, b = 0;
    switch (cmd) {
      case 'M': case 'L': in >> a >> b; x = a, y = b; break;
      case 'm': case 'l': in >> a >> b; x += a, y += b; break;
      case 'H': in >> a; x = a; break;
      case 'h': in >> a; x += a; break;
      case 'V': in >> a; y = a; break;
      case 'v': in >> a; y += a; break;
      default: FAIL() << "unexpected path command " << cmd; return;
    }
    if (!in) {
      ADD_FAILURE() << "bad path data";
      return;
    }
    add();
    if (cmd == 'M') cmd = 'L';
    if (cmd == 'm') cmd = 'l';
  }
}

// y range (pixels) of every <path data-series="label"> in a panel.
YRange series_y_range(const std::string& panel, const std::string& label) {
  YRange r;
  const std::string key = "data-series=\"" + label + "\"";
  for (size_t at = panel.find(key); at != std::string::npos; at = panel.find(key, at + 1)) {
    const size_t d0 = panel.find(" d=\"", at) + 4, d1 = panel.find('"', d0);
    path_y_range(panel.substr(d0, d1 - d0), r);
  }
  return r;
}

struct Panel {
  double ymin = 0, ymax = 0, top = 0, height = 0;
  double value(double py) const { return ymax - (py - top) / height * (ymax - ymin); }
  double px() const { return (ymax - ymin) / height; }  // one pixel in value units
};
Panel panel_geometry(const std::string& svg, const std::string& id) {
  auto a = attrs_of(svg, "id=\"panel-" + id + "\"");
  Panel p;
  EXPECT_TRUE(a.count("data-ymin")) << id;
  if (!a.count("data-ymin")) return p;
  p.ymin = std::stod(a["data-ymin"]), p.ymax = std::stod(a["data-ymax"]);
  p.top = std::stod(a["data-top"]), p.height = std::stod(a["data-height"]);
  return p;
}

// A synthetic job: n samples along x at `speed` (frac 32), 2 axes; ticks of a
// constant-speed plan if `ticks`.
struct Synth {
  Path path;
  JobConfig cfg;
  JobResult res;
  Samples s;
};
Synth synth(size_t n, double speed, bool ticks) {
  Synth y{load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json"), {}, {}, {}};  // 2 axes
  y.res.header.frac_bits = 32;
  y.res.header.degree = 5;
  const double h = y.cfg.machine.period, lsb = std::ldexp(1.0, -32);
  const long long step = std::llround(speed * h / lsb);
  y.s.v.resize(n);
  for (size_t k = 0; k < n; ++k) y.s.v[k] = {static_cast<long long>(k) * step, 0, 0};
  if (ticks) {
    y.res.ticks.resize(n);
    for (size_t k = 0; k < n; ++k) {
      TickSample& t = y.res.ticks[k];
      t = TickSample{};
      t.t = k * h, t.s = k * speed * h, t.v = speed;
      t.x[0] = t.s, t.dx[0] = speed;
    }
  }
  return y;
}

// A straight 3-axis path (write_plots takes the number of axes from it).
Path path_3d(const fs::path& dir) {
  const fs::path f = dir / "line3.json";
  std::ofstream(f) << "{\"degree\": 1, \"knots\": [0, 0, 1, 1], \"control_points\": [[0, 0, 0], [1, 1, 1]]}\n";
  return load_path(f.string());
}

size_t count_of(const std::string& s, const std::string& what) {
  size_t c = 0;
  for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++c;
  return c;
}

}  // namespace

TEST(Plots, XmlCheckerRejectsBrokenSvg) {  // the checker the other tests rely on
  EXPECT_EQ(xml_problem("<svg><g><path d=\"M0 0\"/></g></svg>\n"), "");
  EXPECT_NE(xml_problem("<svg><g></svg>"), "");
  EXPECT_NE(xml_problem("<svg><text>a & b</text></svg>"), "");
  EXPECT_NE(xml_problem("<svg><text x=\"1<2\">a</text></svg>"), "");
  EXPECT_NE(xml_problem("<svg></svg><svg></svg>"), "");
}

// The real job (butterfly, 50 mm/s, the host's exact prediction of the core's
// samples): both files well-formed, labelled, every panel's y range covering
// its data and limits, and small.
TEST(Plots, ButterflyJobWellFormedAndLabelled) {
  const Path p = load_path(std::string(TRAJ_ASSETS) + "/butterfly_nurbs.json");
  JobConfig cfg;
  const JobResult r = run_job(p, cfg);
  const Samples s = predicted_samples(r);
  const fs::path dir = fresh_dir("butterfly");
  write_plots(dir.string(), p, cfg, r, s);
  EXPECT_FALSE(has_tmp_file(dir));

  const std::string path = slurp(dir / "path_feed.svg"), prof = slurp(dir / "profile.svg");
  EXPECT_EQ(xml_problem(path), "");
  EXPECT_EQ(xml_problem(prof), "");
  for (const std::string* f : {&path, &prof}) {
    EXPECT_EQ(f->find("nan"), std::string::npos);
    EXPECT_EQ(f->find("inf\""), std::string::npos);
    EXPECT_LT(f->size(), 2u << 20);
  }
  // path: axes in mm, colour bar 0..feed with its label and end ticks
  EXPECT_NE(path.find(">x (mm)</text>"), std::string::npos);
  EXPECT_NE(path.find(">y (mm)</text>"), std::string::npos);
  auto cb = attrs_of(path, "id=\"colourbar\"");
  EXPECT_EQ(cb["data-vmin"], "0");
  EXPECT_EQ(cb["data-vmax"], "50");
  EXPECT_NE(path.find(">output feed (mm/s)</text>"), std::string::npos);
  const size_t cbat = path.find("id=\"colourbar\"");
  EXPECT_NE(path.find(">0</text>", cbat), std::string::npos);
  EXPECT_NE(path.find(">50</text>", cbat), std::string::npos);
  EXPECT_NE(path.find("<use xlink:href=\"#band"), std::string::npos);  // the coloured path

  // profile: every panel with a title, a y label in units, tick labels, a
  // legend with plan, output and the dashed limit; y range covers the limits
  EXPECT_NE(prof.find(">time (s)</text>"), std::string::npos);
  struct Want {
    const char* id;
    const char* ylabel;
    double limit;
    bool symmetric;
  };
  const auto& L = cfg.limits;
  const Want want[] = {{"speed", "speed (mm/s)", L.feed, false},
                       {"a_tan", "a_tan (mm/s\xC2\xB2)", L.a_tan, true},
                       {"j_tan", "j_tan (mm/s\xC2\xB3)", L.j_tan, true},
                       {"a_x", "a_x (mm/s\xC2\xB2)", L.a_axis[0], true},
                       {"a_y", "a_y (mm/s\xC2\xB2)", L.a_axis[1], true},
                       {"j_x", "j_x (mm/s\xC2\xB3)", L.j_axis[0], true},
                       {"j_y", "j_y (mm/s\xC2\xB3)", L.j_axis[1], true},
                       {"a_cen", "a_cen (mm/s\xC2\xB2)", L.a_cen, false},
                       {"j_cen", "j_cen (mm/s\xC2\xB3)", L.j_cen, false}};
  for (const Want& w : want) {
    SCOPED_TRACE(w.id);
    const std::string P = panel_text(prof, w.id);
    ASSERT_FALSE(P.empty());
    EXPECT_NE(P.find(std::string(">") + w.ylabel + "</text>"), std::string::npos);
    EXPECT_NE(P.find("font-weight=\"bold\""), std::string::npos);  // the title
    EXPECT_NE(P.find("peaks: plan"), std::string::npos);
    EXPECT_NE(P.find("class=\"legend\""), std::string::npos);
    EXPECT_NE(P.find("stroke-dasharray"), std::string::npos);  // limit lines
    const std::string legend = P.substr(P.find("class=\"legend\""));
    EXPECT_NE(legend.find(">output</text>"), std::string::npos);
    EXPECT_NE(legend.find(">plan"), std::string::npos);
    // tick labels: more than 3 in the panel's tick groups
    size_t labels = 0;
    for (size_t at = P.find("<g font-size=\"10\""); at != std::string::npos; at = P.find("<g font-size=\"10\"", at + 1))
      labels += 1;
    EXPECT_GE(labels, 2u);
    const Panel g = panel_geometry(prof, w.id);
    EXPECT_GE(g.ymax, w.limit);
    if (w.symmetric) {
      EXPECT_LE(g.ymin, -w.limit);
    }
    // the output series is drawn and stays inside the plot box
    const YRange yr = series_y_range(P, "output");
    EXPECT_GT(yr.points, 100u);
    EXPECT_GE(yr.lo, g.top - 0.5);
    EXPECT_LE(yr.hi, g.top + g.height + 0.5);
  }
}

// One sample of 1,000,000 displaced by 2 um in y: the y acceleration of the
// output has one value -4000 mm/s^2 (second difference) among zeros, twice the
// limit, 1 sample in ~1100 per pixel column. The y range covers it (nothing
// clamped) and the drawn envelope reaches it (decimation keeps extremes).
TEST(Plots, EnvelopeKeepsOneSampleSpike) {
  const size_t n = 1000000, k0 = 500001;
  Synth y = synth(n, 20, false);
  const double lsb = std::ldexp(1.0, -32), h = y.cfg.machine.period, delta = 2e-3;
  y.s.v[k0][1] += std::llround(delta / lsb);
  const double spike_a = -2 * delta / (h * h);      // -4000
  const double spike_j = 3 * delta / (h * h * h);   // +6e6 (and -6e6)
  const fs::path dir = fresh_dir("spike");
  write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
  const std::string prof = slurp(dir / "profile.svg");
  ASSERT_EQ(xml_problem(prof), "");

  const Panel a = panel_geometry(prof, "a_y");
  EXPECT_LE(a.ymin, spike_a);
  EXPECT_GE(a.ymax, 0.5 * -spike_a);
  const YRange ar = series_y_range(panel_text(prof, "a_y"), "output");
  ASSERT_GT(ar.points, 0u);
  EXPECT_LE(a.value(ar.hi), spike_a + 1.5 * a.px()) << "the drawn a_y does not reach the spike";
  EXPECT_GE(a.value(ar.lo), 0.5 * -spike_a - 1.5 * a.px());

  const Panel j = panel_geometry(prof, "j_y");
  EXPECT_GE(j.ymax, spike_j);
  EXPECT_LE(j.ymin, -spike_j);
  const YRange jr = series_y_range(panel_text(prof, "j_y"), "output");
  EXPECT_GE(j.value(jr.lo), spike_j - 1.5 * j.px()) << "the drawn j_y does not reach the spike";
  EXPECT_LE(j.value(jr.hi), -spike_j + 1.5 * j.px());
  // the title reports the true peak, above the limit
  const std::string P = panel_text(prof, "a_y");
  EXPECT_NE(P.find("output 4000"), std::string::npos);
  EXPECT_NE(P.find("ABOVE THE LIMIT"), std::string::npos);
  // x never moved off its constant speed: its acceleration panel is flat at 0
  const Panel ax = panel_geometry(prof, "a_x");
  const YRange xr = series_y_range(panel_text(prof, "a_x"), "output");
  EXPECT_NEAR(ax.value(xr.lo), 0, 1.5 * ax.px());
  EXPECT_NEAR(ax.value(xr.hi), 0, 1.5 * ax.px());
}

// The worst case for size: 1,000,000 ticks (plan and output) on a spiral of
// 300 turns whose speed jumps at random every tick (the feed colour changes
// at every sample, every pixel column of every panel is a band).
TEST(Plots, SizeBoundedOnLongNoisyRun) {
  const size_t n = 1000000;
  Synth y = synth(n, 20, true);
  const double lsb = std::ldexp(1.0, -32), h = y.cfg.machine.period;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(0.05, 1.2);
  double phi = 0;
  for (size_t k = 0; k < n; ++k) {
    const double rad = 5 + 45 * double(k) / n;
    phi += U(rng) * y.cfg.limits.feed * h / rad;
    y.s.v[k] = {std::llround(rad * std::cos(phi) / lsb), std::llround(rad * std::sin(phi) / lsb), 0};
    TickSample& t = y.res.ticks[k];
    t.v = U(rng) * 50, t.a = (U(rng) - 0.6) * 2000, t.j = (U(rng) - 0.6) * 4e4;
    t.ddx[0] = t.a, t.ddx[1] = -t.a, t.dddx[0] = t.j, t.dddx[1] = -t.j;
    t.a_cen = U(rng) * 500, t.j_cen_geo = U(rng) * 3e4;
  }
  const fs::path dir = fresh_dir("long");
  write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
  const auto path_size = fs::file_size(dir / "path_feed.svg"), prof_size = fs::file_size(dir / "profile.svg");
  std::printf("1e6 noisy ticks: path_feed.svg %zu bytes, profile.svg %zu bytes\n", static_cast<size_t>(path_size),
              static_cast<size_t>(prof_size));
  EXPECT_LT(path_size, 2u << 20);
  EXPECT_LT(prof_size, 2u << 20);
  EXPECT_EQ(xml_problem(slurp(dir / "path_feed.svg")), "");
  EXPECT_EQ(xml_problem(slurp(dir / "profile.svg")), "");
  EXPECT_FALSE(has_tmp_file(dir));
}

// Failure to write: a clear error naming the file or folder, no temporary
// file left, no plot half-replaced.
TEST(Plots, TargetThatCannotBeReplacedLeavesNoTempFile) {
  Synth y = synth(2000, 20, true);
  const fs::path dir = fresh_dir("blocked");
  fs::create_directories(dir / "path_feed.svg" / "x");  // a folder where the plot goes
  try {
    write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
    FAIL() << "no error";
  } catch (const PlanError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "path_feed.svg").string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(has_tmp_file(dir));
  EXPECT_FALSE(fs::exists(dir / "profile.svg"));
}

TEST(Plots, FolderUnderAFileGivesError) {
  Synth y = synth(2000, 20, true);
  const fs::path base = fresh_dir("under_file");
  std::ofstream(base / "file") << "x";
  const fs::path dir = base / "file" / "plots";
  try {
    write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
    FAIL() << "no error";
  } catch (const PlanError& e) {
    EXPECT_NE(std::string(e.what()).find(dir.string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(has_tmp_file(base));
}

TEST(Plots, UnwritableFolderGivesErrorAndNoTempFile) {
  if (::geteuid() == 0) GTEST_SKIP() << "root writes into read-only folders";
  Synth y = synth(2000, 20, true);
  const fs::path dir = fresh_dir("read_only");
  fs::permissions(dir, fs::perms::owner_read | fs::perms::owner_exec);
  try {
    write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
    ADD_FAILURE() << "no error";
  } catch (const PlanError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "path_feed.svg").string()), std::string::npos) << e.what();
  }
  fs::permissions(dir, fs::perms::owner_all);
  EXPECT_FALSE(has_tmp_file(dir));
  EXPECT_FALSE(fs::exists(dir / "path_feed.svg"));
}

// Writing over earlier plots replaces them whole.
TEST(Plots, ReplacesEarlierFiles) {
  Synth y = synth(2000, 20, true);
  const fs::path dir = fresh_dir("replace");
  std::ofstream(dir / "profile.svg") << "old";
  write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
  const std::string prof = slurp(dir / "profile.svg");
  EXPECT_EQ(prof.rfind("<?xml", 0), 0u);
  EXPECT_EQ(xml_problem(prof), "");
  EXPECT_FALSE(has_tmp_file(dir));
}

// The second temporary file cannot be opened (a folder holds its name; this
// fails for root too): the first one, already written, is removed, nothing
// is renamed into place, and the folder in the way is left alone.
TEST(Plots, FailedTempFileRemovesTheOthers) {
  Synth y = synth(2000, 20, true);
  const fs::path dir = fresh_dir("tmp_blocked");
  const fs::path blocked = util::temporary_path((dir / "profile.svg").string());
  fs::create_directories(blocked / "x");
  try {
    write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
    FAIL() << "no error";
  } catch (const PlanError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "profile.svg").string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(util::temporary_path((dir / "path_feed.svg").string())));
  EXPECT_FALSE(fs::exists(dir / "path_feed.svg"));
  EXPECT_FALSE(fs::exists(dir / "profile.svg"));
  EXPECT_TRUE(fs::exists(blocked / "x"));
}

// A helix (radius 10 mm, 3 turns, 6 mm down, 3 axes) is drawn as an
// engineering drawing: top (x-y), front (x-z) and side (y-z) panels at one
// scale, each with its axes named in units and the coloured path, views lined
// up (x between top and front, z between front and side), one colour bar. The
// same samples at constant z, and a 2-axis path, give the one x-y plot.
TEST(Plots, HelixGivesThreeProjectionsFlatPathOne) {
  const size_t n = 20000;
  const double lsb = std::ldexp(1.0, -32), pi = std::acos(-1.0);
  const fs::path dir = fresh_dir("helix");
  Synth y = synth(n, 20, false);
  y.path = path_3d(dir);
  ASSERT_EQ(y.path.dim(), 3);
  for (size_t k = 0; k < n; ++k) {
    const double u = double(k) / (n - 1), phi = 6 * pi * u;
    y.s.v[k] = {std::llround(10 * std::cos(phi) / lsb), std::llround(10 * std::sin(phi) / lsb), std::llround(-6 * u / lsb)};
  }
  write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
  const std::string svg = slurp(dir / "path_feed.svg");
  ASSERT_EQ(xml_problem(svg), "");
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  struct Want {
    const char *id, *title, *axes, *h, *v;
  };
  const Want want[] = {{"xy", "top (x-y)", "x y", "x (mm)", "y (mm)"},
                       {"xz", "front (x-z)", "x z", "x (mm)", "z (mm)"},
                       {"yz", "side (y-z)", "y z", "y (mm)", "z (mm)"}};
  std::map<std::string, std::map<std::string, std::string>> geo;
  for (const Want& w : want) {
    SCOPED_TRACE(w.id);
    const std::string P = panel_text(svg, w.id);
    ASSERT_FALSE(P.empty());
    geo[w.id] = attrs_of(svg, std::string("id=\"panel-") + w.id + "\"");
    EXPECT_EQ(geo[w.id]["data-axes"], w.axes);
    EXPECT_NE(P.find(std::string(">") + w.title + "</text>"), std::string::npos);
    EXPECT_EQ(count_of(P, std::string(">") + w.h + "</text>"), 1u);
    EXPECT_EQ(count_of(P, std::string(">") + w.v + "</text>"), 1u);
    EXPECT_NE(P.find(std::string("<use xlink:href=\"#") + w.id + "-band"), std::string::npos);  // the coloured path
    EXPECT_NE(P.find(">start"), std::string::npos);
  }
  EXPECT_EQ(count_of(svg, "id=\"panel-"), 3u);
  EXPECT_EQ(count_of(svg, "id=\"colourbar\""), 1u);
  EXPECT_EQ(geo["xy"]["data-scale"], geo["xz"]["data-scale"]);
  EXPECT_EQ(geo["xz"]["data-scale"], geo["yz"]["data-scale"]);
  EXPECT_EQ(geo["xy"]["data-left"], geo["xz"]["data-left"]);
  EXPECT_EQ(geo["xy"]["data-width"], geo["xz"]["data-width"]);
  EXPECT_EQ(geo["xz"]["data-top"], geo["yz"]["data-top"]);
  EXPECT_EQ(geo["xz"]["data-height"], geo["yz"]["data-height"]);
  EXPECT_GT(std::stod(geo["xz"]["data-top"]), std::stod(geo["xy"]["data-top"]) + std::stod(geo["xy"]["data-height"]));
  EXPECT_GT(std::stod(geo["yz"]["data-left"]), std::stod(geo["xz"]["data-left"]) + std::stod(geo["xz"]["data-width"]));

  // one x-y plot: the helix flattened (3 axes, z constant) and a 2-axis path
  auto one_plot = [&](const std::string& f) {
    EXPECT_EQ(xml_problem(f), "");
    EXPECT_EQ(count_of(f, "id=\"panel-"), 0u);
    EXPECT_EQ(count_of(f, ">x (mm)</text>"), 1u);
    EXPECT_EQ(count_of(f, ">y (mm)</text>"), 1u);
    EXPECT_EQ(count_of(f, "z (mm)"), 0u);
    EXPECT_EQ(count_of(f, "id=\"colourbar\""), 1u);
  };
  for (auto& v : y.s.v) v[2] = 0;
  write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
  const std::string flat = slurp(dir / "path_feed.svg");
  one_plot(flat);
  EXPECT_NE(flat.find("projection on x-y"), std::string::npos);
  y.path = synth(1, 20, false).path;  // 2 axes
  ASSERT_EQ(y.path.dim(), 2);
  write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
  const std::string two = slurp(dir / "path_feed.svg");
  one_plot(two);
  EXPECT_EQ(two.find("projection on x-y"), std::string::npos);
}

// The worst case for size in three projections: 1,000,000 samples on a helix
// of 300 turns whose speed jumps at random every tick; each panel keeps its
// share of the points, the file stays under 2 MB.
TEST(Plots, SizeBoundedOnLongNoisyHelix) {
  const size_t n = 1000000;
  const fs::path dir = fresh_dir("long_helix");
  Synth y = synth(n, 20, false);
  y.path = path_3d(dir);
  const double lsb = std::ldexp(1.0, -32), h = y.cfg.machine.period;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0.05, 1.2);
  double phi = 0;
  for (size_t k = 0; k < n; ++k) {
    phi += U(rng) * y.cfg.limits.feed * h / 20;
    y.s.v[k] = {std::llround(20 * std::cos(phi) / lsb), std::llround(20 * std::sin(phi) / lsb),
                std::llround(-phi * 0.01 / lsb)};
  }
  write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
  const auto size = fs::file_size(dir / "path_feed.svg");
  std::printf("1e6 noisy helix ticks: path_feed.svg %zu bytes\n", static_cast<size_t>(size));
  EXPECT_LT(size, 2u << 20);
  const std::string svg = slurp(dir / "path_feed.svg");
  EXPECT_EQ(xml_problem(svg), "");
  EXPECT_EQ(count_of(svg, "id=\"panel-"), 3u);
}

// The path plot's "rapid" grey is for steps faster than the fastest feed
// move; a feed move's output runs up to about 0.2 % above its feed (the
// fit's feed error: LinuxCNC's flowsnake.ngc at F10 drew 312 steps of its
// feed moves as rapids), so steps within 1 % above the scale's top keep its
// colour. A straight line in x-y at 0.4 % and at 50 % above the scale.
TEST(Plots, FeedJustAboveTheScaleIsNoRapid) {
  JobConfig cfg;
  cfg.limits.feed = 100;
  const double h = 1e-3, scale = 10;
  auto line_at = [&](double speed) {
    const auto pos = [&](size_t k) { return std::array<double, 3>{speed * h * double(k), 0.5 * speed * h * double(k), 0}; };
    return svg::path_svg(2000, pos, 2, cfg, h, 1e-9, scale);
  };
  const double v = scale / std::hypot(1.0, 0.5);  // the x component of a path speed of `scale`
  const std::string near = line_at(1.004 * v), fast = line_at(1.5 * v);
  EXPECT_EQ(xml_problem(near), "");
  EXPECT_EQ(near.find(">rapid<"), std::string::npos);
  EXPECT_NE(fast.find(">rapid<"), std::string::npos);
}

// A toolpath's rapid moves are drawn as rapids by the plan's move kind, at
// any speed: a connecting move slower than the fastest cut must not look
// like a cut (simple-icons' SVGs: their short rapids between subpaths never
// reach the feed). A line at half the scale: its second half a rapid by the
// plan, drawn grey with the legend; without the plan's kinds, none is.
TEST(Plots, RapidByThePlanAtAnySpeed) {
  JobConfig cfg;
  cfg.limits.feed = 100;
  const double h = 1e-3, scale = 10, v = 5;
  const auto pos = [&](size_t k) { return std::array<double, 3>{v * h * double(k), 0, 0}; };
  const std::function<bool(size_t)> second_half = [](size_t k) { return k >= 1000; };
  const std::string by_kind = svg::path_svg(2000, pos, 2, cfg, h, 1e-9, scale, second_half);
  const std::string by_speed = svg::path_svg(2000, pos, 2, cfg, h, 1e-9, scale);
  EXPECT_EQ(xml_problem(by_kind), "");
  EXPECT_NE(by_kind.find(">rapid<"), std::string::npos);
  EXPECT_EQ(by_speed.find(">rapid<"), std::string::npos);
  EXPECT_NE(by_kind.find("stroke=\"" + std::string(svg::kRapidColour) + "\""), std::string::npos);
  EXPECT_EQ(by_speed.find("stroke=\"" + std::string(svg::kRapidColour) + "\""), std::string::npos);
}

// A tall, narrow drawing (a path along y only, its x range 5 % of it): the
// page is sized to the plot at equal scales, which left it about 200 px wide
// and cut the title (LibreCAD's Complete-Lib-V.dxf, 4 m by 19 m). The page
// must hold the title at 15 px bold, taken here at half its size a
// character, narrower than any font draws it.
TEST(Plots, TallNarrowPathKeepsItsTitleOnThePage) {
  Synth y = synth(3000, 50, false);
  for (auto& v : y.s.v) v = {0, v[0], 0};
  const fs::path dir = fresh_dir("tall_narrow");
  write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
  const std::string svg = slurp(dir / "path_feed.svg");
  const std::string title = "Path (x-y) of the core's output samples, coloured by the output feed";
  const size_t at = svg.find(">Path (x-y) of the core");  // the apostrophe is written as an entity
  ASSERT_NE(at, std::string::npos);
  const size_t x_at = svg.rfind("x=\"", at);
  const double left = std::stod(svg.substr(x_at + 3));
  auto root = attrs_of(svg, "<svg ");
  const double width = std::stod(root["width"]);
  std::printf("  page %.0f px wide, title from x = %.0f, %zu characters\n", width, left, title.size());
  EXPECT_GE(width, left + 0.5 * 15 * static_cast<double>(title.size()));
}

// A tall, narrow drawing (a line 150 mm up and 10 mm across): its x axis
// gets at least two tick labels, apart by more than their width (one tick
// step for both axes, from the longer, gave it a single x label, as it gave
// LibreCAD's Complete-Lib-V.dxf). Label width taken at 6 px a character at
// font size 10, wider than sans-serif digits are drawn.
TEST(Plots, TallNarrowPathLabelsItsShortAxis) {
  Synth y = synth(3000, 50, false);
  for (auto& v : y.s.v) v = {v[0] / 15, v[0], 0};
  const fs::path dir = fresh_dir("tall_narrow_ticks");
  write_plots(dir.string(), y.path, y.cfg, y.res, y.s);
  const std::string svg = slurp(dir / "path_feed.svg");
  const std::string group = "<g font-size=\"10\" fill=\"#333\" text-anchor=\"middle\">";
  const size_t from = svg.find(group), to = svg.find("</g>", from);
  ASSERT_NE(from, std::string::npos);
  std::vector<std::pair<double, size_t>> labels;  // centre x, characters
  for (size_t at = svg.find("<text", from); at < to; at = svg.find("<text", at + 1)) {
    const double x = std::stod(svg.substr(svg.find("x=\"", at) + 3));
    const size_t open = svg.find('>', at) + 1;
    std::string s = svg.substr(open, svg.find('<', open) - open);
    size_t chars = 0;
    for (unsigned char c : s) chars += (c & 0xC0) != 0x80;  // UTF-8 characters (the minus sign)
    labels.push_back({x, chars});
  }
  std::printf("  %zu x tick labels\n", labels.size());
  ASSERT_GE(labels.size(), 2u);
  for (size_t i = 1; i < labels.size(); ++i)
    EXPECT_GE(labels[i].first - labels[i - 1].first, 3.0 * double(labels[i].second + labels[i - 1].second)) << i;
}
