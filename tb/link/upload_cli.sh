#!/usr/bin/env bash
# upload.cli.raster_pipe: `trajcore plan --raster 2000 -o - | trajcore upload -`
# against `trajcore board --loopback` on a pseudo-terminal, then on TCP with
# faults; the bytes the board played must equal the records of the same plan
# written to a file (header 64 bytes and end record 16 bytes cut off).
set -euo pipefail
T=$1
dir=$2
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir"
"$T" plan --raster 2000 -o plan.trj > plan.txt
tail -c +65 plan.trj | head -c -16 > records.bin

run() {  # run NAME BOARD-OPTIONS...
  local name=$1
  shift
  "$T" board --loopback --speed 0 --once --played "$name.played" "$@" > "$name.port" 2> "$name.board" &
  local board=$!
  for _ in $(seq 50); do [ -s "$name.port" ] && break; sleep 0.1; done
  "$T" plan --raster 2000 -o - 2> "$name.plan" | "$T" upload - --port "$(cat "$name.port")" > "$name.upload" 2> "$name.err"
  wait "$board"
  cat "$name.upload" "$name.board"
  cmp records.bin "$name.played"
  echo "$name: the board played the $(($(stat -c %s records.bin) / 232)) records of the stream, byte for byte"
}
run pty
run tcp --tcp 0 --corrupt 0.0005 --drop 0.0005 --dup-frames 0.02 --fifo 64
grep -q "faults: [1-9][0-9]* bytes corrupted, [1-9][0-9]* dropped, [1-9][0-9]* frames duplicated" tcp.board
