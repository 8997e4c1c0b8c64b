// SPDX-License-Identifier: Apache-2.0
// Tick-period sweep: planning + compilation of the butterfly main job (whole
// path: load_path + choose_format + run_job, as `trajcore plan` does) and of a
// streamed raster (run_streaming, as `trajcore plan --raster N`) at tick
// periods 1 ms, 100 us, 20 us and 1 us. Each case runs in a child process of
// its own, so that its max RSS is its own. Real-time factor = seconds of
// motion per host second (one core).
//   usage: bench_tick_sweep <butterfly.json> [raster_pieces=200] [--short]
//   --short: 1 ms and 100 us only (the test that keeps it working)
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

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

void row(const char* what, double period, double motion, double host, size_t segments, uint64_t ticks,
         const job::JobConfig& cfg) {
  std::printf("%-10s %8.0f %10.3f %9.3f %11.1f %9zu %11llu %9.1f   %d-bit, 2^-%d\n", what, period * 1e6, motion, host,
              motion / host, segments, static_cast<unsigned long long>(ticks), rss_mib(),
              cfg.machine.format().width, cfg.machine.format().frac_bits);
  std::fflush(stdout);
}

void butterfly(const std::string& file, double period) {
  const auto t0 = Clock::now();
  job::JobConfig cfg;
  cfg.machine.period = period;
  cfg.machine.choose_format(cfg.limits);
  cfg.engine_ticks = false;  // as `trajcore plan` without a report: no sample per engine tick
  const plan::Path p = input::load_path(file);
  const job::JobResult r = job::run_job(p, cfg);
  row("butterfly", period, r.plan.duration(), since(t0), r.segments.size(), r.engine_tick_count, cfg);
  std::printf("  stages: plan %.3f ticks %.3f fit %.3f compile %.3f s\n", r.t_plan, r.t_ticks, r.t_fit, r.t_compile);
}

void raster(size_t pieces, double period) {
  job::JobConfig cfg;
  cfg.machine.period = period;
  cfg.machine.choose_format(cfg.limits);
  input::RasterSource src(pieces);
  size_t segments = 0;
  uint64_t ticks = 0;
  const job::StreamStats st = job::run_streaming(src, cfg, job::StreamOptions{},
                                                 [&](const fd::Compiled& c, const plan::TimeSegment&) {
                                                   ++segments;
                                                   ticks += c.ticks;
                                                 });
  row("raster", period, st.motion_time, st.wall, segments, ticks, cfg);
}

}  // namespace

int main(int argc, char** argv) {
  bool short_run = false;
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) (std::strcmp(argv[i], "--short") == 0 ? void(short_run = true) : pos.push_back(argv[i]));
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
  bool ok = true;
  for (double h : periods) ok = bench::in_child([&] { butterfly(pos[0], h); }, "  failed: ") && ok;
  for (double h : periods) ok = bench::in_child([&] { raster(pieces, h); }, "  failed: ") && ok;
  return ok ? 0 : 1;
}
