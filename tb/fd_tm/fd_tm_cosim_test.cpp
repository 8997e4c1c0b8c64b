// Co-simulation of the time-multiplexed FD engine (rtl/traj_fd_tm.sv):
//   * RTL == hls (hls/traj_fd_tm.hpp) on every cycle, every port, through the
//     lockstep driver (host/sim/lockstep.hpp);
//   * its samples == the parallel engine's hls model (hls/traj_fd_engine.hpp)
//     fed with the same words and ticks: the sequence of real samples always,
//     and tick by tick (underruns included) when ticks leave both engines
//     time to load;
//   * its samples == the host compiler's exact prediction (fd::Compiler::
//     sample_at) for every sample of a compiled segment;
//   * the sample RAM read port (sample_addr_i, random each cycle, compared by
//     the lockstep driver wherever the word is defined) gives the samples of
//     sample_o, word by word (SampleRamPortReadsEverySample).
// Built once per parameter set (CMakeLists.txt): VTOP, FD_AXES, FD_DEGREE,
// FD_WIDTH, FD_CHUNK, FD_GUARD. TRAJ_SEED=<n> reruns one seed.
#include <gtest/gtest.h>
#include <verilated.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "fd/fd_compiler.hpp"
#include "sim/lockstep.hpp"
#include "test_seed.hpp"
#include "traj_fd_engine.hpp"
#include "traj_fd_tm.hpp"
#include VTOP_H

namespace {

using Tm = traj::FdTm<FD_AXES, FD_DEGREE, FD_WIDTH, FD_CHUNK, FD_GUARD>;
using Par = traj::FdEngine<FD_AXES, FD_DEGREE, FD_WIDTH, FD_CHUNK, FD_GUARD>;
using traj::u128;

// The closed forms of the tick spacings, from the parameters: within a
// segment (a pass), and always (the last tick's pass, then a load).
constexpr int kChunks = FD_WIDTH / FD_CHUNK;
constexpr int kRunTick = FD_AXES * (FD_DEGREE + 1) * kChunks + 1 + (FD_AXES == 1 && kChunks == 1 && FD_DEGREE == 1);
constexpr int kMinTick = FD_AXES * kChunks * (FD_DEGREE + 2) + (FD_CHUNK == 16 ? 2 : 1) + 1;
static_assert(Tm::kRunTickClocks == kRunTick && Tm::kMinTickClocks == kMinTick,
              "the model's tick spacings are the closed forms");

// One segment of the stream, with the host's prediction when compiled.
struct Seg {
  std::vector<uint64_t> words;
  uint32_t K = 0;
  bool compiled = false;
  traj::fd::Compiled comp;
};

// Segments: chained compiled segments from the host compiler (a continuous
// random path) and, when raw_share > 0, raw random segments (random register
// bits, K in 0..20) that exercise wrap-around.
class Source {
 public:
  // raw_k >= 0: every raw segment has K = raw_k; -1: K in 0..20; -2: K in 1..20
  Source(uint64_t seed, int raw_in_4, int raw_k) : rng_(seed), comp_(format()), raw_in_4_(raw_in_4), raw_k_(raw_k) {}

  // GuardBits = 0 (every register bit in the sample, so an error in any bit
  // of r[0] shows): the compiler refuses it, so such a build streams raw
  // segments only and keeps a compiler of 1 guard bit that is never used.
  static constexpr bool kRawOnly = FD_GUARD == 0;
  static traj::fd::Format format() { return {FD_AXES, FD_DEGREE, FD_WIDTH, FD_CHUNK, kRawOnly ? 1 : FD_GUARD, 4}; }
  const traj::fd::Compiler& compiler() const { return comp_; }

