#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Formal check of a unit's properties (its `ifdef FORMAL block): Yosys -> SMT2,
# then yosys-smtbmc with z3: bounded model check from reset (DEPTH steps) and
# temporal induction (depth DEPTH). Exit non-zero on any failure.
#   usage: scripts/formal.sh UNIT WORKDIR [Param=Value ...]
#     e.g. scripts/formal.sh traj_fd_engine /tmp/f Axes=3 Degree=3 Width=64 ChunkWidth=16 GuardBits=32
#   env: DEPTH (24; 8 for traj_bcu_gen, whose properties are 1-inductive)
# traj_link_proto is checked to a bound, not for all time: BMC 160 steps
# from reset with ABC's bmc3 on the AIGER model (about a minute; z3 on the
# SMT2 model took 9-13 minutes for 80), and a cover run that must reach each
# of its covers within the bound (a FIFO commit, a whole good SEGMENT frame,
# in step 70 at the test's parameters, and a second one in step 136), so the
# bound covers two complete frames; its induction does not close
# (rtl/README.md). ENGINE=smtbmc runs the BMC with yosys-smtbmc and z3
# instead: it names a failing assertion's line and writes WORKDIR/trace.vcd.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
[ $# -ge 2 ] || { sed -n '5,7p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 1; }
unit=$1 work=$2; shift 2
# traj_bcu_gen is bit-blasted (techmap; abc -g AND) before write_smt2: z3 4.8
# does not finish even step 0 on its word-level model (nested FSM
# multiplexers), and proves the AND-gate model in seconds.
blast=""
case $unit in
  traj_bcu_gen) blast="memory_map; opt -fast; techmap; opt -fast; abc -g AND; opt_clean;"; DEPTH=${DEPTH:-8} ;;
  # traj_seg_fifo: the word-level model takes z3 about 10 minutes for 10 BMC
  # steps (pointer arithmetic modulo the slot count); bit-blasted, seconds.
  traj_seg_fifo) blast="memory_map; opt -fast; techmap; opt -fast; abc -g AND; opt_clean;" ;;
  # traj_fd_tm: z3 does not finish step 0 on the word-level model either
  traj_fd_tm) blast="memory_map; opt -fast; techmap; opt -fast; abc -g AND; opt_clean;"; DEPTH=${DEPTH:-16} ;;
  # traj_time_scale: the S-curve's comparisons and the product's datapath
  traj_time_scale) blast="memory_map; opt -fast; techmap; opt -fast; abc -g AND; opt_clean;"; DEPTH=${DEPTH:-12} ;;
  # traj_status_count: its RAM as flops, so the properties can name its words
  traj_status_count) blast="memory_map; opt -fast; techmap; opt -fast; abc -g AND; opt_clean;" ;;
  traj_link_proto) blast="memory_map; opt -fast; techmap; opt -fast; abc -g AND; opt_clean;"; DEPTH=${DEPTH:-160}
                   bounded=1 ;;
esac
DEPTH=${DEPTH:-24}
files=$("$root/scripts/unit_files.sh" "$unit")
chparam=$("$root/scripts/chparam.sh" "$unit" "$@")
tag=""
for p in "$@"; do tag+="_${p#*=}"; done
mkdir -p "$work"

# The AIGER model for ABC: outputs made internal (only the properties
# remain), assumptions as constraints, `select` choosing the properties:
# the asserts, or the covers as asserts of their negation.
write_aig() {
  local out=$1 select=$2
  yosys -q -p "read_verilog -sv -formal -I$root/rtl $files; $chparam \
    prep -top $unit; flatten; $select setattr -unset keep; delete -output; memory_map; opt -fast; \
    async2sync; chformal -assume -early; setundef -undriven -anyseq; opt -keepdc -fast; techmap; opt -fast; \
    dffunmap; abc -g AND -fast; opt_clean; write_aiger -zinit $out" 2>&1 | grep -v "Replacing memory" || true
  test -s "$out"
}
# The SMT2 model for yosys-smtbmc (bit-blasted where `blast` says).
write_smt() {
  yosys -q -p "read_verilog -sv -formal -I$root/rtl $files; $chparam \
    prep -top $unit; $blast async2sync; dffunmap; write_smt2 -wires $1" 2>&1 | grep -v "Replacing memory" || true
  test -s "$1"
}
# ABC's bmc3 to DEPTH frames on an AIGER model, every property (-a: on
# after the first fails); the log names each failing one's frame.
bmc3() {
  yosys-abc -c "read_aiger $1; fold; strash; bmc3 -a -F $DEPTH; print_status" > "$2" 2>&1
}

if [ -n "${bounded:-}" ]; then
  if [ "${ENGINE:-abc}" = smtbmc ]; then
    smt="$work/$unit$tag.smt2"
    write_smt "$smt"
    echo "bounded model check, $DEPTH steps from reset (yosys-smtbmc, z3):"
    yosys-smtbmc -s z3 --presat -t "$DEPTH" --dump-vcd "$work/trace.vcd" "$smt" > "$work/bmc.log" 2>&1 ||
      { cat "$work/bmc.log"; exit 1; }
    tail -1 "$work/bmc.log"
  else
    echo "bounded model check, $DEPTH steps from reset (ABC bmc3):"
    write_aig "$work/$unit$tag.aig" "chformal -remove -cover;"
    bmc3 "$work/$unit$tag.aig" "$work/bmc.log"
    if ! grep -q "No output asserted in $DEPTH frames" "$work/bmc.log"; then
      grep "was asserted" "$work/bmc.log" || cat "$work/bmc.log"
      echo "an assertion fails (ENGINE=smtbmc DEPTH=N $0 $unit $work $* names it and writes a trace)"
      exit 1
    fi
    echo "PASSED: no assertion fails in $DEPTH steps"
  fi
  echo "cover (each cover reachable within $DEPTH steps):"
  write_aig "$work/$unit${tag}_cover.aig" "chformal -remove -assert; techmap -map $root/scripts/formal_cover_as_assert.v t:\$cover;"
  bmc3 "$work/$unit${tag}_cover.aig" "$work/cover.log"
  sed -n 's/.*Output \([0-9]*\).* was asserted in frame \([0-9]*\).*/cover \1 reached in step \2/p' "$work/cover.log"
  grep -q "All [0-9]* outputs are found to be SAT" "$work/cover.log" ||
    { cat "$work/cover.log"; echo "a cover is not reached within $DEPTH steps: the bound is vacuous for it"; exit 1; }
  exit 0
fi

smt="$work/$unit$tag.smt2"
write_smt "$smt"
echo "bounded model check, $DEPTH steps from reset:"
yosys-smtbmc -s z3 --presat -t "$DEPTH" "$smt" > "$work/bmc.log" 2>&1 || { cat "$work/bmc.log"; exit 1; }
tail -1 "$work/bmc.log"
echo "temporal induction, depth $DEPTH:"
yosys-smtbmc -s z3 -i -t "$DEPTH" "$smt" > "$work/ind.log" 2>&1 || { cat "$work/ind.log"; exit 1; }
tail -1 "$work/ind.log"
