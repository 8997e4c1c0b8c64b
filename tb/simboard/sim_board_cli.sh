#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# sim_board_cli.sh TRAJCORE DIR clean|faults|restart|reset|coarse|timescale
# `trajcore plan` -> `trajcore upload` -> `trajcore board` (the simulated
# board: rtl/traj_board.sv Verilated, pins driven and decoded), on a
# pseudo-terminal as a user runs them, with a short raster (2 pieces, 0.77 s of
# motion at 1 ms ticks):
#   clean:  the decoded step/dir pins equal the stream's exact prediction;
#   faults: the same through corrupted, dropped and duplicated bytes/frames;
#   restart: the tool is killed (SIGKILL) during the upload and started
#           again with --resume: still identical (no segment lost or twice);
#   reset:  the board is reset mid-job: the upload stops with a message naming
#           it and exits non-zero; the board reports no jump (it holds still);
#   coarse: planned at 2 ms ticks: the tool plays it at 2 engine ticks of 1 ms
#           (the segments re-compiled), and the pins equal the prediction of
#           the re-compiled stream, twice as many ticks.
#   timescale: a G1 zigzag planned with --time-scale 1.2 at a 125 us engine
#           tick, uploaded 20 segments ahead; the board overrides to 120 %
#           (FEED), holds by its pin and pauses the link at given times, the tool sets 50 % and holds and
#           resumes through its control socket; the board's check: the pins
#           equal the path through its re-timed output, which lies on the
#           stream's exact prediction and ends on its last sample, and a
#           starved hold happened and resumed.
#   pauses: a G-code program with two M0 planned with --pause-wait: the
#           board plays up to each pause and holds there at rest until the
#           operator's go-ahead (a line on the tool's standard input), then
#           goes on: the pins equal the prediction, the step edges as soon
#           after their crossings as without pauses (each sample timed by
#           the tick it answered, the pause's underrun tick none).
set -euo pipefail
T=$1
dir=$2
mode=${3:-clean}
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir"
period=0.001
[ "$mode" = coarse ] && period=0.002
if [ "$mode" = timescale ]; then
  printf 'G21 G90 G64 P0.01 F3000\nG1 X0 Y0\nG1 X20 Y5\nG1 X5 Y15\nG1 X30 Y20\nG1 X10 Y35\nG1 X40 Y40\nG1 X0 Y45\nG1 X25 Y60\nM2\n' \
    > zigzag.ngc
  "$T" plan zigzag.ngc --period 1.25e-4 --engine-width 96 --time-scale 1.2 -o plan.trj > plan.txt
elif [ "$mode" = pauses ]; then
  printf 'G21 G90\nG1 X2 F1200\nM0 (change the bit)\nG1 X2 Y2\nG1 X0 Y0\nM0\nG1 X-1\nM2\n' > pauses.ngc
  "$T" plan pauses.ngc --pause-wait --engine-width 96 -o plan.trj > plan.txt
else
  "$T" plan --raster 2 --period $period -o plan.trj > plan.txt
fi

board=
trap '[ -n "$board" ] && kill "$board" 2>/dev/null; true' EXIT
start_board() {  # start_board OPTIONS...
  "$T" board --expect plan.trj "$@" > port 2> board.txt &
  board=$!
  for _ in $(seq 100); do [ -s port ] && break; sleep 0.1; done
}
# the tick period in clocks of the clock the board reports in STATUS (the
# restart case gives --clock-hz, which is checked against it)
upload() {
  "$T" upload plan.trj --port "$(cat port)" --step-shift 26 --timeout-ms 3000 "$@" > upload.txt 2> upload.err
}

