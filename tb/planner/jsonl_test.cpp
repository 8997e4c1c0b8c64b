// SPDX-License-Identifier: Apache-2.0
// JSON Lines path files (planner/jsonl_source.hpp): streamed line by line,
// the same segment stream as the same curves in one {"curves": [...]} file,
// errors naming <file>:<line> and the field, joins checked as load_path
// checks them, and memory bounded by the window, not by the file.
#include <gtest/gtest.h>

#include <atomic>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tmp_file.hpp"
#include "geometry/json_io.hpp"
#include "input/path_json.hpp"
#include "input/jsonl_source.hpp"
#include "input/raster.hpp"
#include "job/streaming.hpp"

using namespace traj;
using namespace traj::plan;
using namespace traj::input;
using namespace traj::job;

namespace {

using traj::test::TmpFile;

// The curves of a loaded path, as main.cpp streams a .json file with --window.
struct VecSource : CurveSource {
  std::vector<geo::BSpline> v;
  size_t i = 0;
  bool next(geo::BSpline& b, std::string& w) override {
    if (i >= v.size()) return false;
    b = v[i];
    w = "curve " + std::to_string(i++);
    return true;
  }
};

std::vector<fd::Compiled> stream_all(CurveSource& src, const JobConfig& cfg, const StreamOptions& so,
                                     StreamStats* st = nullptr) {
  std::vector<fd::Compiled> out;
  const StreamStats s = run_streaming(src, cfg, so, [&](const fd::Compiled& c, const TimeSegment&) { out.push_back(c); });
  if (st) *st = s;
  return out;
}

std::string line_of(const geo::BSpline& b) { return geo::to_json(b).dump(); }

geo::BSpline line(double x0, double y0, double x1, double y1) {
  Eigen::VectorXd a(2), b(2);
  a << x0, y0;
  b << x1, y1;
  return geo::make_line(a, b);
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const PlanError& e) {
    return e.what();
  }
  return "(no error)";
}

long rss_kb() {
  std::ifstream f("/proc/self/statm");
  long size = 0, res = 0;
  f >> size >> res;
  return res * (::sysconf(_SC_PAGESIZE) / 1024);
}

}  // namespace

TEST(Jsonl, SameSegmentStreamAsCurvesFile) {
  const size_t pieces = 40;
  TmpFile jl("same.jsonl"), js("same.json");
  {
    // the raster as JSON Lines, with a comment, blank lines and CRLF endings mixed in
    RasterSource src(pieces, 6.0, 1.0);
    std::ostringstream o;
    o << "# raster, " << pieces << " pieces\n\n";
    geo::BSpline b;
    std::string w;
    nlohmann::json all;
    all["curves"] = nlohmann::json::array();
    for (size_t i = 0; src.next(b, w); ++i) {
      o << line_of(b) << (i % 7 == 3 ? "\r\n" : "\n");
      if (i % 11 == 5) o << "   \n  # a comment\n";
      all["curves"].push_back(geo::to_json(b));
    }
    jl.write(o.str());
    js.write(all.dump(1));
  }
  JobConfig cfg;
  cfg.limits.feed = 40;
  StreamOptions so;
  so.window = 8;
  so.commit = 4;
  JsonlSource a(jl.path);
  StreamStats sa, sb;
  const auto ca = stream_all(a, cfg, so, &sa);
  const Path p = load_path(js.path);
  VecSource b;
  for (size_t i = 0; i < p.size(); ++i) b.v.push_back(p.curve(i).spline());
  const auto cb = stream_all(b, cfg, so, &sb);
  EXPECT_EQ(a.curves(), pieces);
  EXPECT_EQ(sa.curves, pieces);
  EXPECT_GT(sa.windows, 5u);
  ASSERT_EQ(ca.size(), cb.size());
  for (size_t i = 0; i < ca.size(); ++i) {
    ASSERT_EQ(ca[i].ticks, cb[i].ticks) << "segment " << i;
    ASSERT_EQ(ca[i].regs, cb[i].regs) << "segment " << i;
  }
  EXPECT_EQ(sa.ticks, sb.ticks);
  // and the same as the raster generated in memory (the JSON numbers round-trip exactly)
  RasterSource r(pieces, 6.0, 1.0);
  const auto cr = stream_all(r, cfg, so);
  ASSERT_EQ(ca.size(), cr.size());
  for (size_t i = 0; i < ca.size(); ++i) ASSERT_EQ(ca[i].regs, cr[i].regs) << "segment " << i;
}

