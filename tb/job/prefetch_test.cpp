// SPDX-License-Identifier: Apache-2.0
// The streaming planner's second thread (host/job/prefetch.hpp): the same
// segments as on one thread, errors in their place, a reader that stays at
// most its capacity ahead and stops when the planner fails.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cam_program.hpp"
#include "tmp_file.hpp"
#include "input/raster.hpp"
#include "job/streaming.hpp"
#include "job/toolpath_stream.hpp"

using namespace traj;

namespace {

struct Streamed {
  std::vector<fd::Compiled> segments;
  std::string error;  // what the run threw ("" if nothing)
};

// Streams a G-code file with small windows and blend chunks (many commits and chunk cuts).
Streamed stream_gcode(const std::string& file, bool prefetch) {
  Streamed r;
  const job::JobConfig cfg;
  job::ToolpathStream src(file, input::FileKind::kGcode, cfg, {}, 64);
  job::StreamOptions so;
  so.window = 16;
  so.commit = 12;
  so.prefetch = prefetch;
  try {
    job::run_streaming(src, src.config(), so,
                       [&](const fd::Compiled& c, const plan::TimeSegment&) { r.segments.push_back(c); });
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  return r;
}

std::string temp_file(const std::string& name, const std::string& text) {
  static const test::TmpDir dir("prefetch_test");
  return dir.write(name, text);
}

void expect_same(const Streamed& a, const Streamed& b) {
  ASSERT_EQ(a.segments.size(), b.segments.size());
  for (size_t i = 0; i < a.segments.size(); ++i) {
    ASSERT_EQ(a.segments[i].ticks, b.segments[i].ticks) << "segment " << i;
    ASSERT_EQ(a.segments[i].regs, b.segments[i].regs) << "segment " << i;
  }
}

// The raster's curves, counted as they are read.
struct CountingRaster : job::StreamSource {
  explicit CountingRaster(size_t pieces) : raster(pieces) {}
  bool next(job::StreamCurve& c) override {
    c.speed = 0;
    c.stop = false;
    if (!raster.next(c.curve, c.where)) return false;
    ++read;
    return true;
  }
  input::RasterSource raster;
  std::atomic<size_t> read{0};
};

}  // namespace

TEST(Prefetch, SameSegmentsOnOneThreadAndTwo) {
  std::ostringstream o;
  bench::write_cam_program(o, 1500);
  const std::string file = temp_file("cam.ngc", o.str());
  const Streamed one = stream_gcode(file, false), two = stream_gcode(file, true);
  EXPECT_EQ(one.error, "");
  EXPECT_EQ(two.error, "");
  EXPECT_GT(one.segments.size(), 1000u);
  expect_same(one, two);
}

TEST(Prefetch, AnErrorReachesThePlannerInItsPlace) {
  // 1200 good lines, then a word the reader refuses
  std::ostringstream o;
  bench::write_cam_program(o, 1200);
  std::string text = o.str();
  const size_t end = text.rfind("G0 Z5");  // before the program's retract and M2
  ASSERT_NE(end, std::string::npos);
  text.insert(end, "G85 X3 Y4 Z-1 R1\n");
  const std::string file = temp_file("bad.ngc", text);
  const Streamed one = stream_gcode(file, false), two = stream_gcode(file, true);
  EXPECT_NE(one.error.find("bad.ngc:"), std::string::npos) << one.error;
  EXPECT_NE(one.error.find("G85"), std::string::npos) << one.error;
  EXPECT_EQ(one.error, two.error);
  EXPECT_GT(one.segments.size(), 500u);  // what was planned before it: emitted alike
  expect_same(one, two);
}

TEST(Prefetch, ReaderStaysWithinItsCapacityAndStopsWhenThePlannerFails) {
  CountingRaster src(100000);
  const job::JobConfig cfg;
  job::StreamOptions so;
  so.window = 16;
  so.commit = 12;
  size_t read_at_first = 0, emitted = 0;
  const std::string why = "the sink gives up";
  try {
    job::run_streaming(src, cfg, so, [&](const fd::Compiled&, const plan::TimeSegment&) {
      if (emitted++ == 0) read_at_first = src.read;
      if (emitted == 50) throw std::runtime_error(why);
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(e.what(), why);
  }
  // The first segments are emitted once the second window has planned: the planner has taken a
  // window and a commit's worth more; the reader is at most 4 windows and the curve it builds ahead.
  const size_t bound = so.window + so.commit + 4 * so.window + 1;
  EXPECT_GE(read_at_first, so.window);
  EXPECT_LE(read_at_first, bound);
  // run_streaming returned: the reader was stopped and joined, far from the raster's end
  const size_t after = src.read;
  EXPECT_LE(after, 200u + bound);
  EXPECT_EQ(src.read, after);
}
