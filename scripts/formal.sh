#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Formal check of a unit's properties (its `ifdef FORMAL block): Yosys -> SMT2,
# then yosys-smtbmc with z3: bounded model check from reset (DEPTH steps) and
# temporal induction (depth DEPTH). Exit non-zero on any failure.
#   usage: scripts/formal.sh UNIT WORKDIR [Param=Value ...]
#     e.g. scripts/formal.sh traj_fd_engine /tmp/f Axes=3 Degree=3 Width=64 ChunkWidth=16 GuardBits=32
#   env: DEPTH (24; 8 for traj_bcu_gen, whose properties are 1-inductive)
# traj_link_proto is checked to a bound, not for all time: BMC 80 steps from
# reset, and a cover run that must reach a FIFO commit (a whole good SEGMENT
# frame, step 70 at the test's parameters) within the bound, so the bound
# covers complete frames; its induction does not close (rtl/README.md).
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
  traj_link_proto) blast="memory_map; opt -fast; techmap; opt -fast; abc -g AND; opt_clean;"; DEPTH=${DEPTH:-80}
                   bounded=1 ;;
esac
DEPTH=${DEPTH:-24}
files=$("$root/scripts/unit_files.sh" "$unit")
chparam=$("$root/scripts/chparam.sh" "$unit" "$@")
tag=""
for p in "$@"; do tag+="_${p#*=}"; done
mkdir -p "$work"
smt="$work/$unit$tag.smt2"
yosys -q -p "read_verilog -sv -formal -I$root/rtl $files; $chparam \
  prep -top $unit; $blast async2sync; dffunmap; write_smt2 -wires $smt" 2>&1 | grep -v "Replacing memory" || true
test -s "$smt"
echo "bounded model check, $DEPTH steps from reset:"
yosys-smtbmc -s z3 --presat -t "$DEPTH" "$smt" > "$work/bmc.log" 2>&1 || { cat "$work/bmc.log"; exit 1; }
tail -1 "$work/bmc.log"
if [ -n "${bounded:-}" ]; then
  echo "cover (a FIFO commit reachable within $DEPTH steps):"
  yosys-smtbmc -s z3 --presat -c -t "$DEPTH" "$smt" > "$work/cover.log" 2>&1 || { cat "$work/cover.log"; exit 1; }
  grep -q "Reached cover statement" "$work/cover.log" || { echo "no commit within $DEPTH steps: the bound is vacuous"; exit 1; }
  grep "Reached cover statement" "$work/cover.log" | sed 's/.*\(in step [0-9]*\).*/commit reached \1/'
  exit 0
fi
echo "temporal induction, depth $DEPTH:"
yosys-smtbmc -s z3 -i -t "$DEPTH" "$smt" > "$work/ind.log" 2>&1 || { cat "$work/ind.log"; exit 1; }
tail -1 "$work/ind.log"
