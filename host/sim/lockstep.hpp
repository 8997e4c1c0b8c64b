// SPDX-License-Identifier: Apache-2.0
// The lockstep driver: a Verilated unit (V) and its hls model (M) clocked
// together with the same inputs; on every cycle from the first reset edge on,
// every output port of the RTL is compared with the model's (tready,
// sample_valid, underrun, seg_done, tick_err always; the sample bus where the
// model's sample_valid is high; a sample RAM read port where the model says
// its word was written). Before the first reset edge the RTL holds its
// random initial state (--x-initial unique), so nothing is compared.
//
// The caller chooses the inputs of every cycle (step(in)); the driver is a
// template with no per-cycle indirection: it is the simulation's inner loop.
// RtlChecker is the RTL side; Lockstep clocks it and the model on one thread
// (the tests), PipelinedLockstep on two (`trajcore sim`).
// Trace: a policy with open(V&, VerilatedContext&) and dump(VerilatedContext&),
// called after every evaluation (NoTrace: none).
#pragma once
#include <verilated.h>

#include <condition_variable>
#include <cstdio>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "sim/ports.hpp"
#include "sim/vl_bits.hpp"

namespace traj::sim {

struct NoTrace {
  template <class V>
  void open(V&, VerilatedContext&) {}
  void dump(VerilatedContext&) {}
};

// The RTL side of a lockstep run: each cycle the inputs applied, the
// outputs of the cycle read and compared with the model's ports `h` of the
// same cycle (from the first reset edge on), then the rising edge.
template <class V, class M, class Trace = NoTrace>
class RtlChecker {
 public:
  using In = typename M::In;
  using Out = Ports<kAxesOf<M>>;
  static constexpr int kAxes = kAxesOf<M>;
  static constexpr int kOutWidth = M::kOutWidth;

  // rand_seed: the seed of the RTL's random initial state (0: Verilator's default).
  explicit RtlChecker(int rand_seed = 0, Trace trace = {})
      : ctx_(std::make_unique<VerilatedContext>()), trace_(std::move(trace)) {
    ctx_->randReset(2);  // a dependence on unreset state shows up as a mismatch
    if (rand_seed) ctx_->randSeed(rand_seed);
    rtl_ = std::make_unique<V>(ctx_.get());
    trace_.open(*rtl_, *ctx_);
    rtl_->clk_i = 0;
  }
  ~RtlChecker() { rtl_->final(); }
  RtlChecker(const RtlChecker&) = delete;
  RtlChecker& operator=(const RtlChecker&) = delete;

  // One clock cycle; returns the RTL's ports of the cycle.
  const Out& cycle(const In& in, const Out& h) {
    apply(in);
    rtl_->clk_i = 0;
    rtl_->eval();
    trace_.dump(*ctx_);
    read_rtl();
    compared_ = armed_;
    if (compared_) compare(h);
    else why_.clear();
    if (!in.rst_n) armed_ = true;
    rtl_->clk_i = 1;
    rtl_->eval();
    trace_.dump(*ctx_);
    ++cycles_;
    return out_;
  }

  bool ok() const { return why_.empty(); }
  const std::string& why() const { return why_; }
  bool compared() const { return compared_; }
  uint64_t mismatches() const { return mismatches_; }
  uint64_t cycles() const { return cycles_; }
  V& rtl() { return *rtl_; }

 private:
  void apply(const In& in) {
    rtl_->rst_ni = in.rst_n;
    rtl_->s_axis_tvalid = in.tvalid;
    rtl_->s_axis_tdata = static_cast<uint64_t>(in.tdata);
    if constexpr (has_tuser()) rtl_->s_axis_tuser = in.tuser;
    if constexpr (has_sample_port()) rtl_->sample_addr_i = in.sample_addr;
    rtl_->tick_i = in.tick;
  }
  static constexpr bool has_sample_port() { return HasSampleAddr<In>::value; }
  template <class I, class = void>
  struct HasSampleAddr : std::false_type {};
  template <class I>
  struct HasSampleAddr<I, std::void_t<decltype(I::sample_addr)>> : std::true_type {};
  static constexpr bool has_tuser() { return HasTuser<In>::value; }
  template <class I, class = void>
  struct HasTuser : std::false_type {};
  template <class I>
  struct HasTuser<I, std::void_t<decltype(I::tuser)>> : std::true_type {};

  void read_rtl() {
    out_.tready = rtl_->s_axis_tready;
    out_.sample_valid = rtl_->sample_valid_o;
    out_.underrun = rtl_->underrun_o;
    out_.seg_done = rtl_->seg_done_o;
    out_.tick_err = rtl_->tick_err_o;
    if (out_.sample_valid)
      for (int a = 0; a < kAxes; ++a) out_.sample[a] = vl_bits(rtl_->sample_o, a * kOutWidth, kOutWidth);
    if constexpr (has_sample_port()) out_.sample_word = rtl_->sample_word_o;
  }