TEST(Jsonl, ErrorsNameFileLineAndField) {
  const std::string l1 = line_of(line(0, 0, 1, 0)), l2 = line_of(line(1, 0, 1, 1));
  TmpFile f("bad.jsonl");
  auto read_all = [&] {
    JsonlSource s(f.path);
    geo::BSpline b;
    std::string w;
    while (s.next(b, w)) {
    }
  };
  // a field check of parse_curve, with where = <file>:<line>
  f.write(l1 + "\n# comment\n" + l2 + "\n" +
          R"({"degree": 1, "knots": [0, 0, 0.7, 0.5], "control_points": [[1, 1], [2, 1]]})" + "\n");
  EXPECT_EQ(error_of(read_all), f.path + ":4: knots[3]: 0.5 < previous 0.7 (knot vector must be non-decreasing)");
  f.write(l1 + "\n\n" + R"({"degree": 1, "knots": [0, 0, 1, 1]})" + "\n");
  EXPECT_EQ(error_of(read_all), f.path + ":3: control_points: missing");
  // JSON syntax and numbers beyond the double range: <file>:<line>:<column>
  f.write(l1 + "\n" + R"({"degree": 1, "knots": [0, 0, 1e999, 1], "control_points": [[1, 0], [2, 0]]})" + "\n");
  EXPECT_EQ(error_of(read_all).rfind(f.path + ":2:31: knots[2]: number overflow", 0), 0u) << error_of(read_all);
  f.write(l1 + "\n" + l2 + "\n" + R"({"degree": 1, "knots": [0, 0, 1, 1], "control_points": [[1, 1], [2, 1]])" + "\n");
  EXPECT_EQ(error_of(read_all).rfind(f.path + ":3:", 0), 0u) << error_of(read_all);
  EXPECT_NE(error_of(read_all).find("syntax error"), std::string::npos) << error_of(read_all);
  // an empty file, a missing one
  f.write("# nothing\n\n");
  EXPECT_EQ(error_of(read_all), f.path + ": no curves (a JSON Lines path holds one curve object per line)");
  EXPECT_EQ(error_of([] { JsonlSource s("/nonexistent/path.jsonl"); }), "/nonexistent/path.jsonl: cannot open file");
}

TEST(Jsonl, JoinsCheckedAsLoadPathChecksThem) {
  const std::string l1 = line_of(line(0, 0, 1, 0)), l2 = line_of(line(1.5, 0, 2, 0));
  TmpFile f("gap.jsonl"), g("gap.json");
  f.write(l1 + "\n#\n" + l2 + "\n");
  g.write(R"({"curves": [)" + l1 + ", " + l2 + "]}");
  std::string e = error_of([&] {
    JsonlSource s(f.path);
    geo::BSpline b;
    std::string w;
    while (s.next(b, w)) {
    }
  });
  EXPECT_EQ(e, f.path + ":3: starts 0.5 units away from the previous curve's end");
  // the same tolerance and message as load_path (which names the curve by index)
  EXPECT_EQ(error_of([&] { load_path(g.path); }), g.path + ": curves[1]: starts 0.5 units away from the previous curve's end");
  // within the tolerance: accepted by both
  f.write(l1 + "\n" + line_of(line(1 + 5e-10, 0, 2, 0)) + "\n");
  EXPECT_EQ(error_of([&] {
              JsonlSource s(f.path);
              geo::BSpline b;
              std::string w;
              while (s.next(b, w)) {
              }
            }),
            "(no error)");
  // a change in the number of axes
  Eigen::VectorXd a(3), b3(3);
  a << 1, 0, 0;
  b3 << 2, 0, 0;
  f.write(l1 + "\n" + line_of(geo::make_line(a, b3)) + "\n");
  e = error_of([&] {
    JsonlSource s(f.path);
    geo::BSpline b;
    std::string w;
    while (s.next(b, w)) {
    }
  });
  EXPECT_EQ(e, f.path + ":2: 3 axes, the path so far has 2");
}

