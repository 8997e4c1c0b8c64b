// SPDX-License-Identifier: Apache-2.0
// trajcore demo: the circle of three 120-degree cubic Bezier segments ([ARC])
// traversed in time, compiled to forward-difference segments, run through the
// Verilated engine (sim::simulate: the hls model beside it on every cycle),
// every sample checked against the host's exact prediction and compared with
// the double-precision Bezier path.
//
// The demo always runs the tool's fd_cubic build (3 axes, degree 3, 64-bit
// registers, 16-bit chunks, 32 guard bits; host/sim/CMakeLists.txt), not the
// build's TRAJ_* engine, so `trajcore` builds and the demo runs whatever
// TRAJ_AXES/DEGREE/WIDTH/CHUNK/GUARD are.
#include "demo.hpp"
#include "util/atomic_file.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "fd/fd_compiler.hpp"
#include "sim/sim.hpp"

namespace traj::app {
namespace {

using Vec = std::array<double, 3>;

struct Bezier {
  std::array<Vec, 4> p;
  Vec eval(double u) const {  // de Casteljau, the double-precision reference
    std::array<Vec, 4> q = p;
    for (int r = 1; r < 4; ++r)
      for (int i = 0; i < 4 - r; ++i)
        for (int a = 0; a < 3; ++a) q[i][a] = (1 - u) * q[i][a] + u * q[i + 1][a];
    return q[0];
  }
  // Power-basis coefficients in u, per axis.
  std::array<std::array<double, 4>, 3> power() const {
    std::array<std::array<double, 4>, 3> c{};
    for (int a = 0; a < 3; ++a) {
      const double P0 = p[0][a], P1 = p[1][a], P2 = p[2][a], P3 = p[3][a];
      c[a] = {P0, 3 * (P1 - P0), 3 * (P0 - 2 * P1 + P2), P3 - P0 + 3 * (P1 - P2)};
    }
    return c;
  }
};

// Arc of angle th from angle a0 on a circle of radius R: k = 4/3 tan(th/4).
Bezier arc(double R, double a0, double th) {
  const double a1 = a0 + th, k = 4.0 / 3.0 * std::tan(th / 4);
  Bezier b;
  b.p[0] = {R * std::cos(a0), R * std::sin(a0), 0};
  b.p[3] = {R * std::cos(a1), R * std::sin(a1), 0};
  b.p[1] = {b.p[0][0] - k * R * std::sin(a0), b.p[0][1] + k * R * std::cos(a0), 0};
  b.p[2] = {b.p[3][0] + k * R * std::sin(a1), b.p[3][1] - k * R * std::cos(a1), 0};
  return b;
}

// c(u0 + s t) as a polynomial in t.
std::vector<double> compose(const std::array<double, 4>& c, double u0, double s) {
  std::vector<double> out(4, 0.0);
  for (int j = 0; j < 4; ++j) {
    // c_j (u0 + s t)^j = c_j sum_m C(j,m) u0^(j-m) s^m t^m
    double binom = 1;
    for (int m = 0; m <= j; ++m) {
      out[m] += c[j] * binom * std::pow(u0, j - m) * std::pow(s, m);
      binom = binom * (j - m) / (m + 1);
    }
  }
  return out;
}

}  // namespace

int run_fd_demo(const DemoOptions& opt, const std::chrono::steady_clock::time_point t_start);

int run_demo(const DemoOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  if (opt.engine != "fd") {
#if TRAJ_APP_CORE
    return run_core_demo(opt);
#else
    throw std::invalid_argument("--engine " + opt.engine + ": this trajcore was built without host/bcu (TRAJ_SKIP)");
#endif
  }
  DemoOptions o = opt;
  if (o.tick_gap <= 0) o.tick_gap = 64;
  return run_fd_demo(o, t_start);
}

int run_fd_demo(const DemoOptions& opt, const std::chrono::steady_clock::time_point t_start) {
  const sim::Build& build = sim::carried("fd_cubic");
  const fd::Compiler comp(build.fd_format(opt.frac_bits));
  if (opt.tick_gap < build.min_tick_gap)
    throw std::invalid_argument("--tick-gap " + std::to_string(opt.tick_gap) + " is shorter than a segment load (" +
                                std::to_string(build.min_tick_gap) +
                                " cycles): ticks would be lost at segment boundaries");

  // Plan: three 120-degree arcs, each traversed with u linear in time over
  // K_arc ticks (the arc length over the feed), cut into `pieces` segments.
  const double th = 2 * M_PI / 3;
  const double arc_len = opt.radius * th;
  const uint64_t K_arc = static_cast<uint64_t>(std::llround(arc_len / opt.feed / opt.period));
  if (K_arc < static_cast<uint64_t>(opt.pieces))
    throw std::invalid_argument("fewer ticks per arc than pieces: raise --feed/--period ratio or lower --pieces");
  struct SegInfo {
    int arc;
    uint64_t k0;  // first tick within the arc
    fd::Compiled c;
  };
  std::vector<Bezier> arcs;
  std::vector<SegInfo> segs;
  const std::vector<mpz_class>* prev = nullptr;
  for (int i = 0; i < 3; ++i) {
    arcs.push_back(arc(opt.radius, i * th, th));
    const auto pc = arcs.back().power();
    for (int p = 0; p < opt.pieces; ++p) {
      const uint64_t k0 = K_arc * p / opt.pieces, k1 = K_arc * (p + 1) / opt.pieces;
      fd::PolySegment seg;
      seg.h = opt.period;
      seg.ticks = k1 - k0;
      const double s = 1.0 / (static_cast<double>(K_arc) * opt.period);  // du/dt
      const double u0 = static_cast<double>(k0) / static_cast<double>(K_arc);
      for (int a = 0; a < 3; ++a) seg.coef.push_back(compose(pc[a], u0, s));
      segs.push_back({i, k0, comp.compile(seg, prev, "arc " + std::to_string(i) + " piece " + std::to_string(p))});
      prev = &segs.back().c.end;
    }
  }

  // Stream everything through the Verilated engine and the hls model.
  std::vector<stream::Record> recs;
  struct Owner {
    size_t seg;
    uint64_t k;
  };
  std::vector<Owner> owner;
  for (size_t s = 0; s < segs.size(); ++s) {
    stream::Record r;
    r.ticks = static_cast<uint32_t>(segs[s].c.ticks);
    r.regs = segs[s].c.regs;
    recs.push_back(r);
    for (uint64_t k = 0; k < segs[s].c.ticks; ++k) owner.push_back({s, k});
  }
  const sim::SimResult sr = sim::simulate(build.header(opt.frac_bits, opt.period, "mm"), recs, opt.tick_gap);
  if (sr.samples.v.size() != owner.size()) throw std::runtime_error("the engine emitted fewer samples than planned");

  util::AtomicFile csv(opt.csv);
  std::ofstream& out = csv.out();
  out << kDemoCsvHeader;

  const double lsb = std::ldexp(1.0, -opt.frac_bits);
  double max_err = 0, max_bound = 0;
  uint64_t n = 0, mismatches = sr.mismatches;
  for (; n < owner.size(); ++n) {
    const auto& ow = owner[n];
    const auto& si = segs[ow.seg];
    const auto& v = sr.samples.v[n];
    const double u = static_cast<double>(si.k0 + ow.k) / static_cast<double>(K_arc);
    const Vec ref = arcs[si.arc].eval(u);
    double err = 0;
    for (int a = 0; a < 3; ++a) {
      if (comp.sample_at(si.c, a, ow.k) != mpz_class(static_cast<long>(v[a]))) ++mismatches;
      err = std::max(err, std::fabs(v[a] - ref[a] / lsb));
    }
    max_err = std::max(max_err, err);
    max_bound = std::max(max_bound, si.c.bound_lsb);
    const double t = static_cast<double>(si.arc * K_arc + si.k0 + ow.k) * opt.period;
    out << n << ',' << t << ',' << ow.seg << ',' << v[0] << ',' << v[1] << ',' << v[2];
    char buf[256];
    std::snprintf(buf, sizeof buf, ",%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.6f\n", v[0] * lsb, v[1] * lsb, v[2] * lsb,
                  ref[0], ref[1], ref[2], err);
    out << buf;
  }
  const auto t_end = std::chrono::steady_clock::now();
  csv.commit();
  const double all_s = std::chrono::duration<double>(t_end - t_start).count();

  std::printf("trajcore demo: circle R=%g mm of three 120-degree cubic Bezier arcs, feed %g mm/s nominal, tick %g ms\n",
              opt.radius, opt.feed, opt.period * 1e3);
  const fd::Format& f = build.fd;
  std::printf("  engine        : traj_fd_engine Axes=%d Degree=%d Width=%d ChunkWidth=%d GuardBits=%d (Verilated)\n",
              f.axes, f.degree, f.width, f.chunk_width, f.guard_bits);
  std::printf("  output format : %d-bit samples, 1 LSB = 2^-%d mm = %.3g um\n", f.out_width(), opt.frac_bits,
              lsb * 1e3);
  std::printf("  segments      : %zu (K = %llu ticks per arc)\n", segs.size(), static_cast<unsigned long long>(K_arc));
  std::printf("  ticks         : %llu samples in %llu clock cycles (tick every %d cycles)\n",
              static_cast<unsigned long long>(n), static_cast<unsigned long long>(sr.cycles), opt.tick_gap);
  std::printf("  max error     : %.4f LSB (%.3g um) against the double-precision Bezier path\n", max_err,
              max_err * lsb * 1e3);
  std::printf("  stated bound  : %.4f LSB (0.5 output rounding + %.4f register error)\n", 0.5 + max_bound, max_bound);
  std::printf("  RTL == hls == host prediction: %s (%llu mismatches)\n", mismatches == 0 ? "yes" : "NO",
              static_cast<unsigned long long>(mismatches));
  std::printf("  tick_err      : %s, underruns %llu\n", sr.tick_err ? "SET" : "clear",
              static_cast<unsigned long long>(sr.underruns));
  std::printf("  samples CSV   : %s\n", opt.csv.c_str());
  std::printf("  time          : %.3f s total, simulation %.0f cycles/s\n", all_s, sr.cycles / sr.seconds);
  const bool ok = mismatches == 0 && !sr.tick_err && sr.underruns == 0 && max_err <= 0.5 + max_bound + 1e-6;
  if (!ok) std::fprintf(stderr, "trajcore demo: FAILED (see above)\n");
  return ok ? 0 : 1;
}

}  // namespace traj::app
