// Planning speed on a long CAM-like G-code program (cam_program.hpp): host
// seconds per second of motion, whole-path (what `trajcore run` and `plan`
// without --window do: read, blend, plan, fit, compile) and streamed (`plan
// --window 64`: the same in bounded memory), with the max RSS of each.
//   usage: bench_gcode [max_lines=100000] [--short]
// Each case runs in a child process of its own, so that its max RSS is its
// own. Real-time factor = seconds of motion per host second (one core).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "cam_program.hpp"
#include "child_process.hpp"
#include "input/gcode.hpp"
#include "job/job.hpp"
#include "job/streaming.hpp"
#include "job/toolpath_job.hpp"
#include "job/toolpath_stream.hpp"

using namespace traj;

namespace {

double mib_rss() {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;
}

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

void print_row(const char* what, long lines, double motion, double host, size_t segments, const std::string& extra) {
  std::printf("%-22s %8ld %12.3f %9.3f %11.0f %10zu %10.1f  %s\n", what, lines, motion, host, motion / host, segments,
              mib_rss(), extra.c_str());
  std::fflush(stdout);
}

void whole(const std::string& file, long lines) {
  const auto t0 = Clock::now();
  const job::JobConfig cfg;
  const input::Toolpath tp = input::read_gcode(file);
  const job::ToolpathPlan tpp = job::toolpath_plan(tp, cfg);
  const job::JobResult r = job::run_job(tpp.path, tpp.cfg);
  const double host = since(t0);
  char b[200];
  std::snprintf(b, sizeof b, "%d corners blended, %d plans, %d repair caps; plan %.2f ticks %.2f fit %.2f compile %.2f s",
                tpp.corners_blended, r.rounds, r.repairs, r.t_plan, r.t_ticks, r.t_fit, r.t_compile);
  print_row("whole path (run_job)", lines, r.plan.duration(), host, r.segments.size(), b);
}

void streamed(const std::string& file, long lines, bool prefetch) {
  const auto t0 = Clock::now();
  const job::JobConfig cfg;
  job::ToolpathStream src(file, input::FileKind::kGcode, cfg);
  job::StreamOptions so;  // window 64, commit 48
  so.prefetch = prefetch;
  const job::StreamStats st = job::run_streaming(src, src.config(), so, [](const fd::Compiled&, const plan::TimeSegment&) {});
  const double host = since(t0);
  char b[200];
  std::snprintf(b, sizeof b, "%d corners blended, %zu windows (%zu planned again), %zu repair caps, %zu moves held at most",
                src.totals().corners_blended, st.windows, st.retries, st.caps, src.totals().max_pending);
  print_row(prefetch ? "streamed, 2 threads" : "streamed, 1 thread", lines, st.motion_time, host, st.segments, b);
}

}  // namespace

int main(int argc, char** argv) {
  long max_lines = 100000;
  bool short_run = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--short") == 0) short_run = true;
    else max_lines = std::strtol(argv[i], nullptr, 10);
  }
  if (short_run) max_lines = 2000;
  const std::string dir = std::filesystem::temp_directory_path() / ("bench_gcode_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::printf("%-22s %8s %12s %9s %11s %10s %10s\n", "case", "lines", "motion_s", "host_s", "realtime_x", "segments",
              "maxrss_MiB");
  bool ok = true;
  for (long n = short_run ? max_lines : 10000; n <= max_lines; n *= 10) {
    const std::string file = dir + "/cam_" + std::to_string(n) + ".ngc";
    {
      std::ofstream o(file);
      bench::write_cam_program(o, n);
    }
    ok = bench::in_child([&] { streamed(file, n, false); }, "FAILED: ") && ok;
    ok = bench::in_child([&] { streamed(file, n, true); }, "FAILED: ") && ok;
    ok = bench::in_child([&] { whole(file, n); }, "FAILED: ") && ok;
  }
  std::filesystem::remove_all(dir);
  return ok ? 0 : 1;
}
