// SPDX-License-Identifier: Apache-2.0
#include "commands.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <set>
#include <vector>

#include "input/jsonl_source.hpp"
#include "input/path_json.hpp"
#include "input/raster.hpp"
#include "input/toolpath_file.hpp"
#include "job/streaming.hpp"
#include "job/toolpath_job.hpp"
#include "job/toolpath_stream.hpp"
#include "report/report.hpp"
#include "report/sample_check.hpp"
#include "sim/sim.hpp"
#include "stream/segment_stream.hpp"
#include "util/atomic_file.hpp"
#include "util/format.hpp"

namespace traj::app {
namespace {

namespace fs = std::filesystem;
using plan::PlanError;

// Progress on stderr: on a terminal one updating line; otherwise (a log, CI)
// a line the first time a stage is seen, else at most one every 5 s, so a
// repair loop that plans many times, or a stream of a million curves, does not
// fill the log.
bool stderr_is_tty() {
  static const bool tty = ::isatty(2);
  return tty;
}

void show_progress(const std::string& stage, const std::string& detail) {
  if (stderr_is_tty()) {
    std::fprintf(stderr, "\r[%s] %s   ", stage.c_str(), detail.c_str());
    return;
  }
  using Clock = std::chrono::steady_clock;
  static std::set<std::string> seen;
  static Clock::time_point last_time;
  const auto now = Clock::now();
  const bool first = seen.insert(stage).second;
  if (!first && now - last_time < std::chrono::seconds(5)) return;
  std::fprintf(stderr, "[%s] %s\n", stage.c_str(), detail.c_str());
  last_time = now;
}

// Ends the updating line on a terminal.
void end_progress() {
  if (stderr_is_tty()) std::fprintf(stderr, "\n");
}

void progress(const std::string& stage, double f) {
  show_progress(stage, util::fmt("%3.0f%%", 100 * f));
  if (stage == "done") end_progress();
}

// The samples CSV, row by row: a column of LSBs and one of units per axis,
// named by `names` (the machine's axis letters; the stream's axes beyond
// them idle).
class CsvWriter {
 public:
  CsvWriter(const std::string& path, const stream::Header& h, const std::string& names = plan::Limits{}.axis_names)
      : file_(path), lsb_(std::ldexp(1.0, -h.frac_bits)), period_(h.period),
        axes_(std::min({h.axes, plan::kMaxAxes, static_cast<int>(names.size())})) {
    std::string head = "tick,t_s", units;
    for (int a = 0; a < axes_; ++a) {
      head += "," + names.substr(static_cast<size_t>(a), 1) + "_lsb";
      units += "," + names.substr(static_cast<size_t>(a), 1);
    }
    file_.out() << head << units << "\n";
  }
  void row(uint64_t k, const report::Sample& v) {
    char b[64];
    std::snprintf(b, sizeof b, "%llu,%.6f", static_cast<unsigned long long>(k), static_cast<double>(k) * period_);
    std::string line = b;
    for (int a = 0; a < axes_; ++a) line += "," + std::to_string(v[a]);
    for (int a = 0; a < axes_; ++a) {
      std::snprintf(b, sizeof b, ",%.10f", v[a] * lsb_);
      line += b;
    }
    file_.out() << line << "\n";
  }
  void commit() { file_.commit(); }  // not committed: nothing is left under the path

 private:
  util::AtomicFile file_;
  double lsb_, period_;
  int axes_;
};

// The compact sample file (host/stream/README.md, "Sample files"): 8 bytes
// "TRJSMP01", u32 axes, i32 fraction bits, f64 tick period (s), then per
// tick one int64 per axis of the stream (output LSB), all little-endian: 24
// bytes a tick for 3 axes against about 100 in CSV.
class SampleFileWriter {
 public:
  SampleFileWriter(const std::string& path, const stream::Header& h)
      : file_(path, std::ios::out | std::ios::binary), axes_(std::min(h.axes, plan::kMaxAxes)) {
    file_.out().write("TRJSMP01", 8);
    put(static_cast<uint32_t>(axes_), 4);
    put(static_cast<uint32_t>(h.frac_bits), 4);
    uint64_t p;
    std::memcpy(&p, &h.period, 8);
    put(p, 8);
  }
  void row(const report::Sample& v) {
    for (int a = 0; a < axes_; ++a) put(static_cast<uint64_t>(v[a]), 8);
  }
  void commit() { file_.commit(); }

