// SPDX-License-Identifier: Apache-2.0
#include "sim/sim.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "engine_builds.hpp"  // generated (host/sim/CMakeLists.txt)
#include "sim/lockstep.hpp"

#if TRAJ_APP_CORE
#include "bcu/bcu_compiler.hpp"
#include "fd/fd_ticker.hpp"
#endif

namespace traj::sim {
namespace {

// The stream words in order, with the kind on tuser (traj_core only): all of
// them in memory (the traj_core path, whose prediction holds the records).
struct Feed {
  std::vector<uint64_t> words;
  std::vector<bool> bcu;  // per word; empty for traj_fd_engine
  size_t first_len = 0;   // words of the first segment
  uint64_t ticks = 0;     // samples the stream holds
  size_t next = 0;        // the word on the bus

  bool valid() { return next < words.size(); }
  uint64_t data() const { return words[next]; }
  bool tuser() const { return !bcu.empty() && bcu[next]; }
  void pop() { ++next; }
  size_t consumed() const { return next; }
  uint64_t ticks_known() const { return ticks; }
  bool all_read() const { return true; }
  uint64_t longest_segment_words() const { return words.size(); }
  double fraction(uint64_t samples) const { return ticks ? double(samples) / ticks : 0; }
};

// The words of an FD stream pulled a segment at a time: one segment's words in
// memory whatever the stream's length.
class PulledFeed {
 public:
  PulledFeed(const stream::Header& h, const RecordPull& pull, uint64_t records)
      : comp_(h.format()), pull_(pull), records_(records) {}
  bool valid() {
    if (next_ == words_.size() && !all_read_) refill();
    return next_ < words_.size();
  }
  uint64_t data() const { return words_[next_]; }
  bool tuser() const { return false; }
  void pop() {
    ++next_;
    ++consumed_;
  }
  size_t consumed() const { return consumed_; }
  uint64_t ticks_known() const { return ticks_; }
  bool all_read() const { return all_read_; }
  uint64_t longest_segment_words() const { return longest_; }
  double fraction(uint64_t) const { return records_ ? double(pulled_) / records_ : 0; }
  const size_t& first_segment_words() const { return first_len_; }

