#!/usr/bin/env bash
# upload_cli.sh TRAJCORE DIR pipe|interrupt|time_scale
# pipe (upload.cli.raster_pipe): `trajcore plan --raster 2000 -o - | trajcore
#   upload -` against `trajcore board --loopback` on a pseudo-terminal, then on
#   TCP with faults.
# interrupt (upload.cli.interrupt_resume): an upload to a paced board stopped by
#   SIGINT (non-zero exit, the STOP message), then `--resume` to the end.
# Either way the bytes the board played must equal the records of the same plan
# written to a file (header 64 bytes and end record 16 bytes cut off).
# time_scale (upload.cli.time_scale): a stream planned with --time-scale to the
#   loopback board (no time-scale unit): its NAK 4 to CONFIG named with the
#   values, nothing played, the control socket removed; the time-scaling
#   options refused by name.
# pauses (upload.cli.program_pauses): a G-code program with two M0 planned
#   with --pause-wait (whole and streamed; refused with --time-scale), uploaded to a
#   paced loopback board with the operator's two go-aheads on standard input:
#   both pauses named with their lines and messages, their underruns no failure, every
#   record played once; with no go-ahead left the tool stops at the pause.
set -euo pipefail
T=$1
dir=$2
mode=${3:-pipe}
assets=$(cd "$(dirname "$0")/../../host/assets" && pwd)
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir"

if [ "$mode" = pauses ]; then
  prog=$(cd "$(dirname "$0")/../input/gcode" && pwd)/tool_change_pause.ngc
  if "$T" plan "$prog" --pause-wait --time-scale 1.2 -o bad.trj > /dev/null 2> bad.txt; then
    echo "accepted: plan --pause-wait --time-scale"
    exit 1
  fi
  grep -q -- "--pause-wait with --time-scale is not supported" bad.txt && test ! -e bad.trj
  "$T" plan "$prog" --pause-wait -o plan.trj > plan.txt 2>&1
  # the records without the two pause records (type 0xFE, 16 bytes and the text's, its length at byte 2)
  records() {
    od -An -v -tu1 -w1 "$1" | LC_ALL=C awk 'NR > 64 { b[n++] = $1 } END {
      for (i = 0; i < n - 16; ) { if (b[i] == 254) { i += 16 + b[i + 2]; p++; continue } for (k = 0; k < 232; k++) printf "%c", b[i++] }
      print p > "/dev/stderr" }'
  }
  records plan.trj > records.bin 2> pauses.txt
  test "$(cat pauses.txt)" = 2 || { echo "pause records: $(cat pauses.txt)"; exit 1; }
  "$T" plan "$prog" --pause-wait --window 16 -o streamed.trj > streamed.txt 2>&1
  records streamed.trj > /dev/null 2> pauses.txt
  test "$(cat pauses.txt)" = 2 || { echo "pause records, streamed: $(cat pauses.txt)"; exit 1; }
  board=
  trap '[ -n "$board" ] && kill "$board" 2>/dev/null; true' EXIT
  "$T" board --loopback --speed 20 --once --played played.bin > port 2> board.txt &
  board=$!
  for _ in $(seq 50); do [ -s port ] && break; sleep 0.1; done
  (sleep 0.5; echo; sleep 0.5; echo) | "$T" upload plan.trj --port "$(cat port)" > up.txt 2> up.err ||
    { cat up.err; exit 1; }
  wait "$board"
  board=
  cat up.txt
  grep -q "underruns 2 (2 at program pauses)" up.txt
  # each with the program's message for it (its "(MSG, ...)" line)
  grep -q 'program pause 1 (line 12): "Change tool bit to drill size 0.8mm"; the machine holds at rest' up.err
  grep -q 'program pause 2 (line 24): "Change tool bit to cutter diameter 1.0mm"; the machine holds at rest' up.err
  cmp records.bin played.bin
  # one go-ahead only: the tool stops at the second pause, the board holding
  "$T" board --loopback --speed 20 --played played2.bin > port2 2> board2.txt &
  board=$!
  for _ in $(seq 50); do [ -s port2 ] && break; sleep 0.1; done
  if echo | "$T" upload plan.trj --port "$(cat port2)" > up2.txt 2> up2.err; then
    echo "the upload went past a pause with no go-ahead"
    exit 1
  fi
  grep -q "program pause 2 (line 24): input ended before the operator's go-ahead; the board holds at rest" up2.err
  echo "pauses: both pauses held and confirmed, the board played the $(($(stat -c %s records.bin) / 232)) records"
  exit 0
