#!/usr/bin/env bash
# The libFuzzer targets of the readers (tb/fuzz): build them with clang
# (-fsanitize=fuzzer,address,undefined) in ${TRAJ_FUZZ_BUILD_DIR:-build-fuzz} and run them.
#
#   scripts/fuzz.sh [target|all] [seconds]   run one target (stream json jsonl gcode svg dxf link) or all,
#                                            each for `seconds` (default 60): the soak
#   scripts/fuzz.sh --build-only             build only (the test suite's fuzz.build fixture)
#
# Each run starts from the seed corpus (tb/fuzz/corpus/<target>) and the regression inputs
# (tb/fuzz/regressions/<target>), with the dictionary tb/fuzz/dict/<target>.dict; inputs the fuzzer
# finds go to <build>/corpus/<target> (never into the repository). A crash, sanitizer report, leak,
# timeout (10 s) or out-of-memory stops the run with a non-zero status and leaves the input in
# <build>/findings/<target>/: copy it to tb/fuzz/regressions/<target>/, fix the reader, and the
# normal test suite replays it from then on (fuzz.unit.Fuzz/Replay.Regressions/<target>).
# Exit 77 (skipped) when clang++ or its libFuzzer runtime (Debian: clang, libclang-rt-14-dev) is missing.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${TRAJ_FUZZ_BUILD_DIR:-$root/build-fuzz}
targets=(stream json jsonl gcode svg dxf link)

clangxx=$(command -v clang++ || command -v clang++-14 || true)
clangc=$(command -v clang || command -v clang-14 || true)
if [ -z "$clangxx" ] || [ -z "$clangc" ] || [ ! -f "$("$clangxx" --print-runtime-dir)/libclang_rt.fuzzer-x86_64.a" ]; then
  echo "fuzz: clang++ with its libFuzzer runtime not found (Debian: clang, libclang-rt-14-dev): skipped"
  exit 77
fi

build_targets() {
  # One configure and one build at a time in this folder (the test suite may start several runs).
  mkdir -p "$build"
  exec 9>"$build/.lock"
  flock 9
  local san="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g"
  local gen=()
  command -v ninja >/dev/null 2>&1 && gen=(-G Ninja)
  if [ ! -f "$build/CMakeCache.txt" ]; then
    launcher=()
    command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
    cmake -S "$root" -B "$build" "${gen[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCMAKE_C_COMPILER="$clangc" -DCMAKE_CXX_COMPILER="$clangxx" "${launcher[@]}" \
      -DCMAKE_C_FLAGS="$san" -DCMAKE_CXX_FLAGS="$san" -DTRAJ_FUZZ=ON >/dev/null
  fi
  cmake --build "$build" -j "$(nproc)" --target fuzz_all
  flock -u 9
}

run_target() {
  local t=$1 secs=$2
  local corpus=$build/corpus/$t findings=$build/findings/$t
  mkdir -p "$corpus" "$findings"
  local seeds=("$root/tb/fuzz/corpus/$t")
  # a target with no failed input yet has no regressions folder (git keeps no empty folder)
  [ -d "$root/tb/fuzz/regressions/$t" ] && seeds+=("$root/tb/fuzz/regressions/$t")
  echo "fuzz: $t for ${secs} s"
  # detect_leaks: the readers must not leak on refusal either; -timeout: a hang is a finding.
  ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1} UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1} \
    "$build/tb/fuzz/fuzz_$t" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
    -dict="$root/tb/fuzz/dict/$t.dict" -artifact_prefix="$findings/" -print_final_stats=1 \
    "$corpus" "${seeds[@]}"
}

case "${1:-all}" in
  --build-only) build_targets; exit 0 ;;
  all) sel=("${targets[@]}") ;;
  *) sel=("$1") ;;
esac
secs=${2:-60}
build_targets
for t in "${sel[@]}"; do
  [ -d "$root/tb/fuzz/corpus/$t" ] || { echo "fuzz: unknown target $t (${targets[*]})"; exit 2; }
  run_target "$t" "$secs"
done
