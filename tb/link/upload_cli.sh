#!/usr/bin/env bash
# upload_cli.sh TRAJCORE DIR pipe|interrupt
# pipe (upload.cli.raster_pipe): `trajcore plan --raster 2000 -o - | trajcore
#   upload -` against `trajcore board --loopback` on a pseudo-terminal, then on
#   TCP with faults.
# interrupt (upload.cli.interrupt_resume): an upload to a paced board stopped by
#   SIGINT (non-zero exit, the STOP message), then `--resume` to the end.
# Either way the bytes the board played must equal the records of the same plan
# written to a file (header 64 bytes and end record 16 bytes cut off).
set -euo pipefail
T=$1
dir=$2
mode=${3:-pipe}
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir"
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
