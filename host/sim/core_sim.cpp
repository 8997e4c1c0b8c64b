// trajcore: a version-2 segment stream (FD and BCU records) through the
// Verilated traj_core (rtl/traj_core.sv, both engines) with the hls model
// (hls/traj_core.hpp) beside it on every cycle, and every sample against the
// exact prediction computed from the records themselves (FD: the register
// recurrence in exact integers, modulo 2^Width as the engine wraps; BCU: the
// closed form of traj::bcu::predict_sample).
#include <verilated.h>

#include <chrono>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>

#include "Vtraj_core_app.h"
#include "bcu/bcu_compiler.hpp"
#include "sim/vl_bits.hpp"
#include "sim/sim.hpp"
#include "traj_core.hpp"

namespace traj::sim {
namespace {

using B = CoreBuild;
using CoreModel = Core<B::kAxes, B::kDegree, B::kWidth, B::kChunk, B::kGuard, B::kCtrl, B::kBcuGuard, B::kMaxDepth>;
static_assert(CoreModel::kOutWidth == B::kWidth - B::kGuard, "one sample port");

struct Expect {
  std::array<long long, 3> v;
  bool done;
};

bool matches(const stream::Header& h) {
  return h.has_bcu() && h.axes == B::kAxes && h.degree == B::kDegree && h.width == B::kWidth &&
         h.chunk_width == B::kChunk && h.guard_bits == B::kGuard && h.bcu_ctrl_width == B::kCtrl &&
         h.bcu_guard_bits == B::kBcuGuard && h.bcu_max_depth == B::kMaxDepth &&
         h.bcu_out_width == CoreModel::kOutWidth;
}

}  // namespace

bool has_core() { return true; }

fd::Format core_fd_format(int frac_bits) {
  fd::Format f;
  f.axes = B::kAxes;
  f.degree = B::kDegree;
  f.width = B::kWidth;
  f.chunk_width = B::kChunk;
  f.guard_bits = B::kGuard;
  f.frac_bits = frac_bits;
  return f;
}

bcu::Format core_bcu_format(int frac_bits) {
  bcu::Format f;
  f.axes = B::kAxes;
  f.chunk_width = B::kChunk;
  f.ctrl_width = B::kCtrl;
  f.guard_bits = B::kBcuGuard;
  f.out_width = CoreModel::kOutWidth;
  f.max_depth = B::kMaxDepth;
  f.frac_bits = frac_bits;
  return f;
}

int core_min_tick_spacing() { return CoreModel::kMinTickSpacing; }

stream::Header core_header(int frac_bits, double period, const std::string& units) {
  return stream::Header::from(core_fd_format(frac_bits), core_bcu_format(frac_bits), period, units);
}

SimResult simulate_core(const stream::Header& h, const std::vector<stream::Record>& recs, int tick_gap,
                        const std::function<void(double)>& progress) {
  if (!matches(h))
    throw std::runtime_error(
        "no core for this stream: axes " + std::to_string(h.axes) + ", FD degree " + std::to_string(h.degree) +
        " width " + std::to_string(h.width) + " chunk " + std::to_string(h.chunk_width) + " guard " +
        std::to_string(h.guard_bits) + ", BCU CtrlWidth " + std::to_string(h.bcu_ctrl_width) + " GuardBits " +
        std::to_string(h.bcu_guard_bits) + " MaxDepth " + std::to_string(h.bcu_max_depth) + " OutWidth " +
        std::to_string(h.bcu_out_width) + " (this tool carries traj_core with 3 axes, FD 3x64/16/32, BCU CtrlWidth " +
        std::to_string(B::kCtrl) + " GuardBits " + std::to_string(B::kBcuGuard) + " MaxDepth " +
        std::to_string(B::kMaxDepth) + ")");
  SimResult res;
  res.engine = "traj_core";
  const int S = CoreModel::kMinTickSpacing;
  if (tick_gap <= 0) tick_gap = S;
  if (tick_gap < S)
    throw std::runtime_error("tick gap " + std::to_string(tick_gap) + " cycles is shorter than the core's minimum tick "
                             "spacing (" + std::to_string(S) + " cycles: a BCU segment switch, hls/traj_core.hpp)");
  res.tick_gap = tick_gap;

  // Words (with the kind on tuser) and the exact prediction of every sample.
  const fd::Compiler fdc(h.format());
  const bcu::Format bf = h.bcu_format();
  const int G = h.guard_bits, W = h.width;
  const mpz_class mod = mpz_class(1) << W;
  std::vector<std::pair<uint64_t, bool>> words;
  std::deque<Expect> expect;
  size_t first_len = 0;
  uint64_t total = 0;
  for (size_t s = 0; s < recs.size(); ++s) {
    const auto& r = recs[s];
    const size_t before = words.size();
    if (r.is_bcu()) {
      const int d = r.depth();
      for (uint64_t w : bcu::stream_words(r.regs, d, bf)) words.push_back({w, true});
      for (uint32_t j = 0; j < r.ticks; ++j) {
        Expect e{};
        for (int a = 0; a < B::kAxes; ++a) e.v[a] = bcu::predict_sample(r.regs[a], d, static_cast<int>(j), bf.guard_bits);
        e.done = j + 1 == r.ticks;
        expect.push_back(e);
      }
      ++res.bcu_segments;
    } else {
      fd::Compiled c;
      c.ticks = r.ticks;
      c.regs = r.regs;
      for (uint64_t w : fdc.words(c)) words.push_back({w, false});
      std::vector<std::vector<mpz_class>> reg = r.regs;
      const size_t e0 = expect.size();
      expect.resize(e0 + r.ticks);
      for (int a = 0; a < B::kAxes; ++a) {
        auto& x = reg[a];
        mpz_class v;
        for (uint32_t k = 0; k < r.ticks; ++k) {
          v = x[0] % mod;  // the engine's r0, W bits two's complement
          if (v < 0) v += mod;
          if (v >= mod / 2) v -= mod;
          mpz_fdiv_q_2exp(v.get_mpz_t(), v.get_mpz_t(), G);
          expect[e0 + k].v[a] = v.get_si();
          expect[e0 + k].done = k + 1 == r.ticks;
          for (int i = 0; i < B::kDegree; ++i) x[i] += x[i + 1];
        }
      }
      ++res.fd_segments;
    }
    if (s > 0 && r.kind != recs[s - 1].kind) ++res.switches;
    if (s == 0) first_len = words.size() - before;
    total += r.ticks;
  }

  auto ctx = std::make_unique<VerilatedContext>();
  ctx->randReset(2);
  auto dut = std::make_unique<Vtraj_core_app>(ctx.get());
  CoreModel model;
  auto cycle = [&](bool rst_n, bool tvalid, uint64_t tdata, bool tuser, bool tick) {
    dut->rst_ni = rst_n;
    dut->s_axis_tvalid = tvalid;
    dut->s_axis_tdata = tdata;
    dut->s_axis_tuser = tuser;
    dut->tick_i = tick;
    dut->clk_i = 0;
    dut->eval();
    CoreModel::In in;
    in.rst_n = rst_n;
    in.tvalid = tvalid;
    in.tdata = tdata;
    in.tuser = tuser;
    in.tick = tick;
    model.clock(in);
    dut->clk_i = 1;
    dut->eval();
    ++res.cycles;
  };
  const auto t0 = std::chrono::steady_clock::now();
  cycle(false, false, 0, false, false);
  cycle(false, false, 0, false, false);
  size_t wi = 0;
  res.samples.v.reserve(total);
  // First tick one gap after the first segment has entered the core (a gap
  // covers a segment's load and descent), then one every gap.
  uint64_t next_tick = ~0ull;
  const uint64_t limit = (total + 4) * static_cast<uint64_t>(tick_gap) * 4 + words.size() * 4 + 10000;
  while (res.samples.v.size() < total) {
    if (res.cycles > limit) throw std::runtime_error("simulation stalled");
    // RTL == hls, every cycle
    CoreModel::In probe;
    if (dut->s_axis_tready != model.tready(probe)) ++res.mismatches;
    if (dut->sample_valid_o != model.sample_valid() || dut->underrun_o != model.underrun() ||
        dut->seg_done_o != model.seg_done() || dut->tick_err_o != model.tick_err())
      ++res.mismatches;
    if (dut->underrun_o) ++res.underruns;
    if (dut->sample_valid_o) {
      std::array<long long, 3> s{};
      for (int a = 0; a < B::kAxes; ++a) {
        const u128 raw = vl_bits(dut->sample_o, a * CoreModel::kOutWidth, CoreModel::kOutWidth);
        if (raw != model.sample_bits(a)) ++res.mismatches;
        s[a] = static_cast<long long>(sext(raw, CoreModel::kOutWidth));
      }
      if (!dut->underrun_o) {
        const Expect& e = expect.front();
        if (s != e.v || static_cast<bool>(dut->seg_done_o) != e.done) ++res.prediction_mismatches;
        expect.pop_front();
        res.samples.v.push_back(s);
        if (progress && (res.samples.v.size() % 100000 == 0)) progress(double(res.samples.v.size()) / total);
      }
    }
    res.tick_err |= dut->tick_err_o;
    const bool tvalid = wi < words.size();
    const uint64_t tdata = tvalid ? words[wi].first : 0;
    const bool tuser = tvalid ? words[wi].second : false;
    if (tvalid && dut->s_axis_tready) ++wi;
    if (next_tick == ~0ull && wi >= first_len) next_tick = res.cycles + tick_gap;
    const bool tick = res.cycles == next_tick;
    if (tick) next_tick += tick_gap;
    cycle(true, tvalid, tdata, tuser, tick);
  }
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  dut->final();
  return res;
}

}  // namespace traj::sim
