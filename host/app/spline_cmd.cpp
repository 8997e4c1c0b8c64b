// SPDX-License-Identifier: Apache-2.0
// trajcore spline: [BCU]'s C1 interpolating cubic Bezier spline (eq. 9,
// host/bcu/bezier_spline.hpp) through the points of a JSON file, compiled for
// traj_core as BCU segments (or, --engine mixed, odd segments as FD), chained
// exactly (traj::bcu::MixedChain), written as a segment stream with a BCU format.
//
// Points file: {"points": [[x, y], ...]} or [[x, y, z], ...] (2 or 3 axes, all
// rows alike; z = 0 for 2 axes), N >= 2 points P_1..P_N to pass through. The
// paper's extra end points are extrapolated: P_0 = 2 P_1 - P_2,
// P_{N+1} = 2 P_N - P_{N-1}. Segment i joins P_i and P_{i+1}.
//
// Timing: segment i takes K_i = 2^d_i ticks with u linear in time. With
// --feed F the speed never exceeds F: the hodograph of a cubic Bezier is the
// quadratic Bezier on 3 (b_{k+1} - b_k), so |dx/dt| <= 3 max_k |b_{k+1} - b_k|
// / (K h) (convex hull); d_i is the least d with that <= F. --depth d fixes it.
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "bcu/bezier_spline.hpp"
#include "bcu/chain.hpp"
#include "demo.hpp"
#include "geometry/json_io.hpp"
#include "sim/sim.hpp"
#include "stream/segment_stream.hpp"
#include "util/tick_period.hpp"