 private:
  void put(uint64_t v, int bytes) {
    char b[8];
    for (int i = 0; i < bytes; ++i) b[i] = static_cast<char>((v >> (8 * i)) & 0xff);
    file_.out().write(b, bytes);
  }
  util::AtomicFile file_;
  int axes_;
};

void write_csv(const std::string& path, const stream::Header& h, const report::Samples& s, const std::string& names) {
  CsvWriter w(path, h, names);
  for (size_t k = 0; k < s.v.size(); ++k) w.row(k, s.v[k]);
  w.commit();
}

// The curves of a path already in memory, as a stream.
struct PathSource : input::CurveSource {
  PathSource(const plan::Path& p, const std::string& file) : path(p), file(file) {}
  bool next(geo::BSpline& b, std::string& w) override {
    if (i >= path.size()) return false;
    b = path.curve(i).spline();
    w = file + ": curve " + std::to_string(i);
    ++i;
    return true;
  }
  plan::Path path;
  std::string file;
  size_t i = 0;
};

// A path file and the configuration to plan it with: a JSON path as it is; a
// toolpath (G-code, SVG, DXF) with its moves' speeds and stops as speed caps.
struct Loaded {
  plan::Path path;
  job::JobConfig cfg;
  std::string toolpath_text;  // a toolpath's moves and corners, for the report
  double fastest_feed_move = 0;  // a toolpath's: the top of the path plot's colour scale (0: the feed limit)
  std::vector<char> rapid_curve;  // a toolpath's: its curves that are rapid moves
};

// A JSON Lines path read whole (run plans and reports the whole path; `plan`
// streams it): the same reader and checks as the streamed plan.
plan::Path load_jsonl(const std::string& file) {
  input::JsonlSource src(file);
  plan::Path p;
  geo::BSpline sp;
  std::string where;
  while (src.next(sp, where)) p.add(sp, where);
  return p;
}

// The G-code reader's options: the machine's axes (--axes: the first
// Machine::axes of the limits' axis names), the tool table, if one is given,
// and what M0/M60 are taken as.
input::GcodeOptions gcode_options(const GcodeArgs& g, const job::JobConfig& cfg) {
  input::GcodeOptions o;
  o.axes.clear();
  for (char c : cfg.limits.axis_names.substr(0, static_cast<size_t>(cfg.machine.axes)))
    o.axes += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (!g.tool_table.empty()) o.tools = input::read_tool_table(g.tool_table);
  o.pauses_as_stops = g.pause_as_stop;
  o.pauses_wait = g.pause_wait;
  return o;
}


// The toolpath report's line on program pauses (none: no line).
std::string pauses_line(size_t pauses) {
  if (pauses == 0) return "";
  return "  program pauses       " + std::to_string(pauses) +
         " (pause records in the stream: `trajcore upload` waits at each for the operator)\n";
}

Loaded load(const std::string& file, const std::string& format, const GcodeArgs& gcode,
            const job::JobConfig& cfg, bool blend_all) {
  const input::FileKind kind = input::file_kind(file, format);
  if (kind == input::FileKind::kJsonl) return {load_jsonl(file), cfg, {}, 0, {}};
  if (!input::is_toolpath(kind)) return {input::load_path(file), cfg, {}, 0, {}};
  const input::Toolpath tp = input::read_toolpath(file, kind, gcode_options(gcode, cfg));
  for (const auto& n : tp.notes) std::fprintf(stderr, "trajcore: note: %s\n", n.c_str());
  job::ToolpathOptions to;
  to.faster_stops = !blend_all;
  job::ToolpathPlan tpp = job::toolpath_plan(tp, cfg, to);
  char b[512];
  std::snprintf(b, sizeof b,
                "Toolpath\n  moves                %zu programmed; %zu feed and %zu rapid curves after blending, %zu exact "
                "stops\n"
                "  corners              %d blended, %d of them wide (largest blend deviation %.4g mm, within %g %% of the "
                "tolerance), %zu kept as stops (%zu of them faster so)\n",
                tp.moves.size(), tpp.feed_moves, tpp.rapids, tpp.stops, tpp.corners_blended, tpp.wide_blends,
                tpp.blend_deviation, 100 * job::ToolpathOptions{}.blend_share, tpp.corner_stops, tpp.faster_stops);
  // the reader's notes (words accepted and not acted on, M0 taken as a stop) in the report as well
  std::string text = b;
  text += pauses_line(tpp.cfg.pauses.size());
  for (const auto& n : tp.notes) text += "  note                 " + n + "\n";
  double fastest = 0;
  for (const auto& m : tp.moves)
    if (m.kind == input::Move::Kind::kFeed) fastest = std::max(fastest, m.feed > 0 ? m.feed : cfg.limits.feed);
  return {std::move(tpp.path), std::move(tpp.cfg), text, fastest, std::move(tpp.rapid_curve)};
}

// Every check of the report; the output's limit check where the allowance is
// small enough to mean something, else (exact form) the samples against the
// fitted polynomials.
bool passes(const job::JobConfig& cfg, const report::Report& rep) {
  const bool output_ok = rep.exact_form ? rep.sample_to_fit <= rep.sample_bound : rep.worst_out <= 1 + 1e-9;
  const double e = cfg.machine.feed_accuracy;
  const bool feed_ok = e <= 0 || std::max(std::fabs(rep.feed_err_max), std::fabs(rep.feed_err_min)) <= e;
  return rep.max_deviation <= cfg.limits.tol && rep.worst_plan <= 1 + 1e-9 && rep.worst_fit <= 1 + 1e-9 && output_ok &&
         feed_ok;
}

int plan_streamed(const PlanArgs& a, bool jsonl) {
  std::unique_ptr<input::CurveSource> src;
  std::unique_ptr<job::ToolpathStream> toolpath;
  job::JobConfig cfg = a.cfg;
  if (a.raster > 0) {
    src = std::make_unique<input::RasterSource>(a.raster);
  } else if (jsonl) {
    src = std::make_unique<input::JsonlSource>(a.input);  // read line by line as the windows need curves
  } else if (input::is_toolpath(input::file_kind(a.input, a.format))) {
    // G-code read a line at a time as the windows need curves, blended in chunks
    job::ToolpathOptions to;
    to.gcode = gcode_options(a.gcode, a.cfg);
    to.faster_stops = !a.blend_all;
    toolpath = std::make_unique<job::ToolpathStream>(a.input, input::file_kind(a.input, a.format), a.cfg, to);
    cfg = toolpath->config();
  } else {
    if (a.input.empty()) throw PlanError("plan: give a path file or --raster N");
    src = std::make_unique<PathSource>(input::load_path(a.input), a.input);  // checks the file and the joins
  }
  job::StreamOptions so;
  so.prefetch = a.threads > 1;
  if (a.window > 0) {
    so.window = std::max<size_t>(a.window, 2);
    so.commit = so.window >= 16 ? so.window * 3 / 4 : so.window / 2;
  }
  stream::StreamWriter w(a.output, a.cfg.machine.header());
  job::StreamStats st;
  try {
    const job::SegmentSink sink = job::write_to(w);
    const job::Progress prog = [](const std::string&, double curves) {
      show_progress("stream", util::fmt("%.0f curves", curves));
    };
    st = toolpath ? job::run_streaming(*toolpath, cfg, so, sink, prog) : job::run_streaming(*src, cfg, so, sink, prog);
  } catch (...) {
    end_progress();  // the writer removes its temporary file
    throw;
  }
  w.finish();
  end_progress();
  // the summary goes to standard error when the stream goes to standard output
  std::FILE* text = a.output == "-" ? stderr : stdout;
  std::fprintf(text, "%s: %zu curves in %zu windows (%zu planned again with half their commit), %zu segments, %lld ticks "
              "(%.3f s of motion) -> %s\n"
              "host time %.3f s on %d thread%s (%.0fx real time), first segment after %.1f ms\n",
              a.raster ? "raster" : a.input.c_str(), st.curves, st.windows, st.retries, st.segments, st.ticks,
              st.motion_time,
              a.output == "-" ? "standard output" : a.output.c_str(), st.wall, a.threads, a.threads > 1 ? "s" : "",
              st.motion_time / st.wall, st.first_segment * 1e3);
  if (toolpath) {
    for (const auto& n : toolpath->notes()) std::fprintf(stderr, "trajcore: note: %s\n", n.c_str());
    const auto& t = toolpath->totals();
    std::fprintf(text, "Toolpath (streamed: blended in %zu chunks, at most %zu moves held, %zu moves cut between chunks)\n"
                "  moves                %zu programmed; %zu feed and %zu rapid curves after blending, %zu exact "
                "stops\n"
                "  corners              %d blended, %d of them wide (largest blend deviation %.4g mm, within %g %% of "
                "the tolerance), %zu kept as stops (%zu of them faster so)\n"
                "  local speed caps     %zu from tick checks and the fit\n%s",
                t.chunks, t.max_pending, t.split_moves, t.moves, t.feed_curves, t.rapid_curves, t.stops,
                t.corners_blended, t.wide_blends, t.blend_deviation, 100 * job::ToolpathOptions{}.blend_share,
                t.corner_stops, t.faster_stops, st.caps,
                pauses_line(t.pauses).c_str());
  }
  return 0;
}

int plan_whole(const PlanArgs& a) {
  if (a.input.empty()) throw PlanError("give a path file");
  const Loaded in = load(a.input, a.format, a.gcode, a.cfg, a.blend_all);
  const plan::Path& path = in.path;
  const job::JobConfig& cfg = in.cfg;
  const auto res = job::run_job(path, cfg, progress);
  // the plan report; the output columns are the host's exact prediction of
  // the core's samples (`trajcore run` confirms them on the Verilated core).
  // Made before the stream is written: a plan without the time-scaling
  // headroom asked for writes nothing.
  const auto rep = report::make_report(path, cfg, res, report::predicted_samples(res));
  stream::Header header = res.header;
  const std::string scale_text = a.scale.on() ? time_scale_text(a.scale, rep, res, header) : std::string();
  stream::write_file(a.output, header, job::records_of(res), job::pauses_of(res));
  std::FILE* text = a.output == "-" ? stderr : stdout;  // the stream may go to standard output
  std::fprintf(text, "%s: %zu segments, %zu ticks (%.3f s of motion) -> %s\n", a.input.c_str(), res.segments.size(),
              res.ticks.size(), res.plan.duration(), a.output.c_str());
  std::fputs((in.toolpath_text + report::report_text(cfg, rep, res)).c_str(), text);
  std::fprintf(text, "(output columns: the host's exact prediction of the core's samples)\n");
  std::fputs(scale_text.c_str(), text);
  const bool ok = passes(cfg, rep);
  if (!ok) std::fprintf(stderr, "trajcore plan: a check FAILED (see the report)\n");
  return ok ? 0 : 1;
}

// A folder inside the output folder that holds the files until all are
// written; removed unless kept.
struct Staging {
  std::string dir;
  bool keep = false;
  ~Staging() {
    std::error_code ec;
    if (!keep) fs::remove_all(dir, ec);
  }
};

// The folders that create() makes for `dir` (it and its missing parents);
// removed again, innermost first and only if empty, unless kept: a run that
// fails leaves no empty output folder of its own making.
struct CreatedFolders {
  std::vector<fs::path> made;  // innermost first
  bool keep = false;
  void create(const std::string& dir) {
    for (fs::path p = fs::path(dir).lexically_normal(); !p.empty() && !fs::exists(p); p = p.parent_path()) {
      made.push_back(p);
      if (p == p.parent_path()) break;
    }
    fs::create_directories(dir);
  }
  ~CreatedFolders() {
    std::error_code ec;
    if (!keep)
      for (const auto& p : made) fs::remove(p, ec);  // fails (kept) if not empty
  }
};

// The simulation's speed, for the summary lines.
std::string sim_speed(const sim::SimResult& sr) {
  const double t = std::max(sr.seconds, 1e-9);
  char b[128];
  std::snprintf(b, sizeof b, "%.2f s, %.1f M cycles/s, %.0f k ticks/s", sr.seconds, sr.cycles / t / 1e6,
                sr.sample_count / t / 1e3);
  return b;
}

std::string core_line(const sim::SimResult& sr) {
  char b[256];
  std::snprintf(b, sizeof b,
                "Core (Verilated traj_fd_engine): %llu cycles in %s, RTL == hls on every cycle: %s, "
                "underruns %llu, tick_err %s\n",
                static_cast<unsigned long long>(sr.cycles), sim_speed(sr).c_str(), sr.mismatches ? "NO" : "yes",
                static_cast<unsigned long long>(sr.underruns), sr.tick_err ? "SET" : "clear");
  return b;
}

}  // namespace

// A time-scaled board holds on the path (a starved hold) once its segments
// ahead no longer cover a stop: at a pause it would halt short of the pause's
// stop, with the plan not at rest there.
void check_pause_wait(const GcodeArgs& g, const TimeScaleArgs& t, const char* cmd) {
  if (g.pause_wait && t.on())
    throw PlanError(std::string(cmd) + ": --pause-wait with --time-scale is not supported: the board's time-scale unit "
                    "would hold short of the pause's stop (a starved hold), not at it");
}

int plan_command(const PlanArgs& a) {
  util::check_output_path(a.output);
  check_pause_wait(a.gcode, a.scale, "plan");
  const bool jsonl = !a.input.empty() && a.raster == 0 && input::file_kind(a.input, a.format) == input::FileKind::kJsonl;
  if (jsonl && a.window_given && a.window == 0)
    throw PlanError("plan: a JSON Lines path is always streamed: --window must be at least 2");
  if ((a.window > 0 || a.raster > 0 || jsonl) && a.scale.on())
    throw PlanError("plan: --time-scale needs the whole path planned at once (no --window, --raster or .jsonl)");
  if (a.window > 0 || a.raster > 0 || jsonl) return plan_streamed(a, jsonl);
  return plan_whole(a);
}

int run_command(const RunArgs& a) {
  if (a.input.empty()) throw PlanError("give a path file");
  check_pause_wait(a.gcode, a.scale, "run");
  const Loaded in = load(a.input, a.format, a.gcode, a.cfg, a.blend_all);
  const plan::Path& path = in.path;
  const job::JobConfig& cfg = in.cfg;
  const auto res = job::run_job(path, cfg, progress);
  // everything is written into a staging folder inside out_dir and moved
  // into place only when all of it is written (nothing half-written)
  const std::vector<std::string> names = {"plan.trj", "samples.csv", "report.txt", "path_feed.svg", "profile.svg"};
  CreatedFolders out_dir;
  out_dir.create(a.out_dir);
  for (const auto& n : names)
    if (fs::exists(a.out_dir + "/" + n) && !fs::is_regular_file(a.out_dir + "/" + n))
      throw PlanError(a.out_dir + "/" + n + ": exists and is not a regular file; nothing written");
  Staging stage{a.out_dir + "/.trajcore-run-" + std::to_string(::getpid())};
  fs::create_directories(stage.dir);
  const auto records = job::records_of(res);
  const auto pauses = job::pauses_of(res);
  stream::write_file(stage.dir + "/plan.trj", res.header, records, pauses);
  std::printf("%s: %zu segments, %zu ticks (%.3f s of motion)\n", a.input.c_str(), res.segments.size(),
              res.ticks.size(), res.plan.duration());
  const auto sr = sim::simulate(res.header, records, 0, [](double f) { progress("sim", f); });
  end_progress();
  write_csv(stage.dir + "/samples.csv", res.header, sr.samples,
            cfg.limits.axis_names.substr(0, static_cast<size_t>(std::max(cfg.machine.axes, path.dim()))));
  const auto rep = report::make_report(path, cfg, res, sr.samples);
  report::write_plots(stage.dir, path, cfg, res, sr.samples, in.fastest_feed_move, in.rapid_curve);
  std::string scale_text;
  if (a.scale.on()) {  // the stream again, with the time-scaling fields in its header
    stream::Header header = res.header;
    scale_text = time_scale_text(a.scale, rep, res, header);
    stream::write_file(stage.dir + "/plan.trj", header, records, pauses);
  }
  const std::string text = in.toolpath_text + report::report_text(cfg, rep, res) + core_line(sr) + scale_text;
  {
    util::AtomicFile f(stage.dir + "/report.txt");
    f.out() << text;
    f.commit();
  }
  for (const auto& n : names) fs::rename(stage.dir + "/" + n, a.out_dir + "/" + n);
  out_dir.keep = true;
  std::fputs(text.c_str(), stdout);
  std::printf("Wrote %s/{plan.trj, samples.csv, report.txt, path_feed.svg, profile.svg}\n", a.out_dir.c_str());
  const bool ok = sr.mismatches == 0 && !sr.tick_err && passes(cfg, rep);
  if (!ok) std::fprintf(stderr, "trajcore run: a check FAILED (see the report)\n");
  return ok ? 0 : 1;
}

namespace {

// A stream file's records, one at a time.
struct FileRecords {
  explicit FileRecords(const std::string& path) : in(path, std::ios::binary), reader(open(in, path), path) {}
  static std::ifstream& open(std::ifstream& in, const std::string& path) {
    if (!in) throw stream::StreamError(path + ": cannot open");
    return in;
  }
  std::ifstream in;
  stream::StreamReader reader;
};

// The allowance a stream's format leaves at most (job::Machine): 1/2 LSB of
// rounding and the register bound the compiler accepts, and the exact
// joints' offset on top in the fine formats.
job::Allowance format_allowance(const stream::Header& header) {
  const fd::Format fmt = header.format();
  const double lsb = std::ldexp(1.0, -header.frac_bits);
  return job::sample_allowance(job::Machine::sample_error_lsb(fmt) * lsb, job::Machine::joint_lsb(fmt) * lsb,
                               header.period);
}

// A binary sample file (SampleFileWriter's format) mapped read-only: the
// plots read the samples on demand, in pages the kernel can drop, so memory
// stays bounded however long the run.
class MappedSamples {
 public:
  MappedSamples(const std::string& path, int axes) : axes_(axes) {
    fd_ = ::open(path.c_str(), O_RDONLY);
    if (fd_ < 0) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || st.st_size < kHeader) throw std::runtime_error(path + ": not a sample file");
    size_ = static_cast<size_t>(st.st_size);
    base_ = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd_, 0);
    if (base_ == MAP_FAILED) throw std::runtime_error(path + ": cannot map: " + std::strerror(errno));
    count_ = (size_ - kHeader) / (8 * static_cast<size_t>(axes_));
  }
  ~MappedSamples() {
    if (base_ != MAP_FAILED) ::munmap(base_, size_);
    if (fd_ >= 0) ::close(fd_);
  }
  MappedSamples(const MappedSamples&) = delete;
  MappedSamples& operator=(const MappedSamples&) = delete;
  size_t count() const { return count_; }
  report::Sample at(size_t k) const {
    report::Sample v{};
    const auto* p = static_cast<const unsigned char*>(base_) + kHeader + k * 8 * static_cast<size_t>(axes_);
    for (int a = 0; a < axes_; ++a) {
      uint64_t u = 0;
      for (int i = 7; i >= 0; --i) u = (u << 8) | p[8 * a + i];  // little-endian, as written
      v[a] = static_cast<long long>(u);
    }
    return v;
  }

