#!/usr/bin/env bash
# Formal check of rtl/traj_bcu_gen.sv's properties (the `ifdef FORMAL block):
# Yosys -> SMT2, then yosys-smtbmc with z3: bounded model check from reset
# (depth 8) and temporal induction (depth 8); the properties are 1-inductive. Exit non-zero on any failure.
#   usage: scripts/formal_bcu.sh WORKDIR Axes ChunkWidth CtrlWidth GuardBits OutWidth MaxDepth
# The model is bit-blasted (techmap; abc -g AND) before write_smt2: z3 4.8
# does not finish even step 0 on this unit's word-level model (its nested
# FSM multiplexers), and finishes the AND-gate model in seconds.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
work=$1; shift
AX=$1 CW=$2 CTRL=$3 G=$4 OUT=$5 DEP=$6
mkdir -p "$work"
smt="$work/bcu_${AX}_${CW}_${CTRL}_${G}_${OUT}_${DEP}.smt2"
yosys -q -p "read_verilog -sv -formal -I$root/rtl $root/rtl/traj_bcu.sv $root/rtl/traj_bcu_gen.sv; \
  chparam -set Axes $AX -set ChunkWidth $CW -set CtrlWidth $CTRL -set GuardBits $G -set OutWidth $OUT \
    -set MaxDepth $DEP traj_bcu_gen; \
  prep -top traj_bcu_gen; memory_map; opt -fast; techmap; opt -fast; abc -g AND; opt_clean; async2sync; dffunmap; write_smt2 -wires $smt" 2>&1 | grep -v "Replacing memory" || true
test -s "$smt"
echo "bounded model check, 8 steps from reset:"
yosys-smtbmc -s z3 --presat -t 8 "$smt" > "$work/bmc.log" 2>&1 || { cat "$work/bmc.log"; exit 1; }
tail -1 "$work/bmc.log"
echo "temporal induction, depth 8:"
yosys-smtbmc -s z3 -i -t 8 "$smt" > "$work/ind.log" 2>&1 || { cat "$work/ind.log"; exit 1; }
tail -1 "$work/ind.log"
