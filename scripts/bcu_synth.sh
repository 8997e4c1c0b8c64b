#!/usr/bin/env bash
# iCE40 synthesis + place-and-route of the BCU generator (3 axes) for the
# figures in tb/bcu/README.md: logic cells and Fmax on UP5K (sg48, 48 MHz
# target) and HX8K (ct256, 100 MHz target). No pin constraints: nextpnr places
# the IOs itself.
#   usage: scripts/bcu_synth.sh [outdir]   (env: BCU_PARAMS="chparam ..." to override)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
rtl="$here/../rtl"
out="${1:-${TMPDIR:-/tmp}/bcu_synth}"
mkdir -p "$out"
params="${BCU_PARAMS:-}"
yosys -q -l "$out/yosys.log" -p "read_verilog -sv -I$rtl $rtl/traj_bcu.sv $rtl/traj_bcu_gen.sv $rtl/board/traj_bcu_synth_top.sv; ${params:+$params;} synth_ice40 -top traj_bcu_synth_top -json $out/out.json"
report() {  # name, nextpnr args...
  local name="$1"; shift
  nextpnr-ice40 "$@" --timing-allow-fail --json "$out/out.json" --asc "$out/$name.asc" --seed 1 \
    > "$out/$name.log" 2>&1 || { echo "$name: nextpnr failed, see $out/$name.log"; return 1; }
  local lc bram fmax
  lc=$(grep -E "ICESTORM_LC:" "$out/$name.log" | tail -1 | sed -E 's/.*ICESTORM_LC: *([0-9]+)\/ *([0-9]+).*/\1 \/ \2/')
  bram=$(grep -E "ICESTORM_RAM:" "$out/$name.log" | tail -1 | sed -E 's/.*ICESTORM_RAM: *([0-9]+)\/ *([0-9]+).*/\1 \/ \2/')
  fmax=$(grep -E "Max frequency for clock" "$out/$name.log" | tail -1 | sed -E 's/.*: ([0-9.]+) MHz.*/\1/')
  printf '%-6s LC %-14s BRAM %-10s Fmax %s MHz\n' "$name" "$lc" "$bram" "$fmax"
}
echo "traj_bcu_synth_top (Axes=3 ChunkWidth=32 CtrlWidth=40 GuardBits=9 OutWidth=32 MaxDepth=12${params:+; $params})"
report up5k --up5k --package sg48 --freq 48
report hx8k --hx8k --package ct256 --freq 100
