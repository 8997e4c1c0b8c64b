// SPDX-License-Identifier: Apache-2.0
// The random seed of a randomised test. Every test and co-simulation reads the
// same variable, TRAJ_SEED: a number reruns that seed, "random" draws a fresh
// one (scripts/soak_cosim.sh), unset gives the test's fixed default, so a
// CTest run is reproducible. test_seed() prints the seed in use once, so a
// failure can be rerun from its log.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

namespace traj::test {

// True if TRAJ_SEED is set.
inline bool env_seed_given() { return std::getenv("TRAJ_SEED") != nullptr; }

// TRAJ_SEED's seed, or `fallback` if it is unset. "random" is drawn once per process.
inline uint64_t env_seed(uint64_t fallback) {
  const char* s = std::getenv("TRAJ_SEED");
  if (!s) return fallback;
  if (std::string(s) == "random") {
    static const uint64_t drawn = (uint64_t{std::random_device{}()} << 32) ^ std::random_device{}();
    return drawn;
  }
  return std::strtoull(s, nullptr, 0);
}

// env_seed(fallback), printed once ("TRAJ_SEED=<n>").
inline uint64_t test_seed(uint64_t fallback) {
  const uint64_t seed = env_seed(fallback);
  static bool printed = false;
  if (!printed) {
    std::printf("TRAJ_SEED=%llu\n", static_cast<unsigned long long>(seed));
    printed = true;
  }
  return seed;
}

}  // namespace traj::test