namespace traj::app {

using namespace traj::sim;
namespace {

[[noreturn]] void bad(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

Eigen::MatrixXd load_points(const std::string& path) {
  const nlohmann::json doc = geo::load_json_file(path);
  if (!doc.is_object() || !doc.contains("points")) bad(path, "expected an object with a \"points\" array");
  const auto& pts = doc["points"];
  if (!pts.is_array()) bad(path, "points: expected an array of points");
  if (pts.size() < 2) bad(path, "points: " + std::to_string(pts.size()) + " point(s); the spline needs at least 2");
  size_t axes = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const std::string w = "points[" + std::to_string(i) + "]";
    if (!pts[i].is_array()) bad(path, w + ": expected an array of 2 or 3 numbers");
    if (i == 0) axes = pts[i].size();
    if (pts[i].size() != axes || axes < 2 || axes > 3)
      bad(path, w + ": " + std::to_string(pts[i].size()) + " coordinates; every point needs the same 2 or 3 (points[0] has " +
                    std::to_string(axes) + ")");
    for (size_t c = 0; c < axes; ++c)
      if (!pts[i][c].is_number())
        bad(path, w + "[" + std::to_string(c) + "]: expected a number, got " + pts[i][c].type_name());
  }
  const int n = static_cast<int>(pts.size());
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(n + 2, 3);
  for (int i = 0; i < n; ++i)
    for (size_t c = 0; c < axes; ++c) p(i + 1, static_cast<int>(c)) = pts[i][c].get<double>();
  for (int i = 1; i <= n; ++i)
    if (i > 1 && (p.row(i) - p.row(i - 1)).norm() == 0)
      bad(path, "points[" + std::to_string(i - 1) + "] repeats the point before it (a segment of length zero)");
  p.row(0) = 2 * p.row(1) - p.row(2);
  p.row(n + 1) = 2 * p.row(n) - p.row(n - 1);
  return p;
}

}  // namespace

int run_spline(const SplineOptions& opt) {
  if (opt.engine != "bcu" && opt.engine != "mixed")
    throw std::invalid_argument("--engine " + opt.engine + ": expected bcu or mixed");
  if (!has_core()) throw std::runtime_error("this trajcore was built without host/bcu: no BCU segments");
  if (!(opt.feed > 0) || !std::isfinite(opt.feed)) throw std::invalid_argument("--feed must be positive and finite");
  if (const std::string m = util::tick_period_problem(opt.period); !m.empty()) throw std::invalid_argument("--period: " + m);
  const Build& core = carried("core");
  const fd::Format ff = core.fd_format(opt.frac_bits);
  const bcu::Format bf = core.bcu_format(opt.frac_bits);
  if (opt.depth > bf.max_depth)
    throw std::invalid_argument("--depth " + std::to_string(opt.depth) + " out of range 0.." +
                                std::to_string(bf.max_depth) + " (MaxDepth)");

  const Eigen::MatrixXd p = load_points(opt.input);
  const double mu = opt.mu < 0 ? opt.lambda : opt.mu;
  std::vector<bcu::BezierSegment> spl;
  try {
    spl = bcu::c1_spline(p, opt.lambda, mu);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(opt.input + ": " + e.what());
  }

  bcu::MixedChain chain(ff, bf);
  uint64_t ticks = 0;
  double vmax = 0;
  int dmin = 99, dmax = -1;
  for (size_t i = 0; i < spl.size(); ++i) {
    const bcu::Controls b = spl[i].transpose();
    const std::string where = opt.input + ": segment " + std::to_string(i) + " (points[" + std::to_string(i) +
                              "] -> points[" + std::to_string(i + 1) + "])";
    double leg = 0;
    for (int k = 0; k < 3; ++k) leg = std::max(leg, (b.col(k + 1) - b.col(k)).norm());
    int d = opt.depth;
    if (d < 0) {
      const double kmin = 3 * leg / (opt.feed * opt.period);
      d = 0;
      while (d <= bf.max_depth && std::ldexp(1.0, d) < kmin) ++d;
      if (d > bf.max_depth) {
        char m[200];
        std::snprintf(m, sizeof m,
                      "needs K >= %.0f ticks to keep the speed <= --feed %g (d > MaxDepth %d): raise --feed or "
                      "--period, or add points",
                      std::ceil(kmin), opt.feed, bf.max_depth);
        bad(where, m);
      }
    }
    const uint64_t K = uint64_t(1) << d;
    if (opt.engine == "mixed" && i % 2 == 1) chain.add_fd_bezier(b, K, opt.period, where);
    else chain.add_bcu(b, d, where);
    ticks += K;
    vmax = std::max(vmax, 3 * leg / (static_cast<double>(K) * opt.period));
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
  }

  std::vector<stream::Record> recs;
  size_t nb = 0, nf = 0;
  double bound = 0;
  for (const auto& pc : chain.pieces()) {
    stream::Record r;
    r.ticks = pc.ticks;
    if (pc.kind == bcu::Kind::kBcu) {
      r.kind = stream::RecordKind::kBcu;
      r.regs = pc.bcu.ctrl;
      ++nb;
      bound = std::max(bound, pc.bcu.bound * std::ldexp(1.0, opt.frac_bits));
    } else {
      r.regs = pc.fd.regs;
      ++nf;
      bound = std::max(bound, 0.5 + pc.fd.bound_lsb);
    }
    recs.push_back(r);
  }
  stream::write_file(opt.output, core.header(opt.frac_bits, opt.period, "mm"), recs);
  std::printf("%s: %lld points, %zu spline segments (lambda %g, mu %g) -> %zu stream segments (%zu BCU, %zu FD), "
              "d %d..%d, %llu ticks (%.3f s), speed <= %.4g units/s, every sample within %.4f LSB of the spline "
              "(1 LSB = 2^-%d) -> %s\n",
              opt.input.c_str(), static_cast<long long>(p.rows() - 2), spl.size(), opt.lambda, mu, recs.size(), nb, nf,
              dmin, dmax, static_cast<unsigned long long>(ticks), ticks * opt.period, vmax, bound, opt.frac_bits,
              opt.output.c_str());
  return 0;
}

}  // namespace traj::app