 private:
  static constexpr long kHeader = 24;
  int axes_;
  int fd_ = -1;
  void* base_ = MAP_FAILED;
  size_t size_ = 0, count_ = 0;
};

// sim --plots: path_feed.svg and profile.svg of the output alone (no plan),
// from the sample file the run wrote.
void write_stream_plots(const std::string& dir, const std::string& samples, const stream::Header& header,
                        int shown_axes, plan::Limits limits, bool feed_limited, double fastest) {
  const MappedSamples m(samples, std::min(header.axes, plan::kMaxAxes));
  report::PlotSource src;
  src.count = m.count();
  src.sample = [&m](size_t k) { return m.at(k); };
  src.axes = shown_axes;
  src.lsb = std::ldexp(1.0, -header.frac_bits);
  src.jerk_claimed = header.degree == 5;
  src.allowance = format_allowance(header);
  src.feed_limited = feed_limited;
  job::JobConfig cfg;
  cfg.machine.period = header.period;
  cfg.machine.units = header.units;
  if (!feed_limited) {
    limits.feed = 0;  // none given; the colour scale's top: the fastest step
    src.scale_feed = fastest;
  }
  cfg.limits = limits;
  report::write_plot_pages(dir, src, cfg);
}

// The axes printed and plotted: those --axes names (the engine's further
// axes carry 0 and are checked all the same), else all of the stream's.
int shown_axes(const SimArgs& a, const stream::Header& header) {
  return a.axes > 0 ? a.axes : std::min(header.axes, plan::kMaxAxes);
}

