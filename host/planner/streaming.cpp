#include "planner/streaming.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>

namespace traj::plan {

StreamStats run_streaming(CurveSource& src, const JobConfig& cfg, const StreamOptions& so, const SegmentSink& sink,
                          const Progress& progress) {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  if (so.window < 2 || so.commit < 1 || so.commit >= so.window)
    throw PlanError("streaming window: need 1 <= commit < window (got commit " + std::to_string(so.commit) +
                    ", window " + std::to_string(so.window) + ")");
  cfg.limits.validate();
  const double h = cfg.plan.period;
  if (!std::isfinite(h) || !(h > 0)) throw PlanError("tick period must be positive and finite");
  fd::Format f = cfg.format;
  f.degree = cfg.degree;
  fd::Compiler comp(f);
  const double lsb = std::ldexp(1.0, -f.frac_bits);
  SegmentOptions sopt;
  sopt.degree = cfg.degree;
  sopt.max_ticks = static_cast<uint32_t>(
      std::min<uint64_t>(fd::Compiler::longest_segment(f.degree, f.guard_bits, f.tol_lsb), f.max_ticks));
  sopt.fit_tol = cfg.limits.tol - (0.5 + f.tol_lsb) * lsb;
  if (!(sopt.fit_tol > 0)) throw PlanError("path tolerance is below the output quantisation");

  StreamStats st;
  std::deque<std::shared_ptr<const PathCurve>> win;  // built once, shared by the windows
  std::deque<geo::BSpline> wsp;                      // their splines (a curve may be cut at a commit)
  bool exhausted = false;
  // The window's start time is k_org h + T0 with 0 <= T0 < h: the tick count
  // is held as an integer, so tick times and the committed tick keep full
  // precision however long the path runs (a double T0 alone would round the
  // tick grid to 7e-9 ticks past 2^25 ticks, 9 hours at 1 ms).
  long long k_org = 0;
  double T0 = 0, v_commit = 0;
  long long k_last = -1;  // last committed tick
  TickSample carried{};
  std::vector<TickSample> ts;  // the window's ticks; storage reused window after window
  bool have_end = false;
  const int dim_engine = f.axes;

  // One PolySegment and one Compiled reused for every segment: the compiler
  // writes into the same storage (no allocation on its common path), and each
  // segment starts from the previous one's exact end state, c.end.
  fd::PolySegment ps;
  ps.h = h;
  ps.coef.assign(dim_engine, std::vector<double>(f.degree + 1, 0.0));
  fd::Compiled c;
  auto emit = [&](const TimeSegment& seg) {
    ps.ticks = seg.K;
    for (int a = 0; a < dim_engine; ++a)
      for (int j = 0; j <= f.degree; ++j) ps.coef[a][j] = seg.coef[a][j];
    try {
      comp.compile(ps, have_end ? &c.end : nullptr, "segment " + std::to_string(st.segments), c);
    } catch (const fd::CompileError& e) {
      throw PlanError(std::string("compile: ") + e.what());
    }
    have_end = true;
    if (st.first_segment < 0) st.first_segment = std::chrono::duration<double>(Clock::now() - t_start).count();
    sink(c, seg);
    ++st.segments;
    st.ticks += seg.K;
  };

  while (true) {
    geo::BSpline b;
    std::string where;
    while (!exhausted && win.size() < so.window) {
      if (src.next(b, where)) {
        win.push_back(std::make_shared<const PathCurve>(b, where));
        wsp.push_back(b);
        ++st.curves;
      } else {
        exhausted = true;
      }
    }
    if (win.empty()) break;
    Path path;
    for (const auto& w : win) path.add(w);
    const bool last = exhausted;
    size_t ncommit = last ? win.size() : std::min(so.commit, win.size() - 1);
    // The commit junction should not be a corner: the next window's first
    // segment must start at the last committed tick, just before the
    // junction, and turn the velocity from there; at a corner (passed at a
    // near-stop within one tick) that can fail where a whole-path fit would
    // have started the turn earlier. The nearest junction without a tangent
    // break is taken instead (earlier first, then later), if there is one;
    // where every junction is a corner (a polyline), the curve after the
    // corner is cut in two inside a knot span (smooth there) and the commit
    // ends at the cut, so the corner itself is fitted within this window.
    if (!last) {
      auto corner_at = [&](size_t i) {  // junction between curves i-1 and i
        const Frame e = frame_at(path, i - 1, path.curve(i - 1).u_end(), path.offset(i));
        const Frame f = frame_at(path, i, path.curve(i).u_begin(), path.offset(i));
        double dot = 0;
        for (int a = 0; a < path.dim(); ++a) dot += e.T[a] * f.T[a];
        return std::acos(std::clamp(dot, -1.0, 1.0)) > cfg.plan.corner_tol;
      };
      if (corner_at(ncommit)) {
        for (size_t d = 1; d < win.size(); ++d) {
          if (ncommit > d && !corner_at(ncommit - d)) {
            ncommit -= d;
            break;
          }
          if (ncommit + d < win.size() && !corner_at(ncommit + d)) {
            ncommit += d;
            break;
          }
        }
      }
      if (corner_at(ncommit)) {
        const geo::BSpline& c = wsp[ncommit];
        const double mid = 0.5 * (c.u_begin() + c.u_end());
        int i = c.degree;
        while (i + 1 < c.n_ctrl() && c.knots[i + 1] <= mid) ++i;
        const double u = 0.5 * (c.knots[i] + c.knots[i + 1]);  // middle of the span holding mid
        auto halves = geo::split_at(c, u);
        const std::string w = win[ncommit]->where;
        auto first = std::make_shared<const PathCurve>(halves.first, w + " (first part)");
        auto second = std::make_shared<const PathCurve>(halves.second, w + " (second part)");
        win[ncommit] = first;
        win.insert(win.begin() + static_cast<long>(ncommit) + 1, second);
        wsp[ncommit] = std::move(halves.first);
        wsp.insert(wsp.begin() + static_cast<long>(ncommit) + 1, std::move(halves.second));
        ++ncommit;
        path = Path();
        for (const auto& x : win) path.add(x);
      }
    }
    const double s_commit = last ? path.length() : path.offset(ncommit);
    PlanOptions po = cfg.plan;
    po.v_start = v_commit;
    if (!last) po.force_stations = {s_commit};
    Plan plan;
    std::vector<TimeSegment> segs;
    double Tc = 0;
    long long k_end = 0;
    const long long k_base = k_last < 0 ? 0 : k_last;
    for (int attempt = 0;; ++attempt) {
      if (attempt > 200) throw PlanError("the limits cannot be met in window " + std::to_string(st.windows));
      plan = plan_path(path, cfg.limits, po);
      check_tick_count(plan.duration(), h, "streaming window " + std::to_string(st.windows) + " (curves from " +
                                              path.entry(0).where + ")");
      if (last) {
        Tc = plan.duration();
      } else {
        double lo = 0, hi = plan.duration();
        for (int it = 0; it < 200 && hi - lo > 1e-15 * (1 + hi); ++it) {
          const double mid = 0.5 * (lo + hi);
          (state_at(plan, mid).s < s_commit ? lo : hi) = mid;
        }
        Tc = hi;
      }
      k_end = k_org + (last ? static_cast<long long>(std::ceil((T0 + Tc) / h - 1e-9))
                            : static_cast<long long>(std::floor((T0 + Tc) / h + 1e-9)));
      ts.clear();
      if (k_last >= 0) ts.push_back(carried);
      append_ticks_range(path, plan, h, T0, k_last + 1, k_end, ts, k_org);
      size_t caps_before = po.caps.size();
      long long lastcap = -1000000;
      for (size_t k = (k_last >= 0 ? 1 : 0); k < ts.size(); ++k) {
        const double q = tick_ratio(ts[k], cfg.limits, path.dim());
        if (q > 1 + 1e-9 && static_cast<long long>(k) > lastcap + 5) {
          const double w = std::max(5 * h * ts[k].v, 1e-9 * path.length()) + 1e-9;
          const double sl = ts[k].s;  // window-local arc length
          po.caps.push_back({sl - w, sl + w, std::max(ts[k].v * 0.95 * std::pow(q, -1.0 / 3.0), 1e-6 * cfg.limits.feed)});
          lastcap = static_cast<long long>(k);
        }
      }
      if (po.caps.size() > caps_before) continue;
      if (ts.size() < 2) break;  // nothing to fit in this window (commit shorter than a tick)
      try {
        segs = fit_segments(path, plan, ts, cfg.limits, sopt, h, T0, k_base);
      } catch (const FitError& e) {
        const long long idx = e.tick - k_base;
        if (idx <= 0 && k_last >= 0)  // at the committed tick: nothing left to slow down
          throw PlanError("streaming window " + std::to_string(st.windows) + " (curves from " + path.entry(0).where +
                          "): the motion committed by the previous window cannot be continued within the limits at "
                          "their junction (" + e.what() + "); plan with a larger window (--window)");
        const TickSample& t = ts[static_cast<size_t>(idx)];
        const double w = std::max(5 * h * t.v, 1e-9 * path.length()) + 1e-9;
        po.caps.push_back({t.s - w, t.s + w, std::max(0.8 * t.v, 1e-6 * cfg.limits.feed)});
        continue;
      }
      break;
    }
    st.caps += po.caps.size();
    st.max_window_ticks = std::max(st.max_window_ticks, ts.size());
    for (const auto& sg : segs) emit(sg);
    // the fitted positions before the committed end: the next window's fit
    // checks its sampled tangential/normal windows across the junction
    {
      auto t = fitted_tail(segs, path.dim(), h, 3);
      auto& hist = sopt.history;
      hist.insert(hist.end(), t.begin(), t.end());
      while (hist.size() > 3) hist.erase(hist.begin());
    }
    if (!ts.empty()) {
      carried = ts.back();
      carried.curve = static_cast<size_t>(-1);
      carried.s = 0;
      k_last = k_end;
    }
    T0 += Tc;
    {
      const double whole = std::floor(T0 / h);
      k_org += static_cast<long long>(whole);
      T0 -= whole * h;
    }
    v_commit = last ? 0 : state_at(plan, Tc).v;
    ++st.windows;
    for (size_t i = 0; i < ncommit; ++i) {
      win.pop_front();
      wsp.pop_front();
    }
    if (progress) progress("stream", static_cast<double>(st.curves));
    if (last) {
      // hold segment: the last sample is the end point
      TimeSegment hold;
      hold.k0 = k_last;
      hold.K = 1;
      hold.degree = cfg.degree;
        for (int a = 0; a < path.dim(); ++a) hold.coef[a][0] = carried.x[a];
      emit(hold);
      break;
    }
  }
  st.motion_time = static_cast<double>(k_org) * h + T0;
  st.wall = std::chrono::duration<double>(Clock::now() - t_start).count();
  return st;
}

}  // namespace traj::plan
