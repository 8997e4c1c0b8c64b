// SPDX-License-Identifier: Apache-2.0
// trajcore: command-line tool.
//   trajcore plan  <path.json> -o out.trj      plan + compile -> segment stream (+ plan report)
//   trajcore plan  <path.jsonl> -o out.trj     the same, streamed: one curve per line, bounded memory
//   trajcore sim   <stream.trj> --csv out.csv  segment stream -> Verilated core -> samples
//   trajcore run   <path.json> --out-dir DIR   both, with the full report and SVG plots
//   trajcore demo                              the built-in circle demo (cubic engine)
//   trajcore demo --engine bcu|mixed           the circle through traj_core (BCU / FD+BCU segments)
//   trajcore spline <points.json> -o out.trj   [BCU]'s C1 spline through points -> BCU segment stream
//   trajcore upload <stream.trj|-> --port P    segment stream -> board (serial, pty, tcp)
//   trajcore board --loopback                  the loopback board on a pty or TCP port (fault injection)
#include <CLI/CLI.hpp>

#include <cctype>
#include <cstdio>
#include <exception>

#include "commands.hpp"
#include "input/gcode.hpp"
#include "demo.hpp"
#include "link_cmds.hpp"
#include "util/atomic_file.hpp"

namespace fd = traj::fd;

namespace {

using traj::job::JobConfig;

const std::vector<std::string> kFormats = {"json", "jsonl", "gcode", "svg", "dxf"};
constexpr const char* kFormatHelp =
    "path file format: json, jsonl, gcode, svg or dxf (default: by the name: .jsonl, .ngc/.nc/.gcode/.tap/.cnc, "
    ".svg, .dxf; JSON otherwise)";

struct AxisArgs {
  std::string axes = "XYZ";
  std::vector<double> v, a, j;
};

// The limits (and the axes they are given for): plan and run plan within
// them, sim --check measures the core's samples against them.
void add_limit_values(CLI::App* c, traj::plan::Limits& L, AxisArgs& ax) {
  c->add_option("--axes", ax.axes,
                "the machine's axes, as LinuxCNC names them: XYZ and up to five of A B C (rotary, degrees) and U V W, "
                "in the engine's order (G-code words of other axes are refused; F is the speed of X Y Z when they "
                "move, else of U V W, else of A B C, as in LinuxCNC)")
      ->capture_default_str();
  c->add_option("--feed", L.feed, "commanded feed, units/s")->capture_default_str();
  c->add_option("--v-axis", ax.v, "per-axis velocity limits in --axes order, e.g. x,y,z (one value: all axes; "
                "A B C in degrees/s)")->delimiter(',');
  c->add_option("--a-axis", ax.a, "per-axis acceleration limits")->delimiter(',');
  c->add_option("--j-axis", ax.j, "per-axis jerk limits")->delimiter(',');
  c->add_option("--a-tan", L.a_tan, "tangential acceleration limit")->capture_default_str();
  c->add_option("--j-tan", L.j_tan, "tangential jerk limit")->capture_default_str();
  c->add_option("--a-cen", L.a_cen, "centripetal acceleration limit")->capture_default_str();
  c->add_option("--j-cen", L.j_cen, "centripetal jerk limit")->capture_default_str();
}

void add_limits(CLI::App* c, JobConfig& cfg, AxisArgs& ax) {
  auto& L = cfg.limits;
  add_limit_values(c, L, ax);
  c->add_option("--period", cfg.machine.period, "tick period, s")->capture_default_str();
  c->add_option("--feed-accuracy", cfg.machine.feed_accuracy,
                "bound on |chord between samples / chord between the planned points - 1| at every tick (0: the default "
                "fit, about 2e-3)")
      ->capture_default_str();
  c->add_option("--tol", L.tol, "path tolerance: max distance of the output from the curve, units")
      ->capture_default_str();
  c->add_option("--degree", cfg.machine.degree, "segment degree: 5 (C2 joins) or 3")->capture_default_str();
  c->add_option("--engine-width", cfg.machine.engine_width,
                "the engine's register width: 96 for the board (rtl/traj_board.sv: quintic, 96-bit, 2^-32 units); "
                "default: the narrowest carried engine whose quantisation allowance is at most 1 % of every limit "
                "(ticks below about 250 us: 128-bit, 2^-44 units)");
}

// How G-code is read: plan and run alike.
void add_gcode_options(CLI::App* c, traj::app::GcodeArgs& g) {
  c->add_option("--tool-table", g.tool_table,
                "LinuxCNC tool table (\"T1 P1 Z12.5 ;comment\", lengths in mm) for G43 H: the moves are then of the "
                "tool's holder, the program's Z plus the length; without one G43 is refused")
      ->check(CLI::ExistingFile);
  c->add_flag("--pause-as-stop", g.pause_as_stop,
              "take M0 and M60 (program pause, e.g. before a manual tool change) as exact stops, as M1: the motion "
              "goes on at once and the machine does NOT wait for an operator; without it such a program is refused");
  c->add_flag("--pause-wait", g.pause_wait,
              "take M0 and M60 (program pause) as exact stops with a pause record in the stream, carrying the "
              "program's last (MSG, ...) before it: `trajcore upload` stops there, shows the message and waits for "
              "the operator (Enter) before it goes on; whole or streamed (--window), not with --time-scale")
      ->excludes("--pause-as-stop");
}

void add_time_scale(CLI::App* c, traj::app::TimeScaleArgs& t) {
  c->add_option("--time-scale", t.s_max,
                "plan for time scaling up to this feed override (e.g. 1.2 for 120 %): below the limits by "
                "--scale-headroom, with the ramp bounds of s that keep every per-axis limit in the report "
                "(host/timescale/README.md)");
  c->add_option("--scale-headroom", t.headroom,
                "with --time-scale: the shares of the acceleration and jerk limits the plan uses")
      ->delimiter(',')
      ->capture_default_str();
  c->add_option("--servo-period", t.servo_period, "with --time-scale: the board's servo tick, s")->capture_default_str();
}

// The machine's axes (--axes) and their limits: one value for all, or one per axis.
void apply_axes(traj::plan::Limits& limits, const AxisArgs& ax) {
  traj::input::check_axes(ax.axes);
  const int n = static_cast<int>(ax.axes.size());
  auto set = [n](double* dst, const std::vector<double>& src, const char* name) {
    if (src.empty()) return;
    if (src.size() != 1 && static_cast<int>(src.size()) != n)
      throw traj::plan::PlanError(std::string("--") + name + " takes 1 or " + std::to_string(n) +
                                  " values (one per axis of --axes), got " + std::to_string(src.size()));
    for (int k = 0; k < traj::plan::kMaxAxes; ++k) dst[k] = src.size() == 1 ? src[0] : src[std::min(k, n - 1)];
  };
  set(limits.v_axis, ax.v, "v-axis");
  set(limits.a_axis, ax.a, "a-axis");
  set(limits.j_axis, ax.j, "j-axis");
  std::string names;
  for (char c : ax.axes) names += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (char c : std::string("xyzabcuvw"))
    if (names.size() < static_cast<size_t>(traj::plan::kMaxAxes) && names.find(c) == std::string::npos) names += c;
  limits.axis_names = names;
}

void apply_axes(JobConfig& cfg, const AxisArgs& ax) {
  apply_axes(cfg.limits, ax);
  cfg.machine.axes = static_cast<int>(ax.axes.size());
}

}  // namespace