// sim --check: the samples' peaks against the limits after the format's
// allowance, printed; false if one is exceeded.
bool limits_held(report::SampleCheck& check, const stream::Header& header, const SimArgs& a) {
  plan::Limits limits = a.limits;
  const bool check_feed = a.check_feed;
  const job::Allowance al = format_allowance(header);
  const bool jerk = header.degree == 5;
  const std::string feed_limit = check_feed ? util::num(limits.feed) : "not checked: no --feed";
  if (!check_feed) limits.feed = std::numeric_limits<double>::infinity();
  const report::Worst w = report::worst_of_samples(check.peaks(), al, limits, header.axes, jerk);
  const plan::Peaks& pk = check.peaks();
  std::printf("  limits on the core's samples (%lld samples at %g s; allowance per axis v %.3g, a %.3g, j %.3g%s):\n",
              check.count(), header.period, al.v, al.a, al.j, jerk ? "" : "; cubic segments: no jerk claim");
  for (int ax = 0; ax < shown_axes(a, header); ++ax)
    std::printf("    %-2s v %-10.5g a %-10.5g j %-10.5g (limits %g, %g, %g)\n", limits.axis(ax).c_str(),
                pk.v_axis[ax], pk.a_axis[ax], pk.j_axis[ax], limits.v_axis[ax], limits.a_axis[ax], limits.j_axis[ax]);
  std::printf("    feed %.5g (%s), a_tan %.5g (%g), a_cen %.5g (%g), j_tan %.5g (%g), j_cen %.5g (%g)\n", pk.feed,
              feed_limit.c_str(), pk.a_tan, limits.a_tan, pk.a_cen, limits.a_cen, pk.j_tan, limits.j_tan, pk.j_cen,
              limits.j_cen);
  const bool held = w.ratio <= 1.0;
  std::printf("  worst peak/limit after the allowance: %.4f%s%s -> %s\n", w.ratio, w.what.empty() ? "" : " ",
              w.what.c_str(), held ? "every limit held" : "EXCEEDED");
  return held;
}