  Seg next() {
    Seg s;
    if (kRawOnly || std::uniform_int_distribution<int>(0, 3)(rng_) < raw_in_4_) {
      s.K = raw_k_ >= 0 ? raw_k_ : std::uniform_int_distribution<uint32_t>(raw_k_ == -2, 20)(rng_);
      for (int b = 0; b < 32; b += FD_CHUNK) s.words.push_back((uint64_t(s.K) >> b) & traj::mask(FD_CHUNK));
      for (int n = 0; n < Par::kRegs * Par::kChunks; ++n)
        s.words.push_back(static_cast<uint64_t>(rng_() & traj::mask(FD_CHUNK)));
      have_prev_ = false;
      return s;
    }
    traj::fd::PolySegment seg;
    seg.h = 1e-3;
    const uint64_t kmax = std::min<uint64_t>(traj::fd::Compiler::longest_segment(FD_DEGREE, FD_GUARD, 0.5), 40);
    seg.ticks = std::uniform_int_distribution<uint64_t>(1, kmax)(rng_);
    const double T = seg.ticks * seg.h;
    const double range = std::ldexp(1.0, std::min(Par::kOutWidth, 44) - 3 - 4);
    std::uniform_real_distribution<double> U(-1, 1);
    for (int a = 0; a < FD_AXES; ++a) {
      std::vector<double> c(FD_DEGREE + 1);
      c[0] = have_prev_ ? x0_[a] : U(rng_) * range / 2;
      double Tj = 1;
      for (int j = 1; j <= FD_DEGREE; ++j) {
        Tj *= T;
        c[j] = U(rng_) * range / (8.0 * FD_DEGREE) / Tj;
      }
      seg.coef.push_back(c);
    }
    s.comp = comp_.compile(seg, have_prev_ ? &prev_end_ : nullptr);
    s.words = comp_.words(s.comp);
    s.K = s.comp.ticks;
    s.compiled = true;
    prev_end_ = s.comp.end;
    x0_.assign(FD_AXES, 0);
    for (int a = 0; a < FD_AXES; ++a) {
      long double v = 0;
      for (int j = FD_DEGREE; j >= 0; --j) v = v * T + seg.coef[a][j];
      x0_[a] = static_cast<double>(v);
    }
    have_prev_ = true;
    return s;
  }

 private:
  std::mt19937_64 rng_;
  traj::fd::Compiler comp_;
  int raw_in_4_;
  int raw_k_;
  bool have_prev_ = false;
  std::vector<mpz_class> prev_end_;
  std::vector<double> x0_;
};

// What an engine answered to one tick.
struct Event {
  bool underrun = false, valid = false, seg_done = false;
  std::vector<u128> sample;
  bool operator==(const Event& o) const {
    return underrun == o.underrun && valid == o.valid && seg_done == o.seg_done &&
           (!valid || sample == o.sample);
  }
};

std::string show(const Event& e) {
  std::string s = e.underrun ? "underrun" : "sample";
  s += e.valid ? " valid" : " invalid";
  if (e.seg_done) s += " seg_done";
  if (e.valid)
    for (auto v : e.sample) s += " " + std::to_string(static_cast<unsigned long long>(v));
  return s;
}

// One engine's side of the bench: its own cursor into the shared word list
// and the events it emitted.
template <class Unit>
struct Side {
  Unit unit;
  size_t word = 0;
  std::vector<Event> events;  // every sample_valid or underrun pulse
  bool tick_err = false;

  template <class Ports>
  void record(const Ports& p) {
    tick_err = p.tick_err;
    if (!p.sample_valid && !p.underrun) return;
    Event e;
    e.underrun = p.underrun;
    e.valid = p.sample_valid;
    e.seg_done = p.seg_done;
    if (p.sample_valid) e.sample.assign(p.sample, p.sample + FD_AXES);
    events.push_back(e);
  }
};

struct Stim {
  bool rst_n = true, tick = false, stall = false;
  int sample_addr = -1;  // the sample RAM address read (-1: random)
};

class Bench {
 public:
  Bench(uint64_t seed, int raw_in_4, double p_valid, int raw_k = -1)
      : src_(seed, raw_in_4, raw_k), rng_(seed * 7 + 1), p_valid_(p_valid) {}

