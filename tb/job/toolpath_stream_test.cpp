// A CAM-like G-code program (tb/bench/cam_program.hpp, 2 000 lines: a
// zig-zag surface finish of 0.5 mm G1 segments with G2/G3 u-turns) planned
// whole (as `trajcore run` does) and streamed in small windows and small
// blending chunks (`plan --window`). Against independent references:
//   * the programmed path, from the program's text parsed here (lines and XY
//     semicircles, not the library's reader): every output sample of both
//     plans within the tolerance of it, every programmed vertex within the
//     tolerance of both outputs, and the two outputs' nearest points to each
//     vertex within the tolerance of each other;
//   * the limits, from the samples' differences (tb/planner/output_check.hpp),
//     on the streamed output run through the hls engine model and on the
//     whole plan's exact prediction of the core's samples.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "cam_program.hpp"
#include "fd_drive.hpp"
#include "input/gcode.hpp"
#include "input/toolpath_file.hpp"
#include "job/job.hpp"
#include "job/streaming.hpp"
#include "job/toolpath_job.hpp"
#include "job/toolpath_stream.hpp"
#include "limit_sets.hpp"
#include "tmp_file.hpp"
#include "output_check.hpp"
#include "report/report.hpp"
#include "stream/segment_stream.hpp"
#include "traj_fd_engine.hpp"

using namespace traj;
using P3 = std::array<double, 3>;

namespace {

// One programmed move: a segment a -> b, or an XY arc about c of radius r
// (z constant) from a to b.
struct Prim {
  bool arc = false;
  P3 a{}, b{}, c{};
  double r = 0;
};

double dist(const P3& p, const P3& q) { return std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]); }

double dist_to(const Prim& m, const P3& p) {
  if (!m.arc) {
    P3 d{m.b[0] - m.a[0], m.b[1] - m.a[1], m.b[2] - m.a[2]};
    const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double t = dd > 0 ? ((p[0] - m.a[0]) * d[0] + (p[1] - m.a[1]) * d[1] + (p[2] - m.a[2]) * d[2]) / dd : 0;
    t = std::clamp(t, 0.0, 1.0);
    return dist(p, {m.a[0] + t * d[0], m.a[1] + t * d[1], m.a[2] + t * d[2]});
  }
  // a semicircle (a and b opposite on it): the u-turn bulges to +x at the
  // pass end x = 100, to -x at x = 0
  const double ex = p[0] - m.c[0], ey = p[1] - m.c[1];
  const double out = (m.a[0] > 50 ? 1.0 : -1.0);
  if (ex * out >= 0) {
    const double rho = std::hypot(ex, ey);
    return std::hypot(rho - m.r, p[2] - m.c[2]);
  }
  return std::min(dist(p, m.a), dist(p, m.b));
}

// The program's moves from its text: G0/G1 with any of X Y Z, and G2/G3 X Y
// I J (the generator's forms), from the start X0 Y0 Z0.
std::vector<Prim> parse(const std::string& text) {
  std::vector<Prim> out;
  std::istringstream in(text);
  std::string line;
  P3 pos{0, 0, 0};
  while (std::getline(in, line)) {
    std::istringstream w(line);
    std::string g, word;
    w >> g;
    if (g != "G0" && g != "G1" && g != "G2" && g != "G3") continue;
    P3 q = pos;
    double i = 0, j = 0;
    while (w >> word) {
      const double v = std::stod(word.substr(1));
      switch (word[0]) {
        case 'X': q[0] = v; break;
        case 'Y': q[1] = v; break;
        case 'Z': q[2] = v; break;
        case 'I': i = v; break;
        case 'J': j = v; break;
        default: break;
      }
    }
    if (g == "G2" || g == "G3")
      out.push_back({true, pos, q, {pos[0] + i, pos[1] + j, pos[2]}, std::hypot(i, j)});
    else
      out.push_back({false, pos, q, {}, 0});
    pos = q;
  }
  return out;
}

// Largest distance of the samples from the programmed feed moves (a cursor
// follows the samples along the program), and of the vertices from the
// samples' polyline, with each vertex's nearest point on it.
struct Compare {
  double sample_dev = 0, vertex_dev = 0;
  std::vector<P3> nearest;  // per vertex (end of each programmed move)
};

P3 nearest_on_polyline(const std::vector<P3>& x, size_t lo, size_t hi, const P3& v) {
  P3 best = x[lo];
  double bd = 1e300;
  for (size_t k = lo; k + 1 <= hi && k + 1 < x.size(); ++k) {
    const P3& a = x[k];
    const P3& b = x[k + 1];
    P3 d{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double t = dd > 0 ? ((v[0] - a[0]) * d[0] + (v[1] - a[1]) * d[1] + (v[2] - a[2]) * d[2]) / dd : 0;
    t = std::clamp(t, 0.0, 1.0);
    const P3 q{a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]};
    if (dist(q, v) < bd) bd = dist(q, v), best = q;
  }
  return best;
}

Compare compare(const std::vector<Prim>& prog, const std::vector<P3>& x) {
  Compare c;
  // samples: a cursor on the program follows them forward
  size_t m = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    double best = 1e300;
    size_t bm = m;
    for (size_t j = m > 2 ? m - 2 : 0; j < std::min(prog.size(), m + 6); ++j) {
      const double d = dist_to(prog[j], x[k]);
      if (d < best) best = d, bm = j;
    }
    m = bm;
    c.sample_dev = std::max(c.sample_dev, best);
  }
  // vertices: their nearest output point, searched in a window of samples
  // that moves forward with them
  size_t lo = 0;
  for (const Prim& p : prog) {
    const P3 v = p.b;
    size_t kbest = lo;
    double bd = 1e300;
    for (size_t k = lo; k < x.size() && k < lo + 400; ++k)
      if (dist(x[k], v) < bd) bd = dist(x[k], v), kbest = k;
    const size_t a = kbest > 2 ? kbest - 2 : 0;
    const P3 q = nearest_on_polyline(x, a, kbest + 2, v);
    c.nearest.push_back(q);
    c.vertex_dev = std::max(c.vertex_dev, dist(q, v));
    lo = a;
  }
  return c;
}

// The samples (mm) of a compiled stream through the hls engine model (the board's format).
std::vector<P3> hls_samples(const std::vector<fd::Compiled>& comp) {
  using Eng = FdEngine<3, 5, 96, 16, 48>;
  fd::Compiler compiler(job::Machine{}.format());
  Eng e;
  std::vector<P3> xs;
  const double lsb = std::ldexp(1.0, -32);
  test::run_segments(e, compiler, comp, Eng::kWords + Eng::kChunks + 2, [&](size_t, uint64_t, const Eng::Out& o) {
    P3 v{};
    for (int a = 0; a < 3; ++a) v[a] = static_cast<double>(sext(o.sample[a], Eng::kOutWidth)) * lsb;
    xs.push_back(v);
  });
  return xs;
}

