// Replays, through the fuzz targets' own entry functions, every seed (corpus/<target>/) and every
// input that ever failed (regressions/<target>/), built with the normal compiler: no libFuzzer
// needed. Each input must be read or refused (fuzz_entries.hpp) within kSecondsPerInput.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "fuzz_entries.hpp"

namespace fs = std::filesystem;

namespace {
constexpr double kSecondsPerInput = 10;  // the hangs replayed here ran for minutes before their fixes

std::vector<fs::path> inputs(const std::string& kind, const std::string& target) {
  std::vector<fs::path> v;
  const fs::path dir = fs::path(TRAJ_FUZZ_DIR) / kind / target;
  if (fs::is_directory(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file() && e.path().filename() != "README.md") v.push_back(e.path());
  std::sort(v.begin(), v.end());
  return v;
}

class Replay : public ::testing::TestWithParam<traj::fuzz::Target> {};

void replay(const traj::fuzz::Target& t, const std::string& kind, size_t min_count) {
  const auto files = inputs(kind, t.name);
  EXPECT_GE(files.size(), min_count) << kind << "/" << t.name;
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto t0 = std::chrono::steady_clock::now();
    t.entry(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_LT(s, kSecondsPerInput) << f;
    std::printf("%-10s %-60s %8zu bytes %8.3f s\n", t.name, f.filename().c_str(), bytes.size(), s);
  }
}
}  // namespace

TEST_P(Replay, Seeds) { replay(GetParam(), "corpus", 1); }
TEST_P(Replay, Regressions) { replay(GetParam(), "regressions", 0); }

INSTANTIATE_TEST_SUITE_P(Fuzz, Replay, ::testing::ValuesIn(traj::fuzz::targets()),
                         [](const auto& info) { return std::string(info.param.name); });
