#!/usr/bin/env bash
# No output is promised on error, and none is left, not even a temporary:
#   plan -o <an existing directory>, plan -o '', sim --csv <a directory>: refused, no "<name>.tmp";
#   a JSON Lines plan stopped by SIGINT or SIGTERM while writing: its o.trj.tmp is removed
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
  rm -f o.trj o.trj.tmp
  "$T" plan big.jsonl --window 8 -o o.trj > /dev/null 2>&1 &
  pid=$!
  for _ in $(seq 100); do test -e o.trj.tmp && break; sleep 0.05; done
  test -e o.trj.tmp || fail "SIG$sig: no o.trj.tmp while planning"
  sleep 0.3
  kill -s "$sig" "$pid"
  wait "$pid"
  rc=$?
  test "$rc" -ne 0 || fail "SIG$sig: exit 0"
  test ! -e o.trj.tmp || fail "SIG$sig: o.trj.tmp left"
  test ! -e o.trj || fail "SIG$sig: o.trj written"
done

c=$(printf 'd%.0s' $(seq 254))
d=$c
for _ in $(seq 15); do d=$d/$c; done  # 4079 characters: the staging folder inside it is beyond PATH_MAX
! "$T" run line.json --out-dir "$d" > /dev/null 2> err4.txt || fail "run into $d succeeded"
test ! -e "$c" || fail "run left the folders it made"
echo "no temporaries left"
