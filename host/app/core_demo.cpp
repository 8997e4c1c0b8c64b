// SPDX-License-Identifier: Apache-2.0
// trajcore demo --engine bcu | mixed: the circle of three 120-degree cubic
// Bezier arcs ([ARC]), the BCU generator's native input, compiled for
// traj_core and run through it (Verilated, hls beside it on every cycle).
//   bcu  : every arc is one BCU segment of K = 2^d ticks;
//   mixed: arcs FD, BCU, FD (the FD arcs cut into --pieces segments, more if
//          the FD format needs it), chained exactly across kinds
//          (traj::bcu::MixedChain, bcu/chain.hpp).
// Both use K = 2^d ticks per arc, d = round(log2(arc length / feed / period)),
// so the feed is the nominal one to within a factor 2^(+-1/2) (printed).
// The segments are written as a segment stream with a BCU format, read back
// from the file and simulated (the same path as `trajcore sim`); every sample
// is checked against the hosts' exact prediction (RTL == hls == host) and
// against the double-precision Bezier path within the per-sample bound:
//   BCU: Segment::bound_lsb (1/2 + (1-t)^3 |offset| + (1-(1-t)^3) 2^-(G+1)
//        + 8 eps max|b| 2^F for the double de Casteljau reference);
//   FD : 1/2 + the compiler's register bound + 256 eps max|b| 2^F, the
//        allowance for the power-basis conversion and composition in double
//        (each coefficient a sum of terms bounded by 8 max|b| with at most ~12
//        roundings each, four coefficients, plus the reference's 8 eps max|b|).
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <vector>

#include "bcu/chain.hpp"
#include "demo.hpp"
#include "util/atomic_file.hpp"
#include "sim/sim.hpp"
#include "stream/segment_stream.hpp"

