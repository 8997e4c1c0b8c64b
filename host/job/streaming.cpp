// SPDX-License-Identifier: Apache-2.0
#include "job/streaming.hpp"

#include "job/prefetch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>

#include "job/plan_fit.hpp"

namespace traj::job {
namespace {

using plan::Path;
using plan::PathCurve;
using plan::PlanError;

// The curves held by the streaming window: each built once (arc-length
// tables) and shared by the windows that plan it, with its spline kept so
// that it can be cut at a commit, and its speed, stop and dwell.
struct Window {
  std::deque<std::shared_ptr<const PathCurve>> curves;
  std::deque<geo::BSpline> splines;
  std::deque<double> speeds;
  std::deque<bool> stops;
  std::deque<double> dwells;
  std::deque<plan::ProgramPause> pauses;

  void push_back(CurvePrefetch::Item&& it) {
    curves.push_back(std::move(it.built));
    StreamCurve& c = it.curve;
    splines.push_back(std::move(c.curve));
    speeds.push_back(c.speed);
    stops.push_back(c.stop);
    dwells.push_back(c.dwell);
    pauses.push_back(std::move(c.pause));
  }
  // Curve i's time at its speed, and its dwell: at least the time it takes.
  double time(size_t i, double feed) const {
    return curves[i]->al->total() / (speeds[i] > 0 ? speeds[i] : feed) + dwells[i];
  }
  double time(double feed) const {
    double t = 0;
    for (size_t i = 0; i < curves.size(); ++i) t += time(i, feed);
    return t;
  }
  // The commit of a window that its curves' time ended (at least
  // `window_time`): the curves within the first three quarters of that time,
  // so that the look-ahead is a quarter of it, not one short curve;
  // `commit` otherwise.
  size_t commit_by_time(size_t commit, double feed, double window_time) const {
    const double total = time(feed);
    if (total < window_time) return commit;
    size_t n = 0;
    double t = time(0, feed);
    while (n + 1 < curves.size() && t <= 0.75 * total) t += time(++n, feed);
    return std::clamp<size_t>(n, 1, commit);
  }
  Path path() const {
    Path p;
    for (const auto& c : curves) p.add(c);
    return p;
  }
  // The first n curves, taken out (a held window's committed curves).
  Window take_front(size_t n) {
    Window w;
    for (size_t i = 0; i < n; ++i) {
      w.curves.push_back(std::move(curves.front()));
      w.splines.push_back(std::move(splines.front()));
      w.speeds.push_back(speeds.front());
      w.stops.push_back(stops.front());
      w.dwells.push_back(dwells.front());
      w.pauses.push_back(std::move(pauses.front()));
      curves.pop_front();
      splines.pop_front();
      speeds.pop_front();
      stops.pop_front();
      dwells.pop_front();
      pauses.pop_front();
    }
    return w;
  }
  // Puts curves taken by take_front back in front.
  void restore_front(Window&& w) {
    curves.insert(curves.begin(), w.curves.begin(), w.curves.end());
    splines.insert(splines.begin(), w.splines.begin(), w.splines.end());
    speeds.insert(speeds.begin(), w.speeds.begin(), w.speeds.end());
    stops.insert(stops.begin(), w.stops.begin(), w.stops.end());
    dwells.insert(dwells.begin(), w.dwells.begin(), w.dwells.end());
    pauses.insert(pauses.begin(), w.pauses.begin(), w.pauses.end());
  }
  // Cuts curve i in two inside the knot span that holds its parameter middle
  // (a smooth place: no knot there).
  void split(size_t i) {
    const geo::BSpline& c = splines[i];
    const double mid = 0.5 * (c.u_begin() + c.u_end());
    int k = c.degree;
    while (k + 1 < c.n_ctrl() && c.knots[k + 1] <= mid) ++k;
    auto halves = geo::split_at(c, 0.5 * (c.knots[k] + c.knots[k + 1]));
    const std::string w = curves[i]->where;
    const auto at = static_cast<long>(i) + 1;
    curves[i] = std::make_shared<const PathCurve>(halves.first, w + " (first part)");
    curves.insert(curves.begin() + at, std::make_shared<const PathCurve>(halves.second, w + " (second part)"));
    splines[i] = std::move(halves.first);
    splines.insert(splines.begin() + at, std::move(halves.second));
    speeds.insert(speeds.begin() + at, speeds[i]);
    stops.insert(stops.begin() + at, stops[i]);
    stops[i] = false;
    dwells.insert(dwells.begin() + at, dwells[i]);
    dwells[i] = 0;
    pauses.insert(pauses.begin() + at, std::move(pauses[i]));
    pauses[i] = {};
  }
  // The curves' speeds and stops as speed caps on `path` (the window's
  // path), and their dwells (the window's end is a stop of its own plan).
  void add_caps(const Path& path, double feed, plan::PlanOptions& o) const {
    for (size_t i = 0; i < curves.size(); ++i) {
      const double s0 = path.offset(i), s1 = path.offset(i + 1);
      if (speeds[i] > 0 && speeds[i] < feed) o.caps.push_back({s0, s1, speeds[i]});
      if (stops[i] && i + 1 < curves.size()) o.caps.push_back(plan::stop_cap(s1, path.length()));
      if (dwells[i] > 0) o.dwells.push_back({s1, dwells[i]});
    }
  }
};

// The curves of a CurveSource, at the feed limit, without stops.
struct PlainSource : StreamSource {
  explicit PlainSource(CurveSource& s) : src(s) {}
  bool next(StreamCurve& c) override {
    c.speed = 0;
    c.stop = false;
    c.dwell = 0;
    c.pause = {};
    return src.next(c.curve, c.where);
  }
  CurveSource& src;
};

// The curves of a source, each longer than `piece_time` seconds at its speed
// (by its control polygon, not shorter than a B-spline or an arc) cut into pieces
// within it, one at a time (a curve of days at a crawl is not held as
// millions of pieces): the front piece is the curve's parameter range
// halved until it fits. The pieces join with the curve's own derivatives
// (exact knot insertion), so the cuts are smooth junctions where a window
// can commit. The last piece keeps the curve's stop, dwell and pause.
class LongCurveCutter : public StreamSource {
 public:
  LongCurveCutter(StreamSource& src, double feed, double piece_time)
      : src_(src), feed_(feed), piece_time_(piece_time) {}
  bool next(StreamCurve& c) override {
    if (!rest_) {
      StreamCurve whole;
      if (!src_.next(whole)) return false;
      rest_ = std::move(whole);
    }
    const double speed = rest_->speed > 0 ? rest_->speed : feed_;
    geo::BSpline front = rest_->curve;
    double u = front.u_end();
    while (polygon_length(front) > piece_time_ * speed) {
      const double mid = front.u_begin() + 0.5 * (u - front.u_begin());
      if (!(mid > front.u_begin() && mid < u)) break;
      front = geo::split_at(front, mid).first;
      u = mid;
    }
    if (u == rest_->curve.u_end()) {
      c = std::move(*rest_);
      rest_.reset();
      return true;
    }
    c = *rest_;
    c.curve = std::move(front);
    c.stop = false;
    c.dwell = 0;
    c.pause = {};
    rest_->curve = geo::split_at(rest_->curve, u).second;
    return true;
  }

