#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# plan -> upload -> simulated board (rtl/traj_board.sv Verilated, 30 MHz,
# 1 Mbaud, UART pins driven bit by bit, step/dir pins decoded) on a
# pseudo-terminal, checked against the stream's exact prediction: the main
# job (the butterfly), then a streamed raster of N pieces
# (`plan --raster N -o -` piped into `upload -`). Prints the board's check,
# the simulated time and the simulation speed.
#   scripts/bench_board.sh [RASTER_PIECES (default 1000)] [extra `trajcore board` options, e.g. --corrupt 1e-4]
# Cost: the board is simulated cycle by cycle, about 7 million cycles a
# second here: the butterfly (9.7 s of motion) takes under a minute, the
# 1000-piece raster at the limits below (398 s of motion) about 30 minutes.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
T=${TRAJCORE:-${TRAJ_BUILD_DIR:-$root/build}/host/app/trajcore}
N=${1:-1000}
shift || true
dir=$(mktemp -d)
board=
trap '[ -n "$board" ] && kill "$board" 2>/dev/null; rm -rf "$dir"' EXIT
upload_opts=(--step-shift 26 --timeout-ms 3000)  # the tick period in the clock the board reports

run() {  # run NAME EXPECT-FILE UPLOAD-INPUT [PLAN-COMMAND...]
  local name=$1 expect=$2 input=$3
  shift 3
  "$T" board --expect "$expect" --once "${BOARD_OPTS[@]}" > "$dir/port" 2> "$dir/$name.board" &
  board=$!
  for _ in $(seq 100); do [ -s "$dir/port" ] && break; sleep 0.1; done
  local start end
  start=$(date +%s.%N)
  if [ "$input" = - ]; then
    "$@" -o - 2> "$dir/$name.plan" | "$T" upload - --port "$(cat "$dir/port")" "${upload_opts[@]}" > "$dir/$name.up" \
      2> "$dir/$name.err"
  else
    "$T" upload "$input" --port "$(cat "$dir/port")" "${upload_opts[@]}" > "$dir/$name.up" 2> "$dir/$name.err"
  fi
  local rc=0
  wait "$board" || rc=$?
  board=
  end=$(date +%s.%N)
  echo "== $name"
  cat "$dir/$name.up" "$dir/$name.board"
  local sim
  sim=$(sed -n 's/.*; \([0-9.]*\) s simulated.*/\1/p' "$dir/$name.board" | tail -n 1)
  awk -v a="$start" -v b="$end" -v s="${sim:-0}" 'BEGIN {
    printf "wall %.1f s for %.3f s simulated: %.3f x real time, %.2f million cycles/s\n", b - a, s, s / (b - a),
      s * 30 / (b - a) }'
  [ "$rc" -eq 0 ] || { echo "$name: the board's pins differ from the prediction"; exit 1; }
}

BOARD_OPTS=("$@")
butterfly=(--feed 50 --period 0.001 --v-axis 200 --a-axis 2000 --j-axis 50000 --a-tan 1000 --j-tan 20000
  --a-cen 1000 --j-cen 50000 --tol 0.001)
"$T" plan "$root/host/assets/butterfly_nurbs.json" -o "$dir/butterfly.trj" "${butterfly[@]}" > /dev/null
run butterfly "$dir/butterfly.trj" "$dir/butterfly.trj"

raster=(--raster "$N" --feed 200 --v-axis 400 --a-axis 10000 --j-axis 1000000 --a-tan 10000 --j-tan 1000000
  --a-cen 10000 --j-cen 1000000)
"$T" plan "${raster[@]}" -o "$dir/raster.trj" > /dev/null
run "raster-$N" "$dir/raster.trj" - "$T" plan "${raster[@]}"
