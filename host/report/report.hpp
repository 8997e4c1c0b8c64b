// SPDX-License-Identifier: Apache-2.0
// The report on a job: what the core outputs (the host's exact prediction of
// its samples, or the samples of a simulation) measured against the path and
// the limits, as text and as SVG plots.
#pragma once
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "job/job.hpp"

namespace traj::report {

// The core's output, as integers per tick and axis (OutWidth <= 63 bits).
// One output sample: a value per axis (LSB), the axes beyond the stream's 0.
using Sample = std::array<long long, plan::kMaxAxes>;
struct Samples {
  std::vector<Sample> v;
};

struct Report {
  double motion_time = 0;
  long long ticks = 0;
  size_t segments = 0;
  uint32_t k_min = 0, k_max = 0;
  double max_deviation = 0;  // distance of output samples to the exact curve, units
  // quant: the samples' largest error about the fitted polynomials, units
  // (1/2 LSB + register bound + exact-joint offset); quant_diff: the same
  // without the offset, which moves no second or higher difference
  double fit_tol = 0, quant = 0, quant_diff = 0;
  double feed_fluct_max = 0, feed_fluct_min = 0, feed_fluct_rms = 0;
  // chord between samples / chord between the planned points - 1: the speed
  // error of the output itself (the chord-vs-arc term kappa^2 (v h)^2 / 24 of
  // feed_fluct is the sampling's, not the output's); --feed-accuracy bounds it
  double feed_err_max = 0, feed_err_min = 0, feed_err_rms = 0;
  plan::Peaks plan_peaks, fit_peaks, out_peaks;
  double out_path_v = 0, out_path_a = 0, out_path_j = 0;  // from sample differences (vector norms)
  double allow_v = 0, allow_a = 0, allow_j = 0;           // quantisation allowance on sample differences, per axis
  double allow_path_v = 0;                                // the same for the path speed (vector norm): sqrt(dim) allow_v
  // The largest allowance as a share of its limit. Above Machine::kAllowanceShare
  // the sample-difference check says nothing useful and the report gives the
  // guarantee in its exact form: every sample within sample_bound of the fitted
  // polynomials (sample_to_fit measured), whose per-axis maxima are the fit column.
  double allow_share = 0;
  std::string allow_share_what;
  bool exact_form = false;
  double sample_to_fit = 0, sample_bound = 0;  // units
  double worst_plan = 0, worst_fit = 0, worst_out = 0;
  std::string worst_plan_what, worst_fit_what, worst_out_what;
  int guard_needed = 0;
};

// The host's exact prediction of the core's samples (fd::Compiler::sample_at
// on every compiled segment): bit for bit what the engine outputs, without
// running it (tb/fd and the co-simulations check that identity).
Samples predicted_samples(const job::JobResult& r);

Report make_report(const plan::Path& p, const job::JobConfig& cfg, const job::JobResult& r, const Samples& s);
std::string report_text(const job::JobConfig& cfg, const Report& rep, const job::JobResult& r);
// SVG plots: path coloured by feed; feed, acceleration and jerk against time.
// scale_feed: the top of the path's colour scale (svg::path_svg);
// rapid_curve: a toolpath's curves that are rapid moves (by index in p;
// empty: none known), drawn as rapids.
void write_plots(const std::string& dir, const plan::Path& p, const job::JobConfig& cfg, const job::JobResult& r,
                 const Samples& s, double scale_feed = 0, const std::vector<char>& rapid_curve = {});

// What the plots are drawn from: the output samples, read on demand (a
// stream's samples from a mapped file: `trajcore sim --plots`), and the plan
// at the ticks when there is one (none: the output alone).
struct PlotSource {
  size_t count = 0;
  std::function<Sample(size_t)> sample;
  int axes = 3;
  double lsb = 1;
  bool jerk_claimed = true;
  job::Allowance allowance;
  const std::vector<plan::TickSample>* plan = nullptr;
  double scale_feed = 0;  // the top of the path's colour scale (0: the feed limit)
  bool feed_limited = true;  // false: the path speed has no limit line (sim without --feed)
  std::function<bool(size_t)> rapid_step;  // step k -> k+1 in a rapid move (empty: not known)
};
// path_feed.svg and profile.svg in `dir` (cfg: the tick period, units and limits).
void write_plot_pages(const std::string& dir, const PlotSource& src, const job::JobConfig& cfg);

}  // namespace traj::report
