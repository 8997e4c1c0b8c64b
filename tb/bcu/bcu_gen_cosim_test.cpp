// SPDX-License-Identifier: Apache-2.0
// Verilator co-simulation: rtl/traj_bcu_gen.sv == hls/traj_bcu_gen.hpp, every
// cycle: control outputs (s_axis_tready, sample_valid_o, underrun_o,
// seg_done_o, tick_err_o) always, sample_o when sample_valid_o.
// Random control values (full range and extremes), random depths, chained and
// unchained segments back to back, random idle cycles on the segment input.
// Phases of tick modes: exactly the uniform minimum (kMinTickSpacing), random
// 1..2x it, sparse, 1..4x it, a tick on EVERY clock while a sample is ready
// (the one-sample-per-clock guarantee), and rare short phases of ticks on every
// clock regardless (too fast at segment switches: tick_err, ended by a reset).
// Some phases force d = MaxDepth with ticks every clock; the run fails unless
// at least one d = MaxDepth segment completes. Resets at random phase ends and
// rarely mid-phase (about once per phase, never in a d = MaxDepth phase), so
// long segments are not cut. Every sample is also checked against the exact
// GMP prediction of the host (hls == host).
//
// usage: cosim_bcu_gen [--seed N] [--cycles N]   (or env TRAJ_SEED)
// Prints the seed; a failure is reproducible from it.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <gmpxx.h>
#include <memory>
#include <random>
#include <string>

#include "test_seed.hpp"
#include "Vtraj_bcu_gen.h"
#include "bcu/bcu_compiler.hpp"
#include "sim/lockstep.hpp"
#include "traj_bcu_gen.hpp"

using Gen = traj::BcuGen<BCU_AXES, BCU_CHUNK, BCU_CTRL, BCU_GUARD, BCU_OUT, BCU_DEPTH>;

struct Expect {  // host prediction of one sample
  std::vector<int64_t> v;
  int depth, j;
  std::vector<std::vector<mpz_class>> c;
};

