// trajcore: command-line tool.
//   trajcore plan  <path.json> -o out.trj      plan + compile -> segment stream (+ plan report)
//   trajcore plan  <path.jsonl> -o out.trj     the same, streamed: one curve per line, bounded memory
//   trajcore sim   <stream.trj> --csv out.csv  segment stream -> Verilated core -> samples
//   trajcore run   <path.json> --out-dir DIR   both, with the full report and SVG plots
//   trajcore demo                              the built-in circle demo (cubic engine)
//   trajcore demo --engine bcu|mixed           the circle through traj_core (BCU / FD+BCU segments)
//   trajcore spline <points.json> -o out.trj   seed 000's C1 spline through points -> BCU segment stream
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "demo.hpp"
#include "input/jsonl_source.hpp"
#include "report/report.hpp"
#include "input/path_json.hpp"
#include "input/raster.hpp"
#include "job/streaming.hpp"
#include "sim/sim.hpp"
#include "stream/segment_stream.hpp"
#include "util/atomic_file.hpp"

namespace fd = traj::fd;

namespace {

using traj::job::JobConfig;

void add_limits(CLI::App* c, JobConfig& cfg, std::vector<double>& v_axis, std::vector<double>& a_axis,
                std::vector<double>& j_axis) {
  auto& L = cfg.limits;
  c->add_option("--feed", L.feed, "commanded feed, units/s")->capture_default_str();
  c->add_option("--period", cfg.machine.period, "tick period, s")->capture_default_str();
  c->add_option("--v-axis", v_axis, "per-axis velocity limits x,y,z (one value: all axes)")->delimiter(',');
  c->add_option("--a-axis", a_axis, "per-axis acceleration limits")->delimiter(',');
  c->add_option("--j-axis", j_axis, "per-axis jerk limits")->delimiter(',');
  c->add_option("--a-tan", L.a_tan, "tangential acceleration limit")->capture_default_str();
  c->add_option("--j-tan", L.j_tan, "tangential jerk limit")->capture_default_str();
  c->add_option("--a-cen", L.a_cen, "centripetal acceleration limit")->capture_default_str();
  c->add_option("--j-cen", L.j_cen, "centripetal jerk limit")->capture_default_str();
  c->add_option("--tol", L.tol, "path tolerance: max distance of the output from the curve, units")
      ->capture_default_str();
  c->add_option("--degree", cfg.machine.degree, "segment degree: 5 (C2 joins) or 3")->capture_default_str();
}

void apply_axes(JobConfig& cfg, const std::vector<double>& v, const std::vector<double>& a,
                const std::vector<double>& j) {
  auto set = [](double* dst, const std::vector<double>& src, const char* name) {
    if (src.empty()) return;
    if (src.size() != 1 && src.size() != 3)
      throw traj::plan::PlanError(std::string("--") + name + " takes 1 or 3 values, got " + std::to_string(src.size()));
    for (int k = 0; k < 3; ++k) dst[k] = src.size() == 1 ? src[0] : src[k];
  };
  set(cfg.limits.v_axis, v, "v-axis");
  set(cfg.limits.a_axis, a, "a-axis");
  set(cfg.limits.j_axis, j, "j-axis");
}

void progress(const std::string& stage, double f) {
  std::fprintf(stderr, "\r[%s] %3.0f%%   ", stage.c_str(), 100 * f);
  if (stage == "done") std::fprintf(stderr, "\n");
}

void write_csv(const std::string& path, const traj::stream::Header& h, const traj::report::Samples& s) {
  traj::util::AtomicFile f(path);
  std::ofstream& o = f.out();
  const double lsb = std::ldexp(1.0, -h.frac_bits);
  o << "tick,t_s,x_lsb,y_lsb,z_lsb,x,y,z\n";
  char b[160];
  for (size_t k = 0; k < s.v.size(); ++k) {
    std::snprintf(b, sizeof b, "%zu,%.6f,%lld,%lld,%lld,%.10f,%.10f,%.10f\n", k, k * h.period, s.v[k][0], s.v[k][1],
                  s.v[k][2], s.v[k][0] * lsb, s.v[k][1] * lsb, s.v[k][2] * lsb);
    o << b;
  }
  f.commit();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"trajcore: FPGA motion-trajectory core, host toolchain"};
  app.require_subcommand(1);