  // One cycle of both engines with the same reset and tick.
  ::testing::AssertionResult cycle(const Stim& s) {
    std::uniform_real_distribution<double> U(0, 1);
    drive(tm_, s, !s.stall && U(rng_) < p_valid_);
    if (!tm_.unit.ok()) return ::testing::AssertionFailure() << "RTL != hls: " << tm_.unit.why();
    drive(par_, s, !s.stall && U(rng_) < p_valid_);
    if (!s.rst_n) restart_ = true;
    return ::testing::AssertionSuccess();
  }

  // The real samples of both engines agree (as far as both got), and every
  // sample of a compiled segment is the host's prediction.
  ::testing::AssertionResult samples_agree() const {
    const auto t = real(tm_.events), p = real(par_.events);
    const size_t n = std::min(t.size(), p.size());
    for (size_t i = 0; i < n; ++i)
      if (!(t[i] == p[i])) return ::testing::AssertionFailure() << "real sample " << i << ": tm " << show(t[i]) << ", parallel " << show(p[i]);
    // prediction: walk the segments in stream order
    size_t i = 0;
    for (const Seg& s : segs_) {
      for (uint32_t k = 0; k < s.K && i < t.size(); ++k, ++i) {
        if (t[i].seg_done != (k + 1 == s.K))
          return ::testing::AssertionFailure() << "real sample " << i << ": seg_done " << t[i].seg_done << " at k " << k << " of " << s.K;
        if (!s.compiled) continue;
        for (int a = 0; a < FD_AXES; ++a) {
          const mpz_class want = src_.compiler().sample_at(s.comp, a, k);
          const mpz_class got = signed_mpz(t[i].sample[a]);
          if (want != got)
            return ::testing::AssertionFailure() << "real sample " << i << " axis " << a << ": " << got.get_str() << ", predicted " << want.get_str();
        }
      }
    }
    return ::testing::AssertionSuccess();
  }
  size_t predicted_samples() const {
    size_t n = 0, i = 0;
    const size_t got = real(tm_.events).size();
    for (const Seg& s : segs_)
      for (uint32_t k = 0; k < s.K && i < got; ++k, ++i) n += s.compiled;
    return n;
  }

  const std::vector<Event>& tm_events() const { return tm_.events; }
  // the RTL's sample RAM read port of the last cycle (equal to the model's
  // wherever the model's word is defined: the lockstep driver compares)
  uint64_t tm_sample_word() const { return tm_.last_word; }
  const std::vector<Event>& par_events() const { return par_.events; }
  bool tm_tick_err() const { return tm_.tick_err; }
  bool par_tick_err() const { return par_.tick_err; }
  uint64_t cycles() const { return tm_.unit.cycles(); }

 private:
  static std::vector<Event> real(const std::vector<Event>& ev) {
    std::vector<Event> r;
    for (const auto& e : ev)
      if (e.valid && !e.underrun) r.push_back(e);
    return r;
  }
  static mpz_class signed_mpz(u128 v) {
    const traj::i128 s = traj::sext(v, Par::kOutWidth);
    const bool neg = s < 0;
    const u128 m = neg ? u128(-(s + 1)) + 1 : u128(s);
    mpz_class r(static_cast<unsigned long>(m >> 64));
    r <<= 64;
    r += mpz_class(static_cast<unsigned long>(m & ~uint64_t(0)));
    return neg ? mpz_class(-r) : r;
  }

  uint64_t word(size_t i) {
    while (i >= words_.size()) {
      segs_.push_back(src_.next());
      words_.insert(words_.end(), segs_.back().words.begin(), segs_.back().words.end());
    }
    return words_[i];
  }

  template <class S>
  void drive(S& side, const Stim& s, bool offer) {
    typename S::In in;
    in.rst_n = s.rst_n;
    in.tick = s.tick;
    in.tvalid = offer;
    in.tdata = offer ? word(side.word) : rng_();  // tdata is don't-care when !tvalid
    if constexpr (std::is_same_v<typename S::In, Tm::In>) in.sample_addr = s.sample_addr >= 0 ? s.sample_addr : static_cast<int>(rng_() % Tm::kSampleWords);
    const bool accepted = offer && side.tready() && s.rst_n;
    side.step(in);
    if (accepted) ++side.word;
  }