int main(int argc, char** argv) {
  uint64_t seed = 1;
  seed = traj::test::env_seed(seed);
  uint64_t cycles = 1000000;
  uint64_t trace_from = 0;
  if (const char* s = std::getenv("TRAJ_BCU_TRACE")) trace_from = std::strtoull(s, nullptr, 0);
  for (int i = 1; i + 1 < argc; ++i) {
    if (!std::strcmp(argv[i], "--seed")) seed = std::strtoull(argv[++i], nullptr, 0);
    else if (!std::strcmp(argv[i], "--cycles")) cycles = std::strtoull(argv[++i], nullptr, 0);
  }
  std::printf("cosim_bcu_gen: Axes=%d ChunkWidth=%d CtrlWidth=%d GuardBits=%d OutWidth=%d "
              "MaxDepth=%d seed=%llu cycles=%llu (reproduce: --seed %llu)\n",
              BCU_AXES, BCU_CHUNK, BCU_CTRL, BCU_GUARD, BCU_OUT, BCU_DEPTH,
              (unsigned long long)seed, (unsigned long long)cycles, (unsigned long long)seed);

  traj::sim::Lockstep<Vtraj_bcu_gen, Gen> ls(static_cast<int>(seed & 0x7fffffff));
  const Gen& hls = ls.model();
  std::mt19937_64 rng(seed);

  traj::bcu::Format f{BCU_AXES, BCU_CHUNK, BCU_CTRL, BCU_GUARD, BCU_OUT, BCU_DEPTH};

  std::deque<uint64_t> words;
  std::deque<Expect> expect;      // predicted samples of queued/active segments
  std::vector<int64_t> end_value; // end value of the last completed segment
  std::vector<mpz_class> prevD(BCU_AXES);
  bool have_prev = false;

  auto rand_ctrl = [&](void) {
    mpz_class lim = 1;
    lim <<= (BCU_CTRL - 1);
    const int kind = static_cast<int>(rng() % 8);
    if (kind == 0) return mpz_class(lim - 1);
    if (kind == 1) return mpz_class(-lim);
    mpz_class v = 0;
    for (int k = 0; k < BCU_CTRL; k += 64) {
      v <<= 64;
      v += static_cast<unsigned long>(rng());
    }
    if (kind == 2) v >>= (rng() % BCU_CTRL);  // small values too
    v = v % (2 * lim);
    return mpz_class(v - lim);
  };
  bool force_max = false;  // phase: every segment at d = MaxDepth
  auto add_segment = [&]() {
    int d = static_cast<int>(rng() % (std::min(BCU_DEPTH, 7) + 1));
    if (rng() % 10 == 0) d = static_cast<int>(rng() % (BCU_DEPTH + 1));
    if (force_max) d = BCU_DEPTH;
    std::vector<std::vector<mpz_class>> c(BCU_AXES, std::vector<mpz_class>(4));
    const bool chain = have_prev && (rng() % 4 != 0);
    for (int a = 0; a < BCU_AXES; ++a) {
      for (int i = 0; i < 4; ++i) c[a][i] = rand_ctrl();
      if (chain) c[a][0] = prevD[a];
      prevD[a] = c[a][3];
    }
    have_prev = true;
    const auto w = traj::bcu::stream_words(c, d, f);
    words.insert(words.end(), w.begin(), w.end());
    if (trace_from) std::printf("   add segment d=%d chain=%d queued words %zu\n", d, chain, words.size());
    for (int j = 0; j <= (1 << d); ++j) {
      Expect e;
      e.depth = d;
      e.j = j;
      e.c = c;
      for (int a = 0; a < BCU_AXES; ++a) e.v.push_back(traj::bcu::predict_sample(c[a], d, j, BCU_GUARD));
      expect.push_back(e);  // j = K is the end value (consumed at seg_done)
    }
  };

  // scenario knobs, re-drawn every phase
  int tick_mode = 0, offer_pct = 100;
  uint64_t next_tick = 0, phase_end = 0, phase_len = 1;
  uint64_t n_samples = 0, n_underrun = 0, n_done = 0, n_resets = 0, n_tickerr = 0, n_checked = 0;
  uint64_t n_done_max = 0, n_run_ticks = 0;
  bool in_reset = true;
  int reset_left = 3;
  const int S = Gen::kMinTickSpacing;
  const uint64_t max_seg = (uint64_t(1) << BCU_DEPTH) + Gen::kStartLatencyMax;

  for (uint64_t cyc = 0; cyc < cycles; ++cyc) {
    if (cyc >= phase_end) {
      // the previous phase ends: a reset after a too-fast phase (tick_err is
      // sticky), else now and then
      if (cyc > 0 && !in_reset && (tick_mode == 4 || hls.tick_err() || rng() % 4 == 0)) {
        in_reset = true;
        reset_left = 1 + static_cast<int>(rng() % 3);
      }
      const int r = static_cast<int>(rng() % 16);
      force_max = r < 3;
      tick_mode = force_max ? 5 : (r == 3 ? 4 : (r < 8 ? 5 : static_cast<int>(rng() % 4)));
      offer_pct = (force_max || rng() % 3 == 0) ? 100 : 20 + static_cast<int>(rng() % 80);
      phase_len = force_max ? 3 * max_seg : (tick_mode == 4 ? 500 + rng() % 4000 : 2000 + rng() % 40000 + max_seg);
      phase_end = cyc + phase_len;
    }
    // rare reset mid-phase (also mid-segment), about once per 2 phases
    if (!in_reset && !force_max && tick_mode != 4 && rng() % (2 * phase_len) == 0) {
      in_reset = true;
      reset_left = 1 + static_cast<int>(rng() % 3);
    }
    bool rst_n = true, reset_ends = false;
    if (in_reset) {
      rst_n = false;
      if (--reset_left == 0) {
        in_reset = false;
        reset_ends = true;
      }
    }
    if (rst_n && words.size() < 64 && rng() % 4 != 0) add_segment();

    bool tick = false;
    switch (tick_mode) {
      case 0: tick = cyc >= next_tick; if (tick) next_tick = cyc + S; break;              // exact min
      case 1: tick = cyc >= next_tick; if (tick) next_tick = cyc + S + rng() % S; break;
      case 2: tick = (rng() % 64) == 0; break;                                           // sparse
      case 3: tick = cyc >= next_tick; if (tick) next_tick = cyc + S + rng() % (3 * S); break;
      case 5: tick = hls.state() == Gen::S_READY; n_run_ticks += tick; break;           // every clock
      default: tick = true; break;                                                       // too fast
    }
    const bool offer = !words.empty() && int(rng() % 100) < offer_pct;
    const uint64_t data = offer ? words.front() : rng();  // garbage when not valid

    typename Gen::In in;
    in.rst_n = rst_n;
    in.tick = tick;
    in.tvalid = offer;
    in.tdata = data & ((BCU_CHUNK >= 64) ? ~0ull : ((1ull << BCU_CHUNK) - 1));
    const bool acc = hls.tready() && offer;
    if (trace_from && cyc >= trace_from)
      std::printf("cyc %llu rst %d tick %d offer %d acc %d st %d lvl %d pc %d j %u tq %d\n",
                  (unsigned long long)cyc, rst_n, tick, offer, acc, hls.state(),
                  hls.regs().lvl_q, hls.regs().pc_q, hls.regs().j_q, hls.regs().tick_q);
    // the model's state before the edge, for the messages below
    const int st = hls.state(), depth_q = hls.regs().depth_q;
    const unsigned j_q = hls.regs().j_q;
    const auto& o = ls.step(in);  // RTL == hls on every port, then the clock edge

    bool bad = false;
    if (!ls.ok()) {
      std::printf("MISMATCH %s\n", ls.why().c_str());
      bad = true;
    }
    if (ls.compared() && !bad) {
    if (o.sample_valid) {
      // hls == host prediction
      std::vector<int64_t> got;
      for (int a = 0; a < BCU_AXES; ++a) got.push_back(static_cast<int64_t>(traj::sext(o.sample[a], BCU_OUT)));
      if (o.underrun) {
        if (got != end_value) {
          std::printf("MISMATCH cycle %llu underrun sample is not the end value\n", (unsigned long long)cyc);
          bad = true;
        }
      } else {
        if (expect.empty() || got != expect.front().v) {
          std::printf("MISMATCH cycle %llu sample != host prediction (state %d j %u depth %d, "
                      "queued %zu)\n", (unsigned long long)cyc, st, j_q, depth_q, expect.size());
          for (int a = 0; a < BCU_AXES; ++a)
            std::printf("  axis %d got %lld want %lld\n", a, (long long)got[a],
                        expect.empty() ? 0ll : (long long)expect.front().v[a]);
          if (!expect.empty()) {
            std::printf("  expected d=%d j=%d c:", expect.front().depth, expect.front().j);
            for (auto& r : expect.front().c)
              for (auto& v : r) std::printf(" %s", v.get_str().c_str());
            std::printf("\n");
          }
          bad = true;
        } else {
          if (trace_from && cyc >= trace_from)
            std::printf("   ok d=%d j=%d (hls j %u d %d)\n", expect.front().depth, expect.front().j, j_q, depth_q);
          expect.pop_front();
          ++n_checked;
        }
        if (o.seg_done && !expect.empty() && expect.front().depth == BCU_DEPTH) ++n_done_max;
        if (o.seg_done && !expect.empty()) {
          end_value = expect.front().v;
          expect.pop_front();
        }
      }
    }
    n_samples += o.sample_valid && !o.underrun;
    n_underrun += o.underrun;
    n_done += o.seg_done;
    n_tickerr += o.tick_err;
    }
    if (bad) {
      std::printf("FAIL (seed %llu)\n", (unsigned long long)seed);
      return 1;
    }
    if (acc && rst_n) words.pop_front();
    if (reset_ends) {  // the host restarts its stream after a reset
      ++n_resets;
      words.clear();
      expect.clear();
      end_value.clear();
      have_prev = false;
    }
  }
  std::printf("PASS: %llu samples (%llu checked against the host prediction), %llu seg_done "
              "(%llu at d = MaxDepth = %d), %llu ticks in every-clock phases, %llu underrun ticks, "
              "%llu resets, %llu cycles with tick_err set (%.1f %%)\n",
              (unsigned long long)n_samples, (unsigned long long)n_checked, (unsigned long long)n_done,
              (unsigned long long)n_done_max, BCU_DEPTH, (unsigned long long)n_run_ticks,
              (unsigned long long)n_underrun, (unsigned long long)n_resets, (unsigned long long)n_tickerr,
              100.0 * double(n_tickerr) / double(cycles));
  if (n_done_max == 0) {
    std::printf("FAIL: no segment of depth MaxDepth completed (seed %llu)\n", (unsigned long long)seed);
    return 1;
  }
  return 0;
}