  traj::app::DemoOptions demo;
  auto* d = app.add_subcommand("demo",
                               "Built-in demo: a circle of three 120-degree cubic Bezier segments, compiled to "
                               "forward-difference segments and run through the Verilated engine");
  d->add_option("--radius", demo.radius, "circle radius, mm")->check(CLI::PositiveNumber);
  d->add_option("--feed", demo.feed, "nominal feed along the circle, mm/s")->check(CLI::PositiveNumber);
  d->add_option("--period", demo.period, "tick period, s")->check(CLI::PositiveNumber);
  d->add_option("--pieces", demo.pieces, "time segments per 120-degree arc")->check(CLI::Range(1, 1000));
  d->add_option("--frac-bits", demo.frac_bits, "output fraction bits (1 LSB = 2^-F mm)")->check(CLI::Range(0, 30));
  d->add_option("--csv", demo.csv, "where to write the samples (CSV)");
  d->add_option("--tick-gap", demo.tick_gap,
                 "clock cycles between ticks in the simulation (default: 64 for --engine fd, the core's minimum tick "
                 "spacing for bcu and mixed)")
      ->check(CLI::Range(1, 1000000));
  d->add_option("--engine", demo.engine,
                "fd: forward differences on traj_fd_engine (default); bcu: every arc one BCU segment of K = 2^d "
                "ticks; mixed: arcs FD, BCU, FD chained exactly; bcu and mixed run on traj_core (both engines) "
                "through a version-2 segment stream")
      ->check(CLI::IsMember({"fd", "bcu", "mixed"}))
      ->capture_default_str();
  d->add_option("--stream", demo.stream, "bcu|mixed: the segment stream to write (default out/demo_<engine>.trj)");

  traj::app::SplineOptions spl;
  auto* sp = app.add_subcommand(
      "spline", "Seed 000's C1 interpolating cubic Bezier spline through points (JSON {\"points\": [[x, y(, z)], "
                "...]}), compiled to BCU segments for traj_core: a version-2 segment stream for `trajcore sim`");
  sp->add_option("points", spl.input, "points JSON file")->required();
  sp->add_option("-o,--output", spl.output, "segment stream to write")->capture_default_str();
  sp->add_option("--lambda", spl.lambda, "tension lambda (eq. 9), in (0, 1]")->capture_default_str();
  sp->add_option("--mu", spl.mu, "tension mu (default: lambda, which makes the spline C1; otherwise G1)");
  sp->add_option("--feed", spl.feed, "speed limit, units/s: each segment gets the least K = 2^d ticks that keeps "
                                     "the speed below it (hodograph bound)")
      ->capture_default_str();
  sp->add_option("--period", spl.period, "tick period, s")->capture_default_str();
  sp->add_option("--depth", spl.depth, "K = 2^depth ticks for every segment instead of --feed")->check(CLI::Range(0, 30));
  sp->add_option("--frac-bits", spl.frac_bits, "output fraction bits (1 LSB = 2^-F units)")
      ->check(CLI::Range(0, 30))
      ->capture_default_str();
  sp->add_option("--engine", spl.engine, "bcu: every segment BCU; mixed: odd segments as FD (exact chaining)")
      ->check(CLI::IsMember({"bcu", "mixed"}))
      ->capture_default_str();

  JobConfig cfg;
  std::vector<double> v_axis, a_axis, j_axis;
  std::string input, out_stream = "out/plan.trj", out_dir = "out", csv = "out/samples.csv";
  int tick_gap = 0;