 private:
  void refill() {
    stream::Record r;
    if (!pull_(r)) {
      all_read_ = true;
      return;
    }
    if (r.is_bcu()) throw std::runtime_error("BCU segment in a stream without a BCU format");
    c_.ticks = r.ticks;
    c_.regs = std::move(r.regs);
    words_ = comp_.words(c_);
    if (first_len_ == 0) first_len_ = words_.size();
    next_ = 0;
    longest_ = std::max<uint64_t>(longest_, words_.size());
    ticks_ += r.ticks;
    ++pulled_;
  }
  fd::Compiler comp_;
  RecordPull pull_;
  uint64_t records_;
  fd::Compiled c_;
  std::vector<uint64_t> words_;
  size_t next_ = 0, consumed_ = 0, first_len_ = 0;
  uint64_t ticks_ = 0, pulled_ = 0, longest_ = 0;
  bool all_read_ = false;
};

Feed fd_feed(const stream::Header& h, const std::vector<stream::Record>& recs) {
  Feed f;
  const fd::Compiler comp(h.format());
  for (const auto& r : recs) {
    fd::Compiled c;
    c.ticks = r.ticks;
    c.regs = r.regs;
    const auto w = comp.words(c);
    f.words.insert(f.words.end(), w.begin(), w.end());
    if (f.first_len == 0) f.first_len = f.words.size();
    f.ticks += r.ticks;
  }
  return f;
}

// Ticks every `gap` cycles on the absolute cycle count.
struct EveryGap {
  uint64_t gap;
  bool tick(uint64_t cycle) { return cycle % gap == 0; }
  void fed(size_t, uint64_t) {}
  void sampled() {}
};

// The engine's own pace: the first tick once the first segment is in, then
// one in the cycle after each sample. A tick that meets a segment load waits
// inside the engine (its tick contract); never two are outstanding, so none
// is early, and the simulation runs at the engine's minimum tick spacing.
struct AfterEachSample {
  const size_t& first_len;  // words of the first segment (0 until it is known)
  bool armed = false, due = false;
  bool tick(uint64_t) {
    const bool t = due;
    due = false;
    return t;
  }
  void fed(size_t words_in, uint64_t) {
    if (!armed && first_len > 0 && words_in >= first_len) armed = due = true;
  }
  void sampled() { due = true; }
};

// First tick one gap after the first segment has entered the unit (a gap
// covers a segment's load and descent), then one every gap.
struct GapAfterFirstSegment {
  uint64_t gap;
  size_t first_len;
  uint64_t next = ~0ull;
  bool tick(uint64_t cycle) {
    if (cycle != next) return false;
    next += gap;
    return true;
  }
  void fed(size_t words_in, uint64_t cycle) {
    if (next == ~0ull && words_in >= first_len) next = cycle + gap;
  }
  void sampled() {}
};

// The stream through the build's RTL and hls model in lockstep (two reset
// cycles first); on_sample(sample, seg_done) for every real sample. It ends
// when the feed has given all its words and the core every sample they hold;
// "stalled" if neither a word nor a sample moves for far longer than a
// segment's load and a tick gap take.
template <class B, class F, class Ticks, class OnSample>
void clock_stream(F& f, Ticks ticks, SimResult& res, const std::function<void(double)>& progress,
                  const SampleSink& sink, OnSample on_sample) {
  using M = builds::ModelOf<B>;
  static_assert(B::Axes <= plan::kMaxAxes, "report::Sample holds up to kMaxAxes axes");
  // The RTL on a second thread, compared with the model cycle by cycle; the
  // model's ports drive the run (equal to the RTL's unless a mismatch is
  // counted).
  PipelinedLockstep<typename B::Rtl, M> ls;
  const auto t0 = std::chrono::steady_clock::now();
  typename M::In in;
  in.rst_n = false;
  ls.step(in);
  ls.step(in);
  in.rst_n = true;
  if (!sink) res.samples.v.reserve(f.ticks_known());
  uint64_t& n = res.sample_count;
  uint64_t moved = ls.cycles();
  for (;;) {
    in.tvalid = f.valid();
    if (!in.tvalid && f.all_read() && n >= f.ticks_known()) break;
    const uint64_t quiet = 4 * (static_cast<uint64_t>(res.tick_gap) + f.longest_segment_words()) + 10000;
    if (ls.cycles() - moved > quiet) throw std::runtime_error("simulation stalled");
    in.tdata = in.tvalid ? f.data() : 0;
    if constexpr (builds::kIsCore<B>) in.tuser = in.tvalid && f.tuser();
    in.tick = ticks.tick(ls.cycles());
    const auto& o = ls.step(in);
    if (in.tvalid && o.tready) {
      f.pop();
      moved = ls.cycles();
    }
    ticks.fed(f.consumed(), ls.cycles() - 1);
    if (o.underrun) ++res.underruns;
    res.tick_err |= o.tick_err;
    if (o.sample_valid) ticks.sampled();
    if (o.sample_valid && !o.underrun) {
      report::Sample s{};
      for (int a = 0; a < B::Axes; ++a) s[a] = static_cast<long long>(sext(o.sample[a], M::kOutWidth));
      on_sample(s, o.seg_done);
      if (sink)
        sink(n, s);
      else
        res.samples.v.push_back(s);
      ++n;
      moved = ls.cycles();
      if (progress && (n % 100000 == 0)) progress(f.fraction(n));
    }
  }
  ls.finish();
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  res.cycles = ls.cycles();
  res.mismatches = ls.mismatches();
}

#if TRAJ_APP_CORE
struct Expect {
  report::Sample v;
  bool done;
};

// The exact prediction of every sample from the records themselves (FD:
// fd::FdTicker; BCU: the closed form of traj::bcu::predict_sample), one tick
// at a time: it holds one segment's registers, whatever its K.
template <class B>
class Prediction {
 public:
  Prediction(const std::vector<stream::Record>& recs, const bcu::Format& bf)
      : recs_(recs), bf_(bf), fd_(B::Width, B::GuardBits) {
    load();
  }
  Expect next() {
    if (s_ >= recs_.size()) throw std::runtime_error("the core emitted more samples than the stream holds");
    const auto& r = recs_[s_];
    Expect e{};
    for (int a = 0; a < B::Axes; ++a) e.v[a] = r.is_bcu() ? bcu_sample(r, a) : fd_.sample_and_step(a);
    e.done = k_ + 1 == r.ticks;
    if (++k_ == r.ticks) {
      ++s_;
      k_ = 0;
      load();
    }
    return e;
  }

