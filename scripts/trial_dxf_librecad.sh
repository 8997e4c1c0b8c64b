#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A user trial on drawings trajcore's tests did not write: LibreCAD's parts
# library and hatch patterns (Debian's librecad-data, 1 339 DXF files:
# electrical symbols, architectural plans with blocks and INSERTs, drawing
# sheets), every file through `trajcore plan` at the defaults, planned whole
# and streamed (--window 64), one at a time, each within a time limit.
# Prints per mode the files planned, the drawings refused as empty (nothing
# with length: "no curves") and every other failure (an error, a time-out)
# with its first line; exits 1 if there is any such failure. Not part of the
# test suite: it downloads the package (apt, no install) and takes about 15
# minutes.
#
#   usage: scripts/trial_dxf_librecad.sh [whole|streamed ...]   (default: both)
#   env:   TRAJ_BUILD_DIR (default build/), TRIAL_DIR (the package and the
#          results, default a temporary folder, removed at the end),
#          TRIAL_TIMEOUT (seconds per file and mode, default 60)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
trajcore=${TRAJ_BUILD_DIR:-$root/build}/host/app/trajcore
[ -x "$trajcore" ] || { echo "trial_dxf_librecad.sh: no $trajcore (scripts/build.sh first)" >&2; exit 1; }
work=${TRIAL_DIR:-$(mktemp -d)}
[ -n "${TRIAL_DIR:-}" ] || trap 'rm -rf "$work"' EXIT
mkdir -p "$work"
limit=${TRIAL_TIMEOUT:-60}

. "$root/scripts/librecad_data.sh"
list="$work/files.txt"
librecad_dxf_list "$work" "$list"
n=$(wc -l < "$list")

status=0
for mode in "${@:-whole streamed}"; do
  for m in $mode; do
    case $m in
      whole) args=() ;;
      streamed) args=(--window 64) ;;
      *) echo "trial_dxf_librecad.sh: unknown mode '$m' (whole, streamed)" >&2; exit 1 ;;
    esac
    failed="$work/failed_$m.txt" empty="$work/empty_$m.txt"
    : > "$failed"
    : > "$empty"
    start=$(date +%s.%N)
    while read -r f; do
      rc=0
      out=$(timeout "$limit" "$trajcore" plan "$f" "${args[@]}" -o "$work/out.trj" 2>&1) || rc=$?
      [ "$rc" -eq 0 ] && continue
      name=${f#"$work/x/usr/share/librecad/"}
      if [ "$rc" -eq 124 ]; then
        echo "$name: no result within $limit s" >> "$failed"
      elif grep -q 'no curves:' <<< "$out"; then
        echo "$name" >> "$empty"
      else
        printf '%s: %s\n' "$name" "$(grep -m1 'error' <<< "$out" || tail -n 1 <<< "$out")" >> "$failed"
      fi
    done < "$list"
    rm -f "$work/out.trj"
    secs=$(echo "$(date +%s.%N) - $start" | bc)
    bad=$(wc -l < "$failed")
    none=$(wc -l < "$empty")
    printf '%-9s %5d files, %5d planned, %d empty (refused: no curves), %d failed, %.0f s\n' \
      "$m" "$n" $((n - bad - none)) "$none" "$bad" "$secs"
    if [ "$bad" -gt 0 ]; then
      sed 's/^/    /' "$failed" | head -n 20
      status=1
    fi
  done
done
exit $status