  size_t window = 0, raster = 0;
  std::string format;
  auto* pl = app.add_subcommand("plan", "Plan and compile a path (curve JSON) into a segment stream");
  pl->add_option("path", input,
                 "curve or path JSON (the butterfly format, or {\"curves\": [...]}), or a JSON Lines path "
                 "(*.jsonl: one curve object per line, read as a stream)");
  pl->add_option("-o,--output", out_stream, "segment stream to write")->capture_default_str();
  auto* window_opt = pl->add_option(
      "--window", window,
      "stream in bounded memory: plan a look-ahead window of this many curves, commit three quarters of it "
      "(half below 16), "
      "write segments as they are final (0: plan the whole path at once; a .jsonl path is always streamed, "
      "default window 64)");
  pl->add_option("--format", format, "path file format: json or jsonl (default: jsonl for a name ending in .jsonl)")
      ->check(CLI::IsMember({"json", "jsonl"}));
  pl->footer(
      "JSON Lines paths (*.jsonl or --format jsonl): one curve per line, each a curve object of the butterfly "
      "format (degree, knots, control_points, optional weights); blank lines and lines starting with # are "
      "skipped; consecutive curves must meet. The file is read line by line while the segments are written, so a "
      "path of a million pieces plans in memory bounded by the window. An error names <file>:<line> and the field, "
      "and leaves no output file. (`trajcore run` needs the whole path in memory for its report and plots: for a "
      ".jsonl use `trajcore plan` then `trajcore sim`.)");
  pl->add_option("--raster", raster, "instead of a file: a synthetic raster toolpath of this many pieces (streamed)");
  add_limits(pl, cfg, v_axis, a_axis, j_axis);

  auto* sm = app.add_subcommand("sim", "Run a segment stream through the Verilated core");
  sm->add_option("stream", input, "segment stream (.trj)")->required();
  sm->add_option("--csv", csv, "samples CSV to write")->capture_default_str();
  sm->add_option("--tick-gap", tick_gap, "clock cycles between ticks (0: shortest safe)");
  sm->footer("A version-1 stream (FD segments) runs on traj_fd_engine, a version-2 stream (FD and BCU segments, "
             "from `trajcore demo --engine bcu|mixed` or `trajcore spline`) on traj_core.");

