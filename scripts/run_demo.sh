#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The main job on a fresh machine: install what is missing, build, then
#  1. plan the butterfly NURBS (host/assets/butterfly_nurbs.json) at 50 mm/s with
#     1 ms ticks and the limits below, compile it to quintic forward-difference
#     segments, run them through the Verilated core, and write the report and
#     plots to out/butterfly/;
#  2. run the built-in circle demo (three 120-degree cubic Bezier arcs through
#     the cubic engine) to out/demo_samples.csv.
# Extra arguments go to `trajcore run` (e.g. --feed 100).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh"
build=${TRAJ_BUILD_DIR:-$root/build}
cd "$root"
"$build/host/app/trajcore" run host/assets/butterfly_nurbs.json --out-dir out/butterfly \
  --feed 50 --period 0.001 \
  --v-axis 200 --a-axis 2000 --j-axis 50000 \
  --a-tan 1000 --j-tan 20000 --a-cen 1000 --j-cen 50000 \
  --tol 0.001 "$@"
echo
"$build/host/app/trajcore" demo --csv "$root/out/demo_samples.csv"