// A G-code file streamed (blending chunk, window, commit) and its samples
// through the hls engine, with the limits they show (the stream's limits; the
// largest stated sample error of its segments as the allowance).
struct Streamed {
  job::StreamStats st;
  job::ToolpathStream::Totals totals;
  std::vector<P3> xs;
  test::OutputVerdict limits;
};
Streamed stream_through_hls(const std::string& file, const job::JobConfig& cfg, size_t chunk, size_t window,
                            size_t commit, size_t window_ticks = job::StreamOptions{}.window_ticks) {
  job::ToolpathStream src(file, input::FileKind::kGcode, cfg, {}, chunk);
  job::StreamOptions so;
  so.window = window;
  so.commit = commit;
  so.window_ticks = window_ticks;
  std::vector<fd::Compiled> comp;
  Streamed r;
  r.st = job::run_streaming(src, src.config(), so,
                            [&](const fd::Compiled& c, const plan::TimeSegment&) { comp.push_back(c); });
  r.totals = src.totals();
  r.xs = hls_samples(comp);
  const double lsb = std::ldexp(1.0, -32);
  double q = 0;
  for (const auto& c : comp) q = std::max(q, (0.5 + c.bound_lsb) * lsb);
  r.limits = test::check_output_limits(r.xs, 3, src.config().limits, cfg.machine.period, q, true);
  return r;
}

std::vector<P3> to_mm(const report::Samples& s) {
  const double lsb = std::ldexp(1.0, -32);
  std::vector<P3> x;
  for (const auto& v : s.v) x.push_back({v[0] * lsb, v[1] * lsb, v[2] * lsb});
  return x;
}

}  // namespace

