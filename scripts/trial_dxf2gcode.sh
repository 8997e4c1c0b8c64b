#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A user trial with G-code a CAM program wrote: LibreCAD's parts library
# (Debian's librecad-data) turned into G-code by dxf2gcode (Debian's
# dxf2gcode, its default post "G-CODE for LinuxCNC": contours with depth
# passes, G2/G3 arcs, tool change, spindle and coolant words, F in mm/min),
# then every program through `trajcore plan`, whole and streamed
# (--window 64), each within a time limit. Prints per mode the programs
# planned, those refused as longer than one plan holds (whole only: they
# stream) and every other failure with its first line; exits 1 on any such
# failure. Not part of the test suite: it needs dxf2gcode installed (as root
# it installs it: apt-get install --no-install-recommends dxf2gcode) and
# downloads librecad-data (no install); about 3 s a drawing.
#
#   usage: scripts/trial_dxf2gcode.sh [COUNT]   (default 100: evenly spread over the
#          library's drawings in name order; 0: all of them)
#   env:   TRAJ_BUILD_DIR (default build/), TRIAL_DIR (the packages, the programs and
#          the results, default a temporary folder, removed at the end),
#          TRIAL_TIMEOUT (seconds per program and mode, default 120),
#          TRIAL_REUSE=1 (plan the programs an earlier run left in TRIAL_DIR again, without
#          dxf2gcode: another build of trajcore on the same programs; COUNT is then ignored)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
trajcore=${TRAJ_BUILD_DIR:-$root/build}/host/app/trajcore
[ -x "$trajcore" ] || { echo "trial_dxf2gcode.sh: no $trajcore (scripts/build.sh first)" >&2; exit 1; }
limit=${TRIAL_TIMEOUT:-120}
# dxf2gcode over the library's drawings (COUNT of them): $work/ngc/N.ngc, listed with their drawings
# in $work/programs.txt; sets work and made.
make_programs() {
  if ! [ -x /usr/bin/dxf2gcode ]; then
    [ "$(id -u)" -eq 0 ] ||
      { echo "trial_dxf2gcode.sh: needs dxf2gcode: sudo apt-get install --no-install-recommends dxf2gcode" >&2; exit 1; }
    DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends dxf2gcode > /dev/null
  fi
  work=${TRIAL_DIR:-$(mktemp -d)}
  [ -n "${TRIAL_DIR:-}" ] || trap 'rm -rf "$work"' EXIT
  mkdir -p "$work/ngc"
  local count=$1

  . "$root/scripts/librecad_data.sh"
  librecad_dxf_list "$work" "$work/all.txt"
  all=$(wc -l < "$work/all.txt")
  if [ "$count" -eq 0 ] || [ "$count" -ge "$all" ]; then
    cp "$work/all.txt" "$work/files.txt"
  else
    awk -v n="$all" -v c="$count" 'int((NR - 1) * c / n) != int(NR * c / n)' "$work/all.txt" > "$work/files.txt"
  fi

  # dxf2gcode 20191025 under Python 3.11 and PyQt 5.15 passes floats where Qt
  # takes ints (a font size, a scroll position) and fails before its export;
  # the wrapper rounds them, the program is otherwise as Debian ships it.
  cat > "$work/run_dxf2gcode.py" <<'PY'
import runpy
import sys

from PyQt5 import QtGui, QtWidgets

_QFont = QtGui.QFont


class QFont(_QFont):
    def __init__(self, *args):
        if len(args) >= 2 and isinstance(args[1], float):
            args = (args[0], max(1, int(args[1]))) + tuple(args[2:])
        super().__init__(*args)


QtGui.QFont = QFont
_set_value = QtWidgets.QAbstractSlider.setValue
QtWidgets.QAbstractSlider.setValue = lambda self, v: _set_value(self, int(min(v, 2**31 - 1)))
sys.argv = ["dxf2gcode"] + sys.argv[1:]
sys.path.pop(0)  # the trial's folder: nothing there may stand for dxf2gcode's own modules
runpy.run_path("/usr/bin/dxf2gcode", run_name="__main__")
PY

  start=$(date +%s.%N)
  : > "$work/programs.txt"
  : > "$work/unconverted.txt"
  i=0
  while read -r f; do
    i=$((i + 1))
    out="$work/ngc/$i.ngc"
    QT_QPA_PLATFORM=offscreen XDG_RUNTIME_DIR="$work" timeout "$limit" /usr/bin/python3 "$work/run_dxf2gcode.py" -q \
      -e "$out" "$f" > "$work/dxf2gcode.log" 2>&1 || true
    name=${f#"$work/x/usr/share/librecad/"}
    if [ -s "$out" ]; then echo "$out $name" >> "$work/programs.txt"; else echo "$name" >> "$work/unconverted.txt"; fi
  done < "$work/files.txt"
  made=$(wc -l < "$work/programs.txt")
  printf 'dxf2gcode: %d drawings, %d programs written, %d not converted (dxf2gcode wrote nothing), %.0f s\n' \
    "$(wc -l < "$work/files.txt")" "$made" "$(wc -l < "$work/unconverted.txt")" "$(echo "$(date +%s.%N) - $start" | bc)"
}

if [ -n "${TRIAL_REUSE:-}" ]; then
  work=${TRIAL_DIR:-}
  [ -n "$work" ] && [ -s "$work/programs.txt" ] ||
    { echo "trial_dxf2gcode.sh: TRIAL_REUSE needs TRIAL_DIR with the programs of an earlier run" >&2; exit 1; }
  made=$(wc -l < "$work/programs.txt")
  echo "reusing the $made programs in $work"
else
  make_programs "${1:-100}"
fi

status=0
for m in whole streamed; do
  case $m in
    whole) args=() ;;
    streamed) args=(--window 64) ;;
  esac
  failed="$work/failed_$m.txt" long="$work/long_$m.txt"
  : > "$failed"
  : > "$long"
  start=$(date +%s.%N)
  while read -r p name; do
    rc=0
    out=$(timeout "$limit" "$trajcore" plan "$p" "${args[@]}" -o "$work/out.trj" 2>&1) || rc=$?
    [ "$rc" -eq 0 ] && continue
    if [ "$rc" -eq 124 ]; then
      echo "$name: no result within $limit s" >> "$failed"
    elif [ "$m" = whole ] && grep -q 'more than one plan holds' <<< "$out"; then
      echo "$name" >> "$long"
    else
      printf '%s: %s\n' "$name" "$(grep -m1 'error' <<< "$out" || tail -n 1 <<< "$out")" >> "$failed"
    fi
  done < "$work/programs.txt"
  rm -f "$work/out.trj"
  bad=$(wc -l < "$failed")
  over=$(wc -l < "$long")
  printf '%-9s %5d programs, %5d planned, %d longer than one plan (they stream), %d failed, %.0f s\n' \
    "$m" "$made" $((made - bad - over)) "$over" "$bad" "$(echo "$(date +%s.%N) - $start" | bc)"
  if [ "$bad" -gt 0 ]; then
    sed 's/^/    /' "$failed" | head -n 20
    status=1
  fi
done
exit $status