// After a run: --check's verdict (true without --check) and --plots (from the
// committed sample file; none when the run failed).
bool measured(report::SampleCheck* check, bool run_ok, const stream::Header& header, const SimArgs& a,
              const std::string& sample_file) {
  if (!check) return true;
  check->finish();
  const bool held = !a.check || limits_held(*check, header, a);
  if (run_ok && !a.plots.empty()) {
    write_stream_plots(a.plots, sample_file, header, shown_axes(a, header), a.limits, a.check_feed,
                       check->peaks().feed);
    std::printf("  plots: %s/{path_feed.svg, profile.svg} (samples: %s)\n", a.plots.c_str(), sample_file.c_str());
  }
  return held;
}
}  // namespace

int sim_command(const SimArgs& a) {
  if (!a.csv.empty()) util::check_output_path(a.csv);
  // A first pass checks the whole stream, keeping nothing, so that a bad
  // stream simulates nothing; the second feeds the core record by record
  // (memory bounded however long the stream).
  uint64_t records = 0;
  stream::Header header;
  {
    FileRecords f(a.input);
    stream::Record rec;
    while (f.reader.next(rec)) ++records;
    if (!f.reader.complete()) {
      std::fprintf(stderr, "trajcore: error: %s (%llu segments before it were valid; nothing simulated)\n",
                   f.reader.error().c_str(), static_cast<unsigned long long>(records));
      return 1;
    }
    header = f.reader.header();
  }
  std::unique_ptr<CsvWriter> csv;
  if (!a.csv.empty()) csv = std::make_unique<CsvWriter>(a.csv, header);
  // --plots: the samples to a file (the user's --samples, else <plots>/samples.bin) mapped afterwards
  std::string sample_file = a.samples;
  if (!a.plots.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(a.plots, ec);
    if (ec) throw std::runtime_error("cannot create " + a.plots + ": " + ec.message());
    if (sample_file.empty()) sample_file = a.plots + "/samples.bin";
  }
  std::unique_ptr<SampleFileWriter> bin;
  if (!sample_file.empty()) bin = std::make_unique<SampleFileWriter>(sample_file, header);
  std::unique_ptr<report::SampleCheck> check;
  if (a.check || !a.plots.empty()) {
    // a path of fewer axes than the engine's leaves the rest at 0 (checked all the same)
    if (a.axes > header.axes)
      throw plan::PlanError("--axes names " + std::to_string(a.axes) + " axes; the stream " + a.input + " has " +
                            std::to_string(header.axes));
    check = std::make_unique<report::SampleCheck>(header.axes, std::ldexp(1.0, -header.frac_bits), header.period);
  }
  const sim::SampleSink sink = [&](uint64_t k, const report::Sample& v) {
    if (csv) csv->row(k, v);
    if (bin) bin->row(v);
    if (check) check->add(v);
  };
  const auto commit = [&] {
    if (csv) csv->commit();
    if (bin) bin->commit();
  };
  const auto prog = [](double f) { progress("sim", f); };
  std::string to = csv ? a.csv : std::string();
  if (bin) to += (to.empty() ? "" : ", ") + sample_file;
  if (to.empty()) to = "(no samples written: --csv FILE or --samples FILE writes them)";
  if (header.has_bcu()) {
    // a BCU format: both engines, every sample also against the exact
    // prediction from the records (held in memory: BCU streams are short)
    const auto rd = stream::read_file(a.input);
    const auto sr = sim::simulate(rd.header, rd.records, a.tick_gap, prog, sink);
    end_progress();
    const bool ok = sr.mismatches == 0 && sr.prediction_mismatches == 0 && !sr.tick_err && sr.underruns == 0;
    if (ok) commit();
    std::printf("%s: %zu segments (%llu FD, %llu BCU, %llu kind switches), %llu samples, %llu cycles on traj_core "
                "(tick every %d) in %s, RTL == hls: %s, == host prediction: %s, tick_err %s, underruns %llu -> %s\n",
                a.input.c_str(), rd.records.size(), static_cast<unsigned long long>(sr.fd_segments),
                static_cast<unsigned long long>(sr.bcu_segments), static_cast<unsigned long long>(sr.switches),
                static_cast<unsigned long long>(sr.sample_count), static_cast<unsigned long long>(sr.cycles),
                sr.tick_gap, sim_speed(sr).c_str(), sr.mismatches ? "NO" : "yes",
                sr.prediction_mismatches ? "NO" : "yes", sr.tick_err ? "SET" : "clear",
                static_cast<unsigned long long>(sr.underruns), ok ? to.c_str() : "(no samples written)");
    const bool held = measured(check.get(), ok, header, a, sample_file);
    if (!ok || !held) std::fprintf(stderr, "trajcore sim: a check FAILED (see above)\n");
    return ok && held ? 0 : 1;
  }
  FileRecords f(a.input);
  const sim::RecordPull pull = [&](stream::Record& r) { return f.reader.next(r); };
  const auto sr = sim::simulate_pulled(header, pull, records, a.tick_gap, prog, sink);
  end_progress();
  if (!f.reader.complete())  // the file changed between the passes
    throw stream::StreamError(f.reader.error().empty() ? a.input + ": changed while simulated" : f.reader.error());
  const bool ok = sr.mismatches == 0 && !sr.tick_err;
  if (ok) commit();
  const std::string pace =
      sr.tick_gap ? "tick every " + std::to_string(sr.tick_gap) : std::string("a tick after each sample");
  std::printf("%s: %llu segments, %llu samples, %llu cycles (%s) in %s, RTL == hls: %s, tick_err %s, "
              "underruns %llu -> %s\n",
              a.input.c_str(), static_cast<unsigned long long>(records),
              static_cast<unsigned long long>(sr.sample_count), static_cast<unsigned long long>(sr.cycles), pace.c_str(),
              sim_speed(sr).c_str(), sr.mismatches ? "NO" : "yes", sr.tick_err ? "SET" : "clear",
              static_cast<unsigned long long>(sr.underruns), ok ? to.c_str() : "(no samples written)");
  if (header.has_time_scaling())
    std::printf("  time scaling (header): s <= %g, |ds/dt| <= %g /s, |d2s/dt2| <= %g /s^2\n", header.scale_max,
                static_cast<double>(header.scale_rate), static_cast<double>(header.scale_accel));
  const bool held = measured(check.get(), ok, header, a, sample_file);
  if (!ok || !held) std::fprintf(stderr, "trajcore sim: a check FAILED (see above)\n");
  return ok && held ? 0 : 1;
}

}  // namespace traj::app