 private:
  static double polygon_length(const geo::BSpline& b) {
    double l = 0;
    for (int i = 1; i < b.n_ctrl(); ++i) l += (b.ctrl.row(i) - b.ctrl.row(i - 1)).norm();
    return l;
  }

  StreamSource& src_;
  const double feed_, piece_time_;
  std::optional<StreamCurve> rest_;  // what is left of the curve being cut
};

// True if curves i-1 and i of `path` meet at a tangent break, a curvature
// step (the planner's test: a jump of d2C/ds2 on an axis) or, with
// `jerk_steps`, a step of d3C/ds3 (a line meeting a curvature-continuous
// blend): the speed bound's jerk terms (|Q| v^3) differ on the two sides
// there, and a window that starts at the junction takes the far side's,
// which may be below the speed the previous window committed with the near
// side's (a rounded rectangle of the Rust embedded book's rust_layers.svg,
// streamed in windows of 8: 33.6 mm/s committed at a line's end, 31.1 the
// next window's bound at its blend's start, and no tick could join the two).
bool corner_at(const Path& path, size_t i, double corner_tol, bool jerk_steps) {
  const plan::Frame e = plan::frame_at(path, i - 1, path.curve(i - 1).u_end(), path.offset(i));
  const plan::Frame f = plan::frame_at(path, i, path.curve(i).u_begin(), path.offset(i));
  double dot = 0, kscale = 0, kjump = 0, qscale = 0, qjump = 0;
  for (int a = 0; a < path.dim(); ++a) {
    dot += e.T[a] * f.T[a];
    kscale = std::max({kscale, std::fabs(e.K[a]), std::fabs(f.K[a])});
    kjump = std::max(kjump, std::fabs(f.K[a] - e.K[a]));
    qscale = std::max({qscale, std::fabs(e.Q[a]), std::fabs(f.Q[a])});
    qjump = std::max(qjump, std::fabs(f.Q[a] - e.Q[a]));
  }
  return std::acos(std::clamp(dot, -1.0, 1.0)) > corner_tol || kjump > 1e-9 * (1 + kscale) ||
         (jerk_steps && qjump > 1e-9 * (1 + qscale));
}

// How many curves of a (not last) window to commit, at most `limit`. The
// commit junction should not be a corner (nor a curvature step, which the
// planner passes at a station of its own jump speed, like a corner): the next
// window's first segment must start at the last committed tick, just before
// the junction, and turn the velocity from there; at a corner (passed at a
// near-stop within one tick) that can fail where a whole-path fit would have
// started the turn earlier. The nearest junction without a tangent break is
// taken (earlier first, then later, up to `limit`); where every junction is
// a corner (a polyline), the curve after the corner is cut in two inside a
// knot span and the commit ends at the cut, so the corner itself is fitted
// within this window.
// A retry (`limit` set) commits at the corner where the cut would commit
// more than `limit`: cutting the curve before it instead would commit half
// of one curve, then half of what is left, down to a zero-length piece
// (LinuxCNC's spiral.ngc in windows of 8). A retry also takes steps of
// d3C/ds3 for junctions like any other: where the commits that avoid them
// fail one after another (cut inside tight blends: bootstrap-icons' gear.svg
// at --window 32 and 64), one at such a step continues.
size_t choose_commit(Window& win, Path& path, size_t ncommit, size_t limit, double corner_tol) {
  const bool retry = limit != SIZE_MAX;
  auto corner = [&](size_t i) { return corner_at(path, i, corner_tol, !retry); };
  if (corner(ncommit)) {
    for (size_t d = 1; d < win.curves.size(); ++d) {
      if (ncommit > d && !corner(ncommit - d)) return ncommit - d;
      if (ncommit + d < win.curves.size() && ncommit + d <= limit && !corner(ncommit + d))
        return ncommit + d;
    }
    if (ncommit + 1 > limit) return ncommit;  // a retry's: at the corner, or fewer curves on the next retry
    win.split(ncommit);
    path = win.path();
    return ncommit + 1;
  }
  return ncommit;
}

// s, or the curve junction of `path` it lies at up to rounding (a station
// carried from the previous window, whose arc lengths started elsewhere): a
// station a rounding error away from a junction would be a second grid point
// beside it, without the junction's speed bound.
double snap_to_junction(const Path& path, double s) {
  const size_t i = path.curve_at(s);
  const double eps = 1e-9 * std::max(1.0, path.length());
  if (std::fabs(s - path.offset(i)) <= eps) return path.offset(i);
  if (std::fabs(s - path.offset(i + 1)) <= eps) return path.offset(i + 1);
  return s;
}

// Time at which `plan` reaches arc length s (bisection on the profile), or
// leaves it when it dwells there (a commit takes the dwell with it: a pause's
// rest, a G4). The dwell is found by its place, not by the bisection's time:
// an S-curve stop reaches s to within rounding micro-seconds before it stops
// (s - s(t) ~ j (t_stop - t)^3 / 6 falls below s's last bit 3 us early at
// j = 1000 mm/s^3, s = 20 mm), and a commit there without its rest dropped
// the rest and left the pause without a segment ending in it.
double time_at_arc_length(const plan::Plan& plan, double s) {
  const double eps = 1e-9 * std::max(1.0, std::fabs(s));
  for (const plan::Piece& q : plan.pieces)
    if (q.dwell && std::fabs(plan::state_at(plan, q.t0).s - s) <= eps) return q.t0 + q.T;
  double lo = 0, hi = plan.duration();
  for (int it = 0; it < 200 && hi - lo > 1e-15 * (1 + hi); ++it) {
    const double mid = 0.5 * (lo + hi);
    (plan::state_at(plan, mid).s < s ? lo : hi) = mid;
  }
  return hi;
}

}  // namespace

SegmentSink write_to(stream::StreamWriter& w) {
  return [&w](const fd::Compiled& c, const plan::TimeSegment& seg) {
    w.add({c.ticks, c.regs});
    if (seg.pause) w.pause(static_cast<uint32_t>(seg.pause.line), seg.pause.text);
  };
}

StreamStats run_streaming(CurveSource& src, const JobConfig& cfg, const StreamOptions& so, const SegmentSink& sink,
                          const Progress& progress) {
  PlainSource plain(src);
  return run_streaming(plain, cfg, so, sink, progress);
}

namespace {

// What a window hands to the next, exactly: the window's start time
// k_org h + T0 with 0 <= T0 < h (the tick count is held as an integer, so
// tick times and the committed tick keep full precision however long the path
// runs: a double T0 alone would round the tick grid to 7e-9 ticks past 2^25
// ticks, 9 hours at 1 ms), the speed at the commit, the last committed tick
// and its sample, the fitted positions before it, relative to it (the next fit checks its
// sampled tangential/normal windows across the junction), and the stations
// and repair caps of the plan beyond the commit.
struct Carry {
  long long k_org = 0;
  double T0 = 0, v = 0;
  long long k_last = -1;  // last committed tick (-1: at rest, nothing committed)
  plan::TickSample tick{};
  std::vector<std::array<double, plan::kMaxAxes>> history;
  std::vector<double> stations;
  std::vector<plan::SpeedCap> caps;
};

struct WindowPlan {
  std::vector<plan::TimeSegment> segments;
  size_t ncommit = 0;  // curves committed
  Carry next;
  size_t repairs = 0, ticks = 0;
};

// Plans the window `win` from `in`, committing about `commit_max` curves
// (all if `last`), never more than `commit_limit`.
WindowPlan plan_window(Window& win, const Carry& in, size_t commit_max, bool last, const JobConfig& cfg,
                       size_t index, std::vector<plan::TickSample>& ts, size_t commit_limit = SIZE_MAX) {
  const double h = cfg.machine.fit_period();  // the window is planned and fitted on the fit tick
  WindowPlan wp;
  Path path = win.path();
  check_path_range(path, cfg.machine);
  size_t ncommit = last ? win.curves.size() : std::min(commit_max, win.curves.size() - 1);
  if (!last) ncommit = choose_commit(win, path, ncommit, commit_limit, cfg.plan.corner_tol);
  wp.ncommit = ncommit;
  const double s_commit = last ? path.length() : path.offset(ncommit);

  double Tc = 0;
  long long k_end = 0;
  PlanFitRequest req;
  req.path = &path;
  req.limits = &cfg.limits;
  req.options = cfg.plan_options();
  req.options.v_start = in.v;
  req.options.tick_offset = in.T0;  // tick k at plan time (k - k_org) h - T0
  win.add_caps(path, cfg.limits.feed, req.options);
  const size_t own_caps = req.options.caps.size();
  req.options.caps.insert(req.options.caps.end(), in.caps.begin(), in.caps.end());
  if (!last) req.options.force_stations = {s_commit};
  for (double sc : in.stations)
    if (sc < s_commit) req.options.force_stations.push_back(snap_to_junction(path, sc));
  req.segments = cfg.segment_options();
  req.segments.history = in.history;
  req.what = "streaming window " + std::to_string(index) + " (curves from " + path.entry(0).where + ")";
  req.carried = in.k_last >= 0;
  req.t_offset = in.T0;
  req.k_base = in.k_last < 0 ? 0 : in.k_last;
  req.sample = [&](const plan::Plan& plan, std::vector<plan::TickSample>& out) {
    Tc = last ? plan.duration() : time_at_arc_length(plan, s_commit);
    k_end = in.k_org + (last ? static_cast<long long>(std::ceil((in.T0 + Tc) / h - 1e-9))
                             : static_cast<long long>(std::floor((in.T0 + Tc) / h + 1e-9)));
    out.clear();
    if (in.k_last >= 0) out.push_back(in.tick);
    plan::append_ticks_range(path, plan, h, in.T0, in.k_last + 1, k_end, out, in.k_org);
  };
  if (!last)
    req.sample_ahead = [&](const plan::Plan& plan, std::vector<plan::TickSample>& out) {
      // Only a cap within the next window's braking distance from the
      // committed speed can slow its start: the look-ahead up to twice the
      // distance of an S-curve stop at the plan's A_t and J_t.
      const double v = plan::state_at(plan, Tc).v;
      const double reach = v * (v / plan.A_t + plan.A_t / plan.J_t);
      const double T = time_at_arc_length(plan, std::min(s_commit + reach, path.length()));
      const long long k_ahead = in.k_org + static_cast<long long>(std::floor((in.T0 + T) / h + 1e-9));
      out.clear();
      plan::append_ticks_range(path, plan, h, in.T0, k_end + 1, k_ahead, out, in.k_org);
    };
  PlanFitResult fit = plan_and_fit(req, ts);
  std::vector<JobConfig::PauseAt> pauses;  // of the committed curves: their rests are committed with them
  for (size_t i = 0; i < ncommit; ++i)
    if (win.pauses[i]) pauses.push_back({path.offset(i + 1), win.pauses[i]});
  mark_pauses(fit.segments, ts, req.k_base, cfg.machine.fit_ticks(), pauses, path.length());
  wp.repairs = fit.repairs;
  wp.ticks = ts.size();

  Carry& next = wp.next;
  next.history = in.history;  // relative to this window's first tick: then to its last
  if (ts.size() > 1)
    for (auto& q : next.history)
      for (int a = 0; a < path.dim(); ++a) q[a] -= ts.back().x[a] - ts.front().x[a];
  {
    auto t = plan::fitted_tail(fit.segments, path.dim(), req.segments.engine_period(h), 3);
    next.history.insert(next.history.end(), t.begin(), t.end());
    while (next.history.size() > 3) next.history.erase(next.history.begin());
  }
  next.k_last = in.k_last;
  next.tick = in.tick;
  if (!ts.empty()) {
    next.tick = ts.back();
    next.tick.curve = static_cast<size_t>(-1);
    next.tick.s = 0;
    next.k_last = k_end;
  }
  next.T0 = in.T0 + Tc;
  next.k_org = in.k_org;
  {
    const double whole = std::floor(next.T0 / h);
    next.k_org += static_cast<long long>(whole);
    next.T0 -= whole * h;
  }
  next.v = last ? 0 : plan::state_at(fit.plan, Tc).v;
  // The stations of this plan beyond the commit become stations of the
  // next window, and the repair caps found there its caps: its plan from
  // v_commit then has the blocks and the speed bounds of this one there.
  for (size_t i = own_caps; i < req.options.caps.size(); ++i) {
    const plan::SpeedCap& cp = req.options.caps[i];
    if (cp.s1 > s_commit) next.caps.push_back({cp.s0 - s_commit, cp.s1 - s_commit, cp.v});
  }
  for (const auto& stn : fit.plan.stations)
    if (stn.s > s_commit + 1e-12 && stn.s < path.length() - 1e-12) next.stations.push_back(stn.s - s_commit);
  wp.segments = std::move(fit.segments);
  return wp;
}

}  // namespace

StreamStats run_streaming(StreamSource& src, const JobConfig& cfg, const StreamOptions& so, const SegmentSink& sink,
                          const Progress& progress) {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  if (so.window < 2 || so.commit < 1 || so.commit >= so.window)
    throw PlanError("streaming window: need 1 <= commit < window (got commit " + std::to_string(so.commit) +
                    ", window " + std::to_string(so.window) + ")");
  cfg.validate();
  const double h = cfg.machine.fit_period();  // windows, commits and carries are on the fit tick
  const int n = cfg.machine.fit_ticks();
  const uint32_t kmax = cfg.machine.longest_segment();

  StreamStats st;
  Window win;
  bool exhausted = false;
  std::vector<plan::TickSample> ts;  // the window's ticks; storage reused window after window

  SegmentCompiler sc(cfg.machine);
  std::vector<plan::TimeSegment> pieces;  // one fitted segment on the engine's tick; storage reused
  auto emit_engine = [&](const plan::TimeSegment& seg) {
    const fd::Compiled& c = sc.compile(seg, st.segments);
    if (st.first_segment < 0) st.first_segment = std::chrono::duration<double>(Clock::now() - t_start).count();
    sink(c, seg);
    ++st.segments;
    st.ticks += seg.K;
  };
  auto emit = [&](const plan::TimeSegment& fit) {  // a fitted segment, on the engine's tick
    pieces.clear();
    engine_pieces(fit, kmax, cfg.machine.period, pieces);
    for (const plan::TimeSegment& seg : pieces) emit_engine(seg);
  };

  // A window's segments are emitted once the next window has planned from
  // its commit: a restarted plan (other stations, other grid points) can
  // occasionally not continue the committed motion within the limits; the
  // held window is then planned again with half its commit (more of the
  // slow-down is left to the next window), and the next window retried.
  // four windows ahead: about a blend chunk of a toolpath (256 moves), which
  // comes in one burst, so that blending one chunk overlaps planning the last
  const double window_time = static_cast<double>(so.window_ticks) * h;
  LongCurveCutter cutter(src, cfg.limits.feed, window_time / 4);
  CurvePrefetch ahead(cutter, 4 * so.window, so.prefetch);
  Carry carry;             // into the window to plan
  Carry held_from;         // into the held window
  std::optional<WindowPlan> held;
  Window held_curves;      // the held window's committed curves
  while (true) {
    CurvePrefetch::Item c;
    while (!exhausted && win.curves.size() < so.window &&
           !(win.curves.size() >= 2 && win.time(cfg.limits.feed) >= window_time)) {
      if (ahead.next(c)) {
        win.push_back(std::move(c));
        ++st.curves;
      } else {
        exhausted = true;
      }
    }
    if (win.curves.empty()) break;
    const bool last = exhausted;
    WindowPlan wp;
    try {
      wp = plan_window(win, carry, win.commit_by_time(so.commit, cfg.limits.feed, window_time), last, cfg,
                       st.windows, ts);
    } catch (const JunctionError&) {
      if (!held || held->ncommit <= 1) throw;
      win.restore_front(std::move(held_curves));
      // fewer curves than before, or the same commit (moved off a corner
      // to where it was) fails the same way again and again
      held = plan_window(win, held_from, held->ncommit / 2, false, cfg, st.windows - 1, ts, held->ncommit - 1);
      carry = held->next;
      held_curves = win.take_front(held->ncommit);
      ++st.retries;
      continue;
    }
    st.caps += wp.repairs;
    st.max_window_ticks = std::max(st.max_window_ticks, wp.ticks);
    if (held)
      for (const auto& sg : held->segments) emit(sg);
    ++st.windows;
    if (progress) progress("stream", static_cast<double>(st.curves));
    if (last) {
      for (const auto& sg : wp.segments) emit(sg);
      const Carry& end = wp.next;
      emit_engine(hold_segment(end.k_last * n, end.tick.x, win.splines.front().dim(), cfg.machine.degree));
      st.motion_time = static_cast<double>(end.k_org) * h + end.T0;
      break;
    }
    held_from = std::move(carry);
    carry = wp.next;
    held_curves = win.take_front(wp.ncommit);
    held = std::move(wp);
  }
  st.wall = std::chrono::duration<double>(Clock::now() - t_start).count();
  return st;
}

}  // namespace traj::job
