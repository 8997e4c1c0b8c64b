#include "sim/sim.hpp"

#include <verilated.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>

#include "Vtraj_fd_cubic.h"
#include "Vtraj_fd_quintic.h"
#include "sim/vl_bits.hpp"
#include "traj_fd_engine.hpp"

namespace traj::sim {
namespace {

template <class V, class Eng>
SimResult run(const stream::Header& h, const std::vector<stream::Record>& recs, int tick_gap,
              const std::function<void(double)>& progress) {
  SimResult res;
  fd::Compiler comp(h.format());
  std::vector<uint64_t> words;
  uint64_t total = 0;
  for (const auto& r : recs) {
    fd::Compiled c;
    c.ticks = r.ticks;
    c.regs = r.regs;
    const auto w = comp.words(c);
    words.insert(words.end(), w.begin(), w.end());
    total += r.ticks;
  }
  if (tick_gap <= 0) tick_gap = Eng::kWords + Eng::kChunks + 2;
  if (tick_gap < Eng::kWords + Eng::kChunks + 1)
    throw std::runtime_error("tick gap " + std::to_string(tick_gap) + " cycles is shorter than a segment load (" +
                             std::to_string(Eng::kWords + Eng::kChunks + 1) + ")");
  auto ctx = std::make_unique<VerilatedContext>();
  ctx->randReset(2);
  auto dut = std::make_unique<V>(ctx.get());
  Eng model;
  auto cycle = [&](bool rst_n, bool tvalid, uint64_t tdata, bool tick) {
    dut->rst_ni = rst_n;
    dut->s_axis_tvalid = tvalid;
    dut->s_axis_tdata = tdata;
    dut->tick_i = tick;
    dut->clk_i = 0;
    dut->eval();
    typename Eng::In in;
    in.rst_n = rst_n;
    in.tvalid = tvalid;
    in.tdata = tdata;
    in.tick = tick;
    model.clock(in);
    dut->clk_i = 1;
    dut->eval();
    ++res.cycles;
  };
  const auto t0 = std::chrono::steady_clock::now();
  cycle(false, false, 0, false);
  cycle(false, false, 0, false);
  size_t wi = 0;
  res.samples.v.reserve(total);
  const uint64_t limit = (total + 4) * static_cast<uint64_t>(tick_gap) * 4 + words.size() * 4 + 1000;
  while (res.samples.v.size() < total) {
    if (res.cycles > limit) throw std::runtime_error("simulation stalled");
    if (dut->sample_valid_o) {
      const auto mo = model.outputs();
      std::array<long long, 3> s{};
      for (int a = 0; a < 3; ++a) {
        const u128 raw = vl_bits(dut->sample_o, a * Eng::kOutWidth, Eng::kOutWidth);
        if (raw != mo.sample[a]) ++res.mismatches;
        s[a] = static_cast<long long>(sext(raw, Eng::kOutWidth));
      }
      if (dut->underrun_o) ++res.underruns;
      else res.samples.v.push_back(s);
      if (progress && (res.samples.v.size() % 100000 == 0)) progress(double(res.samples.v.size()) / total);
    }
    if (dut->s_axis_tready != model.outputs().tready || dut->sample_valid_o != model.outputs().sample_valid)
      ++res.mismatches;
    res.tick_err |= dut->tick_err_o;
    const bool tvalid = wi < words.size();
    const uint64_t tdata = tvalid ? words[wi] : 0;
    if (tvalid && dut->s_axis_tready) ++wi;
    cycle(true, tvalid, tdata, res.cycles % tick_gap == 0);
  }
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  dut->final();
  return res;
}

bool is(const stream::Header& h, int deg, int w, int c, int g) {
  return h.axes == 3 && h.degree == deg && h.width == w && h.chunk_width == c && h.guard_bits == g;
}

}  // namespace

#if TRAJ_APP_CORE
SimResult simulate_core(const stream::Header& h, const std::vector<stream::Record>& recs, int tick_gap,
                        const std::function<void(double)>& progress);  // core_sim.cpp
#else
bool has_core() { return false; }
#endif

SimResult simulate(const stream::Header& h, const std::vector<stream::Record>& recs, int tick_gap,
                   const std::function<void(double)>& progress) {
  if (h.has_bcu()) {
#if TRAJ_APP_CORE
    return simulate_core(h, recs, tick_gap, progress);
#else
    throw std::runtime_error("this stream carries a BCU format (version 2) and this trajcore was built without "
                             "host/bcu (TRAJ_SKIP): no traj_core to run it on");
#endif
  }
  for (const auto& r : recs)
    if (r.is_bcu()) throw std::runtime_error("BCU segment in a stream without a BCU format");
  if (is(h, 3, 64, 16, 32)) return run<Vtraj_fd_cubic, FdEngine<3, 3, 64, 16, 32>>(h, recs, tick_gap, progress);
  if (is(h, 5, 96, 16, 48)) return run<Vtraj_fd_quintic, FdEngine<3, 5, 96, 16, 48>>(h, recs, tick_gap, progress);
  throw std::runtime_error("no engine for this stream: axes " + std::to_string(h.axes) + ", degree " +
                           std::to_string(h.degree) + ", width " + std::to_string(h.width) + ", chunk " +
                           std::to_string(h.chunk_width) + ", guard " + std::to_string(h.guard_bits) +
                           " (this tool carries 3x3x64/16/32 and 3x5x96/16/48)");
}

}  // namespace traj::sim