TEST(ToolpathStream, CamProgramStreamedAgreesWithWholePath) {
  const auto dir = std::filesystem::temp_directory_path() / ("toolpath_stream_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "cam.ngc").string();
  std::string text;
  {
    std::ostringstream o;
    bench::write_cam_program(o, 2000);
    text = o.str();
    std::ofstream(file) << text;
  }
  const std::vector<Prim> prog = parse(text);
  ASSERT_GT(prog.size(), 1900u);
  const job::JobConfig cfg;  // tolerance 0.001 mm; the program's G64 P0.05 for the blends
  // blends within blend_share of P, the fit within the rest of --tol
  const double share = job::ToolpathOptions{}.blend_share;
  const double tol = 0.05 * share + cfg.limits.tol * (1 - share);

  // whole path, as `trajcore run` plans it; its exact prediction of the core's samples
  const input::Toolpath tp = input::read_gcode(file);
  const job::ToolpathPlan tpp = job::toolpath_plan(tp, cfg);
  const job::JobResult wr = job::run_job(tpp.path, tpp.cfg);
  const std::vector<P3> xw = to_mm(report::predicted_samples(wr));

  // streamed: small windows and small blending chunks, so that the test
  // crosses many commits and chunk cuts
  const Streamed sm = stream_through_hls(file, cfg, 64, 16, 12);
  const job::StreamStats& st = sm.st;
  const std::vector<P3>& xs = sm.xs;
  EXPECT_GT(st.windows, 30u);  // runs of short segments are single curves: fewer curves than moves
  EXPECT_GT(sm.totals.chunks, 10u);
  EXPECT_LE(sm.totals.max_pending, 2 * 64u);
  EXPECT_EQ(sm.totals.stops, tpp.stops);  // the report's count, the path's end left out by both
  const double lsb = std::ldexp(1.0, -32);
  EXPECT_EQ(static_cast<long long>(xs.size()), st.ticks);

  // limits at the samples (q: the largest stated sample error of the segments)
  const auto& vs = sm.limits;
  EXPECT_LE(vs.worst, 1 + 1e-9) << "streamed: " << vs.what << " at tick " << vs.tick;
  double qw = 0;
  for (const auto& c : wr.compiled) qw = std::max(qw, (0.5 + c.bound_lsb) * lsb);
  const auto vw = test::check_output_limits(xw, 3, tpp.cfg.limits, cfg.machine.period, qw, true);
  EXPECT_LE(vw.worst, 1 + 1e-9) << "whole: " << vw.what << " at tick " << vw.tick;

  // against the programmed path
  const Compare cs = compare(prog, xs), cw = compare(prog, xw);
  EXPECT_LE(cs.sample_dev, tol);
  EXPECT_LE(cw.sample_dev, tol);
  EXPECT_LE(cs.vertex_dev, tol);
  EXPECT_LE(cw.vertex_dev, tol);
  double agree = 0;
  for (size_t i = 0; i < cs.nearest.size(); ++i) agree = std::max(agree, dist(cs.nearest[i], cw.nearest[i]));
  EXPECT_LE(agree, tol);
  // both start and end where the program does
  EXPECT_LE(dist(xs.back(), xw.back()), 1e-9);
  EXPECT_LE(dist(xs.front(), xw.front()), 1e-9);
  // about the same motion time (each plan is greedy; a window sees less)
  EXPECT_NEAR(st.motion_time / wr.plan.duration(), 1.0, 0.05);
  std::printf("  whole %.3f s, streamed %.3f s (%zu windows, %zu planned again, %zu chunks); deviation from the "
              "program: samples %.4g / %.4g mm, vertices %.4g / %.4g mm (streamed / whole), nearest points agree "
              "within %.4g mm; worst limit ratio %.4f / %.4f\n",
              wr.plan.duration(), st.motion_time, st.windows, st.retries, sm.totals.chunks, cs.sample_dev,
              cw.sample_dev, cs.vertex_dev, cw.vertex_dev, agree, vs.worst, vw.worst);
  std::filesystem::remove_all(dir);
}

namespace {

// A square spiral pocket (legs 24 mm down to 4 mm, 90 degree corners) at feed `feed`, limits of a
// fast machine (bench_toolpaths' set (i)).
input::Toolpath spiral_pocket(double feed) {
  input::Toolpath tp;
  tp.axes = 2;
  double x = 0, y = 0, len = 24;
  const double dx[4] = {1, 0, -1, 0}, dy[4] = {0, 1, 0, -1};
  for (int k = 0; len >= 4; ++k) {
    Eigen::VectorXd a(2), b(2);
    a << x, y;
    x += len * dx[k % 4];
    y += len * dy[k % 4];
    b << x, y;
    input::Move m;
    m.curve = geo::make_line(a, b);
    m.feed = feed;
    m.where = "pocket: G1 " + std::to_string(k + 1);
    tp.moves.push_back(m);
    if (k % 2 == 1) len -= 4;
  }
  return tp;
}

job::JobConfig fast_machine() {
  job::JobConfig c;
  auto& L = c.limits;
  for (int a = 0; a < plan::kMaxAxes; ++a) L.v_axis[a] = 100, L.a_axis[a] = 3000, L.j_axis[a] = 60000;
  L.a_tan = L.a_cen = 3000;
  L.j_tan = L.j_cen = 60000;
  L.feed = 100;
  L.tol = 0.05;
  c.machine.period = 0.5e-3;
  return c;
}

double planned_time(const input::Toolpath& tp, const job::JobConfig& cfg, bool faster_stops, size_t& stops) {
  job::ToolpathOptions o;
  o.faster_stops = faster_stops;
  const job::ToolpathPlan r = job::toolpath_plan(tp, cfg, o);
  stops = r.faster_stops;
  return plan::plan_path(r.path, r.cfg.limits, r.cfg.plan_options()).duration();
}

}  // namespace

// At 100 mm/s a 90 degree corner's blend is passed at a few mm/s over its whole length, and stopping
// at the corner is faster: the corners are left stops, and the whole pocket, planned whole, takes less
// time than with every corner blended. At 2 mm/s the blends pass at the feed: all stay blended.
TEST(ToolpathPlan, SharpCornersStopWhereThatIsFaster) {
  const job::JobConfig cfg = fast_machine();
  size_t stops_on = 0, stops_off = 0;
  const input::Toolpath fast = spiral_pocket(100);
  const double t_on = planned_time(fast, cfg, true, stops_on);
  const double t_off = planned_time(fast, cfg, false, stops_off);
  EXPECT_EQ(stops_on, fast.moves.size() - 1);
  EXPECT_EQ(stops_off, 0u);
  EXPECT_LT(t_on, 0.9 * t_off) << t_on << " s with the stops, " << t_off << " s blended";
  // the moves' feed decides, also above the job's own feed (the program's F runs as programmed)
  job::JobConfig slow_job = cfg;
  slow_job.limits.feed = 2;
  EXPECT_LT(planned_time(fast, slow_job, true, stops_on), 0.9 * planned_time(fast, slow_job, false, stops_off));
  EXPECT_EQ(stops_on, fast.moves.size() - 1);
  const input::Toolpath slow = spiral_pocket(2);
  const double s_on = planned_time(slow, cfg, true, stops_on);
  const double s_off = planned_time(slow, cfg, false, stops_off);
  EXPECT_EQ(stops_on, 0u);
  EXPECT_EQ(s_on, s_off);
}

// The local decision (stop_is_faster plans the corner on legs no longer than two speed-ups to the
// feed past its blend) against the whole path: one corner between two legs of 60 mm, at turns from
// 20 to 170 degrees, at feeds of 10 to 100 mm/s on a fast machine and of 10 to 50 mm/s at the main
// job's limits with a tolerance of 0.25 mm (as LinuxCNC's craftsmancnc.ngc, where legs of one
// speed-up past the blend turned a 146 degree corner at 23.3 mm/s). The corner is left a stop exactly
// where the two moves planned whole, stopped at the corner (G61 there), take less time than with the
// corner blended; where the two differ by less than two ticks either is right. The whole path is
// planned as the decision assumes the path goes on (a corner inside a program: its blend is not
// re-timed as one curved move from rest to rest, align_curved_moves off; with it, a lone 170 degree
// corner at 100 mm/s would be faster blended, 1.284 s against 1.371 s).
TEST(ToolpathPlan, CornerStopsWhereTheWholePathIsFasterSo) {
  auto whole_time = [](const input::Toolpath& tp, const job::JobConfig& cfg) {
    job::ToolpathOptions o;
    o.faster_stops = false;
    const job::ToolpathPlan r = job::toolpath_plan(tp, cfg, o);
    plan::PlanOptions po = r.cfg.plan_options();
    po.align_curved_moves = false;
    return plan::plan_path(r.path, r.cfg.limits, po).duration();
  };
  job::JobConfig main_job;
  main_job.limits.tol = 0.25;
  const std::pair<job::JobConfig, std::vector<double>> sets[] = {{fast_machine(), {10, 30, 100}},
                                                                  {main_job, {10, 23.3, 50}}};
  int stops = 0, blends = 0;
  for (const auto& [cfg, feeds] : sets)
  for (double feed : feeds) {
    for (double deg : {20.0, 45.0, 70.0, 90.0, 110.0, 135.0, 146.0, 150.0, 170.0}) {
      const double th = deg * M_PI / 180;
      Eigen::VectorXd a(2), v(2), b(2);
      a << -60, 0;
      v << 0, 0;
      b << 60 * std::cos(th), 60 * std::sin(th);
      input::Toolpath tp;
      tp.axes = 2;
      for (const auto& [p, q] : {std::pair{a, v}, std::pair{v, b}}) {
        input::Move m;
        m.curve = geo::make_line(p, q);
        m.feed = feed;
        m.where = "corner";
        tp.moves.push_back(m);
      }
      size_t decided = 0;
      planned_time(tp, cfg, true, decided);
      const double t_blend = whole_time(tp, cfg);
      tp.moves[0].exact_stop = true;
      const double t_stop = whole_time(tp, cfg);
      const std::string at = std::to_string(deg) + " deg at " + std::to_string(feed) + " mm/s: stopped " +
                             std::to_string(t_stop) + " s, blended " + std::to_string(t_blend) + " s";
      if (std::abs(t_stop - t_blend) >= 2 * cfg.machine.period) {
        EXPECT_EQ(decided == 1, t_stop < t_blend) << at;
      }
      (decided == 1 ? stops : blends) += 1;
    }
  }
  // both decisions occur (else the cases test one side only)
  EXPECT_GT(stops, 3);
  EXPECT_GT(blends, 3);
}

// simple-icons' apachecassandra.svg (and audiomack.svg): a cubic whose end
// handle is retracted (P2 = P3, an SVG cusp) after a corner the blend cuts
// the curve at. The knot insertion of that cut once moved P2 by an ulp,
// leaving the curve an end speed of about 1e-16: the speed bound there made
// the plan cruise its last 1e-15 mm at 1e-28 mm/s, 4.3e13 s in all ("more
// than one plan holds"). The cut keeps P2 = P3 exactly; the path (a rapid
// from the origin, 1.4 mm of cut) plans in well under a second.
TEST(ToolpathPlan, RetractedHandleSplitByABlendStaysRetracted) {
  const std::string file = (std::filesystem::temp_directory_path() / "traj_retracted_handle.svg").string();
  {
    std::ofstream f(file);
    f << "<svg viewBox=\"0 0 24 24\" xmlns=\"http://www.w3.org/2000/svg\"><path d=\""
         "M18.497 14.348c0 0-1.06-1.16-1.35-.959c-.29.202 1.514 3.218 1.514 3.218\"/></svg>";
  }
  const input::Toolpath tp = input::read_toolpath(file, input::FileKind::kSvg);
  std::filesystem::remove(file);
  const job::JobConfig cfg;
  const job::ToolpathPlan r = job::toolpath_plan(tp, cfg);
  const geo::BSpline& last = r.path.curve(r.path.size() - 1).spline();
  const int n = last.n_ctrl();
  EXPECT_EQ(last.ctrl.row(n - 1), last.ctrl.row(n - 2)) << "the retracted handle moved";
  const double T = plan::plan_path(r.path, r.cfg.limits, r.cfg.plan_options()).duration();
  EXPECT_LT(T, 1.0);
}

// Two simple-icons logos (tb/job/assets/simple-icons, CC0) that planned as
// 1.4e15 s and 1.3e15 s (ulp-sized blocks at cusps cruising at 1e-29 mm/s):
// each plans within ten times the time of its path at the feed (the motion
// stops at its many cusps; about 7 and 6 s now).
TEST(ToolpathPlan, SimpleIconsLogosPlan) {
  for (const char* name : {"gitea.svg", "audiomack.svg"}) {
    const std::string file = std::string(TRAJ_JOB_ASSETS) + "/simple-icons/" + name;
    const input::Toolpath tp = input::read_toolpath(file, input::FileKind::kSvg);
    const job::JobConfig cfg;
    const job::ToolpathPlan r = job::toolpath_plan(tp, cfg);
    const double T = plan::plan_path(r.path, r.cfg.limits, r.cfg.plan_options()).duration();
    EXPECT_LT(T, 10 * r.path.length() / cfg.limits.feed) << name;
    EXPECT_GT(T, r.path.length() / cfg.limits.feed) << name;
  }
}

// Four simple-icons logos (tb/job/assets/simple-icons, CC0) that failed after
// 200 rounds of repairs ("the limits cannot be met"): handles retracted to
// within rounding of their end points (ferrari, endeavouros), a cusp 8.6 nm
// inside a cubic (furrynetwork), a turn of 179.8 degrees (pubg). Each now
// plans and fits, and every limit holds on the hls engine's samples
// (output_check.hpp, apart from the planner).
TEST(ToolpathPlan, SimpleIconsCuspsAndReversalsPlan) {
  for (const char* name : {"ferrari.svg", "endeavouros.svg", "furrynetwork.svg", "pubg.svg"}) {
    SCOPED_TRACE(name);
    const std::string file = std::string(TRAJ_JOB_ASSETS) + "/simple-icons/" + name;
    const input::Toolpath tp = input::read_toolpath(file, input::FileKind::kSvg);
    const job::JobConfig cfg;
    const job::ToolpathPlan r = job::toolpath_plan(tp, cfg);
    const job::JobResult jr = job::run_job(r.path, r.cfg);
    ASSERT_EQ(jr.header.frac_bits, 32) << "to_mm's scale";
    double q = 0;
    const double lsb = std::ldexp(1.0, -32);
    for (const auto& c : jr.compiled) q = std::max(q, (0.5 + c.bound_lsb) * lsb);
    const auto v = test::check_output_limits(to_mm(report::predicted_samples(jr)), r.path.dim(), r.cfg.limits,
                                             cfg.machine.period, q, true);
    std::printf("  %s: %zu curves, %.2f s of motion, %d rounds, %d caps, worst %.4f (%s)\n", name, r.path.size(),
                jr.plan.duration(), jr.rounds, jr.repairs, v.worst, v.what.c_str());
    EXPECT_LE(v.worst, 1 + 1e-9) << v.what << " at tick " << v.tick;
  }
}

// Ferris's shell (tb/job/assets/ferris, from the Rust book's panics.svg) at bench_toolpaths' set
// (i), 0.5 ms ticks. The plan is checked, and repaired, at its fit ticks (1 ms apart here); between
// them its centripetal jerk bound reads up to 1.06 of the limit at the engine's ticks. The report
// held the plan to the engine's ticks, and `trajcore plan` exited 1 while the core's samples kept
// every limit. The report (and the profile plot) now give the plan's peaks at the ticks it is
// checked on. The guarantee is the samples': checked here apart from the planner, at every engine tick.
TEST(ToolpathPlan, PlanHeldAtItsFitTicksWhereTheEngineTickIsFiner) {
  const job::JobConfig cfg = bench::fast_machine();
  ASSERT_EQ(cfg.machine.fit_ticks(), 2);
  const std::string file = std::string(TRAJ_JOB_ASSETS) + "/ferris/panics-shell.svg";
  const job::ToolpathPlan tpp = job::toolpath_plan(input::read_toolpath(file, input::FileKind::kSvg), cfg);
  const job::JobResult r = job::run_job(tpp.path, tpp.cfg);
  const int d = tpp.path.dim();
  const plan::Limits& L = tpp.cfg.limits;
  std::string what;
  const double at_engine = plan::worst_ratio(plan::peaks_of(r.ticks, d), L, d, &what);
  const double at_fit =
      plan::worst_ratio(plan::peaks_of(plan::sample_ticks(tpp.path, r.plan, tpp.cfg.machine.fit_period()), d), L, d);
  const report::Samples s = report::predicted_samples(r);
  const report::Report rep = report::make_report(tpp.path, tpp.cfg, r, s);
  ASSERT_EQ(r.header.frac_bits, 32) << "to_mm's scale";
  double q = 0;
  for (const auto& c : r.compiled) q = std::max(q, (0.5 + c.bound_lsb) * std::ldexp(1.0, -32));
  const auto out = test::check_output_limits(to_mm(s), d, L, tpp.cfg.machine.period, q, true);
  std::printf("  Ferris's shell at set (i): plan peak/limit %.4f at the engine ticks (%s), %.4f at the fit ticks, "
              "report %.4f; output %.4f (%s)\n", at_engine, what.c_str(), at_fit, rep.worst_plan, out.worst,
              out.what.c_str());
  EXPECT_GT(at_engine, 1) << "the case this test is for: the plan above a bound between its fit ticks";
  EXPECT_LE(at_fit, 1 + 1e-9);
  EXPECT_DOUBLE_EQ(rep.worst_plan, at_fit);
  EXPECT_LE(out.worst, 1 + 1e-9) << out.what << " at tick " << out.tick;
  EXPECT_LE(rep.max_deviation, L.tol);
  // the profile plot draws the plan at the same ticks: no peak flagged above its limit
  const auto dir = std::filesystem::temp_directory_path() / ("ferris_plots_" + std::to_string(::getpid()));
  report::write_plots(dir.string(), tpp.path, tpp.cfg, r, s);
  std::ifstream in(dir / "profile.svg");
  const std::string prof((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(prof.find("plan: the planner at the fit ticks"), std::string::npos);
  EXPECT_EQ(prof.find("ABOVE THE LIMIT"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// An eye of the same drawing (panics-eye.svg) at set (i): a curved move between two stops
// (its cusps) that no one speed re-times within the limits. The bisection for that speed went on
// down to 1/1024 of the feed, checking ever slower and longer moves whole: 6.2e8 frames, 77 s of
// planning for 4.1 s of motion. Now a one-speed candidate more than 4 times slower than the move
// as planned is not checked, and the level move's are no slower than the one-speed move found.
// The re-timing tries at most 495 candidates per move (curved_move: 18 shares x 11, then 2 x 18;
// level_move: 10 tops x 24 rounds; curved_block: 3 x 7 per block, each no slower than its block),
// each evaluating 2 frames per tick and one more per piece: its frames stay within 4000 per tick
// of the plan before re-timing (with no repair cap: the same plan as re-timing off).
TEST(ToolpathPlan, RetimingChecksNoMoveFarSlowerThanPlanned) {
  const job::JobConfig cfg = bench::fast_machine();
  const std::string file = std::string(TRAJ_JOB_ASSETS) + "/ferris/panics-eye.svg";
  const job::ToolpathPlan tpp = job::toolpath_plan(input::read_toolpath(file, input::FileKind::kSvg), cfg);
  job::JobConfig off = tpp.cfg;
  off.plan.align_straight_moves = false;
  const job::JobResult r = job::run_job(tpp.path, tpp.cfg);
  const job::JobResult before = job::run_job(tpp.path, off);
  ASSERT_EQ(r.repairs, 0);
  ASSERT_EQ(before.repairs, 0);
  const double ticks = before.plan.duration() / tpp.cfg.machine.fit_period();
  std::printf("  Ferris's eye at set (i): %.4f s of motion (%.4f s before re-timing), %lld frames checked, %.3g per "
              "tick of the plan before re-timing\n", r.plan.duration(), before.plan.duration(), r.plan.check_frames,
              static_cast<double>(r.plan.check_frames) / ticks);
  EXPECT_GT(r.plan.check_frames, 0) << "the case this test is for: moves re-timed on the tick grid";
  EXPECT_LE(static_cast<double>(r.plan.check_frames), 4000 * ticks);
  EXPECT_LE(r.plan.duration(), before.plan.duration());
}

// The repair rounds of plan_and_fit plan the same path again with more caps,
// and take a curved move's re-timing search from an earlier plan where every
// comparison that search made against the move's planned time (max_T) comes
// out the same (plan::RetimeMemo). Here the same path is planned at sixteen
// tick offsets, a sixteenth of a tick apart (which move the rests that put
// moves on ticks), each with the searches of the plans before: every plan
// must equal, piece for piece, the plan made without them. (The moves here
// start where the move before ended, on a tick, so their max_T stays the
// same and every search is taken; pubg.svg at set (i) makes 6 searches again
// in its repair rounds.)
TEST(ToolpathPlan, RetimingTakenFromAnEarlierPlanIsTheOneASearchGives) {
  const job::JobConfig cfg = bench::fast_machine();
  for (const char* name : {"ferris/panics-eye.svg", "simple-icons/gitea.svg"}) {
    const std::string file = std::string(TRAJ_JOB_ASSETS) + "/" + name;
    const job::ToolpathPlan tpp = job::toolpath_plan(input::read_toolpath(file, input::FileKind::kSvg), cfg);
    plan::PlanOptions o = tpp.cfg.plan_options();
    plan::RetimeMemo memo;
    long long first = 0, differ = 0;
    for (int k = 0; k < 16; ++k) {
      o.tick_offset = o.period * k / 16;
      const plan::Plan with = plan::plan_path(tpp.path, tpp.cfg.limits, o, &memo);
      const plan::Plan fresh = plan::plan_path(tpp.path, tpp.cfg.limits, o);
      if (k == 0) first = memo.searched;
      ASSERT_EQ(with.pieces.size(), fresh.pieces.size()) << name << ", offset " << k << "/16";
      for (size_t i = 0; i < with.pieces.size(); ++i) {
        const plan::Piece &a = with.pieces[i], &b = fresh.pieces[i];
        differ += !(a.t0 == b.t0 && a.T == b.T && a.s0 == b.s0 && a.v0 == b.v0 && a.a0 == b.a0 && a.j == b.j &&
                    a.dwell == b.dwell && a.on_tick == b.on_tick);
      }
    }
    std::printf("  %s: %lld curved moves' searches in the first plan, %lld in the next 15, %lld taken from an "
                "earlier plan; %lld pieces differ\n", name, first, memo.searched - first, memo.reused, differ);
    EXPECT_EQ(differ, 0) << name;
    EXPECT_GT(first, 0) << name << ": the case this test is for: curved moves re-timed";
    EXPECT_EQ(memo.reused, 15 * first) << name;
  }
}

// A round whose fit fails goes on looking for further failures a few ticks
// past each one (job/plan_fit.cpp), and each fit prepares its whole part of
// the ticks before it fits the first (at fine ticks, the samples between fit
// ticks). Where that part went on to the end of a 65 536-tick part, each
// failure prepared the rest of the path again: pubg.svg at set (i) spent
// 10.1 s in one round's fit with 68 failures (0.6 s for a fit without any).
// Now the search goes on in parts of 4 096 ticks, so a round prepares its
// ticks and at most 4 096 more per failure. simple-icons' ferrari.svg at set
// (i) (several failures per round): 212 331 ticks prepared before, about
// 145 000 now, against a bound of 156 000.
TEST(ToolpathPlan, FitFailuresDoNotPrepareTheRestOfThePathAgain) {
  const job::JobConfig cfg = bench::fast_machine();
  const std::string file = std::string(TRAJ_JOB_ASSETS) + "/simple-icons/ferrari.svg";
  const job::ToolpathPlan tpp = job::toolpath_plan(input::read_toolpath(file, input::FileKind::kSvg), cfg);
  const job::JobResult r = job::run_job(tpp.path, tpp.cfg);
  const size_t fit_ticks = (r.ticks.size() - 1) / static_cast<size_t>(tpp.cfg.machine.fit_ticks()) + 1;
  const size_t bound = static_cast<size_t>(r.rounds) * fit_ticks + r.fit_failures * 4096;
  std::printf("  ferrari.svg at set (i): %d plans, %zu fit failures, %zu ticks given to the fit (bound %zu: %zu "
              "fit ticks a plan)\n", r.rounds, r.fit_failures, r.fit_ticks, bound, fit_ticks);
  EXPECT_GE(r.fit_failures, 5u) << "the case this test is for: fits that fail";
  EXPECT_LE(r.fit_ticks, bound);
}

// LinuxCNC's own logo (linuxcnc-uspace's linuxcnc-logo.svg) at the main job's
// limits: an exact stop at a cusp, and 4.6 µm past it a grid point of the next
// curve. The stop's speed cap of 0 spanned 1e-9 of the path's length (11 µm)
// and held that point too; the profile, at speed 0 at both ends of the stretch
// between, jumped over it, and the fit failed there round after round ("the
// limits cannot be met: 452 local speed caps in 200 rounds did not suffice").
// Now a stop's cap spans the rounding of its arc length only
// (plan::stop_cap): the plan is continuous in arc length, piece to piece, and
// the job passes.
TEST(ToolpathPlan, ExactStopHoldsOnlyItsJunction) {
  const std::string file = "/usr/share/icons/hicolor/scalable/apps/linuxcnc-logo.svg";
  if (!std::ifstream(file)) GTEST_SKIP() << file << " not installed (linuxcnc-uspace)";
  const job::JobConfig cfg;
  const job::ToolpathPlan tpp = job::toolpath_plan(input::read_toolpath(file, input::FileKind::kSvg), cfg);
  ASSERT_GT(tpp.stops, 0) << "the case this test is for: exact stops";
  const job::JobResult r = job::run_job(tpp.path, tpp.cfg);
  double worst_gap = 0;
  for (size_t i = 1; i < r.plan.pieces.size(); ++i) {
    const plan::Piece &a = r.plan.pieces[i - 1], &b = r.plan.pieces[i];
    worst_gap = std::max(worst_gap, std::fabs(b.s0 - a.s(a.T)));
  }
  std::printf("  linuxcnc-logo.svg: %.3f s of motion, %d plans, largest jump of s between pieces %.3g mm\n",
              r.plan.duration(), r.rounds, worst_gap);
  EXPECT_LE(worst_gap, 1e-9 * tpp.path.length());
}

namespace {

// The flowsnake curve of LinuxCNC's flowsnake.ngc, computed here: each level
// replaces a segment s -> e by four through the thirds and a point off the
// middle by |e - s| / sqrt(12). Level 5 from (0.25, 1) to (3.75, 1): 1024
// segments of 3.4 um to 4.7 um, at the program's F10 (10 mm/min).
void flowsnake(int level, Eigen::Vector2d s, Eigen::Vector2d e, input::Toolpath& tp) {
  if (level == 0) {
    input::Move m;
    m.curve = geo::make_line(s, e);
    m.feed = 10.0 / 60;
    m.where = "flowsnake: G1 " + std::to_string(tp.moves.size() + 1);
    tp.moves.push_back(m);
    return;
  }
  const Eigen::Vector2d d = e - s, p1 = s + d / 3, p3 = s + 2 * d / 3;
  const Eigen::Vector2d p2 = (s + e) / 2 + Eigen::Vector2d(d.y(), -d.x()) / std::sqrt(12.0);
  flowsnake(level - 1, s, p1, tp);
  flowsnake(level - 1, p1, p2, tp);
  flowsnake(level - 1, p2, p3, tp);
  flowsnake(level - 1, p3, e, tp);
}

}  // namespace

// Short speed changes (PlanOptions::jerk_phase_ticks). With tangential
// limits raised to a_tan 3000, j_tan 60000 the flowsnake's slow-downs between
// its blends became S-curves shorter than a tick: no one-tick segment
// followed them within j_axis, each repair's slow-down made the changes
// shorter still, and the plan took 128 rounds, 22 618 caps and 491 s of
// motion (82 s at the default limits). Now it plans in a few rounds, within
// 10 % of its time at the default limits, every limit held on the core's
// samples. (Not faster: the higher tangential jerk takes more of each axis's
// jerk, and leaves less for turning through the blends.)
TEST(ToolpathPlan, ShortSpeedChangesNeedNoRepairRounds) {
  input::Toolpath tp;
  tp.axes = 2;
  flowsnake(5, {0.25, 1}, {3.75, 1}, tp);
  ASSERT_EQ(tp.moves.size(), 1024u);
  job::JobConfig base;
  base.limits.tol = 0.05;
  job::JobConfig high = base;
  high.limits.a_tan = 3000;
  high.limits.j_tan = 60000;
  const job::ToolpathPlan bp = job::toolpath_plan(tp, base);
  const job::JobResult br = job::run_job(bp.path, bp.cfg);
  const job::ToolpathPlan hp = job::toolpath_plan(tp, high);
  const job::JobResult hr = job::run_job(hp.path, hp.cfg);
  std::printf("  default limits: %.3f s, %d rounds, %d caps; raised tangential limits: %.3f s, %d rounds, %d caps\n",
              br.plan.duration(), br.rounds, br.repairs, hr.plan.duration(), hr.rounds, hr.repairs);
  EXPECT_LE(hr.rounds, 3);
  EXPECT_LT(hr.plan.duration(), 1.1 * br.plan.duration());
  double q = 0;
  const double lsb = std::ldexp(1.0, -32);
  for (const auto& c : hr.compiled) q = std::max(q, (0.5 + c.bound_lsb) * lsb);
  const auto v = test::check_output_limits(to_mm(report::predicted_samples(hr)), 3, hp.cfg.limits,
                                           high.machine.period, q, true);
  EXPECT_LE(v.worst, 1 + 1e-9) << v.what << " at tick " << v.tick;
}

// Straight moves between exact stops (G61) are re-timed on the tick grid
// (host/planner/README.md, step 5). Streamed, each window's plan starts
// between two ticks (the commit falls inside a tick), so its moves must be
// put on the global grid (PlanOptions::tick_offset): where they are not, the
// fit does not break at their jerk switches and the repairs slow them down.
// Streamed and whole plans need no repair, agree to within 2 % (a move cut
// by a window's commit is planned as before), keep every limit on the hls
// engine's samples, and are faster than the moves as first planned
// (align_straight_moves off).
TEST(ToolpathStream, ExactStopMovesOnTheTickGridStreamedAndWhole) {
  const auto dir = std::filesystem::temp_directory_path() / ("toolpath_grid_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "g61.ngc").string();
  {
    std::ofstream o(file);
    o << "G21 G90 G61 G17\nG0 X0 Y0\n";
    double x = 0, y = 0;
    for (int i = 1; i <= 60; ++i) {
      const double len = 0.3 + 29.7 * std::fmod(i * 0.6180339887, 1.0), ang = 2.4 * i;
      x += len * std::cos(ang);
      y += len * std::sin(ang);
      char line[96];
      std::snprintf(line, sizeof line, "%s X%.4f Y%.4f%s\n", i % 10 == 0 ? "G0" : "G1", x, y, i == 1 ? " F3000" : "");
      o << line;
    }
    o << "M2\n";
  }
  job::JobConfig cfg;
  const input::Toolpath tp = input::read_gcode(file);
  const job::ToolpathPlan tpp = job::toolpath_plan(tp, cfg);
  const job::JobResult wr = job::run_job(tpp.path, tpp.cfg);
  job::JobConfig off = tpp.cfg;
  off.plan.align_straight_moves = false;
  const job::JobResult wo = job::run_job(tpp.path, off);

  const Streamed sm = stream_through_hls(file, cfg, 16, 8, 6);
  const job::StreamStats& st = sm.st;
  const auto& vs = sm.limits;
  EXPECT_LE(vs.worst, 1 + 1e-9) << "streamed: " << vs.what << " at tick " << vs.tick;
  const double h = cfg.machine.period;
  std::printf("  60 moves with exact stops: whole %.4f s (%d caps), streamed %.4f s in %zu windows (%zu caps), "
              "as first planned %.4f s\n",
              wr.plan.duration(), wr.repairs, st.motion_time, st.windows, st.caps, wo.plan.duration());
  EXPECT_EQ(wr.repairs, 0);
  EXPECT_EQ(st.caps, 0u);
  EXPECT_GT(st.windows, 5u);
  // a window's commit cuts a move (every junction here is a stop): that move
  // and its rest in the next window are planned as before
  EXPECT_GE(st.motion_time, wr.plan.duration() - h);
  EXPECT_LT(st.motion_time, 1.02 * wr.plan.duration());
  EXPECT_LT(wr.plan.duration(), 0.97 * wo.plan.duration());
  std::filesystem::remove_all(dir);
}

// The report's distance of the output to the exact curve, on a run of thousands of CAM chords
// (LinuxCNC's flowsnake.ngc at bench_toolpaths' set (i): one smoothing cubic over its 3 072
// corners, between its lead-in and lead-out moves). Newton's method from the planned parameter oversteps on such a curve and converged
// on a far part of it: the report read 2.45 mm against the fit's 0.005 and `trajcore run` failed.
// Every planned point lies on the curve, so the distance to the curve is at most the distance to
// it: the report may not exceed that, computed here apart from the report, sample by sample.
TEST(ToolpathPlan, ReportDistanceOnARunOfThousandsOfChords) {
  const std::string file = "/usr/share/linuxcnc/ncfiles/flowsnake.ngc";
  if (!std::ifstream(file)) GTEST_SKIP() << file << " not installed";
  const job::JobConfig cfg = bench::fast_machine();
  const job::ToolpathPlan tpp = job::toolpath_plan(input::read_gcode(file), cfg);
  bool long_run = false;
  for (size_t i = 0; i < tpp.path.size(); ++i) long_run |= tpp.path.entry(i).where.find("run of 3072 corners") != std::string::npos;
  ASSERT_TRUE(long_run) << "the case this test is for: one run over the program's corners";
  const job::JobResult r = job::run_job(tpp.path, tpp.cfg);
  const report::Samples s = report::predicted_samples(r);
  const report::Report rep = report::make_report(tpp.path, tpp.cfg, r, s);
  ASSERT_EQ(r.header.frac_bits, 32) << "to_mm's scale";
  const std::vector<P3> x = to_mm(s);
  ASSERT_GE(r.ticks.size(), x.size());
  double to_planned = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    double d2 = 0;
    for (int a = 0; a < 2; ++a) d2 += (x[k][a] - r.ticks[k].x[a]) * (x[k][a] - r.ticks[k].x[a]);
    to_planned = std::max(to_planned, std::sqrt(d2));
  }
  std::printf("  flowsnake.ngc at set (i): %zu samples, report's distance to the curve %.3g mm, to the planned "
              "points %.3g mm (fit tolerance %.3g)\n", x.size(), rep.max_deviation, to_planned, r.fit_tol);
  EXPECT_LE(rep.max_deviation, to_planned);
  EXPECT_LE(rep.max_deviation, r.fit_tol + 1e-9);
}

// A raster row of LinuxCNC's 3D_Chips.ngc (30.5 mm over Y and Z, the program's own numbers, its
// F2250000 mm/min far above the axes), between two corners kept as stops, at bench_toolpaths'
// set (i). Its move from rest to rest is re-timed whole (host/planner/README.md, step 5): (1) the
// bisection for its one speed runs up to the axes' top speed, not to the feed (at the feed its 10
// steps were 37 mm/s apart), so the row plans the same as at F = that top speed; (2) its speed
// levels take their top from the geometry, not from the speed cap, so it dips at its tight
// stretch (R 3 mm) and runs faster elsewhere, against one speed for the whole row before.
TEST(ToolpathPlan, CamRowAtAFeedFarAboveTheAxesDipsAtItsTightStretch) {
  auto program = [](double f) {
    std::ostringstream o;
    o << "G21 G90 G64 P0.1\nG0 X-29.5 Y9.112 Z-19.021\nG1 F" << std::fixed << f << "\n"
      "Y9.05Z-18.948\nY8.925Z-18.784\nY8.737Z-18.528\nY8.487Z-18.006\nY7.737Z-16.575\nY7.237Z-15.482\n"
      "Y6.237Z-13.677\nY4.737Z-11.229\nY4.237Z-10.475\nY3.237Z-9.204\nY2.737Z-8.696\nY2.237Z-8.264\n"
      "Y1.737Z-7.875\nY1.612Z-7.808\nY1.487Z-7.751\nY1.237Z-7.667\nY0.987Z-7.589\nY0.737Z-7.512\n"
      "Y0.237Z-7.381\nY0.112Z-7.367\nY-0.013Z-7.363\nY-0.263Z-7.387\nY-0.388Z-7.415\nY-0.763Z-7.538\n"
      "Y-1.263Z-7.712\nY-1.763Z-7.933\nY-1.825Z-7.972\nY-2.013Z-8.116\nY-2.763Z-8.786\nY-3.263Z-9.309\n"
      "Y-4.263Z-10.601\nY-4.763Z-11.369\nY-5.763Z-12.979\nY-6.763Z-14.71\nY-7.763Z-16.661\n"
      "Y-8.263Z-17.601\nY-8.513Z-18.098\nY-8.7Z-18.497\nY-8.763Z-18.602\nY-9.083Z-19.015\n"
      "Y-9.122Z-19.024\n" << "M2\n";
    std::istringstream in(o.str());
    return input::read_gcode(in, "row.ngc");
  };
  const job::JobConfig cfg = bench::fast_machine();
  job::JobConfig no_levels = cfg;
  no_levels.plan.align_level_moves = false;
  auto motion = [&](double f, const job::JobConfig& c) {
    const job::ToolpathPlan tpp = job::toolpath_plan(program(f), c);
    return job::run_job(tpp.path, tpp.cfg).plan.duration();
  };
  const double* v = cfg.limits.v_axis;
  const double top = 60 * std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);  // the axes together, mm/min
  const double far = motion(2250000, cfg), at_top = motion(top, cfg), one_speed = motion(2250000, no_levels);
  std::printf("  F2250000: %.4f s; F at the axes' top speed (%.0f): %.4f s; without speed levels %.4f s\n", far, top,
              at_top, one_speed);
  EXPECT_NEAR(far, at_top, 1e-9);
  EXPECT_LT(far, one_speed - 0.02);
}

// A rounded rectangle (lines meeting tangent arcs, each curvature step
// blended) streamed in small windows. The blends are curvature-continuous,
// but at a line's end d3C/ds3 steps, and the speed bound's jerk terms with
// it: a window committed at such a junction left the next one starting
// above its own bound there, no tick could join the two, and the held
// window, planned again with half its commit, moved its commit back off a
// corner to where it was, again and again (the Rust embedded book's
// rust_layers.svg hung `trajcore plan --window 64`). Every window must now
// continue the last without a retry, and the limits hold on the hls
// engine's samples.
TEST(ToolpathStream, RoundedRectangleStreamsInSmallWindows) {
  const traj::test::TmpFile file("rounded_rectangle.ngc");
  file.write(
      "G21 G90 G64 P0.001 G17\nG0 X283.4 Y150.5\nG1 X283.4 Y145.2 F3000\nG2 X278.1 Y139.9 I-5.3 J0\n"
      "G1 X39.7 Y139.9\nG2 X34.4 Y145.2 I0 J5.3\nG1 X34.4 Y155.8\nG2 X39.7 Y161.1 I5.3 J0\n"
      "G1 X278.1 Y161.1\nG2 X283.4 Y155.8 I0 J-5.3\nG1 X283.4 Y150.5\nM2\n");
  const job::JobConfig cfg;
  const job::ToolpathPlan tpp = job::toolpath_plan(input::read_gcode(file.path), cfg);
  const job::JobResult wr = job::run_job(tpp.path, tpp.cfg);
  for (const size_t window : {4, 8, 16}) {
    const Streamed sm = stream_through_hls(file.path, cfg, 64, window, window / 2);
    std::printf("  window %zu: %zu windows, %zu planned again, %.3f s (whole %.3f s), worst limit ratio %.4f\n",
                window, sm.st.windows, sm.st.retries, sm.st.motion_time, wr.plan.duration(), sm.limits.worst);
    EXPECT_EQ(sm.st.retries, 0u) << "window " << window;
    EXPECT_GE(sm.st.windows, 2u) << "window " << window;
    EXPECT_LE(sm.limits.worst, 1 + 1e-9) << "window " << window << ": " << sm.limits.what;
    EXPECT_NEAR(sm.st.motion_time / wr.plan.duration(), 1.0, 0.02) << "window " << window;
  }
}

// LinuxCNC's plasmatest.ngc (plasma lettering: long lines at F5840 into
// corners and 0.75 mm fillets) streamed. A window's look-ahead (planned
// again by the next window) was not checked at its ticks: the next window
// found a tick above a limit at a corner just beyond the commit, capped the
// speed there, and could then not slow down from the committed speed in
// time, so the held window was planned again with half its commit (12 times
// at a window of 16, twice at 64). The look-ahead's ticks are now checked
// too and its caps go with the commit: at the default window no window is
// planned again, at 16 fewer than before; the limits hold on the hls
// engine's samples and the motion is the whole path's within 2 %.
TEST(ToolpathStream, LookAheadCheckedSoThatTheNextWindowContinues) {
  const std::string file = "/usr/share/linuxcnc/ncfiles/plasmatest.ngc";
  if (!std::ifstream(file)) GTEST_SKIP() << file << " not installed";
  const job::JobConfig cfg;
  const job::ToolpathPlan tpp = job::toolpath_plan(input::read_gcode(file), cfg);
  const double whole = job::run_job(tpp.path, tpp.cfg).plan.duration();
  for (const size_t window : {16, 64}) {
    const Streamed sm = stream_through_hls(file, cfg, 256, window, window * 3 / 4);
    std::printf("  window %zu: %zu windows, %zu planned again, %.3f s (whole %.3f s), worst limit ratio %.4f\n",
                window, sm.st.windows, sm.st.retries, sm.st.motion_time, whole, sm.limits.worst);
    if (window == 64) {
      EXPECT_EQ(sm.st.retries, 0u);
    } else {
      EXPECT_LT(sm.st.retries, 12u);
    }
    EXPECT_LE(sm.limits.worst, 1 + 1e-9) << "window " << window << ": " << sm.limits.what;
    EXPECT_NEAR(sm.st.motion_time / whole, 1.0, 0.02) << "window " << window;
  }
}

// Long, slow moves (a drawing of metres at 400 mm/min, as dxf2gcode writes
// LibreCAD's plans: 2.8 GB streamed before) stream in windows of bounded
// ticks: 857 mm of lines and a half circle of R 50 at 600 mm/min, 86 s of
// motion, with windows of 20 000 ticks. The curves are cut into pieces of
// at most 5 s, no window commits more than its 20 000 ticks and a piece
// (about 86 000 in one window without the bound), the limits hold on the
// hls engine's samples, the motion is that of the whole path within 1 %,
// and the stream ends on the program's end point.
TEST(ToolpathStream, LongSlowMovesStreamInWindowsOfBoundedTicks) {
  const traj::test::TmpFile file("long_slow.ngc");
  file.write("G21 G90 G64 P0.01 G17\nG1 X300 F600\nG1 Y100\nG2 X300 Y200 I0 J50\nG1 X0\nM2\n");
  const job::JobConfig cfg;
  const job::ToolpathPlan tpp = job::toolpath_plan(input::read_gcode(file.path), cfg);
  const double whole = job::run_job(tpp.path, tpp.cfg).plan.duration();
  const Streamed bounded = stream_through_hls(file.path, cfg, 64, 64, 48, 20000);
  const Streamed unbounded = stream_through_hls(file.path, cfg, 64, 64, 48, 1u << 30);
  std::printf("  bounded: %zu curves in %zu windows, at most %zu ticks a window, %.3f s; without the bound %zu "
              "curves, %zu ticks; whole path %.3f s; worst limit ratio %.4f\n",
              bounded.st.curves, bounded.st.windows, bounded.st.max_window_ticks, bounded.st.motion_time,
              unbounded.st.curves, unbounded.st.max_window_ticks, whole, bounded.limits.worst);
  EXPECT_GE(bounded.st.curves, 86000u / 5000);
  EXPECT_LE(bounded.st.max_window_ticks, 25000u);
  EXPECT_GT(unbounded.st.max_window_ticks, 80000u);
  EXPECT_LE(bounded.limits.worst, 1 + 1e-9) << bounded.limits.what;
  EXPECT_NEAR(bounded.st.motion_time / whole, 1.0, 0.01);
  ASSERT_FALSE(bounded.xs.empty());
  EXPECT_LT(dist(bounded.xs.back(), {0, 200, 0}), 1e-6);
}

// Program pauses with their operator messages (tb/input/gcode/operator_messages.ngc,
// --pause-wait: six M0/M60 after moves of 1-10 mm, three with a "(MSG, ...)"),
// whole and streamed in windows of 4, 8 and 16: every pause record in place,
// with the program's line and text, read back from the stream file; the
// streamed motion keeps every pause's rest (no shorter than the whole plan's
// but for a tick). At a window of 4 a commit fell on a pause whose stop the
// plan reaches, to within s's last bit, microseconds before it stops: the
// commit left the rest out and the pause had no segment ending in it.
TEST(ToolpathStream, PausesAndTheirMessagesInEveryWindow) {
  const std::string file = std::string(TRAJ_SOURCE_DIR) + "/tb/input/gcode/operator_messages.ngc";
  input::GcodeOptions go;
  go.pauses_wait = true;
  const std::vector<uint32_t> lines = {9, 13, 15, 18, 20, 23};
  const std::vector<std::string> texts = {"Change tool bit to drill 0.8mm", "second", "on the line", "", "", ""};
  auto check = [&](const std::vector<stream::Pause>& got, const std::string& what) {
    ASSERT_EQ(got.size(), lines.size()) << what;
    for (size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].line, lines[i]) << what << " pause " << i;
      EXPECT_EQ(got[i].text, texts[i]) << what << " pause " << i;
    }
  };
  const job::JobConfig cfg;
  const job::ToolpathPlan tpp = job::toolpath_plan(input::read_gcode(file, go), cfg);
  const job::JobResult wr = job::run_job(tpp.path, tpp.cfg);
  check(job::pauses_of(wr), "whole");
  job::ToolpathOptions to;
  to.gcode = go;
  for (const size_t window : {4, 8, 16}) {
    const traj::test::TmpFile out("pauses_" + std::to_string(window) + ".trj");
    job::ToolpathStream src(file, input::FileKind::kGcode, cfg, to);
    job::StreamOptions so;
    so.window = window;
    so.commit = window / 2;
    stream::StreamWriter w(out.path, cfg.machine.header());
    const job::StreamStats st = job::run_streaming(src, src.config(), so, job::write_to(w));
    w.finish();
    const stream::ReadResult rr = stream::read_file(out.path);
    ASSERT_TRUE(rr.complete) << rr.error;
    check(rr.pauses, "window " + std::to_string(window));
    EXPECT_GE(st.motion_time, wr.plan.duration() - cfg.machine.period) << "window " << window;
  }
}