  // The units behind a common stepping interface.
  struct TmSide : Side<traj::sim::Lockstep<VTOP, Tm>> {
    using In = Tm::In;
    bool tready() const { return unit.model().outputs().tready; }
    uint64_t last_word = 0;
    void step(const In& in) {
      const auto& p = unit.step(in);
      last_word = p.sample_word;
      if (unit.compared()) record(p);  // before the first reset edge the RTL holds random state
    }
  };
  struct ParSide : Side<traj::sim::HlsUnit<Par>> {
    using In = Par::In;
    bool tready() const { return unit.model().outputs().tready; }
    void step(const In& in) { record(unit.step(in)); }
  };

  Source src_;
  std::vector<Seg> segs_;
  std::vector<uint64_t> words_;
  std::mt19937_64 rng_;
  double p_valid_;
  bool restart_ = false;
  TmSide tm_;
  ParSide par_;
};

std::vector<uint64_t> seeds() {
  if (traj::test::env_seed_given()) return {traj::test::env_seed(0)};
  return {1, 2};
}

// Random tick spacing in [lo, hi] clocks; the engines get words with
// probability p_valid per cycle; no reset after the first.
void run_random(uint64_t seed, int lo, int hi, double p_valid, uint64_t cycles, bool expect_no_err) {
  std::printf("  seed %llu (rerun: TRAJ_SEED=%llu)\n", static_cast<unsigned long long>(seed),
              static_cast<unsigned long long>(seed));
  Bench b(seed, 1, p_valid);
  std::mt19937_64 rng(seed ^ 0x5bd1e995ull);
  std::uniform_int_distribution<int> gap(lo, hi);
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(b.cycle({false, false, false}));
  int next = gap(rng);
  for (uint64_t c = 0; c < cycles; ++c) {
    Stim s;
    if (--next <= 0) {
      s.tick = true;
      next = gap(rng);
    }
    ASSERT_TRUE(b.cycle(s)) << "seed " << seed << " cycle " << c;
  }
  ASSERT_TRUE(b.samples_agree()) << "seed " << seed;
  if (expect_no_err) {
    EXPECT_FALSE(b.tm_tick_err()) << "ticks at least MinTickClocks apart";
  }
  std::printf("    %llu cycles, %zu events, %zu samples checked against the prediction\n",
              static_cast<unsigned long long>(b.cycles()), b.tm_events().size(), b.predicted_samples());
  if (!Source::kRawOnly) {
    EXPECT_GT(b.predicted_samples(), 0u);
  }
}

}  // namespace

TEST(FdTmCosim, RandomTicksAndBackPressure) {
  for (auto s : seeds()) run_random(s, kMinTick, kMinTick + 4 * Par::kWords, 0.6, 200000, false);
}

TEST(FdTmCosim, FastTicksOverrun) {
  // ticks faster than the engine can follow: tick_err and every port still
  // match the model; the real samples still come in stream order
  for (auto s : seeds()) run_random(s, 1, kMinTick + 2, 0.9, 60000, false);
}

TEST(FdTmCosim, ResetMidSegment) {
  for (auto seed : seeds()) {
    Bench b(seed, 1, 0.8);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> U(0, 1);
    std::uniform_int_distribution<int> gap(kMinTick, 3 * Par::kWords + kMinTick);
    for (int i = 0; i < 2; ++i) ASSERT_TRUE(b.cycle({false, false, false}));
    int next = gap(rng);
    for (int c = 0; c < 150000; ++c) {
      Stim s;
      s.rst_n = !(U(rng) < 0.002);
      if (--next <= 0) {
        s.tick = true;
        next = gap(rng);
      }
      ASSERT_TRUE(b.cycle(s)) << "seed " << seed << " cycle " << c;
    }
    EXPECT_GT(b.tm_events().size(), 0u);
  }
}

