#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Logic of a board top per unit and in total, from Yosys alone (no placement):
# the figures rtl/README.md quotes per unit.
#
#   usage: scripts/unit_stats.sh icebreaker|hx8k
#   env:   PARAMS  parameters of the top, "Name=Value ..." (e.g. "TimeScale=1")
#
# Prints, per module of `synth_ice40 -noflatten` (the options bitstream.sh
# uses for the board), SB_LUT4 / SB_CARRY / flip-flops / SB_RAM40_4K /
# SB_MAC16, then the same for the flattened design (what placement starts
# from: fewer, since flattening drops what a unit computes that nothing
# reads). A logic cell is
# a LUT and a flip-flop; scripts/bitstream.sh gives the placed count.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
[ $# -eq 1 ] || { sed -n '6,7p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 1; }
case $1 in
  icebreaker) top=traj_icebreaker_top opts="-spram" ;;
  hx8k)       top=traj_hx8k_top       opts="" ;;
  *) echo "unit_stats.sh: unknown board '$1' (icebreaker or hx8k)" >&2; exit 1 ;;
esac
# shellcheck disable=SC2086  # PARAMS is a list of Name=Value words
chparam=$("$root/scripts/chparam.sh" "$top" ${PARAMS:-})
files=$("$root/scripts/unit_files.sh" "$top")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# per module of a Yosys `stat` report: name, LUTs, carries, flip-flops, block RAMs, DSPs
table() {
  awk '/^=== /{m=$2; sub(/^\$paramod[$\\]*[0-9a-f]*\\*/, "", m); sub(/\\.*/, "", m); mods[m]=1}
       /^ +SB_LUT4 /{l[m]+=$2} /^ +SB_CARRY /{c[m]+=$2} /^ +SB_DFF/{f[m]+=$2} /^ +SB_RAM40_4K /{r[m]+=$2}
       /^ +SB_MAC16 /{d[m]+=$2}
       END{printf "%-24s %7s %7s %7s %5s %4s\n", "module", "LUT4", "CARRY", "FF", "BRAM", "DSP"
           for (k in mods) printf "%-24s %7d %7d %7d %5d %4d\n", k, l[k], c[k], f[k], r[k], d[k]}' "$1"
}

for mode in noflatten flat; do
  flag=""; [ $mode = noflatten ] && flag="-noflatten"
  if ! yosys -q -l "$work/$mode.log" -p "read_verilog -sv -I$root/rtl $files; $chparam synth_ice40 $opts $flag -top $top; tee -q -o $work/$mode.txt stat" \
       >/dev/null 2>&1; then
    echo "unit_stats.sh: yosys failed, see the log:" >&2; tail -5 "$work/$mode.log" >&2; exit 1
  fi
done
echo "$top${PARAMS:+ ($PARAMS)}, synth_ice40 $opts -noflatten, per module (a unit used twice is counted once):"
table "$work/noflatten.txt" | { read -r h; echo "$h"; sort; }
echo "flattened (what placement starts from):"
awk '/^ +SB_LUT4 /{l=$2} /^ +SB_CARRY /{c=$2} /^ +SB_DFF/{f+=$2} /^ +SB_RAM40_4K /{r=$2} /^ +SB_MAC16 /{d=$2}
     END{printf "%-24s %7d %7d %7d %5d %4d\n", "design", l, c, f, r, d}' "$work/flat.txt"
