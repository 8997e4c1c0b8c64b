#!/usr/bin/env bash
# Bitstream of a board top: Yosys synth_ice40 -> nextpnr-ice40 (one run per
# placement seed, with the board's pin file and its core clock as the timing
# target) -> icepack, and icetime on the shipped placement.
#
#   usage: scripts/bitstream.sh BOARD
#     BOARD  icebreaker (iCE40UP5K-SG48, rtl/board/traj_icebreaker_top.sv, SPRAM FIFO)
#            hx8k       (iCE40HX8K-CT256 breakout, rtl/board/traj_hx8k_top.sv, BRAM FIFO)
#   env: SEEDS          nextpnr placement seeds ("1 2 3 4 5")
#        OUT            work directory (build/bitstreams/work_BOARD)
#        PARAMS         parameters of the top, "Name=Value ..." (e.g. "TimeScale=1")
#        YOSYS_EXTRA    more synth_ice40 options (e.g. "-abc9 -device u")
#        NEXTPNR_EXTRA  more nextpnr-ice40 options (e.g. "--opt-timing")
#        PACK_ONLY      1: only pack (seconds): print the logic cells the design
#                       needs, also when they exceed the device (no placement)
#
# Output: build/bitstreams/BOARD.bin (BOARD_<PARAMS>.bin with PARAMS) from the
# first seed in SEEDS; one line per seed: logic cells, block RAM, SPRAM, Fmax
# of the core clock. Exit status 0 when every seed meets the core clock, 1
# when a tool fails, 2 when a seed misses timing.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
[ $# -eq 1 ] || { sed -n '6,13p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 1; }
board=$1
SEEDS=${SEEDS:-"1 2 3 4 5"}

# device, package, top, pin file, core clock (MHz, the top's ClkHz / PLL), Yosys options
case $board in
  icebreaker) device=up5k package=sg48  top=traj_icebreaker_top pcf=icebreaker.pcf    mhz=30 synth_opts="-spram" ;;
  hx8k)       device=hx8k package=ct256 top=traj_hx8k_top       pcf=hx8k_breakout.pcf mhz=60 synth_opts="" ;;
  *) echo "bitstream.sh: unknown board '$board' (icebreaker or hx8k)" >&2; exit 1 ;;
esac
# the top's ClkHz when PARAMS set it or pick another default (the iCEBreaker
# with the time-scale unit: 24 MHz, rtl/board/traj_icebreaker_top.sv)
case " ${PARAMS:-} " in
  *" ClkHz="*) mhz=$(( $(echo " $PARAMS " | sed -E 's/.* ClkHz=([0-9_]+) .*/\1/; s/_//g') / 1000000 )) ;;
  *" TimeScale=1 "*) [ "$board" = icebreaker ] && mhz=24 ;;
esac
pcf=$root/constraints/$pcf
dist=$root/build/bitstreams
out=${OUT:-$dist/work_$board}
mkdir -p "$out" "$dist"

# last "<cell>: used/avail" figure of a nextpnr log, "used" only
cell_count() { { grep -E "$1:" "$2" || true; } | tail -1 | sed -E "s/.*$1: *([0-9]+)\/.*/\1/"; }

# shellcheck disable=SC2086  # PARAMS is a list of Name=Value words
chparam=$("$root/scripts/chparam.sh" "$top" ${PARAMS:-})

files=$("$root/scripts/unit_files.sh" "$top")
json=$out/$top.json
if ! yosys -q -l "$out/yosys.log" -p "read_verilog -sv -I$root/rtl $files; $chparam synth_ice40 $synth_opts ${YOSYS_EXTRA:-} -top $top -json $json" \
     >/dev/null 2>&1; then
  echo "bitstream.sh: yosys failed, see $out/yosys.log" >&2; exit 1
fi

echo "$board: $top on $device-$package, core clock $mhz MHz, pins $(basename "$pcf")${PARAMS:+, $PARAMS}"
if [ "${PACK_ONLY:-0}" = 1 ]; then
  nextpnr-ice40 --"$device" --package $package --pcf "$pcf" --json "$json" --pack-only >"$out/nextpnr_pack.log" 2>&1 ||
    { echo "bitstream.sh: nextpnr-ice40 --pack-only failed, see $out/nextpnr_pack.log" >&2; exit 1; }
  echo "logic cells needed: $({ grep -E "ICESTORM_LC: *[0-9]+/" "$out/nextpnr_pack.log" || true; } | tail -1 |
    sed -E 's/.*ICESTORM_LC: *([0-9]+\/ *[0-9]+).*/\1/; s/ //g') (packed, not placed)"
  exit 0
fi
printf '%-5s %6s %5s %6s %4s %10s\n' seed LCs BRAM SPRAM DSP Fmax_MHz
status=0 shipped=""
for seed in $SEEDS; do
  log=$out/nextpnr_s$seed.log
  asc=$out/${board}_s$seed.asc
  if ! nextpnr-ice40 --"$device" --package $package --pcf "$pcf" --freq $mhz --timing-allow-fail ${NEXTPNR_EXTRA:-} \
        --seed "$seed" --json "$json" --asc "$asc" >"$log" 2>&1; then
    need=$({ grep -E "ICESTORM_LC: *[0-9]+/" "$log" || true; } | tail -1 | sed -E 's/.*ICESTORM_LC: *([0-9]+\/ *[0-9]+).*/\1/; s/ //g')
    echo "seed $seed: nextpnr-ice40 failed ($(grep -m1 ERROR "$log" || echo "no ERROR line"))${need:+; logic cells $need}, see $log" >&2
    status=1; continue
  fi
  lcs=$(cell_count ICESTORM_LC "$log"); bram=$(cell_count ICESTORM_RAM "$log"); spram=$(cell_count ICESTORM_SPRAM "$log")
  dsp=$(cell_count ICESTORM_DSP "$log")
  # the core clock is the PLL output (the 12 MHz pin only feeds the PLL)
  fmax=$({ grep -E "Max frequency for clock 'clk'" "$log" || true; } | tail -1 | sed -E 's/.*: ([0-9.]+) MHz.*/\1/')
  printf '%-5s %6s %5s %6s %4s %10s\n' "$seed" "$lcs" "${bram:-0}" "${spram:-0}" "${dsp:-0}" "${fmax:-?}"
  if [ -z "$fmax" ] || awk -v f="$fmax" -v t=$mhz 'BEGIN { exit !(f < t) }'; then
    echo "  seed $seed: Fmax ${fmax:-?} MHz below the core clock $mhz MHz" >&2
    [ $status -ne 0 ] || status=2
  fi
  [ -n "$shipped" ] || shipped=$asc
done
[ -n "$shipped" ] || { echo "bitstream.sh: no seed placed" >&2; exit 1; }
bin=$dist/$board${PARAMS:+_$(echo "$PARAMS" | tr ' =' '_-')}.bin  # a build with other parameters beside the default's
icepack "$shipped" "$bin"
# icetime's pin-file reader takes no -nowarn
sed 's/ -nowarn//' "$pcf" >"$out/icetime.pcf"
if icetime -d "${device}" -P $package -p "$out/icetime.pcf" -c $mhz -t "$shipped" >"$out/icetime.log" 2>&1; then
  echo "icetime ($(basename "$shipped")): $(grep -E 'Total path delay' "$out/icetime.log" | tail -1)"
else
  echo "icetime ($(basename "$shipped")) did not run: $(tail -1 "$out/icetime.log")"
fi
echo "bitstream: $bin"
exit $status