fi
if [ "$mode" = time_scale ]; then
  "$T" plan "$assets/butterfly_nurbs.json" --time-scale 1.2 --period 3.125e-5 -o ts.trj > ts.txt 2>&1
  "$T" plan --raster 5 -o plain.trj > plain.txt 2>&1
  board=
  trap '[ -n "$board" ] && kill "$board" 2>/dev/null; true' EXIT
  "$T" board --loopback --speed 0 > ts.port 2> ts.board &
  board=$!
  for _ in $(seq 50); do [ -s ts.port ] && break; sleep 0.1; done
  refused() {  # refused WHAT-IT-SAYS UPLOAD-ARGS...: non-zero exit, the message on stderr
    local says=$1
    shift
    if "$T" upload "$@" --port "$(cat ts.port)" > out.txt 2> err.txt; then
      echo "accepted: upload $*"
      exit 1
    fi
    grep -v '^\[upload' err.txt
    grep -qF -- "$says" err.txt || { echo "upload $*: the message does not say: $says"; exit 1; }
  }
  refused "S_max 9830, override 6554, shift 24" ts.trj --feed 80 \
    --control ts.sock
  grep -qF "refuses CONFIG as bad content: time scaling m " err.txt
  grep -qF "A build without the time-scale unit" err.txt
  test ! -e ts.sock || { echo "the control socket was not removed"; exit 1; }
  refused "--feed 200 %: the stream was planned for 0 .. 119.995 %" ts.trj --feed 200
  refused "--servo-period 0.0007 s is not the engine tick" ts.trj --servo-period 0.0007
  for opt in "--feed 80" "--servo-period 0.001" --no-auto-resume "--control plain.sock"; do
    refused "the stream was planned without --time-scale" plain.trj $opt
    grep -qF -- "${opt%% *}" err.txt
  done
  test ! -e plain.sock
  kill -INT "$board"
  wait "$board" || true
  board=
  grep -q "^board: 0 segments played" ts.board
  echo "time_scale: the board without the unit refused the time-scaled job by name; the options were refused"
  exit 0
fi
"$T" plan --raster 2000 -o plan.trj > plan.txt
tail -c +65 plan.trj | head -c -16 > records.bin

board=
trap '[ -n "$board" ] && kill "$board" 2>/dev/null; true' EXIT
run() {  # run NAME BOARD-OPTIONS...
  local name=$1
  shift
  "$T" board --loopback --speed 0 --once --played "$name.played" "$@" > "$name.port" 2> "$name.board" &
  board=$!
  for _ in $(seq 50); do [ -s "$name.port" ] && break; sleep 0.1; done
  "$T" plan --raster 2000 -o - 2> "$name.plan" | "$T" upload - --port "$(cat "$name.port")" > "$name.upload" 2> "$name.err" ||
    { cat "$name.plan" "$name.err"; exit 1; }
  wait "$board"
  board=
  cat "$name.upload" "$name.board"
  cmp records.bin "$name.played"
  echo "$name: the board played the $(($(stat -c %s records.bin) / 232)) records of the stream, byte for byte"
}

if [ "$mode" = pipe ]; then
  run pty
  run tcp --tcp 0 --corrupt 0.0005 --drop 0.0005 --dup-frames 0.02 --fifo 64
  grep -q "faults: [1-9][0-9]* bytes corrupted, [1-9][0-9]* dropped, [1-9][0-9]* frames duplicated" tcp.board
  exit 0
fi

# interrupt: a 300-piece raster, 113 s of motion at 100 x real time: 1.1 s
"$T" plan --raster 300 -o plan.trj > plan.txt
tail -c +65 plan.trj | head -c -16 > records.bin
"$T" board --loopback --speed 100 --once --played int.played > int.port 2> int.board &
board=$!
for _ in $(seq 50); do [ -s int.port ] && break; sleep 0.1; done
"$T" upload plan.trj --port "$(cat int.port)" > int.upload 2> int.err &
tool=$!
sleep 0.5
kill -INT "$tool"
rc=0
wait "$tool" || rc=$?
grep -v '^\[upload' int.err
[ "$rc" -ne 0 ] || { echo "the interrupted upload exited 0"; exit 1; }
grep -q "interrupted: STOP sent and acknowledged" int.err
"$T" upload plan.trj --port "$(cat int.port)" --resume > int2.upload 2> int2.err || { cat int2.err; exit 1; }
wait "$board"
board=
cat int2.upload int.board
grep -q "(resumed at [1-9]" int2.upload
cmp records.bin int.played
echo "interrupt: the board played the $(($(stat -c %s records.bin) / 232)) records once each, across the interruption"
