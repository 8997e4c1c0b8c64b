#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# rtl.formal.traj_link_proto.mutants: the bounded check of traj_link_proto
# (scripts/formal.sh, ABC bmc3) can fail. On a copy of rtl/ and scripts/:
#   * an assertion made false at a store (the words a store has written,
#     SegWords + 1): the BMC must fail, in the frame of the first commit;
#   * the unchanged unit at DEPTH=100: the second cover (a second commit, in
#     step 136) must be reported unreached, the bound vacuous for it.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
cp -r "$root/rtl" "$root/scripts" "$d/"
params=(Axes=1 Degree=1 Width=16 ChunkWidth=16 GuardBits=4)
proto=$d/rtl/traj_link_proto.sv
sed -i "s/assert (f_wr == 12'(SegWords));/assert (f_wr == 12'(SegWords) + 12'd1);/" "$proto"
grep -q "12'(SegWords) + 12'd1" "$proto" || { echo "the mutation did not apply"; exit 1; }
if DEPTH=80 "$d/scripts/formal.sh" traj_link_proto "$d/w1" "${params[@]}" > "$d/out1" 2>&1; then
  cat "$d/out1"; echo "the false assertion passed"; exit 1
fi
grep -q "was asserted in frame 69" "$d/out1" || { cat "$d/out1"; echo "not failed at the first commit"; exit 1; }
cp "$root/rtl/traj_link_proto.sv" "$proto"
if DEPTH=100 "$d/scripts/formal.sh" traj_link_proto "$d/w2" "${params[@]}" > "$d/out2" 2>&1; then
  cat "$d/out2"; echo "a second commit reported within 100 steps"; exit 1
fi
grep -q "cover 0 reached in step 70" "$d/out2" && grep -q "a cover is not reached within 100 steps" "$d/out2" ||
  { cat "$d/out2"; exit 1; }
echo "mutants: the false assertion fails in frame 69, the second cover is unreached at 100 steps"