case "$mode" in
clean | faults | restart | coarse)
  case "$mode" in
  clean | restart | coarse) start_board --once ;;
  faults) start_board --once --corrupt 0.001 --drop 0.001 --dup-frames 0.05 --seed 3 ;;
  esac
  if [ "$mode" = restart ]; then
    # the tool itself in the background (a function would fork a shell, and
    # SIGKILL would leave the tool running)
    "$T" upload plan.trj --port "$(cat port)" --clock-hz 30e6 --step-shift 26 --timeout-ms 3000 > upload.txt \
      2> upload.err &
    tool=$!
    sleep 0.4
    kill -KILL "$tool"
    wait "$tool" 2> /dev/null && { echo "the first upload ended before it was killed"; exit 1; }
    grep -v '^\[upload' upload.err || true
    upload --resume || { cat upload.err board.txt; exit 1; }
  else
    upload || { cat upload.err board.txt; exit 1; }
  fi
  rc=0
  wait "$board" || rc=$?
  board=
  cat upload.txt board.txt
  [ "$rc" -eq 0 ] || { echo "the board's check failed (exit $rc)"; exit 1; }
  ticks=$(sed -n 's/.* \([0-9]*\) ticks (.*/\1/p' plan.txt)
  if [ "$mode" = coarse ]; then
    grep -q "stream tick 2 ms played at 2 engine ticks per tick (1 ms)" upload.err
    grep -q "played at 2 engine ticks of 1 ms" board.txt
    ticks=$((2 * ticks))
  fi
  grep -q "pins decoded against the exact prediction of $ticks ticks .*: identical" board.txt
  if [ "$mode" = faults ]; then
    grep -q "faults: [1-9][0-9]* bytes corrupted, [1-9][0-9]* dropped, [1-9][0-9]* frames duplicated" board.txt
  fi
  ;;
timescale)
  start_board --once --feed 0.1:120 --hold 0.3:0.4 --starve 0.8:1.5
  # --ahead 20: about 0.7 s of motion stored ahead (the FIFO would take the
  # whole job), so that the link's pause empties it
  "$T" upload plan.trj --port "$(cat port)" --step-shift 26 --timeout-ms 3000 --retries 1000 --ahead 20 \
    --control "$PWD/feed.sock" > upload.txt 2> upload.err &
  tool=$!
  ask() { echo "$1" | socat -t 20 - UNIX-CONNECT:feed.sock; }  # one command, its answer
  for _ in $(seq 100); do [ -S feed.sock ] && break; sleep 0.1; done
  # at the start of the job, before the link pauses
  for c in "feed 50" hold resume "feed 250" status; do ask "$c" | tee -a answers.txt; done
  rc=0
  wait "$tool" || rc=$?
  [ "$rc" -eq 0 ] || { cat upload.err board.txt; exit 1; }
  wait "$board" || rc=$?
  board=
  cat upload.txt board.txt answers.txt
  [ "$rc" -eq 0 ] || { echo "the board's check failed (exit $rc)"; exit 1; }
  grep -q "^ok feed 50.00 %" answers.txt
  grep -q "^ok hold" answers.txt
  grep -q "^ok resume" answers.txt
  grep -q "^error: feed 250 %" answers.txt
  grep -q "^ok feed .*(target 50.00 %), hold off" answers.txt
  grep -q "FEED 120 %" board.txt
  grep -q "hold pin pressed" board.txt
  grep -q "link paused" board.txt
  grep -q "time scaling: S [0-9]* at the end, [1-9][0-9]* starved holds" board.txt
  grep -q "pins decoded against the board's time-scaled output samples .*: identical" board.txt
  grep -q "on the path of the exact prediction (re-timed): yes: .* ending on the last sample" board.txt
  ;;
pauses)
  start_board --once
  (sleep 1; echo; sleep 1; echo) | upload || { cat upload.err board.txt; exit 1; }
  rc=0
  wait "$board" || rc=$?
  board=
  cat upload.txt board.txt
  [ "$rc" -eq 0 ] || { echo "the board's check failed (exit $rc)"; exit 1; }
  grep -q "underruns 2 (2 at program pauses)" upload.txt
  grep -q "program pause 1 (line 3): the machine holds at rest" upload.err
  grep -q "program pause 2 (line 6): the machine holds at rest" upload.err
  ticks=$(sed -n 's/.* \([0-9]*\) ticks (.*/\1/p' plan.txt)
  grep -q "pins decoded against the exact prediction of $ticks ticks ($ticks samples seen): identical" board.txt
  # every edge within 20 us of its crossing (a sample timed by the wrong tick is 1 ms or a pause late)
  ! grep "edge after its path crossing" board.txt | grep -qv "\.\. [0-9]\.[0-9]* us\|\.\. 1[0-9]\.[0-9]* us"
  ;;
reset)
  start_board --reset-after 10
  rc=0
  upload || rc=$?
  kill -TERM "$board"
  wait "$board" || true
  board=
  cat upload.err board.txt
  [ "$rc" -ne 0 ] || { echo "the upload went on through a board reset"; exit 1; }
  grep -q "the board was reset mid-job" upload.err
  grep -q "1 board resets" board.txt
  ;;
esac
