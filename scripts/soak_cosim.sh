#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Soak: the FD engine co-simulation (RTL == hls, every cycle) at every built
# parameter set, on N random seeds each (default 20). CTest runs fixed seeds;
# this is the long randomised run. A failing seed is printed with the command
# that reruns it.
#   usage: scripts/soak_cosim.sh [N]   (after scripts/build.sh)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${TRAJ_BUILD_DIR:-$root/build}
n=${1:-20}
fail=0
runs=0
for bin in "$build"/tb/fd/fd_cosim_*; do
  [ -x "$bin" ] && [ -f "$bin" ] || continue
  case "$bin" in *.cmake) continue ;; esac
  for i in $(seq 1 "$n"); do
    if ! out=$(TRAJ_SEED=random "$bin" 2>&1); then
      echo "FAIL $(basename "$bin"):"
      echo "$out" | grep -E "seed|Failure|cycle" | head -5
      fail=1
    fi
  done
  echo "$(basename "$bin"): $n random seeds x 6 tests done"
  runs=$((runs + 1))
done
if [ "$runs" -eq 0 ]; then
  echo "soak_cosim: no fd_cosim_* binaries under $build/tb/fd (run scripts/build.sh, or set TRAJ_BUILD_DIR)" >&2
  exit 2
fi
exit $fail
