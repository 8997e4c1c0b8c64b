#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The test suite on a fresh machine: install what is missing, build, run CTest
# (unit tests, hls-vs-host, Verilator co-simulation, RTL lint/elaboration/synthesis checks).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh"
build=${TRAJ_BUILD_DIR:-$root/build}
cd "$build"
ctest --output-on-failure -j "$(nproc)" --timeout 1200
