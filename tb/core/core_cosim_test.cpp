// SPDX-License-Identifier: Apache-2.0
// Verilator co-simulation: rtl/traj_core.sv == hls/traj_core.hpp, every cycle:
// control outputs (s_axis_tready, sample_valid_o, underrun_o, seg_done_o,
// tick_err_o) always, sample_o when sample_valid_o. Random mixed-kind segment
// sequences (FD with random registers and K, BCU with random control values and
// depths, chained and not), random idle cycles on the stream (back-pressure
// comes from the engines), random tick spacing (exactly the documented minimum,
// random above it, sparse; BCU runs: a tick on every clock while the BCU owns
// the segment and has a sample ready, FD ticks at the minimum; and, in rare
// phases ended by a reset, too fast: tick_err, where only RTL == hls is
// checked), starved stream (underrun and
// recovery), random resets (also mid-segment). Every real sample is also
// checked against the exact host prediction (FD: closed form; BCU: GMP), in
// order, across kind switches; every underrun sample must hold the last output
// or be the last BCU segment's end value.
//
// usage: cosim_core [--seed N] [--cycles N]   (or env TRAJ_SEED)
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <gmpxx.h>
#include <memory>
#include <random>
#include <vector>

#include "test_seed.hpp"
#include "Vtraj_core.h"
#include "bcu/bcu_compiler.hpp"
#include "fd/fd_compiler.hpp"
#include "sim/lockstep.hpp"
#include "traj_core.hpp"

using traj::u128;
#ifndef C_FDTM
#define C_FDTM 0
#endif
using Core = traj::Core<C_AXES, C_DEGREE, C_WIDTH, C_CHUNK, C_GUARD, C_CTRL, C_BGUARD, C_DEPTH, C_FDTM != 0>;
constexpr int kOut = Core::kOutWidth;

struct Word {
  uint64_t data;
  bool kind;
};
struct Expect {
  std::vector<int64_t> v;
  bool done;
  bool bcu;
  std::vector<int64_t> bcu_end;  // for the last BCU sample: the end value
};