 private:
  void load() {
    if (s_ < recs_.size() && !recs_[s_].is_bcu()) fd_.load(recs_[s_].regs);
  }
  long long bcu_sample(const stream::Record& r, int a) const {
    return bcu::predict_sample(r.regs[a], r.depth(), static_cast<int>(k_), bf_.guard_bits);
  }
  const std::vector<stream::Record>& recs_;
  bcu::Format bf_;
  fd::FdTicker fd_;
  size_t s_ = 0;
  uint32_t k_ = 0;
};

// The words of a stream with a BCU format (kind on tuser).
template <class B>
Feed core_feed(const stream::Header& h, const std::vector<stream::Record>& recs, SimResult& res) {
  Feed f;
  const fd::Compiler fdc(h.format());
  const bcu::Format bf = h.bcu_format();
  auto add = [&](const std::vector<uint64_t>& w, bool bcu) {
    f.words.insert(f.words.end(), w.begin(), w.end());
    f.bcu.insert(f.bcu.end(), w.size(), bcu);
  };
  for (size_t s = 0; s < recs.size(); ++s) {
    const auto& r = recs[s];
    if (r.is_bcu()) {
      add(bcu::stream_words(r.regs, r.depth(), bf), true);
      ++res.bcu_segments;
    } else {
      fd::Compiled c;
      c.ticks = r.ticks;
      c.regs = r.regs;
      add(fdc.words(c), false);
      ++res.fd_segments;
    }
    if (s > 0 && r.kind != recs[s - 1].kind) ++res.switches;
    if (s == 0) f.first_len = f.words.size();
    f.ticks += r.ticks;
  }
  return f;
}
#endif

// The records of a run: all in memory, or pulled one at a time (FD streams).
struct Source {
  const std::vector<stream::Record>& records;
  RecordPull pull;        // set: records is empty and unused
  uint64_t expected = 0;  // records the pull will give (0: unknown), for the progress
};

template <class B>
SimResult run(const stream::Header& h, const Source& src, int tick_gap, const std::function<void(double)>& progress,
              const SampleSink& sink) {
  using M = builds::ModelOf<B>;
  using U = typename B::Unit;
  constexpr int kMin = U::template kMinGap<M>;
  const bool paced = tick_gap == 0 && src.pull && !builds::kIsCore<B>;  // AfterEachSample
  if (tick_gap <= 0) tick_gap = U::template kDefaultGap<M>;
  if (tick_gap < kMin)
    throw std::runtime_error("tick gap " + std::to_string(tick_gap) + " cycles is shorter than " + U::kGapReason +
                             " (" + std::to_string(kMin) + " cycles)");
  SimResult res;
  res.engine = U::kName;
  res.tick_gap = paced ? 0 : tick_gap;
  if constexpr (builds::kIsCore<B>) {
#if TRAJ_APP_CORE
    Feed f = core_feed<B>(h, src.records, res);
    Prediction<B> expect(src.records, h.bcu_format());
    clock_stream<B>(f, GapAfterFirstSegment{static_cast<uint64_t>(tick_gap), f.first_len}, res, progress, sink,
                    [&](const report::Sample& s, bool done) {
                      const Expect e = expect.next();
                      if (s != e.v || done != e.done) ++res.prediction_mismatches;
                    });
#endif
  } else if (src.pull) {
    PulledFeed f(h, src.pull, src.expected);
    const auto none = [](const report::Sample&, bool) {};
    if (paced)
      clock_stream<B>(f, AfterEachSample{f.first_segment_words()}, res, progress, sink, none);
    else
      clock_stream<B>(f, EveryGap{static_cast<uint64_t>(tick_gap)}, res, progress, sink, none);
  } else {
    Feed f = fd_feed(h, src.records);
    clock_stream<B>(f, EveryGap{static_cast<uint64_t>(tick_gap)}, res, progress, sink,
                    [](const report::Sample&, bool) {});
  }
  return res;
}

template <class B>
Build describe() {
  using M = builds::ModelOf<B>;
  using U = typename B::Unit;
  Build b;
  b.name = B::kName;
  b.unit = U::kName;
  b.fd.axes = B::Axes;
  b.fd.degree = B::Degree;
  b.fd.width = B::Width;
  b.fd.chunk_width = B::ChunkWidth;
  b.fd.guard_bits = B::GuardBits;
  if constexpr (builds::kIsCore<B>) {
    b.has_bcu = true;
    b.bcu.axes = B::Axes;
    b.bcu.chunk_width = B::ChunkWidth;
    b.bcu.ctrl_width = B::CtrlWidth;
    b.bcu.guard_bits = B::BcuGuardBits;
    b.bcu.out_width = M::kOutWidth;
    b.bcu.max_depth = B::MaxDepth;
  }
  b.min_tick_gap = U::template kMinGap<M>;
  b.default_tick_gap = U::template kDefaultGap<M>;
  return b;
}

template <class... B>
std::vector<Build> describe_all(builds::List<B...>) {
  return {describe<B>()...};
}

bool matches(const Build& b, const stream::Header& h) {
  const bool fd = h.axes == b.fd.axes && h.degree == b.fd.degree && h.width == b.fd.width &&
                  h.chunk_width == b.fd.chunk_width && h.guard_bits == b.fd.guard_bits;
  if (!b.has_bcu) return fd && !h.has_bcu();
  return fd && h.has_bcu() && h.bcu_ctrl_width == b.bcu.ctrl_width && h.bcu_guard_bits == b.bcu.guard_bits &&
         h.bcu_max_depth == b.bcu.max_depth && h.bcu_out_width == b.bcu.out_width;
}

std::string describe_format(const fd::Format& f, const bcu::Format* b) {
  std::string s = "axes " + std::to_string(f.axes) + ", FD degree " + std::to_string(f.degree) + " width " +
                  std::to_string(f.width) + " chunk " + std::to_string(f.chunk_width) + " guard " +
                  std::to_string(f.guard_bits);
  if (b)
    s += ", BCU CtrlWidth " + std::to_string(b->ctrl_width) + " GuardBits " + std::to_string(b->guard_bits) +
         " MaxDepth " + std::to_string(b->max_depth) + " OutWidth " + std::to_string(b->out_width);
  return s;
}

std::string describe_format(const stream::Header& h) {
  const bcu::Format b = h.has_bcu() ? h.bcu_format() : bcu::Format{};
  return describe_format(h.format(), h.has_bcu() ? &b : nullptr);
}

std::string describe_carried() {
  std::string s;
  for (const auto& b : carried()) {
    if (!s.empty()) s += "; ";
    s += b.name + " (" + b.unit + ": " + describe_format(b.fd, b.has_bcu ? &b.bcu : nullptr) + ")";
  }
  return s;
}

template <class... B>
SimResult dispatch(builds::List<B...>, const stream::Header& h, const Source& src, int tick_gap,
                   const std::function<void(double)>& progress, const SampleSink& sink) {
  SimResult res;
  bool found = false;
  auto try_one = [&](auto tag) {
    using One = typename decltype(tag)::type;
    if (found || !matches(describe<One>(), h)) return;
    found = true;
    res = run<One>(h, src, tick_gap, progress, sink);
  };
  (try_one(std::common_type<B>{}), ...);
  if (!found)
    throw std::runtime_error("no engine for this stream (" + describe_format(h) + "): this tool carries " +
                             describe_carried());
  return res;
}

}  // namespace

fd::Format Build::fd_format(int frac_bits) const {
  fd::Format f = fd;
  f.frac_bits = frac_bits;
  return f;
}

bcu::Format Build::bcu_format(int frac_bits) const {
  bcu::Format f = bcu;
  f.frac_bits = frac_bits;
  return f;
}

stream::Header Build::header(int frac_bits, double period, const std::string& units) const {
  return has_bcu ? stream::Header::from(fd_format(frac_bits), bcu_format(frac_bits), period, units)
                 : stream::Header::from(fd_format(frac_bits), period, units);
}

const std::vector<Build>& carried() {
  static const std::vector<Build> all = describe_all(builds::Carried{});
  return all;
}

const Build& carried(const std::string& name) {
  for (const auto& b : carried())
    if (b.name == name) return b;
  throw std::runtime_error("this trajcore carries no engine build " + name + " (it carries " + describe_carried() +
                           ")");
}

bool has_core() {
  for (const auto& b : carried())
    if (b.has_bcu) return true;
  return false;
}

SimResult simulate(const stream::Header& h, const std::vector<stream::Record>& recs, int tick_gap,
                   const std::function<void(double)>& progress, const SampleSink& sink) {
  if (!h.has_bcu())
    for (const auto& r : recs)
      if (r.is_bcu()) throw std::runtime_error("BCU segment in a stream without a BCU format");
  if (h.has_bcu() && !has_core())
    throw std::runtime_error("this stream carries a BCU format and this trajcore was built without "
                             "host/bcu (TRAJ_SKIP): no traj_core to run it on");
  return dispatch(builds::Carried{}, h, Source{recs, {}, 0}, tick_gap, progress, sink);
}

SimResult simulate_pulled(const stream::Header& h, const RecordPull& pull, uint64_t records, int tick_gap,
                          const std::function<void(double)>& progress, const SampleSink& sink) {
  if (h.has_bcu()) throw std::runtime_error("simulate_pulled: a stream with a BCU format runs through simulate()");
  static const std::vector<stream::Record> none;
  return dispatch(builds::Carried{}, h, Source{none, pull, records}, tick_gap, progress, sink);
}

}  // namespace traj::sim
