#!/usr/bin/env bash
# The main job on a fresh machine: install what is missing, build, and run the
# built-in demo (circle of three 120-degree Bezier arcs through the Verilated
# forward-difference engine). Extra arguments go to `trajcore demo`.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
build=${TRAJ_BUILD_DIR:-$root/build}
cd "$root"
"$build/host/app/trajcore" demo --csv "$root/out/demo_samples.csv" "$@"