namespace traj::app {

using namespace traj::sim;
namespace {

// Arc of angle th from angle a0 on a circle of radius R: k = 4/3 tan(th/4).
bcu::Controls arc_controls(double R, double a0, double th) {
  const double a1 = a0 + th, k = 4.0 / 3.0 * std::tan(th / 4);
  bcu::Controls b = bcu::Controls::Zero(3, 4);
  b(0, 0) = R * std::cos(a0);
  b(1, 0) = R * std::sin(a0);
  b(0, 3) = R * std::cos(a1);
  b(1, 3) = R * std::sin(a1);
  b(0, 1) = b(0, 0) - k * R * std::sin(a0);
  b(1, 1) = b(1, 0) + k * R * std::cos(a0);
  b(0, 2) = b(0, 3) + k * R * std::sin(a1);
  b(1, 2) = b(1, 3) - k * R * std::cos(a1);
  return b;
}

}  // namespace

int run_core_demo(const DemoOptions& opt) {
  if (opt.engine != "bcu" && opt.engine != "mixed")
    throw std::invalid_argument("--engine " + opt.engine + ": expected fd, bcu or mixed");
  if (!has_core()) throw std::runtime_error("this trajcore was built without host/bcu: no traj_core demo");
  const auto t_start = std::chrono::steady_clock::now();
  const Build& core = carried("core");
  const int S = core.min_tick_gap;
  const int gap = opt.tick_gap > 0 ? opt.tick_gap : S;
  if (gap < S)
    throw std::invalid_argument("--tick-gap " + std::to_string(gap) + " is shorter than the core's minimum tick spacing (" +
                                std::to_string(S) + " cycles)");
  const fd::Format ff = core.fd_format(opt.frac_bits);
  const bcu::Format bf = core.bcu_format(opt.frac_bits);
  const std::string stream_path = opt.stream.empty() ? "out/demo_" + opt.engine + ".trj" : opt.stream;

  // K = 2^d ticks per arc
  const double th = 2 * M_PI / 3;
  const double arc_len = opt.radius * th;
  const double k_nom = arc_len / opt.feed / opt.period;
  const int d = static_cast<int>(std::lround(std::log2(std::max(k_nom, 1.0))));
  if (d > bf.max_depth)
    throw std::invalid_argument("an arc of " + std::to_string(std::llround(k_nom)) + " ticks needs d = " +
                                std::to_string(d) + " > MaxDepth " + std::to_string(bf.max_depth) +
                                " (K = 2^d ticks per BCU segment): raise --feed or --period");
  const uint64_t K = uint64_t(1) << d;
  const double feed = arc_len / (static_cast<double>(K) * opt.period);

  // Compile: one chain, each segment starting at the previous one's exact end.
  bcu::MixedChain chain(ff, bf);
  struct Span {
    int arc;
    uint64_t k0;  // first tick of the piece within its arc
  };
  std::vector<Span> span;
  std::vector<bcu::Controls> arcs;
  for (int i = 0; i < 3; ++i) {
    arcs.push_back(arc_controls(opt.radius, i * th, th));
    const std::string where = "arc " + std::to_string(i);
    const bool as_bcu = opt.engine == "bcu" || i % 2 == 1;
    if (as_bcu) {
      chain.add_bcu(arcs.back(), d, where);
      span.push_back({i, 0});
    } else {
      const size_t p0 = chain.pieces().size();
      const int n = chain.add_fd_bezier(arcs.back(), K, opt.period, where, opt.pieces);
      for (int p = 0; p < n; ++p) span.push_back({i, K * p / n});
      (void)p0;
    }
  }

  // The stream (with the BCU format), written atomically, then read back from the file.
  std::vector<stream::Record> recs;
  for (const auto& p : chain.pieces()) {
    stream::Record r;
    r.ticks = p.ticks;
    if (p.kind == bcu::Kind::kBcu) {
      r.kind = stream::RecordKind::kBcu;
      r.regs = p.bcu.ctrl;
    } else {
      r.regs = p.fd.regs;
    }
    recs.push_back(r);
  }
  const stream::Header hdr = core.header(opt.frac_bits, opt.period, "mm");
  stream::write_file(stream_path, hdr, recs);
  const auto rd = stream::read_file(stream_path);
  if (!rd.complete) throw std::runtime_error(rd.error);
  const SimResult sr = simulate(rd.header, rd.records, gap);

  // Compare: host prediction (the chain's), hand-offs, double reference.
  const double lsb = std::ldexp(1.0, -opt.frac_bits);
  const double eps = std::numeric_limits<double>::epsilon() / 2;
  util::AtomicFile csv(opt.csv);
  std::ofstream& out = csv.out();
  out << kDemoCsvHeader;
  uint64_t n = 0, pred_mismatch = 0, handoffs = 0, handoff_ok = 0, over = 0;
  double max_err = 0, max_bound = 0, worst_margin = std::numeric_limits<double>::infinity();
  const auto& pieces = chain.pieces();
  for (size_t s = 0; s < pieces.size(); ++s) {
    const auto& pc = pieces[s];
    const bcu::Controls& b = arcs[span[s].arc];
    if (s > 0 && pc.kind != pieces[s - 1].kind) {
      ++handoffs;
      handoff_ok += pc.samples[0] == pieces[s - 1].samples[pieces[s - 1].ticks];
    }
    const double fd_ref = 256 * eps * b.cwiseAbs().maxCoeff() / lsb;
    for (uint64_t k = 0; k < pc.ticks; ++k, ++n) {
      if (n >= sr.samples.v.size()) throw std::runtime_error("the core emitted fewer samples than the stream holds");
      const auto& v = sr.samples.v[n];
      const double u = static_cast<double>(span[s].k0 + k) / static_cast<double>(K);
      double ref[3], err = 0;
      for (int a = 0; a < 3; ++a) {
        const double bb[4] = {b(a, 0), b(a, 1), b(a, 2), b(a, 3)};
        ref[a] = bcu::de_casteljau(bb, u);
        if (v[a] != pc.samples[k][a]) ++pred_mismatch;
        const double e = std::fabs(static_cast<double>(v[a]) - ref[a] / lsb);
        const double bound = pc.kind == bcu::Kind::kBcu ? pc.bcu.bound_lsb(a, static_cast<int>(k))
                                                        : pc.bound_lsb(a, k) + fd_ref;
        if (e > bound) ++over;
        worst_margin = std::min(worst_margin, bound - e);
        max_bound = std::max(max_bound, bound);
        err = std::max(err, e);
      }
      max_err = std::max(max_err, err);
      const double t = static_cast<double>(span[s].arc * K + span[s].k0 + k) * opt.period;
      char buf[320];
      std::snprintf(buf, sizeof buf, "%llu,%.6f,%zu,%lld,%lld,%lld,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.6f\n",
                    static_cast<unsigned long long>(n), t, s, v[0], v[1], v[2], v[0] * lsb, v[1] * lsb, v[2] * lsb,
                    ref[0], ref[1], ref[2], err);
      out << buf;
    }
  }
  csv.commit();
  const auto t_end = std::chrono::steady_clock::now();

  size_t nf = 0, nb = 0;
  for (const auto& p : pieces) (p.kind == bcu::Kind::kBcu ? nb : nf)++;
  std::printf("trajcore demo --engine %s: circle R=%g mm of three 120-degree cubic Bezier arcs, K = 2^%d = %llu ticks "
              "per arc, feed %.4g mm/s (nominal %g), tick %g ms\n",
              opt.engine.c_str(), opt.radius, d, static_cast<unsigned long long>(K), feed, opt.feed, opt.period * 1e3);
  std::printf("  engine        : traj_core = traj_fd_engine Degree=%d Width=%d GuardBits=%d + traj_bcu_gen CtrlWidth=%d "
              "GuardBits=%d MaxDepth=%d, Axes=3 ChunkWidth=%d (Verilated)\n",
              ff.degree, ff.width, ff.guard_bits, bf.ctrl_width, bf.guard_bits, bf.max_depth, bf.chunk_width);
  std::printf("  output format : %d-bit samples, 1 LSB = 2^-%d mm = %.3g um\n", bf.out_width, opt.frac_bits, lsb * 1e3);
  std::printf("  segments      : %zu (%zu BCU, %zu FD), %llu kind switches\n", pieces.size(), nb, nf,
              static_cast<unsigned long long>(sr.switches));
  std::printf("  stream        : %s (version %d, %llu bytes), read back and simulated\n", stream_path.c_str(),
              stream::kVersion, static_cast<unsigned long long>(std::filesystem::file_size(stream_path)));
  std::printf("  ticks         : %llu samples in %llu clock cycles (tick every %d cycles; core minimum %d)\n",
              static_cast<unsigned long long>(n), static_cast<unsigned long long>(sr.cycles), sr.tick_gap, S);
  std::printf("  max error     : %.4f LSB (%.3g um) against the double-precision Bezier path\n", max_err,
              max_err * lsb * 1e3);
  std::printf("  stated bound  : %.4f LSB at most, per sample (%llu samples above it; smallest margin %.2e LSB)\n",
              max_bound, static_cast<unsigned long long>(over), worst_margin);
  std::printf("  kind switches : %llu, first sample of the new segment == end sample of the previous: %s\n",
              static_cast<unsigned long long>(handoffs), handoff_ok == handoffs ? "yes" : "NO");
  const uint64_t mism = sr.mismatches + sr.prediction_mismatches + pred_mismatch;
  std::printf("  RTL == hls == host prediction: %s (%llu mismatches)\n", mism == 0 ? "yes" : "NO",
              static_cast<unsigned long long>(mism));
  std::printf("  tick_err      : %s, underruns %llu\n", sr.tick_err ? "SET" : "clear",
              static_cast<unsigned long long>(sr.underruns));
  std::printf("  samples CSV   : %s\n", opt.csv.c_str());
  std::printf("  time          : %.3f s total\n", std::chrono::duration<double>(t_end - t_start).count());
  const bool ok = mism == 0 && !sr.tick_err && sr.underruns == 0 && over == 0 && handoff_ok == handoffs &&
                  n == sr.samples.v.size();
  if (!ok) std::fprintf(stderr, "trajcore demo: FAILED (see above)\n");
  return ok ? 0 : 1;
}

}  // namespace traj::app
