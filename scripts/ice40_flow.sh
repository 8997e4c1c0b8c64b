#!/usr/bin/env bash
# iCE40 flow for the forward-difference engine: Yosys synth_ice40 -> nextpnr-ice40
# -> icepack, on UP5K (SG48, iCEBreaker pins) and HX8K (CT256).
# Prints logic cells and Fmax per device; exits non-zero if a tool fails.
#
# usage: scripts/ice40_flow.sh [outdir] [Axes Degree Width ChunkWidth GuardBits]
#   defaults: build/ice40  3 3 64 16 32
#   env SEED (nextpnr seed, default 1), UP5K_MHZ (48), HX8K_MHZ (100)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/build/ice40}
AX=${2:-3}; DEG=${3:-3}; W=${4:-64}; CW=${5:-16}; G=${6:-32}
SEED=${SEED:-1}; UP5K_MHZ=${UP5K_MHZ:-48}; HX8K_MHZ=${HX8K_MHZ:-100}
mkdir -p "$out"
top=traj_fd_synth_top
srcs=("$root/rtl/traj_fd_engine.sv" "$root/rtl/board/traj_fd_synth_top.sv")
params="chparam -set Axes $AX -set Degree $DEG -set Width $W -set ChunkWidth $CW -set GuardBits $G $top"

yosys -q -l "$out/yosys.log" -p "read_verilog -sv -I$root/rtl ${srcs[*]}; $params; synth_ice40 -top $top -json $out/fd.json"

printf '%-6s %-10s %8s %10s %10s\n' device config LCs Fmax_MHz target_MHz
status=0
for dev in up5k hx8k; do
  if [ "$dev" = up5k ]; then pkg=sg48; freq=$UP5K_MHZ; pcf=(--pcf "$root/constraints/icebreaker_fd.pcf");
  else pkg=ct256; freq=$HX8K_MHZ; pcf=(--pcf "$root/constraints/hx8k_breakout_fd.pcf"); fi
  log="$out/nextpnr_$dev.log"
  if ! nextpnr-ice40 --$dev --package $pkg --json "$out/fd.json" "${pcf[@]}" \
        --freq "$freq" --seed "$SEED" --asc "$out/fd_$dev.asc" --report "$out/report_$dev.json" \
        >"$log" 2>&1; then
    echo "nextpnr-ice40 failed for $dev; see $log" >&2; status=1; continue
  fi
  icepack "$out/fd_$dev.asc" "$out/fd_$dev.bin"
  lcs=$(grep -E 'ICESTORM_LC:' "$log" | tail -1 | sed -E 's/.*ICESTORM_LC: *([0-9]+)\/ *([0-9]+).*/\1\/\2/')
  fmax=$(grep -E "Max frequency for clock" "$log" | tail -1 | sed -E 's/.*: ([0-9.]+) MHz.*/\1/')
  printf '%-6s %-10s %8s %10s %10s\n' "$dev" "${AX}x${DEG}x${W}" "$lcs" "$fmax" "$freq"
  if awk -v f="$fmax" -v t="$freq" 'BEGIN{exit !(f < t)}'; then
    echo "  $dev: Fmax $fmax MHz below target $freq MHz" >&2; status=2
  fi
done
exit $status
