// SPDX-License-Identifier: Apache-2.0
// Tick-period sweep: planning + compilation of the butterfly main job (whole
// path: load_path + choose_format + run_job, as `trajcore plan` does) and of a
// streamed raster (run_streaming, as `trajcore plan --raster N`) at tick
// periods 1 ms, 100 us, 20 us and 1 us. Each case runs in a child process of
// its own, so that its max RSS is its own, 21 times (the median host time). Real-time factor = seconds of
// motion per host second (one core).
//   usage: bench_tick_sweep <butterfly.json> [raster_pieces=200] [--short] [--one PERIOD]
//   --short: 1 ms and 100 us only (the test that keeps it working)
//   --one PERIOD: that tick period only, in this process (for a profiler)
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "input/path_json.hpp"
#include "input/raster.hpp"
#include "job/job.hpp"
#include "job/streaming.hpp"

using namespace traj;

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double rss_mib() {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;
}

// Each case runs kRuns times in its process (the butterfly loaded afresh
// each time); the row gives the median host time.
constexpr int kRuns = 21;

double median(std::vector<double> t) {
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

void row(const char* what, double period, double motion, double host, size_t segments, uint64_t ticks,
         const job::JobConfig& cfg, const std::string& extra = "") {
  std::printf("%-10s %8.0f %10.3f %9.4f %11.1f %9zu %11llu %9.1f   %d-bit, 2^-%d%s\n", what, period * 1e6, motion,
              host, motion / host, segments, static_cast<unsigned long long>(ticks), rss_mib(),
              cfg.machine.format().width, cfg.machine.format().frac_bits, extra.c_str());
  std::fflush(stdout);
}

// host_s: planning + compilation (run_job), the median of kRuns; the load
// (JSON, curves, arc-length tables) on top in the last column.
void butterfly(const std::string& file, double period) {
  std::vector<double> job_s, all_s;
  job::JobResult r;
  job::JobConfig cfg;
  std::vector<std::array<double, 4>> stages;
  for (int i = 0; i < kRuns; ++i) {
    const auto t0 = Clock::now();
    cfg = job::JobConfig{};
    cfg.machine.period = period;
    cfg.machine.choose_format(cfg.limits);
    cfg.engine_ticks = false;  // as `trajcore plan` without a report: no sample per engine tick
    const plan::Path p = input::load_path(file);
    const auto t1 = Clock::now();
    r = job::run_job(p, cfg);
    job_s.push_back(since(t1));
    all_s.push_back(since(t0));
    stages.push_back({r.t_plan, r.t_ticks, r.t_fit, r.t_compile});
  }
  const double with_load = median(all_s);
  char extra[96];
  std::snprintf(extra, sizeof extra, "   with loading %.4f s, %.0fx", with_load, r.plan.duration() / with_load);
  row("butterfly", period, r.plan.duration(), median(job_s), r.segments.size(), r.engine_tick_count, cfg, extra);
  std::vector<size_t> order(job_s.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return job_s[a] < job_s[b]; });
  const auto& st = stages[order[order.size() / 2]];
  std::printf("  stages (median run): plan %.1f ms, fit-tick samples %.1f ms, fit %.1f ms, compile %.1f ms\n",
              1e3 * st[0], 1e3 * st[1], 1e3 * st[2], 1e3 * st[3]);
}

void raster(size_t pieces, double period) {
  std::vector<double> host;
  job::JobConfig cfg;
  cfg.machine.period = period;
  cfg.machine.choose_format(cfg.limits);
  size_t segments = 0;
  uint64_t ticks = 0;
  double motion = 0;
  for (int i = 0; i < kRuns; ++i) {
    input::RasterSource src(pieces);
    segments = 0;
    ticks = 0;
    const job::StreamStats st = job::run_streaming(src, cfg, job::StreamOptions{},
                                                   [&](const fd::Compiled& c, const plan::TimeSegment&) {
                                                     ++segments;
                                                     ticks += c.ticks;
                                                   });
    host.push_back(st.wall);
    motion = st.motion_time;
  }
  row("raster", period, motion, median(host), segments, ticks, cfg);
}

}  // namespace

int main(int argc, char** argv) {
  bool short_run = false;
  double one = 0;  // --one PERIOD: that period only, in this process (for a profiler)
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--short") == 0) short_run = true;
    else if (std::strcmp(argv[i], "--one") == 0 && i + 1 < argc) one = std::atof(argv[++i]);
    else pos.push_back(argv[i]);
  }
  if (pos.empty()) {
    std::fprintf(stderr, "usage: %s <butterfly.json> [raster_pieces=200] [--short]\n", argv[0]);
    return 2;
  }
  const size_t pieces = pos.size() > 1 ? std::strtoull(pos[1].c_str(), nullptr, 10) : 200;
  const std::vector<double> periods =
      short_run ? std::vector<double>{1e-3, 100e-6} : std::vector<double>{1e-3, 100e-6, 20e-6, 1e-6};
  std::printf("%-10s %8s %10s %9s %11s %9s %11s %9s   %s\n", "case", "tick_us", "motion_s", "host_s", "realtime_x",
              "segments", "ticks", "rss_MiB", "engine");
  std::fflush(stdout);  // before the children copy the buffer
  if (one > 0) {
    butterfly(pos[0], one);
    raster(pos.size() > 1 ? std::strtoull(pos[1].c_str(), nullptr, 10) : 200, one);
    return 0;
  }
  bool ok = true;
  for (double h : periods) ok = bench::in_child([&] { butterfly(pos[0], h); }, "  failed: ") && ok;
  for (double h : periods) ok = bench::in_child([&] { raster(pieces, h); }, "  failed: ") && ok;
  return ok ? 0 : 1;
}
