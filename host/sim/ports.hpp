// SPDX-License-Identifier: Apache-2.0
// The output ports of a streaming unit (traj_fd_engine, traj_bcu_gen,
// traj_core) in one cycle, read the same way from each hls model, and the
// clocking of an hls model alone (the runs without RTL beside it).
#pragma once
#include <cstdint>
#include <type_traits>
#include <utility>

#include "traj_common.hpp"

namespace traj::sim {

template <int Axes>
struct Ports {
  bool tready = false, sample_valid = false, underrun = false, seg_done = false, tick_err = false;
  u128 sample[Axes] = {};  // OutWidth-bit two's complement; read only where sample_valid
  // a sample RAM read port (traj_fd_tm): the word read, and (from the model)
  // whether it is defined; compared only where defined
  uint64_t sample_word = 0;
  bool sample_word_known = false;
};

namespace detail {
template <class M, class = void>
struct HasOutputs : std::false_type {};  // traj_fd_engine's model returns its ports as one Out
template <class M>
struct HasOutputs<M, std::void_t<decltype(std::declval<const M&>().outputs())>> : std::true_type {};
template <class O, class = void>
struct HasSampleWord : std::false_type {};  // traj_fd_tm's model has a sample RAM read port
template <class O>
struct HasSampleWord<O, std::void_t<decltype(O::sample_word)>> : std::true_type {};
template <class M, bool = HasOutputs<M>::value>
struct AxesOf {
  static constexpr int value = M::kAxes;
};
template <class M>
struct AxesOf<M, true> {
  static constexpr int value = static_cast<int>(std::extent_v<decltype(M::Out::sample)>);
};
}  // namespace detail

template <class M>
inline constexpr int kAxesOf = detail::AxesOf<M>::value;

// The hls model's ports this cycle (its outputs are registered: they do not
// depend on this cycle's inputs).
template <class M>
Ports<kAxesOf<M>> hls_ports(const M& m) {
  Ports<kAxesOf<M>> p;
  if constexpr (detail::HasOutputs<M>::value) {
    const auto o = m.outputs();
    p.tready = o.tready;
    p.sample_valid = o.sample_valid;
    p.underrun = o.underrun;
    p.seg_done = o.seg_done;
    p.tick_err = o.tick_err;
    for (int a = 0; a < kAxesOf<M>; ++a) p.sample[a] = o.sample[a];
    if constexpr (detail::HasSampleWord<typename M::Out>::value) {
      p.sample_word = o.sample_word;
      p.sample_word_known = o.sample_word_known;
    }
  } else {
    p.tready = m.tready();
    p.sample_valid = m.sample_valid();
    p.underrun = m.underrun();
    p.seg_done = m.seg_done();
    p.tick_err = m.tick_err();
    if (p.sample_valid)
      for (int a = 0; a < kAxesOf<M>; ++a) p.sample[a] = m.sample_bits(a);
  }
  return p;
}

// An hls model clocked alone, with the stepping interface of Lockstep
// (lockstep.hpp): step(in) returns the ports of the cycle, then the edge.
template <class M>
class HlsUnit {
 public:
  using Model = M;
  using In = typename M::In;
  using Out = Ports<kAxesOf<M>>;

  const Out& step(const In& in) {
    out_ = hls_ports(model_);
    model_.clock(in);
    ++cycles_;
    return out_;
  }
  M& model() { return model_; }
  const M& model() const { return model_; }
  uint64_t cycles() const { return cycles_; }

 private:
  M model_;
  Out out_;
  uint64_t cycles_ = 0;
};

}  // namespace traj::sim
