// SPDX-License-Identifier: Apache-2.0
// Planner benchmark: planning + compilation time per second of motion, time to
// the first segment, and memory while streaming long raster paths.
//   usage: bench_planner [max_pieces=1000000] [butterfly.json]
// Prints one line per run. Real-time factor = seconds of motion planned and
// compiled per host second (one core).
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "input/path_json.hpp"
#include "report/report.hpp"
#include "input/raster.hpp"
#include "job/streaming.hpp"

using namespace traj::plan;
using namespace traj::input;
using namespace traj::job;

static long rss_kib() {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss;
}

int main(int argc, char** argv) {
  const size_t max_pieces = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1000000;
  const std::string butterfly = argc > 2 ? argv[2] : "";
  std::printf("%-34s %10s %12s %10s %12s %12s %12s %10s\n", "case", "pieces", "motion_s", "host_s", "realtime_x",
              "first_seg_ms", "segments", "maxrss_MiB");
  if (!butterfly.empty()) {
    // The main job's planning and compilation, 7 times, each on a path loaded
    // afresh: load_path (JSON, power basis, arc-length tables; the geometry
    // the planner needs) + run_job. The first run (cold: page faults, caches)
    // and the median are printed, with and without the loading.
    JobConfig cfg;
    cfg.limits.feed = 50;
    std::vector<double> walls, jobs;
    JobResult r;
    double first = 0, first_job = 0;
    for (int rep = 0; rep < 7; ++rep) {
      const auto t0 = std::chrono::steady_clock::now();
      const Path p = load_path(butterfly);
      const auto t1 = std::chrono::steady_clock::now();
      JobResult ri = run_job(p, cfg);
      const auto t2 = std::chrono::steady_clock::now();
      const double wall = std::chrono::duration<double>(t2 - t0).count();
      const double job = std::chrono::duration<double>(t2 - t1).count();
      if (rep == 0) first = wall, first_job = job;
      walls.push_back(wall);
      jobs.push_back(job);
      r = std::move(ri);
    }
    std::sort(walls.begin(), walls.end());
    std::sort(jobs.begin(), jobs.end());
    const double wall = walls[walls.size() / 2], job = jobs[jobs.size() / 2];
    const double T = r.plan.duration();
    std::printf("%-34s %10d %12.3f %10.4f %12.1f %12.1f %12zu %10.1f\n", "butterfly load+plan (median of 7)", 1, T,
                wall, T / wall, wall * 1e3, r.segments.size(), rss_kib() / 1024.0);
    std::printf("%-34s %10d %12.3f %10.4f %12.1f %12.1f\n", "butterfly load+plan (first run)", 1, T, first, T / first,
                first * 1e3);
    std::printf("%-34s %10d %12.3f %10.4f %12.1f %12.1f\n", "butterfly run_job only (median)", 1, T, job, T / job,
                job * 1e3);
    std::printf("%-34s %10d %12.3f %10.4f %12.1f %12.1f\n", "butterfly run_job only (first run)", 1, T, first_job,
                T / first_job, first_job * 1e3);
    std::printf("    stages (last run): plan %.1f ms, ticks %.1f ms, fit %.1f ms, compile %.1f ms\n", r.t_plan * 1e3,
                r.t_ticks * 1e3, r.t_fit * 1e3, r.t_compile * 1e3);
    std::fflush(stdout);
  }
  for (size_t n = 1000; n <= max_pieces; n *= 10) {
    RasterSource src(n, 20.0, 1.0);
    JobConfig cfg;
    cfg.limits.feed = 50;
    StreamOptions so;
    size_t segs = 0;
    // From 100 000 pieces on, the rate of each tenth of the run is printed too
    // (does the cost per piece grow with the length?).
    std::vector<std::pair<double, double>> tenths;  // (host s, motion s) per tenth
    double motion = 0, last_curves = 0, last_motion = 0;
    auto t_last = std::chrono::steady_clock::now();
    const double h = cfg.machine.period;
    Progress progress;
    if (n >= 100000)
      progress = [&](const std::string&, double curves) {
        if (curves - last_curves < n / 10.0 && curves < n) return;
        const auto now = std::chrono::steady_clock::now();
        tenths.push_back({std::chrono::duration<double>(now - t_last).count(), motion - last_motion});
        t_last = now;
        last_curves = curves;
        last_motion = motion;
      };
    const StreamStats st = run_streaming(
        src, cfg, so,
        [&](const traj::fd::Compiled&, const TimeSegment& sg) {
          ++segs;
          motion += sg.K * h;
        },
        progress);
    char name[64];
    std::snprintf(name, sizeof name, "raster %zu pieces (streaming)", n);
    std::printf("%-34s %10zu %12.3f %10.3f %12.1f %12.1f %12zu %10.1f\n", name, n, st.motion_time, st.wall,
                st.motion_time / st.wall, st.first_segment * 1e3, segs, rss_kib() / 1024.0);
    if (!tenths.empty()) {
      std::printf("    real-time factor per tenth of the run:");
      for (const auto& x : tenths) std::printf(" %.0f", x.second / x.first);
      std::printf("\n");
    }
    std::fflush(stdout);
  }
  return 0;
}