TEST(Jsonl, ZeroLengthCurveRejected) {
  TmpFile f("zero.jsonl");
  f.write(line_of(line(0, 0, 1, 0)) + "\n" + R"({"degree": 1, "knots": [0, 0, 1, 1], "control_points": [[1, 0], [1, 0]]})" +
          "\n" + line_of(line(1, 0, 2, 0)) + "\n");
  JobConfig cfg;
  StreamOptions so;
  so.window = 4;
  so.commit = 2;
  JsonlSource s(f.path);
  const std::string e = error_of([&] { stream_all(s, cfg, so); });
  EXPECT_EQ(e.rfind(f.path + ":2: zero-length curve", 0), 0u) << e;
}

// Memory is bounded by the window, not by the file: (1) the source holds one
// line and one end point, so reading a long file leaves the resident set flat;
// (2) the streaming planner pulls curves from it only a window ahead of what
// it has committed.
TEST(Jsonl, SourceMemoryFlatOverLongFile) {
  const size_t pieces = 100000;
  TmpFile f("big.jsonl");
  {
    std::ofstream o(f.path, std::ios::binary);
    RasterSource r(pieces);
    ASSERT_EQ(write_jsonl(r, o), pieces);
  }
  const auto bytes = std::filesystem::file_size(f.path);
  JsonlSource src(f.path);
  geo::BSpline b;
  std::string w;
  long base = -1, peak = 0;
  size_t n = 0;
  while (src.next(b, w)) {
    if (++n == pieces / 10) base = rss_kb();
    if (n > pieces / 10 && n % 1000 == 0) peak = std::max(peak, rss_kb());
  }
  EXPECT_EQ(n, pieces);
  EXPECT_EQ(w, f.path + ":" + std::to_string(pieces));
  std::printf("  %zu curves (%.1f MB of JSON Lines): RSS %.1f MB after 10%%, peak after %.1f MB\n", pieces, bytes / 1e6,
              base / 1024.0, peak / 1024.0);
  // the curves alone, held, would take more than the file; the growth allowed is a tenth of it
  EXPECT_LT(peak - base, 2 * 1024) << "resident set grew with the file";
  EXPECT_GT(bytes, 16u * 1024 * 1024);
}

TEST(Jsonl, PlannerReadsOnlyAWindowAhead) {
  const size_t pieces = 400;
  TmpFile f("ahead.jsonl");
  {
    std::ofstream o(f.path, std::ios::binary);
    RasterSource r(pieces, 0.5, 0.25, 10);
    ASSERT_EQ(write_jsonl(r, o), pieces);
  }
  struct Counting : CurveSource {
    JsonlSource in;
    std::atomic<size_t> n{0};
    explicit Counting(const std::string& p) : in(p) {}
    bool next(geo::BSpline& b, std::string& w) override { return in.next(b, w) && (++n, true); }
  };
  // The most curves read beyond the committed ones while a window emits.
  auto ahead = [&](bool prefetch) {
    Counting src(f.path);
    JobConfig cfg;
    StreamOptions so;
    so.window = 16;
    so.commit = 8;
    so.prefetch = prefetch;
    size_t windows = 0, worst = 0, segs = 0;
    const StreamStats st = run_streaming(
        src, cfg, so,
        [&](const fd::Compiled&, const TimeSegment&) {
          ++segs;
          // while window `windows` emits: the curves read are that window's and the committed ones before it
          worst = std::max(worst, src.n - std::min<size_t>(src.n, windows * so.commit));
        },
        [&](const std::string&, double) { ++windows; });
    EXPECT_EQ(st.curves, pieces);
    EXPECT_EQ(st.windows, windows);
    EXPECT_GT(segs, 0u);
    return worst;
  };
  // one thread: the planner reads exactly a window
  const size_t one = ahead(false);
  EXPECT_EQ(one, 16u) << "read more than a window ahead of the committed curves";
  // two: the reading thread adds at most four windows and the curve it holds (job/prefetch.hpp)
  const size_t two = ahead(true);
  EXPECT_GE(two, 16u);
  EXPECT_LE(two, 16u + 4 * 16u + 1);
}