int main(int argc, char** argv) {
  uint64_t seed = 1;
  seed = traj::test::env_seed(seed);
  uint64_t cycles = 1000000;
  uint64_t trace_from = ~0ull;
  if (const char* s = std::getenv("TRAJ_CORE_TRACE")) trace_from = std::strtoull(s, nullptr, 0);
  for (int i = 1; i + 1 < argc; ++i) {
    if (!std::strcmp(argv[i], "--seed")) seed = std::strtoull(argv[++i], nullptr, 0);
    else if (!std::strcmp(argv[i], "--cycles")) cycles = std::strtoull(argv[++i], nullptr, 0);
  }
  std::printf("cosim_core: Axes=%d Degree=%d Width=%d ChunkWidth=%d GuardBits=%d CtrlWidth=%d "
              "BcuGuardBits=%d MaxDepth=%d FdTimeMux=%d min tick spacing %d, seed=%llu cycles=%llu "
              "(reproduce: --seed %llu or TRAJ_SEED=%llu)\n",
              C_AXES, C_DEGREE, C_WIDTH, C_CHUNK, C_GUARD, C_CTRL, C_BGUARD, C_DEPTH, C_FDTM,
              Core::kMinTickSpacing, (unsigned long long)seed, (unsigned long long)cycles,
              (unsigned long long)seed, (unsigned long long)seed);

  traj::sim::Lockstep<Vtraj_core, Core> ls(static_cast<int>(seed & 0x7fffffff));
  const Core& hls = ls.model();
  std::mt19937_64 rng(seed);

  traj::bcu::Format bf{C_AXES, C_CHUNK, C_CTRL, C_BGUARD, kOut, C_DEPTH};
  traj::fd::Format ff{C_AXES, C_DEGREE, C_WIDTH, C_CHUNK, C_GUARD};
  const traj::fd::Compiler fdc(ff);

  std::deque<Word> words;
  std::deque<Expect> expect;
  std::vector<mpz_class> prevD(C_AXES);
  bool have_prevD = false;

  auto rand_bits = [&](int w) {  // random signed w-bit value, extremes now and then
    mpz_class lim = 1;
    lim <<= (w - 1);
    const int kind = static_cast<int>(rng() % 8);
    if (kind == 0) return mpz_class(lim - 1);
    if (kind == 1) return mpz_class(-lim);
    mpz_class v = 0;
    for (int k = 0; k < w; k += 64) {
      v <<= 64;
      v += static_cast<unsigned long>(rng());
    }
    if (kind == 2) v >>= (rng() % w);
    v = v % (2 * lim);
    return mpz_class(v - lim);
  };
  auto add_bcu = [&]() {
    int d = static_cast<int>(rng() % (std::min(C_DEPTH, 5) + 1));
    if (rng() % 16 == 0) d = static_cast<int>(rng() % (std::min(C_DEPTH, 9) + 1));
    std::vector<std::vector<mpz_class>> c(C_AXES, std::vector<mpz_class>(4));
    const bool chain = have_prevD && rng() % 3 != 0;
    for (int a = 0; a < C_AXES; ++a) {
      for (int i = 0; i < 4; ++i) c[a][i] = rand_bits(C_CTRL);
      if (chain) c[a][0] = prevD[a];
      prevD[a] = c[a][3];
    }
    have_prevD = true;
    for (uint64_t w : traj::bcu::stream_words(c, d, bf)) words.push_back({w, true});
    const int K = 1 << d;
    std::vector<int64_t> end;
    for (int a = 0; a < C_AXES; ++a) end.push_back(traj::bcu::predict_sample(c[a], d, K, C_BGUARD));
    for (int j = 0; j < K; ++j) {
      Expect e;
      for (int a = 0; a < C_AXES; ++a) e.v.push_back(traj::bcu::predict_sample(c[a], d, j, C_BGUARD));
      e.done = j == K - 1;
      e.bcu = true;
      if (e.done) e.bcu_end = end;
      expect.push_back(e);
    }
  };
  auto add_fd = [&]() {
    traj::fd::Compiled cs;
    cs.ticks = 1 + static_cast<uint32_t>(rng() % 40);
    if (rng() % 16 == 0) cs.ticks = 1 + static_cast<uint32_t>(rng() % 300);
    cs.regs.assign(C_AXES, std::vector<mpz_class>(C_DEGREE + 1));
    for (auto& ax : cs.regs)
      for (auto& r : ax) r = rand_bits(C_WIDTH);
    for (uint64_t w : fdc.words(cs)) words.push_back({w, false});
    const mpz_class mod = mpz_class(1) << C_WIDTH;
    for (uint32_t k = 0; k < cs.ticks; ++k) {
      Expect e;
      for (int a = 0; a < C_AXES; ++a) {
        mpz_class v = traj::fd::Compiler::state_at(cs, a, k) % mod;
        if (v < 0) v += mod;
        if (v >= mod / 2) v -= mod;  // signed W bits
        mpz_fdiv_q_2exp(v.get_mpz_t(), v.get_mpz_t(), C_GUARD);
        e.v.push_back(v.get_si());
      }
      e.done = k + 1 == cs.ticks;
      e.bcu = false;
      expect.push_back(e);
    }
  };

  int tick_mode = 0, offer_pct = 100;
  bool starve = false;
  uint64_t next_tick = 0, phase_end = 0;
  uint64_t n_run = 0, n_samples_unchecked = 0, n_samples = 0, n_underrun = 0, n_done = 0, n_resets = 0, n_err = 0, n_switch = 0;
  bool in_reset = true, last_was_bcu = false, have_last_kind = false;
  int reset_left = 3;
  std::vector<int64_t> last_out, last_bcu_end;
  const int S = Core::kMinTickSpacing;

  for (uint64_t cyc = 0; cyc < cycles; ++cyc) {
    if (cyc >= phase_end) {
      if (tick_mode == 4 && !in_reset) {  // leave the too-fast phase through a reset
        in_reset = true;
        reset_left = 1 + static_cast<int>(rng() % 3);
      }
      tick_mode = static_cast<int>(rng() % 6);  // 0..3, 5 respect the minimum spacing
      if (tick_mode == 4 || rng() % 12 == 0) tick_mode = (rng() % 3 == 0) ? 4 : 5;  // 4: too fast
      offer_pct = (rng() % 3 == 0) ? 100 : 20 + static_cast<int>(rng() % 80);
      starve = rng() % 6 == 0;
      phase_end = cyc + 5000 + rng() % 60000;
    }
    if (!in_reset && rng() % 60000 == 0) {
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
    if (rst_n && !starve && words.size() < 200 && rng() % 3 == 0) {
      if (rng() % 2) add_bcu();
      else add_fd();
    }

    bool tick = false;
    switch (tick_mode) {
      case 0: tick = cyc >= next_tick; if (tick) next_tick = cyc + S; break;
      case 1: tick = cyc >= next_tick; if (tick) next_tick = cyc + S + rng() % S; break;
      case 2: tick = cyc >= next_tick; if (tick) next_tick = cyc + S + rng() % (8 * S); break;
      case 3: tick = cyc >= next_tick; if (tick) next_tick = cyc + S + rng() % (2 * S); break;
      case 5: {  // BCU runs at one sample per clock, FD ticks at the minimum
        const auto ck = hls.comb(Core::In{});
        const auto& br = hls.bcu().regs();
        if (ck.tick_kind) {
          // not the tick after the last sample of a BCU segment (it could
          // belong to an FD segment: the core needs the BCU's seg_done first)
          tick = hls.bcu().state() == Core::Bcu::S_READY && !(br.tick_q && br.tag[Core::Bcu::kC - 1].last);
          n_run += tick;
        } else {
          tick = cyc >= next_tick;
          if (tick) next_tick = cyc + S;
        }
        break;
      }
      default: tick = rng() % 5 == 0; break;
    }
    const bool offer = !words.empty() && int(rng() % 100) < offer_pct;
    const uint64_t cmask = C_CHUNK >= 64 ? ~0ull : ((1ull << C_CHUNK) - 1);
    const uint64_t data = (offer ? words.front().data : rng()) & cmask;
    const bool user = offer ? words.front().kind : (rng() & 1);

    Core::In in;
    in.rst_n = rst_n;
    in.tick = tick;
    in.tvalid = offer;
    in.tdata = data;
    in.tuser = user;
    const bool acc = hls.tready(in) && offer;
    if (cyc >= trace_from) {
      const auto c = hls.comb(in);
      std::printf("cyc %llu rst %d tick %d->%s offer %d kind %d acc %d | nb %d fdf %d fpos %d last %d sel %d | "
                  "fd v%d u%d d%d act %d | bcu v%d u%d d%d st %d | out v%d u%d | exp %zu %s\n",
                  (unsigned long long)cyc, rst_n, tick, c.tick_kind ? "bcu" : "fd", offer, user, acc,
                  hls.regs().nb_q, hls.regs().fdf_q, hls.regs().fpos_q, hls.regs().last_kind_q,
                  hls.regs().sel_q, hls.fd().outputs().sample_valid, hls.fd().outputs().underrun,
                  hls.fd().outputs().seg_done, hls.fd().active(), hls.bcu().sample_valid(),
                  hls.bcu().underrun(), hls.bcu().seg_done(), hls.bcu().state(), hls.sample_valid(),
                  hls.underrun(), expect.size(), expect.empty() ? "-" : (expect.front().bcu ? "bcu" : "fd"));
    }
    const auto& o = ls.step(in);  // RTL == hls on every port, then the clock edge

    bool bad = false;
    if (!ls.ok()) {
      std::printf("MISMATCH %s\n", ls.why().c_str());
      bad = true;
    }
    if (ls.compared() && !bad) {
      if (o.sample_valid) {
        std::vector<int64_t> got;
        for (int a = 0; a < C_AXES; ++a) got.push_back(static_cast<int64_t>(traj::sext(o.sample[a], kOut)));
        if (o.tick_err) {
          // ticks faster than the engines: samples may be late or out of
          // order; only RTL == hls is checked until the next reset
          ++n_samples_unchecked;
        } else if (o.underrun) {
          if (got != last_out && got != last_bcu_end) {
            std::printf("MISMATCH cycle %llu underrun sample neither holds nor is the BCU end value\n",
                        (unsigned long long)cyc);
            bad = true;
          }
        } else if (expect.empty() || got != expect.front().v || o.seg_done != expect.front().done) {
          std::printf("MISMATCH cycle %llu sample != host prediction (queued %zu, seg_done %d)\n",
                      (unsigned long long)cyc, expect.size(), o.seg_done);
          for (int a = 0; a < C_AXES; ++a)
            std::printf("  axis %d got %lld want %lld\n", a, (long long)got[a],
                        expect.empty() ? 0ll : (long long)expect.front().v[a]);
          bad = true;
        } else {
          const Expect& e = expect.front();
          if (have_last_kind && e.bcu != last_was_bcu) ++n_switch;
          have_last_kind = true;
          last_was_bcu = e.bcu;
          if (e.done && e.bcu) last_bcu_end = e.bcu_end;
          expect.pop_front();
          ++n_samples;
        }
        last_out = got;
      }
      n_underrun += o.underrun;
      n_done += o.seg_done;
      n_err += o.tick_err;
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
      last_out.clear();
      last_bcu_end.clear();
      have_prevD = false;
      have_last_kind = false;
    }
  }
  std::printf("PASS: %llu samples checked against the host prediction (%llu more under tick_err: RTL == hls only), %llu kind switches, "
              "%llu seg_done, %llu ticks in BCU runs at one per clock, %llu underrun ticks, %llu resets, %llu cycles with tick_err set\n",
              (unsigned long long)n_samples, (unsigned long long)n_samples_unchecked, (unsigned long long)n_switch,
              (unsigned long long)n_done, (unsigned long long)n_run, (unsigned long long)n_underrun,
              (unsigned long long)n_resets, (unsigned long long)n_err);
  return 0;
}