  void compare(const Out& h) {
    why_.clear();
    port("s_axis_tready", out_.tready, h.tready);
    port("sample_valid_o", out_.sample_valid, h.sample_valid);
    port("underrun_o", out_.underrun, h.underrun);
    port("seg_done_o", out_.seg_done, h.seg_done);
    port("tick_err_o", out_.tick_err, h.tick_err);
    if (h.sample_valid)
      for (int a = 0; a < kAxes; ++a) {
        const u128 r = out_.sample_valid ? out_.sample[a] : vl_bits(rtl_->sample_o, a * kOutWidth, kOutWidth);
        if (r != h.sample[a]) differ("sample_o axis " + std::to_string(a), r, h.sample[a]);
      }
    if constexpr (has_sample_port())
      if (h.sample_word_known && out_.sample_word != h.sample_word) differ("sample_word_o", out_.sample_word, h.sample_word);
  }
  void port(const char* name, bool rtl, bool hls) {
    if (rtl != hls) differ(name, rtl, hls);
  }
  void differ(const std::string& name, u128 rtl, u128 hls) {
    ++mismatches_;
    char buf[192];
    std::snprintf(buf, sizeof buf, "cycle %llu: %s rtl=%llx hls=%llx%s", static_cast<unsigned long long>(cycles_),
                  name.c_str(), static_cast<unsigned long long>(rtl), static_cast<unsigned long long>(hls),
                  (rtl >> 64) || (hls >> 64) ? " (low 64 bits)" : "");
    if (!why_.empty()) why_ += '\n';
    why_ += buf;
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<V> rtl_;
  Trace trace_;
  Out out_;
  std::string why_;
  bool armed_ = false, compared_ = false;  // a reset edge was seen; the last step was compared
  uint64_t cycles_ = 0, mismatches_ = 0;
};

// The RTL and the model clocked together on the caller's thread.
template <class V, class M, class Trace = NoTrace>
class Lockstep {
 public:
  using Model = M;
  using In = typename M::In;
  using Out = Ports<kAxesOf<M>>;
  static constexpr int kAxes = kAxesOf<M>;
  static constexpr int kOutWidth = M::kOutWidth;

  explicit Lockstep(int rand_seed = 0, Trace trace = {}) : rtl_(rand_seed, std::move(trace)) {}

  // One clock cycle: the inputs applied, the outputs of the cycle compared,
  // then the rising edge of both. Returns the RTL's ports of the cycle.
  const Out& step(const In& in) {
    const Out& o = rtl_.cycle(in, hls_ports(model_));
    model_.clock(in);
    return o;
  }

  bool ok() const { return rtl_.ok(); }                    // the last step matched
  const std::string& why() const { return rtl_.why(); }    // what differed in it, one line per port
  bool compared() const { return rtl_.compared(); }        // the last step's outputs were compared
  uint64_t mismatches() const { return rtl_.mismatches(); }  // ports that differed, over all steps
  uint64_t cycles() const { return rtl_.cycles(); }
  const M& model() const { return model_; }
  V& rtl() { return rtl_.rtl(); }

 private:
  RtlChecker<V, M, Trace> rtl_;
  M model_;
};

// The same comparison with the RTL on a second thread, for long runs: the
// model runs on the caller's thread and step(in) returns the MODEL's ports
// (equal to the RTL's wherever the comparison holds); every cycle's inputs
// and model ports go, in batches, to a thread that clocks the RTL with the
// same inputs and compares. At most kQueued batches wait (bounded memory).
// finish() waits for the RTL to catch up; mismatches() and first_why() are
// final after it.
template <class V, class M>
class PipelinedLockstep {
 public:
  using Model = M;
  using In = typename M::In;
  using Out = Ports<kAxesOf<M>>;

  PipelinedLockstep() : worker_([this] { run_rtl(); }) { batch_.reserve(kBatch); }
  ~PipelinedLockstep() { finish(); }
  PipelinedLockstep(const PipelinedLockstep&) = delete;
  PipelinedLockstep& operator=(const PipelinedLockstep&) = delete;

  const Out& step(const In& in) {
    out_ = hls_ports(model_);
    batch_.push_back({in, out_});
    if (batch_.size() == kBatch) hand_over();
    model_.clock(in);
    ++cycles_;
    return out_;
  }

  void finish() {
    if (!worker_.joinable()) return;
    hand_over();
    {
      std::lock_guard<std::mutex> l(m_);
      done_ = true;
    }
    cv_.notify_all();
    worker_.join();
  }

  uint64_t cycles() const { return cycles_; }
  uint64_t mismatches() const { return mismatches_; }
  const std::string& first_why() const { return first_why_; }
  const M& model() const { return model_; }

 private:
  static constexpr size_t kBatch = 4096, kQueued = 8;
  struct Cycle {
    In in;
    Out hls;
  };

  void hand_over() {
    if (batch_.empty()) return;
    std::unique_lock<std::mutex> l(m_);
    cv_.wait(l, [&] { return queue_.size() < kQueued; });
    queue_.push_back(std::move(batch_));
    l.unlock();
    cv_.notify_all();
    batch_ = {};
    batch_.reserve(kBatch);
  }

  void run_rtl() {
    RtlChecker<V, M> rtl;
    for (;;) {
      std::vector<Cycle> b;
      {
        std::unique_lock<std::mutex> l(m_);
        cv_.wait(l, [&] { return !queue_.empty() || done_; });
        if (queue_.empty()) break;
        b = std::move(queue_.front());
        queue_.pop_front();
      }
      cv_.notify_all();
      for (const Cycle& c : b) {
        rtl.cycle(c.in, c.hls);
        if (!rtl.ok() && first_why_.empty()) first_why_ = rtl.why();
      }
    }
    mismatches_ = rtl.mismatches();
  }

  M model_;
  Out out_;
  uint64_t cycles_ = 0;
  std::vector<Cycle> batch_;
  std::deque<std::vector<Cycle>> queue_;
  std::mutex m_;
  std::condition_variable cv_;
  bool done_ = false;
  uint64_t mismatches_ = 0;  // written by the worker, read after finish()
  std::string first_why_;
  std::thread worker_;  // last: started once everything above exists
};

}  // namespace traj::sim
