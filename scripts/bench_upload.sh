#!/usr/bin/env bash
# The million-piece upload: `trajcore plan --raster N -o - | trajcore upload -`
# against the loopback board (`trajcore board --loopback`, unpaced) on a
# pseudo-terminal, in bounded memory. Prints the upload's rate and both
# processes' maximum resident set size (GNU time), and the board's count of
# the records it played.
#   scripts/bench_upload.sh [PIECES (default 1000000)] [extra `trajcore board` options, e.g. --corrupt 1e-4]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
T=${TRAJCORE:-${TRAJ_BUILD_DIR:-$root/build}/host/app/trajcore}
N=${1:-1000000}
shift || true
[ -x /usr/bin/time ] || { echo "bench_upload: needs GNU time (/usr/bin/time, Debian package time)" >&2; exit 1; }
dir=$(mktemp -d)
trap 'kill "$board" 2>/dev/null || true; rm -rf "$dir"' EXIT

"$T" board --loopback --speed 0 --once "$@" > "$dir/port" 2> "$dir/board" &
board=$!
for _ in $(seq 50); do [ -s "$dir/port" ] && break; sleep 0.1; done
port=$(cat "$dir/port")
echo "bench_upload: $N raster pieces, trajcore plan -o - | trajcore upload - --port $port (loopback board, unpaced)"
start=$(date +%s.%N)
/usr/bin/time -v -o "$dir/plan.time" "$T" plan --raster "$N" -o - 2> "$dir/plan.err" |
  /usr/bin/time -v -o "$dir/upload.time" "$T" upload - --port "$port" > "$dir/upload.out" 2> "$dir/upload.err"
end=$(date +%s.%N)
wait "$board"
board=
rss() { awk -F': ' '/Maximum resident set size/ {printf "%.1f MB", $2 / 1024}' "$1"; }
cat "$dir/upload.out"
grep -v '^\[' "$dir/plan.err" | tail -2
cat "$dir/board"
segs=$(sed -n 's/^upload: \([0-9]*\) segments.*/\1/p' "$dir/upload.out")
awk -v s="$segs" -v a="$start" -v b="$end" 'BEGIN {
  t = b - a; printf "wall %.1f s, %.0f segments/s, %.1f MB/s of frames (%.1f Mbaud equivalent at 10 bits a byte)\n",
  t, s / t, s * 248 / t / 1e6, s * 248 * 10 / t / 1e6 }'
echo "max RSS: upload $(rss "$dir/upload.time"), plan $(rss "$dir/plan.time")"