int main(int argc, char** argv) {
  // an interrupted command leaves no "<output>.<pid>.tmp" behind (SIGKILL excepted)
  traj::util::remove_temporaries_on_signals();
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
                "through a segment stream with a BCU format")
      ->check(CLI::IsMember({"fd", "bcu", "mixed"}))
      ->capture_default_str();
  d->add_option("--stream", demo.stream, "bcu|mixed: the segment stream to write (default out/demo_<engine>.trj)");

  traj::app::SplineOptions spl;
  auto* sp = app.add_subcommand(
      "spline", "[BCU]'s C1 interpolating cubic Bezier spline through points (JSON {\"points\": [[x, y(, z)], "
                "...]}), compiled to BCU segments for traj_core: a segment stream with a BCU format for `trajcore sim`");
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

  traj::app::PlanArgs pa;
  traj::app::RunArgs ra;
  traj::app::SimArgs sa;
  AxisArgs axes, sim_axes;
  auto* pl = app.add_subcommand("plan", "Plan and compile a path (curve JSON) into a segment stream");
  pl->add_option("path", pa.input,
                 "G-code (.ngc .nc .gcode .tap), SVG, DXF, curve or path JSON (the butterfly format, or "
                 "{\"curves\": [...]}), or a JSON Lines path (*.jsonl: one curve object per line, read as a stream)");
  pl->add_option("-o,--output", pa.output, "segment stream to write (- : standard output, e.g. piped into `trajcore upload -`)")->capture_default_str();
  auto* window_opt = pl->add_option(
      "--window", pa.window,
      "stream in bounded memory (JSON, JSON Lines, and toolpaths: G-code read a line at a time, corners blended in chunks): plan a look-ahead window of this many curves, commit three quarters of it "
      "(half below 16), "
      "write segments as they are final (0: plan the whole path at once; a .jsonl path is always streamed, "
      "default window 64)");
  pl->add_option("--threads", pa.threads,
                 "threads of a streamed plan: 2 reads, blends and builds the curves' arc-length tables beside the "
                 "planning (the same stream); 1 does all on one")
      ->check(CLI::Range(1, 2))
      ->capture_default_str();
  pl->add_option("--format", pa.format, kFormatHelp)->check(CLI::IsMember(kFormats));
  add_gcode_options(pl, pa.gcode);

  pl->add_flag("--blend-all", pa.blend_all,
              "blend every corner within the tolerance, also a sharp one where stopping at it is faster at the limits "
                 "(by default such a corner is an exact stop on the programmed vertex: host/corners/README.md)");

  pl->footer(
      "JSON Lines paths (*.jsonl or --format jsonl): one curve per line, each a curve object of the butterfly "
      "format (degree, knots, control_points, optional weights); blank lines and lines starting with # are "
      "skipped; consecutive curves must meet. The file is read line by line while the segments are written, so a "
      "path of a million pieces plans in memory bounded by the window. An error names <file>:<line> and the field, "
      "and leaves no output file. (`trajcore run` reads a .jsonl whole: its report and plots are of the whole "
      "path, planned at once.)");
  pl->add_option("--raster", pa.raster, "instead of a file: a synthetic raster toolpath of this many pieces (streamed)");
  add_limits(pl, pa.cfg, axes);
  add_time_scale(pl, pa.scale);

  auto* sm = app.add_subcommand("sim", "Run a segment stream through the Verilated core");
  sm->add_option("stream", sa.input, "segment stream (.trj)")->required();
  sm->add_option("--csv", sa.csv, "samples CSV to write (default: none; the summary is always printed)");
  sm->add_option("--samples", sa.samples,
                 "binary sample file to write: a 24-byte header, then one little-endian int64 per axis per tick "
                 "(host/stream/README.md)");
  sm->add_option("--tick-gap", sa.tick_gap,
                 "clock cycles between ticks (0: the engine's pace, a tick after each sample; BCU streams: the "
                 "core's minimum spacing)");
  sm->add_flag("--check", sa.check,
               "measure the core's samples against the limits (the options below, as given to plan; defaults: "
               "plan's; the path speed only with --feed: a toolpath's feeds and rapids vary by move) after the "
               "quantisation allowance of the stream's format, in bounded memory; exit 1 if one is exceeded");
  sm->add_option("--plots", sa.plots,
                 "folder for path_feed.svg and profile.svg of the core's output (and samples.bin, which they are drawn "
                 "from, unless --samples names the file), in bounded memory");
  add_limit_values(sm, sa.limits, sim_axes);
  sm->footer("A stream without a BCU format (FD segments) runs on traj_fd_engine, one with a BCU format (FD and BCU segments, "
             "from `trajcore demo --engine bcu|mixed` or `trajcore spline`) on traj_core.");

  auto* rn = app.add_subcommand("run", "Plan, compile, simulate on the Verilated core, and report (text + SVG)");
  rn->add_option("path", ra.input,
                 "G-code (.ngc .nc .gcode .tap), SVG, DXF, curve/path JSON, or a JSON Lines path (read whole; "
                 "`plan` streams it, `sim --check` measures that stream)")
      ->required();
  rn->add_option("--format", ra.format, kFormatHelp)->check(CLI::IsMember(kFormats));
  add_gcode_options(rn, ra.gcode);

  rn->add_flag("--blend-all", ra.blend_all, "blend every corner within the tolerance, also a sharp one where stopping at it is faster at the limits "
                 "(by default such a corner is an exact stop on the programmed vertex: host/corners/README.md)");
  rn->add_option("--out-dir", ra.out_dir, "where to write plan.trj, samples.csv, report.txt, *.svg")->capture_default_str();
  add_limits(rn, ra.cfg, axes);
  add_time_scale(rn, ra.scale);

  traj::app::LinkCommands lc;
  traj::app::add_link_commands(app, lc);

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
    if (*pl) {
      apply_axes(pa.cfg, axes);
      if (pa.scale.on()) traj::app::apply_time_scale_headroom(pa.cfg, pa.scale);
      pa.cfg.machine.choose_format(pa.cfg.limits);
      pa.window_given = window_opt->count() > 0;
      return traj::app::plan_command(pa);
    }
    if (*rn) {
      apply_axes(ra.cfg, axes);
      if (ra.scale.on()) traj::app::apply_time_scale_headroom(ra.cfg, ra.scale);
      ra.cfg.machine.choose_format(ra.cfg.limits);
      return traj::app::run_command(ra);
    }
    if (*sm) {
      apply_axes(sa.limits, sim_axes);
      if (sm->get_option("--axes")->count() > 0) sa.axes = static_cast<int>(sim_axes.axes.size());
      sa.check_feed = sm->get_option("--feed")->count() > 0;
      return traj::app::sim_command(sa);
    }
    if (*lc.upload) return traj::app::upload_command(lc.up);
    if (*lc.board) return traj::app::board_command(lc.bd);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "trajcore: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
