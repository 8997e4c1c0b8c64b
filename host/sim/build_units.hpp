// SPDX-License-Identifier: Apache-2.0
// The units an engine build of the tool can be (engine_builds.hpp, generated
// from TRAJ_SIM_BUILDS in host/sim/CMakeLists.txt): each names its hls model
// from the build's RTL parameters.
#pragma once
#include <type_traits>

#include "traj_core.hpp"
#include "traj_fd_engine.hpp"

namespace traj::sim::builds {

template <class... B>
struct List {};

namespace unit {
// Per unit: the hls model, and the clock cycles between ticks the unit needs
// (kMinGap; kDefaultGap when the caller gives none) and why.
struct traj_fd_engine {
  static constexpr const char* kName = "traj_fd_engine";
  static constexpr const char* kGapReason = "a segment load";
  template <class M>
  static constexpr int kMinGap = M::kWords + M::kChunks + 1;
  template <class M>
  static constexpr int kDefaultGap = kMinGap<M> + 1;
  template <class B>
  using Model = FdEngine<B::Axes, B::Degree, B::Width, B::ChunkWidth, B::GuardBits>;
};
struct traj_core {
  static constexpr const char* kName = "traj_core";
  static constexpr const char* kGapReason = "the core's minimum tick spacing: a BCU segment switch, hls/traj_core.hpp";
  template <class M>
  static constexpr int kMinGap = M::kMinTickSpacing;
  template <class M>
  static constexpr int kDefaultGap = kMinGap<M>;
  template <class B>
  using Model = Core<B::Axes, B::Degree, B::Width, B::ChunkWidth, B::GuardBits, B::CtrlWidth, B::BcuGuardBits,
                     B::MaxDepth>;
};
}  // namespace unit

template <class B>
using ModelOf = typename B::Unit::template Model<B>;
template <class B>
inline constexpr bool kIsCore = std::is_same_v<typename B::Unit, unit::traj_core>;

}  // namespace traj::sim::builds
