#!/usr/bin/env bash
# iCE40 synthesis + place-and-route of the core (FD engine + BCU generator, 3 axes, default
# parameters) for the figures in tb/core/README.md: logic cells, block RAMs and
# Fmax on UP5K (sg48, 48 MHz target) and HX8K (ct256, 100 MHz target), for
# every nextpnr seed in SEEDS. No pin constraints: nextpnr places the IOs.
# Exits non-zero if a tool fails or any device/seed misses its target.
#   usage: scripts/core_synth.sh [outdir]
#   env: SEEDS ("1 2 3"), UP5K_MHZ (48), HX8K_MHZ (100),
#        CORE_PARAMS ("chparam -set ... traj_core_synth_top" to override parameters)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
rtl="$here/../rtl"
out="${1:-${TMPDIR:-/tmp}/core_synth}"
SEEDS=${SEEDS:-"1 2 3"}; UP5K_MHZ=${UP5K_MHZ:-48}; HX8K_MHZ=${HX8K_MHZ:-100}
mkdir -p "$out"
params="${CORE_PARAMS:-}"
yosys -q -l "$out/yosys.log" -p "read_verilog -sv -I$rtl $rtl/traj_fd_engine.sv $rtl/traj_bcu_gen.sv $rtl/traj_core.sv $rtl/board/traj_core_synth_top.sv; ${params:+$params;} synth_ice40 -top traj_core_synth_top -json $out/out.json"
echo "traj_core_synth_top (Axes=3 Degree=3 Width=64 ChunkWidth=16 GuardBits=32 CtrlWidth=40 BcuGuardBits=9 MaxDepth=12${params:+; $params})"
printf '%-6s %-5s %-14s %-10s %9s %10s\n' device seed LCs BRAM Fmax_MHz target_MHz
status=0
for dev in up5k hx8k; do
  if [ "$dev" = up5k ]; then pkg=sg48; freq=$UP5K_MHZ; else pkg=ct256; freq=$HX8K_MHZ; fi
  for seed in $SEEDS; do
    log="$out/${dev}_s$seed.log"
    if ! nextpnr-ice40 --$dev --package $pkg --freq "$freq" --timing-allow-fail --seed "$seed" \
          --json "$out/out.json" --asc "$out/${dev}_s$seed.asc" >"$log" 2>&1; then
      echo "$dev seed $seed: nextpnr failed, see $log" >&2; status=1; continue
    fi
    lc=$(grep -E "ICESTORM_LC:" "$log" | tail -1 | sed -E 's/.*ICESTORM_LC: *([0-9]+)\/ *([0-9]+).*/\1\/\2/')
    bram=$(grep -E "ICESTORM_RAM:" "$log" | tail -1 | sed -E 's/.*ICESTORM_RAM: *([0-9]+)\/ *([0-9]+).*/\1\/\2/')
    fmax=$(grep -E "Max frequency for clock" "$log" | tail -1 | sed -E 's/.*: ([0-9.]+) MHz.*/\1/')
    printf '%-6s %-5s %-14s %-10s %9s %10s\n' "$dev" "$seed" "$lc" "$bram" "$fmax" "$freq"
    if [ -z "$fmax" ] || awk -v f="$fmax" -v t="$freq" 'BEGIN{exit !(f < t)}'; then
      echo "  $dev seed $seed: Fmax ${fmax:-?} MHz below target $freq MHz" >&2; status=2
    fi
  done
done
exit $status
