// SPDX-License-Identifier: Apache-2.0
#include "report/report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "fd/fd_ticker.hpp"
#include "planner/sampled.hpp"
#include "report/sample_check.hpp"
#include "util/format.hpp"

namespace traj::report {

using namespace plan;
using job::JobConfig;
using job::JobResult;
using util::fmt;

Samples predicted_samples(const JobResult& r) {
  Samples s;
  const int axes = std::min(kMaxAxes, r.header.axes);
  fd::FdTicker t(r.header.width, r.header.guard_bits);
  size_t n = 0;
  for (const auto& c : r.compiled) n += c.ticks;
  s.v.reserve(n);
  for (size_t i = 0; i < r.compiled.size(); ++i) {
    const fd::Compiled& c = r.compiled[i];
    t.load(c.regs);
    for (uint32_t k = 0; k < c.ticks; ++k) {
      Sample v{};
      for (int a = 0; a < axes; ++a) v[a] = t.sample_and_step(a);
      s.v.push_back(v);
    }
    // the recurrence against the compiler's closed form of the end state
    for (int a = 0; a < axes; ++a)
      if (!t.holds(a, c.end[a]))
        throw std::logic_error("predicted_samples: segment " + std::to_string(i) + " axis " + std::to_string(a) +
                               " ends off the compiler's end state");
  }
  return s;
}

namespace {

// The largest distance of a sample from its fitted polynomial, evaluated in
// long double (64-bit significand: a rounding error below 1e-3 LSB at 2^-48
// and |x| < 2^15), and the bound the compiler proves for it: 1/2 LSB of
// output rounding plus the register error bound of the segment.
void sample_to_fit(const JobResult& r, const Samples& s, double h, double lsb, Report& rep) {
  size_t k = 0;
  const int axes = std::min(3, r.header.axes);
  for (size_t i = 0; i < r.segments.size() && i < r.compiled.size(); ++i) {
    const plan::TimeSegment& sg = r.segments[i];
    for (uint32_t t = 0; t < sg.K && k < s.v.size(); ++t, ++k)
      for (int a = 0; a < axes; ++a) {
        const long double tau = static_cast<long double>(t) * h;
        long double x = 0;
        for (int j = sg.degree; j >= 0; --j) x = x * tau + sg.coef[a][j];
        const long double e = std::fabs(static_cast<long double>(s.v[k][a]) * lsb - x);
        rep.sample_to_fit = std::max(rep.sample_to_fit, static_cast<double>(e));
      }
    // + 1e-6 LSB: the long double evaluation's rounding, far above its size
    rep.sample_bound =
        std::max(rep.sample_bound, (0.5 + r.compiled[i].bound_lsb + r.compiled[i].offset_lsb + 1e-6) * lsb);
  }
}

// Largest, smallest and RMS of a series (all 0 for an empty one).
struct Spread {
  double max = -1e300, min = 1e300, sum2 = 0;
  long long n = 0;
  void add(double v) {
    max = std::max(max, v);
    min = std::min(min, v);
    sum2 += v * v;
    ++n;
  }
  void into(double& mx, double& mn, double& rms) const {
    mx = n ? max : 0;
    mn = n ? min : 0;
    rms = n ? std::sqrt(sum2 / n) : 0;
  }
};

}  // namespace

Report make_report(const Path& p, const JobConfig& cfg, const JobResult& r, const Samples& s) {
  Report rep;
  const int d = p.dim();
  const double h = cfg.machine.period;
  const double lsb = std::ldexp(1.0, -r.header.frac_bits);
  rep.ticks = static_cast<long long>(s.v.size());
  rep.motion_time = (rep.ticks - 1) * h;
  rep.segments = r.segments.size();
  rep.k_min = ~0u;
  for (const auto& sg : r.segments) {
    rep.k_min = std::min(rep.k_min, sg.K);
    rep.k_max = std::max(rep.k_max, sg.K);
  }
  rep.fit_tol = r.fit_tol;
  double bound = 0;
  double offset = 0;
  for (const auto& c : r.compiled) {
    bound = std::max(bound, c.bound_lsb);
    offset = std::max(offset, c.offset_lsb);
  }
  rep.quant = (0.5 + bound + offset) * lsb;
  rep.quant_diff = (0.5 + bound) * lsb;
  rep.guard_needed = fd::Compiler::guard_bits_needed(r.header.degree, rep.k_max, cfg.machine.format().tol_lsb);
  rep.plan_peaks = r.plan_peaks ? *r.plan_peaks : peaks_of(r.ticks, d);
  rep.worst_plan = worst_ratio(rep.plan_peaks, cfg.limits, d, &rep.worst_plan_what);
  for (const auto& sg : r.segments) {
    const SegmentPeaks pk = segment_peaks(sg, d, h);
    for (int a = 0; a < d; ++a) {
      rep.fit_peaks.v_axis[a] = std::max(rep.fit_peaks.v_axis[a], pk.v[a]);
      rep.fit_peaks.a_axis[a] = std::max(rep.fit_peaks.a_axis[a], pk.a[a]);
      rep.fit_peaks.j_axis[a] = std::max(rep.fit_peaks.j_axis[a], pk.j[a]);
    }
  }
  // output samples
  const size_t n = s.v.size();
  std::vector<std::array<double, kMaxAxes>> x(n);
  for (size_t k = 0; k < n; ++k)
    for (int a = 0; a < kMaxAxes; ++a) x[k][a] = static_cast<double>(s.v[k][a]) * lsb;
  // distance to the exact curve: Newton on (C(u) - x).C'(u) = 0 from the planned u, keeping the
  // nearest point it visits (the planned point is one: a step that overshoots along a curve whose
  // parametric speed changes fast, as a run over thousands of tiny CAM chords, may land on a far part
  // of it and converge there)
  for (size_t k = 0; k < n && k < r.ticks.size(); ++k) {
    const geo::Curve& c = p.curve(r.ticks[k].curve);
    double u = r.ticks[k].u;
    double buf[3 * kMaxAxes];
    double best2 = std::numeric_limits<double>::infinity();
    for (int it = 0; it <= 8; ++it) {
      c.eval(u, 2, buf);
      double e2 = 0, f = 0, fp = 0;
      for (int a = 0; a < d; ++a) {
        const double e = buf[a] - x[k][a];
        e2 += e * e;
        f += e * buf[d + a];
        fp += buf[d + a] * buf[d + a] + e * buf[2 * d + a];
      }
      best2 = std::min(best2, e2);
      if (it == 8 || fp <= 0) break;
      const double un = std::clamp(u - f / fp, c.u_begin(), c.u_end());
      if (un == u) break;
      u = un;
    }
    rep.max_deviation = std::max(rep.max_deviation, std::sqrt(best2));
  }
  // per tick where the path moves: feed fluctuation (the output's chord over
  // the planned arc) and feed error (over the planned points' chord)
  Spread fluct, err;
  for (size_t k = 0; k + 1 < n && k + 1 < r.ticks.size(); ++k) {
    const double ds = r.ticks[k + 1].s - r.ticks[k].s;
    if (ds < cfg.limits.feed_floor(d) * h) continue;
    double c2 = 0, p2 = 0;
    for (int a = 0; a < d; ++a) {
      c2 += (x[k + 1][a] - x[k][a]) * (x[k + 1][a] - x[k][a]);
      p2 += (r.ticks[k + 1].x[a] - r.ticks[k].x[a]) * (r.ticks[k + 1].x[a] - r.ticks[k].x[a]);
    }
    fluct.add(std::sqrt(c2) / ds - 1);
    if (p2 > 0) err.add(std::sqrt(c2 / p2) - 1);
  }
  fluct.into(rep.feed_fluct_max, rep.feed_fluct_min, rep.feed_fluct_rms);
  err.into(rep.feed_err_max, rep.feed_err_min, rep.feed_err_rms);
  // the limits on the samples (sample_check.hpp)
  SampleCheck check(d, lsb, h);
  for (const Sample& v : s.v) check.add(v);
  check.finish();
  rep.out_peaks = check.peaks();
  rep.out_path_v = rep.out_peaks.feed;
  rep.out_path_a = check.path_a();
  rep.out_path_j = check.path_j();
  const job::Allowance al = job::sample_allowance(rep.quant_diff, rep.quant - rep.quant_diff, h);
  rep.allow_v = al.v;
  rep.allow_a = al.a;
  rep.allow_j = al.j;
  rep.allow_path_v = std::sqrt(static_cast<double>(d)) * rep.allow_v;
  {
    const job::AllowanceShare sh = job::allowance_share(al, cfg.limits, d, r.header.degree);
    rep.allow_share = sh.share;
    rep.allow_share_what = sh.limit;
    rep.exact_form = sh.share > job::Machine::kAllowanceShare;
  }
  sample_to_fit(r, s, h, lsb, rep);
  // tangential and normal (centripetal) quantities of the fitted polynomials
  // at the ticks (sampled.hpp; the samples' own are SampleCheck's)
  const bool jerk_claimed = r.header.degree == 5;
  // From the steps x(k+1) - x(k): each window's positions relative to its
  // first tick, rounded at the scale of the window's travel (absolute
  // coordinates would round the fitted polynomials' third differences to
  // noise at 1 us ticks).
  auto sampled_peaks = [&](const std::vector<std::array<double, kMaxAxes>>& step, double min_chord, Peaks& pk) {
    for (size_t k = 0; k + 1 < step.size(); ++k) {
      double p[4][kMaxAxes] = {};
      const size_t m = std::min<size_t>(3, step.size() - k);
      for (size_t i = 0; i < m; ++i)
        for (int a = 0; a < d; ++a) p[i + 1][a] = p[i][a] + step[k + i][a];
      const SampledWindow w = sampled_window(p[0], p[1], p[2], m == 3 ? p[3] : nullptr, d, h, min_chord);
      pk.a_tan = std::max(pk.a_tan, w.at);
      pk.a_cen = std::max(pk.a_cen, w.an);
      pk.j_tan = std::max(pk.j_tan, w.jt);
      pk.j_cen = std::max(pk.j_cen, w.jn);
    }
  };
  {
    // each segment's steps from its travel (q(tau) - q(0)); a join's step is
    // the rest of one segment's travel, the next one starting where it ends
    std::vector<std::array<double, kMaxAxes>> step;
    step.reserve(n);
    // (in long double: a step of a long segment at 1 us is a difference of
    // travels a million times larger)
    for (const auto& sg : r.segments) {
      long double prev[kMaxAxes] = {};
      for (uint32_t k = 1; k <= sg.K; ++k) {
        std::array<double, kMaxAxes> q{};
        for (int a = 0; a < d; ++a) {
          const long double t = sg.travel_ld(a, static_cast<long double>(k) * h);
          q[a] = static_cast<double>(t - prev[a]);
          prev[a] = t;
        }
        step.push_back(q);
      }
    }
    sampled_peaks(step, 1e-9 * cfg.limits.top_speed(d) * h, rep.fit_peaks);
  }
  const Worst worst = worst_of_samples(rep.out_peaks, al, cfg.limits, d, jerk_claimed);
  rep.worst_out = worst.ratio;
  rep.worst_out_what = worst.what;
  // the fit: per-axis exact maxima, tangential/normal at the ticks
  {
    Peaks f = rep.fit_peaks;
    Limits lim = cfg.limits;
    lim.feed = 1e300;
    if (!jerk_claimed) {
      for (int a = 0; a < kMaxAxes; ++a) f.j_axis[a] = 0;
      f.j_tan = f.j_cen = 0;
    }
    rep.worst_fit = worst_ratio(f, lim, d, &rep.worst_fit_what);
  }
  return rep;
}

std::string report_text(const JobConfig& cfg, const Report& rep, const JobResult& r) {
  std::ostringstream o;
  const auto& L = cfg.limits;
  const int d = r.ticks.empty() ? 0 : 2 + (std::fabs(r.ticks.front().x[2]) > 0 || L.v_axis[2] < 0);
  (void)d;
  o << "Plan\n";
  o << "  path length          " << fmt("%.6f", r.plan.length) << " " << cfg.machine.units << "\n";
  o << "  motion time          " << fmt("%.4f", rep.motion_time) << " s (" << rep.ticks << " samples at "
    << fmt("%g", cfg.machine.period * 1e3) << " ms)\n";
  o << "  stations             " << r.plan.stations.size() << " (" << r.plan.refinements << " added by refinement, "
    << r.plan.grid_points << " grid points, " << r.repairs << " local speed caps from tick checks and the fit, "
    << r.rounds << (r.rounds == 1 ? " plan" : " plans") << "; exact checks of moves on the tick grid "
    << fmt("%.3g", static_cast<double>(r.check_frames)) << " frames, "
    << fmt("%.3g", static_cast<double>(r.check_frames) / std::max<long long>(rep.ticks, 1)) << " per sample"
    << (r.rounds > 1 && r.moves_searched > 0 ? ", " + std::to_string(r.moves_reused) + " of " +
                           std::to_string(r.moves_reused + r.moves_searched) +
                           " curved moves' searches taken from an earlier plan"
                     : std::string())
    << ")\n";
  o << "  segments             " << rep.segments << " (K " << rep.k_min << ".." << rep.k_max << " ticks, degree "
    << r.header.degree << ")\n";
  o << "  engine format        Width " << r.header.width << ", Guard " << r.header.guard_bits << " (K_max "
    << rep.k_max << " needs " << rep.guard_needed << "), output " << (r.header.width - r.header.guard_bits)
    << " bits, 1 LSB = 2^-" << r.header.frac_bits << " " << cfg.machine.units << "\n";
  {
    const long long rec = static_cast<long long>(stream::record_size(r.header, stream::RecordKind::kFd));
    const long long bytes = stream::kHeaderBytes + static_cast<long long>(rep.segments) * rec + stream::kEndBytes;
    o << "  segment stream       " << bytes << " bytes (" << rec << " per segment: " << r.header.axes << " axes x "
      << (r.header.degree + 1) << " registers x " << r.header.width
      << " bits + 128 bits of type, K, sequence number and CRC; "
      << fmt("%.1f", 8.0 * bytes / std::max(1.0, rep.motion_time)) << " bit/s of motion)\n";
  }
  o << "Accuracy (output samples of the core)\n";
  o << "  max distance to the exact curve  " << fmt("%.4g", rep.max_deviation) << " " << cfg.machine.units << "  (tolerance "
    << fmt("%g", L.tol) << ": fit " << fmt("%.4g", rep.fit_tol) << " + quantisation " << fmt("%.3g", rep.quant)
    << ")\n";
  o << "  feed fluctuation (chord / planned arc - 1)  max " << fmt("%+.3e", rep.feed_fluct_max) << "  min "
    << fmt("%+.3e", rep.feed_fluct_min) << "  RMS " << fmt("%.3e", rep.feed_fluct_rms) << "\n";
  o << "  feed error (chord / planned chord - 1)      max " << fmt("%+.3e", rep.feed_err_max) << "  min "
    << fmt("%+.3e", rep.feed_err_min) << "  RMS " << fmt("%.3e", rep.feed_err_rms)
    << (cfg.machine.feed_accuracy > 0 ? "  (--feed-accuracy " + fmt("%g", cfg.machine.feed_accuracy) + ")" : std::string())
    << "\n";
  o << "Limits            limit       plan peak   fit peak    output peak (sample differences)\n";
  for (int a = 0; a < kMaxAxes; ++a) {
    if (rep.plan_peaks.v_axis[a] == 0 && rep.out_peaks.v_axis[a] == 0) continue;
    const std::string ax = L.axis(a);
    o << "  v_" << ax << "           " << fmt("%10.4g", L.v_axis[a]) << "  " << fmt("%10.4g", rep.plan_peaks.v_axis[a])
      << "  " << fmt("%10.4g", rep.fit_peaks.v_axis[a]) << "  " << fmt("%10.4g", rep.out_peaks.v_axis[a]) << "\n";
    o << "  a_" << ax << "           " << fmt("%10.4g", L.a_axis[a]) << "  " << fmt("%10.4g", rep.plan_peaks.a_axis[a])
      << "  " << fmt("%10.4g", rep.fit_peaks.a_axis[a]) << "  " << fmt("%10.4g", rep.out_peaks.a_axis[a]) << "\n";
    o << "  j_" << ax << "           " << fmt("%10.4g", L.j_axis[a]) << "  " << fmt("%10.4g", rep.plan_peaks.j_axis[a])
      << "  " << fmt("%10.4g", rep.fit_peaks.j_axis[a]) << "  " << fmt("%10.4g", rep.out_peaks.j_axis[a]) << "\n";
  }
  o << "  feed          " << fmt("%10.4g", L.feed) << "  " << fmt("%10.4g", rep.plan_peaks.feed) << "              "
    << fmt("%10.4g", rep.out_path_v) << "\n";
  const bool jerk = r.header.degree == 5;
  auto row = [&](const char* name, double lim, double plan, double fit, double out, bool claimed) {
    o << "  " << name << fmt("%10.4g", lim) << "  " << fmt("%10.4g", plan) << "  " << fmt("%10.4g", fit) << "  "
      << fmt("%10.4g", out) << (claimed ? "" : "   (not limited: cubic segments join C1)") << "\n";
  };
  row("a_tangential  ", L.a_tan, rep.plan_peaks.a_tan, rep.fit_peaks.a_tan, rep.out_peaks.a_tan, true);
  row("j_tangential  ", L.j_tan, rep.plan_peaks.j_tan, rep.fit_peaks.j_tan, rep.out_peaks.j_tan, jerk);
  row("a_centripetal ", L.a_cen, rep.plan_peaks.a_cen, rep.fit_peaks.a_cen, rep.out_peaks.a_cen, true);
  row("j_centripetal ", L.j_cen, rep.plan_peaks.j_cen, rep.fit_peaks.j_cen, rep.out_peaks.j_cen, jerk);
  o << "  (tangential: chord speed and its differences; centripetal: normal part of the 2nd/3rd difference;\n"
       "   plan: kappa v^2 and |Q| v^3 + 3 kappa v |a|"
    << (cfg.machine.fit_ticks() > 1 ? ", at the fit ticks (" + std::to_string(cfg.machine.fit_ticks()) +
                                          " engine ticks apart), where the plan is checked"
                                    : std::string())
    << "; fit: the fitted polynomials at the ticks)\n";
  o << "  |a|, |j| of the path (output, for information; the per-axis limits apply) " << fmt("%.4g", rep.out_path_a)
    << ", " << fmt("%.4g", rep.out_path_j) << "\n";
  o << "  quantisation allowance on sample differences (per axis; sqrt(axes) x for path quantities): v "
    << fmt("%.3g", rep.allow_v) << ", a " << fmt("%.3g", rep.allow_a) << ", j " << fmt("%.3g", rep.allow_j) << " ("
    << fmt("%.2g", 100 * rep.allow_share) << " % of the " << rep.allow_share_what << " limit, the largest share)\n";
  o << "  samples to the fitted polynomials  " << fmt("%.3g", rep.sample_to_fit) << " " << cfg.machine.units
    << " (bound " << fmt("%.3g", rep.sample_bound) << ": 1/2 LSB + the register error bound"
    << (rep.quant > rep.quant_diff ? " + the exact joints' offset" : "") << ")\n";
  if (rep.exact_form)
    o << "  guarantee (exact form): the allowance is above " << fmt("%g", 100 * job::Machine::kAllowanceShare)
      << " % of a limit at this tick period and output LSB,\n"
         "   so the output column is not checked against the limits. Instead: every sample is within the bound\n"
         "   above of the fitted polynomials (checked), whose per-axis v, a, j are the fit column (exact maxima\n"
         "   over each segment; tangential and centripetal at the ticks), within the limits (checked)\n";
  o << "  worst peak/limit: plan " << fmt("%.4f", rep.worst_plan) << " (" << rep.worst_plan_what << "), fit "
    << fmt("%.4f", rep.worst_fit) << " (" << rep.worst_fit_what << "), output " << fmt("%.4f", rep.worst_out) << " ("
    << rep.worst_out_what << (rep.exact_form ? ", after the allowance; not checked: exact form)\n" : ", after the allowance)\n");
  o << "Host time: plan " << fmt("%.1f", r.t_plan * 1e3) << " ms, ticks " << fmt("%.1f", r.t_ticks * 1e3)
    << " ms, fit " << fmt("%.1f", r.t_fit * 1e3) << " ms, compile " << fmt("%.1f", r.t_compile * 1e3) << " ms\n";
  return o.str();
}

}  // namespace traj::report