TEST(FdTmCosim, EveryTickAsTheParallelEngine) {
  // Ticks G clocks apart, G leaving both engines time to finish a pass and
  // load the next segment; the stream stalls for whole tick periods (stalls
  // start just after a tick), so both engines underrun on the same ticks.
  // (No K = 0 segments here: a tick waits for their load too.)
  // The answer to every tick (sample, underrun, seg_done) is the parallel
  // engine's; compiled samples are the host's prediction.
  const int G = kMinTick + Par::kWords + 4;
  for (auto seed : seeds()) {
    Bench b(seed, 1, 1.0, -2);
    std::mt19937_64 rng(seed + 99);
    for (int i = 0; i < 2; ++i) ASSERT_TRUE(b.cycle({false, false, false}));
    int stall_left = 0;
    for (int t = 0; t < 3000; ++t) {
      for (int c = 0; c < G; ++c) {
        // (not in the first period: its tick waits for the first load)
        if (t > 0 && c == 1 && stall_left == 0 && rng() % 40 == 0) stall_left = static_cast<int>(1 + rng() % 5) * G;
        Stim s;
        s.tick = c == 0;
        s.stall = stall_left > 0;
        if (s.stall) --stall_left;
        ASSERT_TRUE(b.cycle(s)) << "seed " << seed << " tick " << t;
      }
    }
    const auto& te = b.tm_events();
    const auto& pe = b.par_events();
    ASSERT_EQ(te.size(), pe.size()) << "one answer per tick in both engines";
    for (size_t i = 0; i < te.size(); ++i) ASSERT_TRUE(te[i] == pe[i]) << "tick " << i << ": tm " << show(te[i]) << ", parallel " << show(pe[i]);
    ASSERT_TRUE(b.samples_agree());
    EXPECT_FALSE(b.tm_tick_err());
    EXPECT_FALSE(b.par_tick_err());
    size_t under = 0;
    for (const auto& e : te) under += e.underrun;
    EXPECT_GT(under, 0u);
    EXPECT_GT(te.size() - under, 1000u);
  }
}

TEST(FdTmCosim, CompiledStreamAtMinimumSpacing) {
  // A compiled path only (the host's fd compiler output, chained), ticks
  // exactly MinTickClocks apart: no tick waits (no tick_err), and every
  // sample is the host's exact prediction and the parallel engine's.
  for (auto seed : seeds()) {
    Bench b(seed, 0, 1.0);
    for (int i = 0; i < 2; ++i) ASSERT_TRUE(b.cycle({false, false, false}));
    // load the first segment before the first tick
    for (int c = 0; c < Par::kWords + 2; ++c) ASSERT_TRUE(b.cycle({}));
    for (int t = 0; t < 400; ++t)
      for (int c = 0; c < kMinTick; ++c) ASSERT_TRUE(b.cycle({true, c == 0, false}));
    EXPECT_FALSE(b.tm_tick_err()) << "ticks MinTickClocks apart";
    ASSERT_TRUE(b.samples_agree());
    if (!Source::kRawOnly) {
      EXPECT_GT(b.predicted_samples(), 10u);
    }
  }
}

// Ticks `spacing` clocks apart on a loaded engine for `ticks` ticks; returns
// whether tick_err was set.
bool tick_err_at(Bench& b, int spacing, int ticks) {
  for (int i = 0; i < 2; ++i) EXPECT_TRUE(b.cycle({false, false, false}));
  for (int c = 0; c < Par::kWords + 2; ++c) EXPECT_TRUE(b.cycle({}));
  for (int t = 0; t < ticks; ++t)
    for (int c = 0; c < spacing; ++c) EXPECT_TRUE(b.cycle({true, c == 0, false}));
  return b.tm_tick_err();
}

TEST(FdTmCosim, TickSpacingsAreTight) {
  // Within a segment (K = 100 000) kRunTick is enough and kRunTick - 1 is
  // not; segments of one tick each need kMinTick, and kMinTick - 1 is not
  // enough (a late tick falls one clock further behind each time until one
  // arrives while another is pending).
  {
    Bench b(3, 4, 1.0, 100000);
    EXPECT_FALSE(tick_err_at(b, kRunTick, 300));
  }
  {
    Bench b(3, 4, 1.0, 100000);
    EXPECT_TRUE(tick_err_at(b, kRunTick - 1, 2 * kRunTick + 4));
  }
  {
    Bench b(3, 4, 1.0, 1);
    EXPECT_FALSE(tick_err_at(b, kMinTick, 300));
    ASSERT_TRUE(b.samples_agree());
  }
  {
    Bench b(3, 4, 1.0, 1);
    EXPECT_TRUE(tick_err_at(b, kMinTick - 1, 2 * kMinTick + 4));
  }
}