  auto* rn = app.add_subcommand("run", "Plan, compile, simulate on the Verilated core, and report (text + SVG)");
  rn->add_option("path", input, "curve or path JSON (not .jsonl: plan a JSON Lines path with `plan`, then `sim`)")
      ->required();
  rn->add_option("--out-dir", out_dir, "where to write plan.trj, samples.csv, report.txt, *.svg")->capture_default_str();
  add_limits(rn, cfg, v_axis, a_axis, j_axis);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (*d) return traj::app::run_demo(demo);
#if TRAJ_APP_CORE
    if (*sp) return traj::app::run_spline(spl);
#else
    if (*sp) throw std::runtime_error("spline: this trajcore was built without host/bcu (TRAJ_SKIP)");
#endif
    const bool jsonl = !input.empty() && raster == 0 && traj::input::is_jsonl(input, format);
    if (*rn && traj::input::is_jsonl(input))
      throw traj::plan::PlanError(
          "run: " + input + " is a JSON Lines path, which is planned as a stream; run needs the whole path in "
          "memory (report, plots): use `trajcore plan " + input + " -o plan.trj` (streamed) then `trajcore sim "
          "plan.trj`");
    if (*pl && jsonl && window_opt->count() > 0 && window == 0)
      throw traj::plan::PlanError("plan: a JSON Lines path is always streamed: --window must be at least 2");
    if (*pl && (window > 0 || raster > 0 || jsonl)) {
      apply_axes(cfg, v_axis, a_axis, j_axis);
      struct VecSource : traj::input::CurveSource {
        std::vector<std::pair<traj::geo::BSpline, std::string>> v;
        size_t i = 0;
        bool next(traj::geo::BSpline& b, std::string& w) override {
          if (i >= v.size()) return false;
          b = v[i].first;
          w = v[i].second;
          ++i;
          return true;
        }
      };
      std::unique_ptr<traj::input::CurveSource> src;
      if (raster > 0) {
        src = std::make_unique<traj::input::RasterSource>(raster);
      } else if (jsonl) {
        src = std::make_unique<traj::input::JsonlSource>(input);  // read line by line as the windows need curves
      } else {
        if (input.empty()) throw traj::plan::PlanError("plan: give a path file or --raster N");
        const auto path = traj::input::load_path(input);  // checks the file and the joins
        auto vs = std::make_unique<VecSource>();
        for (size_t i = 0; i < path.size(); ++i) vs->v.push_back({path.curve(i).spline(), input + ": curve " + std::to_string(i)});
        src = std::move(vs);
      }
      traj::job::StreamOptions so;
      if (window > 0) {
        so.window = std::max<size_t>(window, 2);
        so.commit = so.window >= 16 ? so.window * 3 / 4 : so.window / 2;
      }
      traj::stream::StreamWriter w(out_stream, cfg.machine.header());
      traj::job::StreamStats st;
      try {
        st = traj::job::run_streaming(
            *src, cfg, so, [&](const fd::Compiled& c, const traj::plan::TimeSegment&) { w.add({c.ticks, c.regs}); },
            [](const std::string&, double curves) { std::fprintf(stderr, "\r[stream] %.0f curves   ", curves); });
      } catch (...) {
        std::fprintf(stderr, "\n");  // end the progress line; the writer removes its temporary file
        throw;
      }
      w.finish();
      std::fprintf(stderr, "\n");
      std::printf("%s: %zu curves in %zu windows, %zu segments, %lld ticks (%.3f s of motion) -> %s\n"
                  "host time %.3f s (%.0fx real time), first segment after %.1f ms\n",
                  raster ? "raster" : input.c_str(), st.curves, st.windows, st.segments, st.ticks, st.motion_time,
                  out_stream.c_str(), st.wall, st.motion_time / st.wall, st.first_segment * 1e3);
      return 0;
    }
    if (*pl || *rn) {
      if (input.empty()) throw traj::plan::PlanError("give a path file");
      apply_axes(cfg, v_axis, a_axis, j_axis);
      const auto path = traj::input::load_path(input);
      const auto res = traj::job::run_job(path, cfg, progress);
      auto verdict = [&](const traj::report::Report& rep) {
        return rep.max_deviation <= cfg.limits.tol && rep.worst_plan <= 1 + 1e-9 && rep.worst_fit <= 1 + 1e-9 &&
               rep.worst_out <= 1 + 1e-9;
      };
      if (*pl) {
        traj::stream::write_file(out_stream, res.header, traj::job::records_of(res));
        std::printf("%s: %zu segments, %zu ticks (%.3f s of motion) -> %s\n", input.c_str(), res.segments.size(),
                    res.ticks.size(), res.plan.duration(), out_stream.c_str());
        // the plan report; the output columns are the host's exact prediction
        // of the core's samples (`trajcore run` confirms them on the Verilated core)
        const auto rep = traj::report::make_report(path, cfg, res, traj::report::predicted_samples(res));
        std::fputs(traj::report::report_text(cfg, rep, res).c_str(), stdout);
        std::printf("(output columns: the host's exact prediction of the core's samples)\n");
        if (!verdict(rep)) std::fprintf(stderr, "trajcore plan: a check FAILED (see the report)\n");
        return verdict(rep) ? 0 : 1;
      }
      // run: everything is written into a staging folder inside out_dir and
      // moved into place only when all of it is written (nothing half-written)
      namespace fs = std::filesystem;
      const std::vector<std::string> names = {"plan.trj", "samples.csv", "report.txt", "path_feed.svg", "profile.svg"};
      fs::create_directories(out_dir);
      for (const auto& n : names)
        if (fs::exists(out_dir + "/" + n) && !fs::is_regular_file(out_dir + "/" + n))
          throw traj::plan::PlanError(out_dir + "/" + n + ": exists and is not a regular file; nothing written");
      struct Staging {
        std::string dir;
        bool keep = false;
        ~Staging() {
          std::error_code ec;
          if (!keep) fs::remove_all(dir, ec);
        }
      } stage{out_dir + "/.trajcore-run-" + std::to_string(::getpid())};
      fs::create_directories(stage.dir);
      traj::stream::write_file(stage.dir + "/plan.trj", res.header, traj::job::records_of(res));
      std::printf("%s: %zu segments, %zu ticks (%.3f s of motion)\n", input.c_str(), res.segments.size(),
                  res.ticks.size(), res.plan.duration());
      auto sr = traj::sim::simulate(res.header, traj::job::records_of(res), 0,
                                    [](double f) { progress("sim", f); });
      std::fprintf(stderr, "\n");
      write_csv(stage.dir + "/samples.csv", res.header, sr.samples);
      const auto rep = traj::report::make_report(path, cfg, res, sr.samples);
      traj::report::write_plots(stage.dir, path, cfg, res, sr.samples);
      std::string text = traj::report::report_text(cfg, rep, res);
      char b[256];
      std::snprintf(b, sizeof b,
                    "Core (Verilated traj_fd_engine): %llu cycles in %.2f s, RTL == hls on every cycle: %s, "
                    "underruns %llu, tick_err %s\n",
                    static_cast<unsigned long long>(sr.cycles), sr.seconds, sr.mismatches ? "NO" : "yes",
                    static_cast<unsigned long long>(sr.underruns), sr.tick_err ? "SET" : "clear");
      text += b;
      {
        std::ofstream o(stage.dir + "/report.txt");
        o << text;
        o.close();
        if (!o) throw traj::plan::PlanError("write failed: " + stage.dir + "/report.txt");
      }
      for (const auto& n : names) fs::rename(stage.dir + "/" + n, out_dir + "/" + n);
      std::fputs(text.c_str(), stdout);
      std::printf("Wrote %s/{plan.trj, samples.csv, report.txt, path_feed.svg, profile.svg}\n", out_dir.c_str());
      const bool ok = sr.mismatches == 0 && !sr.tick_err && verdict(rep);
      if (!ok) std::fprintf(stderr, "trajcore run: a check FAILED (see the report)\n");
      return ok ? 0 : 1;
    }
    if (*sm) {
      const auto rd = traj::stream::read_file(input);
      if (!rd.complete) {
        std::fprintf(stderr, "trajcore: error: %s (%zu segments before it were valid; nothing simulated)\n",
                     rd.error.c_str(), rd.records.size());
        return 1;
      }
      auto sr = traj::sim::simulate(rd.header, rd.records, tick_gap, [](double f) { progress("sim", f); });
      if (sr.engine == "traj_core") {
        // version 2: both engines; every sample also against the exact prediction from the records
        const bool ok = sr.mismatches == 0 && sr.prediction_mismatches == 0 && !sr.tick_err && sr.underruns == 0;
        if (ok) write_csv(csv, rd.header, sr.samples);
        std::printf("%s: %zu segments (%llu FD, %llu BCU, %llu kind switches), %zu samples, %llu cycles on traj_core "
                    "(tick every %d), RTL == hls: %s, == host prediction: %s, tick_err %s, underruns %llu -> %s\n",
                    input.c_str(), rd.records.size(), static_cast<unsigned long long>(sr.fd_segments),
                    static_cast<unsigned long long>(sr.bcu_segments), static_cast<unsigned long long>(sr.switches),
                    sr.samples.v.size(), static_cast<unsigned long long>(sr.cycles), sr.tick_gap,
                    sr.mismatches ? "NO" : "yes", sr.prediction_mismatches ? "NO" : "yes",
                    sr.tick_err ? "SET" : "clear", static_cast<unsigned long long>(sr.underruns),
                    ok ? csv.c_str() : "(no CSV written)");
        if (!ok) std::fprintf(stderr, "trajcore sim: a check FAILED (see above)\n");
        return ok ? 0 : 1;
      }
      write_csv(csv, rd.header, sr.samples);
      std::printf("%s: %zu segments, %zu samples, %llu cycles, RTL == hls: %s -> %s\n", input.c_str(),
                  rd.records.size(), sr.samples.v.size(), static_cast<unsigned long long>(sr.cycles),
                  sr.mismatches ? "NO" : "yes", csv.c_str());
      return sr.mismatches ? 1 : 0;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "trajcore: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
