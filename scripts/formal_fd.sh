#!/usr/bin/env bash
# Formal check of rtl/traj_fd_engine.sv's properties (the `ifdef FORMAL block):
# Yosys -> SMT2, then yosys-smtbmc with z3: bounded model check from reset
# (depth 24) and temporal induction (depth 24). Exit non-zero on any failure.
#   usage: scripts/formal_fd.sh WORKDIR Axes Degree Width ChunkWidth GuardBits
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
work=$1; shift
AX=$1 DEG=$2 W=$3 CW=$4 G=$5
mkdir -p "$work"
smt="$work/fd_${AX}_${DEG}_${W}_${CW}_${G}.smt2"
yosys -q -p "read_verilog -sv -formal -I$root/rtl $root/rtl/traj_fd_engine.sv; \
  chparam -set Axes $AX -set Degree $DEG -set Width $W -set ChunkWidth $CW -set GuardBits $G traj_fd_engine; \
  prep -top traj_fd_engine; async2sync; dffunmap; write_smt2 -wires $smt" 2>&1 | grep -v "Replacing memory" || true
test -s "$smt"
echo "bounded model check, 24 steps from reset:"
yosys-smtbmc -s z3 --presat -t 24 "$smt" > "$work/bmc.log" 2>&1 || { cat "$work/bmc.log"; exit 1; }
tail -1 "$work/bmc.log"
echo "temporal induction, depth 24:"
yosys-smtbmc -s z3 -i -t 24 "$smt" > "$work/ind.log" 2>&1 || { cat "$work/ind.log"; exit 1; }
tail -1 "$work/ind.log"
