// SPDX-License-Identifier: Apache-2.0
#include "job/job.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "job/plan_fit.hpp"
#include "util/format.hpp"

namespace traj::job {

using plan::PlanError;
using util::fmt;

void JobConfig::validate() const {
  limits.validate();
  machine.validate();
}

plan::PlanOptions JobConfig::plan_options() const {
  plan::PlanOptions po = plan;
  po.period = machine.fit_period();
  if (machine.fit_ticks() > 1) {
    po.feed_share = std::min(po.feed_share, kFineFeedShare);
    po.corner_stops = true;
    po.corner_rest = 2 * machine.period;
  }
  return po;
}

plan::SegmentOptions JobConfig::segment_options() const {
  plan::SegmentOptions so;
  so.degree = machine.degree;
  so.fine_ticks = machine.fit_ticks();
  so.fine_period = machine.period;
  // in fit ticks; longer polynomials are cut into pieces the compiler takes (engine_pieces)
  so.max_ticks = so.fine_ticks == 1 ? machine.longest_segment() : kMaxFitTicks;
  so.fit_tol = machine.fit_budget(limits.tol);
  // each tick within feed_rel of its travel: the chord between two ticks
  // within 2 feed_rel of the planned arc; where the fit tick is coarser than
  // the engine's, the fit's velocity error keeps the chords within 2
  // feed_rel of the plan's, by default 2e-3 (fit_segments_fine)
  if (so.fine_ticks > 1) so.feed_rel = kFineFeedRel;
  if (machine.feed_accuracy > 0) {
    so.feed_rel = machine.feed_accuracy / 2;
    so.feed_bound = true;
    const fd::Format f = machine.format();
    const int d = f.axes;
    // the samples' error on a chord: the allowance of the first differences (sample_allowance), over a tick
    const double lsb = machine.lsb();
    so.feed_quant = std::sqrt(static_cast<double>(d)) * machine.period *
                    sample_allowance(Machine::sample_error_lsb(f) * lsb, Machine::joint_lsb(f) * lsb, machine.period).v;
    // the report's feed figures start at 1 % of the top speed (as the fit's checks): half the bound there at most
    const double v_floor = limits.feed_floor(d), chord = v_floor * machine.period;
    if (so.feed_quant > 0.5 * machine.feed_accuracy * chord)
      throw PlanError("feed accuracy " + fmt("%g", machine.feed_accuracy) + ": the output's rounding (" +
                      fmt("%.3g", so.feed_quant) + " " + machine.units + " on a chord) is more than half of it on the " +
                      fmt("%.3g", chord) + " " + machine.units +
                      " chord at 1 % of the top speed; give a larger bound, a longer tick or a wider --engine-width");
  }
  return so;
}

void check_tick_count(double duration, double period, const std::string& what) {
  const double n = std::ceil(duration / period);
  if (!(n <= kMaxPlanTicks))
    throw PlanError(what + ": motion of " + fmt("%.4g", duration) + " s is " + fmt("%.4g", n) + " ticks at " +
                    fmt("%g", period) + " s per tick, more than one plan holds (" + fmt("%.0f", kMaxPlanTicks) +
                    " ticks, about 2 GB); stream it in windows of bounded ticks (trajcore plan FILE --window 64 -o" +
                    " plan.trj, then trajcore sim plan.trj --check --plots DIR), raise the feed or the limits, or" +
                    " use a longer tick period");
}

void check_path_range(const plan::Path& p, const Machine& m) {
  for (size_t i = 0; i < p.size(); ++i) m.check_range(p.curve(i).spline(), p.entry(i).where);
}

SegmentCompiler::SegmentCompiler(const Machine& m) : comp_(m.format()) {
  const fd::Format f = m.format();
  ps_.h = m.period;
  ps_.coef.assign(f.axes, std::vector<double>(f.degree + 1, 0.0));
  joint_bound_ = Machine::joint_lsb(f);
}

void SegmentCompiler::load(const plan::TimeSegment& seg) {
  ps_.ticks = seg.K;
  for (size_t a = 0; a < ps_.coef.size(); ++a)
    for (size_t j = 0; j < ps_.coef[a].size(); ++j) ps_.coef[a][j] = seg.coef[a][j];
}

double SegmentCompiler::quant_bound(uint32_t K) {
  if (K >= qbound_.size()) qbound_.resize(K + 1, -1.0);
  if (qbound_[K] < 0) qbound_[K] = comp_.quant_bound_lsb(K);  // exact, in GMP: once per length
  return qbound_[K];
}

double SegmentCompiler::joint_lsb(const plan::TimeSegment& seg) const {
  const fd::Format& f = comp_.format();
  // long double (64-bit significand): each Horner step and the difference
  // round by at most 2^-64 relative, the product h K too, so 64 2^-64 of the
  // terms' magnitudes bounds the error with room to spare.
  const long double T_prev = static_cast<long double>(ps_.h) * static_cast<long double>(prev_.K);
  const long double lsb_units = std::ldexp(1.0L, f.frac_bits);
  double joint = 0;
  for (int a = 0; a < f.axes; ++a) {
    long double end = 0, mag = 0;
    for (int j = f.degree; j >= 0; --j) {
      end = end * T_prev + static_cast<long double>(prev_.coef[a][j]);
      mag = mag * T_prev + std::fabs(static_cast<long double>(prev_.coef[a][j]));
    }
    const long double start = seg.coef[a][0];
    const long double err = std::ldexp(64.0L * (mag + std::fabs(start)), -64);
    joint = std::max(joint, static_cast<double>((std::fabs(end - start) + err) * lsb_units));
  }
  return joint;
}

void SegmentCompiler::compile_joined(const plan::TimeSegment& seg, const std::string& where) {
  const double joint = joint_lsb(seg);
  if (joint > joint_bound_)
    throw fd::CompileError(where + ": starts " + util::fmt("%g", joint) +
                           " LSB from where the previous segment's polynomial ends (more than " +
                           util::fmt("%g", joint_bound_) + "): the path is not continuous here");
  // The start is the previous segment's exact register end: within that
  // segment's Q(K) of its polynomial's end (the blend of its own start is 0
  // there), and that end within `joint` of this polynomial's start. The
  // compiler blends the whole difference out linearly, as the carried error
  // always is; it is stated here in its two parts: the carried error, which
  // the register bound counts, and the joint (offset_lsb), which moves
  // positions and first differences only.
  const double carried = quant_bound(prev_.K);
  load(seg);
  comp_.compile(ps_, &c_.end, where, c_, joint_bound_);
  c_.carried_lsb = carried;
  c_.bound_lsb = carried + quant_bound(seg.K);
  c_.offset_lsb = joint;
}

const fd::Compiled& SegmentCompiler::compile(const plan::TimeSegment& seg, size_t index) {
  const std::string where = "segment " + std::to_string(index);
  try {
    if (have_end_) {
      compile_joined(seg, where);
    } else {
      load(seg);
      comp_.compile(ps_, have_end_ ? &c_.end : nullptr, where, c_);
    }
  } catch (const fd::CompileError& e) {
    throw PlanError(std::string("compile: ") + e.what());
  }
  have_end_ = true;
  prev_ = seg;
  return c_;
}

void mark_pauses(std::vector<plan::TimeSegment>& segs, const std::vector<plan::TickSample>& ts, long long k_base,
                 int n, const std::vector<JobConfig::PauseAt>& pauses, double length) {
  const double tol = 1e-9 * std::max(1.0, length);
  auto rests_at = [&](size_t i, double s) { return std::fabs(ts[i].v) < 1e-9 && std::fabs(ts[i].s - s) <= tol; };
  for (const JobConfig::PauseAt& pz : pauses) {
    size_t i = 0;
    while (i < ts.size() && !rests_at(i, pz.s)) ++i;
    size_t j = i;
    while (j + 1 < ts.size() && rests_at(j + 1, pz.s)) ++j;
    // the segment's last sample (the one the board holds while it waits)
    // and the next segment's first both within the rest
    const long long lo = (k_base + static_cast<long long>(i)) * n, hi = (k_base + static_cast<long long>(j)) * n;
    auto ends_in_rest = [&](const plan::TimeSegment& sg) {
      const long long e = sg.k0 + static_cast<long long>(sg.K);
      return e - 1 >= lo && e <= hi;
    };
    const auto it = i < ts.size() ? std::find_if(segs.begin(), segs.end(), ends_in_rest) : segs.end();
    if (it == segs.end())
      throw PlanError("program pause at line " + std::to_string(pz.pause.line) + " (arc length " + util::num(pz.s) +
                      "): no segment of the fit ends where the plan rests there");
    it->pause = pz.pause;
  }
}

std::vector<stream::Pause> pauses_of(const JobResult& r) {
  std::vector<stream::Pause> v;
  for (size_t i = 0; i + 1 < r.segments.size(); ++i)
    if (const plan::ProgramPause& p = r.segments[i].pause)
      v.push_back({i + 1, static_cast<uint32_t>(p.line), p.text});
  return v;
}

void engine_pieces(const plan::TimeSegment& seg, uint32_t kmax, double h, std::vector<plan::TimeSegment>& out) {
  const uint64_t K = seg.K;
  const uint64_t pieces = (K + kmax - 1) / kmax;
  for (uint64_t i = 0; i < pieces; ++i) {
    // equal pieces (lengths differ by at most one tick): no short remainder
    const uint64_t a = K * i / pieces, b = K * (i + 1) / pieces;
    plan::TimeSegment p = seg;
    p.k0 = seg.k0 + static_cast<long long>(a);
    p.K = static_cast<uint32_t>(b - a);
    if (i + 1 < pieces) {  // the pause follows the last piece
      p.pause = {};
    }
    if (a > 0) {
      // Taylor shift to tau0 = a h by repeated synthetic division
      const double tau0 = static_cast<double>(a) * h;
      for (int ax = 0; ax < plan::kMaxAxes; ++ax) {
        auto& c = p.coef[ax];
        for (int i0 = 0; i0 < seg.degree; ++i0)
          for (int j = seg.degree - 1; j >= i0; --j) c[j] += tau0 * c[j + 1];
      }
    }
    out.push_back(p);
  }
}

plan::TimeSegment hold_segment(long long k0, const double* x, int dim, int degree) {
  plan::TimeSegment hold;
  hold.k0 = k0;
  hold.K = 1;
  hold.degree = degree;
  for (int a = 0; a < dim; ++a) hold.coef[a][0] = x[a];
  return hold;
}

JobResult run_job(const plan::Path& p, const JobConfig& cfg, const Progress& progress) {
  using Clock = std::chrono::steady_clock;
  cfg.validate();
  const Machine& m = cfg.machine;
  check_path_range(p, m);  // before the planner's arc-length grid, whose size grows with the extent
  JobResult r;
  PlanFitRequest req;
  req.path = &p;
  req.limits = &cfg.limits;
  req.options = cfg.plan_options();
  req.segments = cfg.segment_options();
  req.what = "the path";
  const double H = m.fit_period();
  const int n = m.fit_ticks();
  // every round samples into the same buffer (the samples are most of a whole path's memory)
  req.sample = [&](const plan::Plan& plan, std::vector<plan::TickSample>& ts) { plan::sample_ticks(p, plan, H, ts); };
  req.progress = progress;
  r.fit_tol = req.segments.fit_tol;
  PlanFitResult fit = plan_and_fit(req, r.ticks);
  r.plan = std::move(fit.plan);
  r.repairs = static_cast<int>(fit.repairs);
  r.rounds = fit.rounds;
  r.check_frames = fit.check_frames;
  r.moves_searched = fit.moves_searched;
  r.moves_reused = fit.moves_reused;
  r.fit_ticks = fit.fit_ticks;
  r.fit_failures = fit.fit_failures;
  mark_pauses(fit.segments, r.ticks, 0, m.fit_ticks(), cfg.pauses, p.length());
  const long long last = (static_cast<long long>(r.ticks.size()) - 1) * n;  // the end, on the engine's tick
  const uint32_t kmax = m.longest_segment();
  r.segments.reserve(fit.segments.size() + 1);
  for (const plan::TimeSegment& s : fit.segments) engine_pieces(s, kmax, m.period, r.segments);
  r.segments.push_back(hold_segment(last, r.ticks.back().x, p.dim(), m.degree));
  r.engine_tick_count = static_cast<uint64_t>(last) + 1;
  r.plan_peaks = plan::peaks_of(r.ticks, p.dim());
  if (n > 1 && cfg.engine_ticks) {
    std::vector<plan::TickSample>().swap(r.ticks);  // the fit's samples go before the engine's come
    plan::append_ticks_range(p, r.plan, m.period, 0.0, 0, last, r.ticks);
  }

  const auto t3 = Clock::now();
  SegmentCompiler sc(m);
  r.compiled.reserve(r.segments.size());
  for (size_t i = 0; i < r.segments.size(); ++i) {
    r.compiled.push_back(sc.compile(r.segments[i], i));
    if (progress && (i % 1024 == 0)) progress("compile", double(i) / r.segments.size());
  }
  r.header = m.header();
  r.t_plan = fit.t_plan;
  r.t_ticks = fit.t_ticks;
  r.t_fit = fit.t_fit;
  r.t_compile = std::chrono::duration<double>(Clock::now() - t3).count();
  if (progress) progress("done", 1);
  return r;
}

std::vector<stream::Record> records_of(const JobResult& r) {
  std::vector<stream::Record> v;
  v.reserve(r.compiled.size());
  for (const auto& c : r.compiled) v.push_back({c.ticks, c.regs});
  return v;
}

}  // namespace traj::job