TEST(FdTmCosim, OneStrobeIsOneTick) {
  // A strobe of any width is one tick (one answer); wider than one clock it
  // sets tick_err. Reference: the number of strobes sent.
  Bench b(5, 0, 1.0);
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(b.cycle({false, false, false}));
  for (int c = 0; c < Par::kWords + 2; ++c) ASSERT_TRUE(b.cycle({}));
  auto strobe = [&](int width) {
    for (int i = 0; i < width; ++i) ASSERT_TRUE(b.cycle({true, true, false}));
    for (int i = 0; i < 2 * kMinTick + Par::kWords; ++i) ASSERT_TRUE(b.cycle({}));
  };
  for (int t = 0; t < 3; ++t) strobe(1);
  EXPECT_EQ(b.tm_events().size(), 3u);
  EXPECT_FALSE(b.tm_tick_err());
  strobe(2);
  EXPECT_EQ(b.tm_events().size(), 4u) << "a 2-clock strobe is one tick";
  EXPECT_TRUE(b.tm_tick_err());
  strobe(12);
  EXPECT_EQ(b.tm_events().size(), 5u);
}

TEST(FdTmCosim, SampleRamPortReadsEverySample) {
  // After each sample_valid the port is read at every {axis, chunk}: the
  // words, reassembled, are sample_o's sample (bits GuardBits and up of
  // r[0]), which the other tests check against the parallel engine and the
  // host's prediction. Ticks 2 * MinTickClocks apart leave time to read.
  constexpr int kWordsRead = FD_AXES * kChunks;
  constexpr int kChB = Tm::kSampleAddrWidth - (FD_AXES > 1 ? 32 - __builtin_clz(FD_AXES - 1) : 0);
  static_assert(2 * kMinTick > kRunTick + kWordsRead + 4, "time to read the port between ticks");
  Bench b(11, 1, 1.0);
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(b.cycle({false, false, false}));
  size_t checked = 0;
  for (int t = 0; t < 300; ++t) {
    const size_t before = b.tm_events().size();
    int c = 0;
    for (; c < 2 * kMinTick && b.tm_events().size() == before; ++c) ASSERT_TRUE(b.cycle({true, c == 0, false}));
    if (b.tm_events().size() == before || !b.tm_events().back().valid) {
      for (; c < 2 * kMinTick; ++c) ASSERT_TRUE(b.cycle({}));
      continue;
    }
    const Event e = b.tm_events().back();
    std::vector<u128> reg(FD_AXES, 0);
    for (int w = 0; w <= kWordsRead; ++w, ++c) {  // address w; its word a clock later
      Stim s;
      s.sample_addr = w < kWordsRead ? ((w / kChunks) << kChB) | (w % kChunks) : 0;
      ASSERT_TRUE(b.cycle(s));
      if (w > 0) {
        const int a = (w - 1) / kChunks, ch = (w - 1) % kChunks;
        reg[a] |= u128(b.tm_sample_word()) << (ch * FD_CHUNK);
      }
    }
    for (int a = 0; a < FD_AXES; ++a) {
      const u128 smp = (reg[a] >> FD_GUARD) & traj::mask(Par::kOutWidth);
      ASSERT_EQ(static_cast<unsigned long long>(smp), static_cast<unsigned long long>(e.sample[a])) << "tick " << t << " axis " << a;
      ASSERT_EQ(static_cast<unsigned long long>(smp >> 64), static_cast<unsigned long long>(e.sample[a] >> 64)) << "tick " << t << " axis " << a;
    }
    ++checked;
    for (; c < 2 * kMinTick; ++c) ASSERT_TRUE(b.cycle({}));
  }
  EXPECT_GT(checked, 200u);
}
