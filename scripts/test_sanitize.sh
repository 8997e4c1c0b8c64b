#!/usr/bin/env bash
# The test suite under AddressSanitizer and UndefinedBehaviorSanitizer (gcc), in a build folder of
# its own (${TRAJ_SANITIZE_BUILD_DIR:-build-sanitize}); the CI step after the normal tests (.ci/run).
#
#   scripts/test_sanitize.sh [all|host]
#     all   (default) the whole tree: every host library, test and tool, and the Verilated
#           co-simulations, compiled with -fsanitize=address,undefined; runs every CTest test
#           except those left out below
#     host  the host libraries and their unit tests only (geometry, fd unit tests, stream, input,
#           corners, the planner's streaming, arc-length table, plot and JSON Lines tests, the
#           job's toolpath streaming, the time-scale reference and hls model, fuzz replay, the
#           link's frame codec and the upload client
#           against the loopback board with faults): no Verilated model is built; the CI step
#           (.ci/run). Left out: planner_test (planner.unit.{PlannerCore,PlannerInput,Profile,
#           Segments}: it links the Verilated engines) and the *.cli.* tests (the trajcore tool)
#
# Left out in both: rtl.* (lint, elaboration, synthesis and formal runs of external tools: no code
# of ours runs under the sanitizers there), fuzz.build / fuzz.short.* (the fuzz targets have
# their own clang ASan+UBSan build, scripts/fuzz.sh) and input.crosscheck.linuxcnc_examples (it
# preloads its printf shim into LinuxCNC's rs274, which an instrumented shim aborts; the G-code
# reader runs under the sanitizers in input.unit.Gcode.* and fuzz.unit.*). Any sanitizer report fails its test
# (-fno-sanitize-recover, halt_on_error). ASan's quarantine is off (quarantine_size_mb=0): the
# tests that measure the memory of a run (app.cli.sim_long_segment_memory) would count freed
# blocks held for use-after-free detection; heap overflows and leaks are still caught.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
scope=${1:-all}
build=${TRAJ_SANITIZE_BUILD_DIR:-$root/build-sanitize}
"$root/scripts/setup.sh"

san="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
gen=()
command -v ninja >/dev/null 2>&1 || { echo "test_sanitize: needs ninja (directory targets)"; exit 1; }
gen=(-G Ninja)
launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$build" "${gen[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo "${launcher[@]}" \
    -DCMAKE_C_FLAGS="$san" -DCMAKE_CXX_FLAGS="$san" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_MODULE_LINKER_FLAGS="-fsanitize=address,undefined"
fi

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:quarantine_size_mb=0:halt_on_error=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
skip='^rtl\.|^fuzz\.(build|short)|^input\.crosscheck\.'
case "$scope" in
  all)
    cmake --build "$build" -j "$(nproc)"
    select='.'
    ;;
  host)
    cmake --build "$build" -j "$(nproc)" --target host/util/all host/geometry/all host/planner/all host/input/all \
      host/corners/all trajcore_fd trajcore_stream tb/geometry/all tb/stream/all tb/input/all tb/corners/all \
      tb/fuzz/all fd_recurrence_test fd_model_test fd_compiler_speed_test fd_compiler_report_test link_test upload_test \
      streaming_test arc_table_test plots_test jsonl_test toolpath_stream_test time_scale_test time_scale_hls_test
    select='^(geometry|fd\.unit|stream|input|corners|fuzz\.unit|link\.host|upload\.e2e|job\.unit|timescale\.(unit|hls))\.'
    select="$select|^planner\.unit\.(Streaming|ArcTable|Plots|Jsonl)\."
    skip="$skip|^stream\.cli\."  # they run the trajcore tool, which carries the Verilated engines
    ;;
  *) echo "usage: $0 [all|host]"; exit 2 ;;
esac
cd "$build"
start=$(date +%s)
ctest --output-on-failure -j "$(nproc)" --timeout 3600 -R "$select" -E "$skip"
echo "test_sanitize ($scope): tests passed in $(( $(date +%s) - start )) s"
