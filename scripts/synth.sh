#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# iCE40 synthesis and place-and-route of one RTL unit: Yosys synth_ice40 ->
# nextpnr-ice40 (one run per seed) -> icepack for units with a board pin file.
#
#   usage: scripts/synth.sh UNIT DEVICE [Param=Value ...]
#     UNIT    a top module named in rtl/units.txt (its files come from there),
#             e.g. traj_fd_synth_top, traj_bcu_synth_top, traj_core_synth_top
#     DEVICE  up5k (SG48 package, target 48 MHz) or hx8k (CT256, target 100 MHz)
#     Param=Value  parameter overrides of the top (Yosys chparam)
#   env: SEEDS  nextpnr seeds ("1 2 3")
#        OUT    work directory (${TMPDIR:-/tmp}/synth_UNIT_DEVICE)
#
# Pins: a unit with a board pin file (constraints/, see board_pcf below) is
# placed with every port pinned and packed into a bitstream; any other unit is
# placed with the pins nextpnr chooses, which needs a package with enough IOs
# for its ports (the byte-wide synthesis tops fit SG48; a bare engine with its
# full sample bus fits only the larger packages, and nextpnr says so otherwise).
#
# Output: one line per seed, then as the last line the worst seed's figures:
#   LCs=<n> BRAM=<n> Fmax=<MHz>
# Exit status: 0 when every seed meets the device's target, 1 when a tool
# fails, 2 when a seed misses the target.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

usage() { sed -n '5,11p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 1; }
[ $# -ge 2 ] || usage
unit=$1 device=$2; shift 2
SEEDS=${SEEDS:-"1 2 3"}
out=${OUT:-${TMPDIR:-/tmp}/synth_${unit}_${device}}

# package and target clock of each device
case $device in
  up5k) package=sg48;  target_mhz=48 ;;
  hx8k) package=ct256; target_mhz=100 ;;
  *) echo "synth.sh: unknown device '$device' (up5k or hx8k)" >&2; exit 1 ;;
esac

# board pin file of a unit on a device, empty when the unit has none
board_pcf() {
  case "$1/$2" in
    traj_fd_synth_top/up5k) echo "$root/constraints/icebreaker_fd.pcf" ;;
    traj_fd_synth_top/hx8k) echo "$root/constraints/hx8k_breakout_fd.pcf" ;;
    *) echo "" ;;
  esac
}

# last "<cell>: used/avail" figure of a nextpnr log, "used" only
cell_count() { grep -E "$1: *[0-9]+/" "$2" | tail -1 | sed -E "s/.*$1: *([0-9]+)\/.*/\1/"; }

files=$("$root/scripts/unit_files.sh" "$unit")
chparam=$("$root/scripts/chparam.sh" "$unit" "$@")
pcf=$(board_pcf "$unit" "$device")
mkdir -p "$out"
json="$out/$unit.json"
if ! yosys -q -l "$out/yosys.log" -p "read_verilog -sv -I$root/rtl $files; $chparam synth_ice40 -top $unit -json $json" \
     >/dev/null 2>&1; then
  echo "synth.sh: yosys failed, see $out/yosys.log" >&2; exit 1
fi

echo "$unit on $device ($package, target $target_mhz MHz${pcf:+, pins $(basename "$pcf")}${*:+; $*})"
printf '%-6s %-5s %8s %6s %9s\n' device seed LCs BRAM Fmax_MHz
status=0 worst=""
for seed in $SEEDS; do
  log="$out/${device}_s$seed.log"
  asc="$out/${unit}_${device}_s$seed.asc"
  if ! nextpnr-ice40 --"$device" --package $package ${pcf:+--pcf "$pcf"} --freq $target_mhz \
        --timing-allow-fail --seed "$seed" --json "$json" --asc "$asc" >"$log" 2>&1; then
    echo "$device seed $seed: nextpnr-ice40 failed ($(grep -m1 ERROR "$log" || echo "no ERROR line")), see $log" >&2
    status=1; continue
  fi
  if [ -n "$pcf" ] && ! icepack "$asc" "${asc%.asc}.bin"; then
    echo "$device seed $seed: icepack failed" >&2; status=1; continue
  fi
  lcs=$(cell_count ICESTORM_LC "$log"); bram=$(cell_count ICESTORM_RAM "$log")
  fmax=$(grep -E "Max frequency for clock" "$log" | tail -1 | sed -E 's/.*: ([0-9.]+) MHz.*/\1/')
  printf '%-6s %-5s %8s %6s %9s\n' "$device" "$seed" "$lcs" "${bram:-0}" "${fmax:-?}"
  if [ -z "$fmax" ] || awk -v f="$fmax" -v t=$target_mhz 'BEGIN { exit !(f < t) }'; then
    echo "  $device seed $seed: Fmax ${fmax:-?} MHz below the target $target_mhz MHz" >&2
    [ $status -ne 0 ] || status=2
  fi
  if [ -z "$worst" ] || awk -v f="${fmax:-0}" -v w="${worst##*=}" 'BEGIN { exit !(f < w) }'; then
    worst="LCs=$lcs BRAM=${bram:-0} Fmax=${fmax:-0}"
  fi
done
[ -n "$worst" ] || { echo "synth.sh: no seed placed" >&2; exit 1; }
echo "$worst"
exit $status
