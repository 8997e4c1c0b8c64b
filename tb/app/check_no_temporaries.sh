#!/usr/bin/env bash
# No output is promised on error, and none is left, not even a temporary:
#   plan -o <an existing directory>, plan -o '', sim --csv <a directory>: refused, no "<name>.<pid>.tmp";
#   a JSON Lines plan stopped by SIGINT or SIGTERM while writing: its o.trj.<pid>.tmp is removed
#   (it is checked to exist before the signal); SIGKILL cannot be caught and is not tested;
#   run whose staging folder cannot be made (a path at PATH_MAX): the output folders it made are removed.
# usage: check_no_temporaries.sh <trajcore> <make_raster_jsonl> <work dir>
set -u
T=$1 RASTER=$2 W=$3
rm -rf "$W" && mkdir -p "$W" && cd "$W" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
printf '{"degree": 1, "knots": [0, 0, 1, 1], "control_points": [[0, 0], [10, 0]]}\n' > line.json

mkdir adir
! "$T" plan line.json -o adir 2> err1.txt || fail "plan -o <dir> succeeded"
grep -q 'adir: it is a directory' err1.txt || fail "plan -o <dir>: $(cat err1.txt)"
! "$T" plan line.json -o '' 2> err2.txt || fail "plan -o '' succeeded"
grep -q 'no output file given' err2.txt || fail "plan -o '': $(cat err2.txt)"
"$T" plan line.json -o line.trj > /dev/null 2>&1 || fail "plan line.json"
! "$T" sim line.trj --csv adir 2> err3.txt || fail "sim --csv <dir> succeeded"
grep -q 'adir: it is a directory' err3.txt || fail "sim --csv <dir>: $(cat err3.txt)"
test -z "$(find . -name '*.tmp')" || fail "temporaries left: $(find . -name '*.tmp')"

"$RASTER" 100000 big.jsonl > /dev/null || fail "make_raster_jsonl"
for sig in INT TERM; do
  rm -f o.trj o.trj.*.tmp
  "$T" plan big.jsonl --window 8 -o o.trj > /dev/null 2>&1 &
  pid=$!
  tmp=o.trj.$pid.tmp
  for _ in $(seq 100); do test -e "$tmp" && break; sleep 0.05; done
  test -e "$tmp" || fail "SIG$sig: no $tmp while planning"
  sleep 0.3
  kill -s "$sig" "$pid"
  wait "$pid"
  rc=$?
  test "$rc" -ne 0 || fail "SIG$sig: exit 0"
  test ! -e "$tmp" || fail "SIG$sig: $tmp left"
  test ! -e o.trj || fail "SIG$sig: o.trj written"
done

# Two plans of different paths into one output at once: each writes its own
# temporary, both succeed, and the file left is one of the two streams whole.
"$RASTER" 300 r1.jsonl > /dev/null && "$RASTER" 301 r2.jsonl > /dev/null || fail "make_raster_jsonl"
"$T" plan r1.jsonl -o a.trj > /dev/null 2>&1 && "$T" plan r2.jsonl -o b.trj > /dev/null 2>&1 || fail "plan a, b"
for _ in $(seq 3); do
  "$T" plan r1.jsonl -o both.trj > /dev/null 2> err5a.txt & p1=$!
  "$T" plan r2.jsonl -o both.trj > /dev/null 2> err5b.txt & p2=$!
  wait $p1 || fail "concurrent plan 1: $(cat err5a.txt)"
  wait $p2 || fail "concurrent plan 2: $(cat err5b.txt)"
  cmp -s both.trj a.trj || cmp -s both.trj b.trj || fail "concurrent plans left a stream that is neither"
done
test -z "$(find . -name '*.tmp')" || fail "temporaries left: $(find . -name '*.tmp')"

c=$(printf 'd%.0s' $(seq 254))
d=$c
for _ in $(seq 15); do d=$d/$c; done  # 4079 characters: the staging folder inside it is beyond PATH_MAX
! "$T" run line.json --out-dir "$d" > /dev/null 2> err4.txt || fail "run into $d succeeded"
test ! -e "$c" || fail "run left the folders it made"
echo "no temporaries left"
