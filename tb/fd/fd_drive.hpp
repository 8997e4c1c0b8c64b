// SPDX-License-Identifier: Apache-2.0
// Test helper: drive an hls FdEngine with compiled segments and ticks.
#pragma once
#include <functional>
#include <random>
#include <vector>

#include "fd/fd_compiler.hpp"
#include "traj_fd_engine.hpp"

namespace traj::test {

inline mpz_class to_mpz_signed(u128 v, int w) {
  const i128 s = sext(v, w);
  const bool neg = s < 0;
  u128 m = neg ? u128(-(s + 1)) + 1 : u128(s);
  mpz_class r = mpz_class(static_cast<unsigned long>(m >> 64));
  r <<= 64;
  r += mpz_class(static_cast<unsigned long>(m & ~uint64_t(0)));
  return neg ? mpz_class(-r) : r;
}

// Feeds all words of all segments, ticking every `gap` cycles (gap >= chunks),
// and calls on_sample(segment, tick, engine) for every sample the engine emits.
template <class Engine>
void run_segments(Engine& e, const traj::fd::Compiler& comp, const std::vector<traj::fd::Compiled>& segs,
                  int gap, const std::function<void(size_t, uint64_t, const typename Engine::Out&)>& on_sample) {
  std::vector<uint64_t> words;
  std::vector<std::pair<size_t, uint64_t>> owner;  // sample index -> (segment, tick)
  for (size_t s = 0; s < segs.size(); ++s) {
    auto w = comp.words(segs[s]);
    words.insert(words.end(), w.begin(), w.end());
    for (uint64_t k = 0; k < segs[s].ticks; ++k) owner.push_back({s, k});
  }
  size_t wi = 0, si = 0;
  uint64_t cyc = 0;
  typename Engine::In in;
  while (si < owner.size()) {
    auto o = e.outputs();
    if (o.sample_valid) {
      if (o.underrun) throw std::runtime_error("unexpected underrun");
      on_sample(owner[si].first, owner[si].second, o);
      ++si;
    }
    in.tvalid = wi < words.size();
    in.tdata = in.tvalid ? words[wi] : 0;
    if (in.tvalid && o.tready) ++wi;
    in.tick = (cyc % gap) == 0 && cyc > 0;
    e.clock(in);
    ++cyc;
  }
}

}  // namespace traj::test
