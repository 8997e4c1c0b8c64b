#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A user trial on drawings trajcore's tests did not write: public SVG icon sets
# from npm, every icon through `trajcore plan` at the defaults, one at a time.
# Prints per set the icons planned, the ones refused (with the first line of
# their message) and the time; exits 1 if any icon is refused. Not part of the
# test suite: it downloads (npm must be reachable) and takes minutes.
#
#   usage: scripts/trial_svg_icons.sh [SET ...]
#   sets:  simple-icons (simple-icons@13.0.0, 3150 logos, CC0),
#          bootstrap (bootstrap-icons@1.13.2, 2078 icons, MIT),
#          tabler (@tabler/icons@3.52.0, 5491 outline + 1054 filled icons, MIT),
#          fontawesome (@fortawesome/fontawesome-free@7.3.1, 2883 solid, regular
#          and brand icons, CC BY 4.0), mdi (@mdi/svg@7.4.47, 7447 Material
#          Design icons, Apache-2.0), octicons (@primer/octicons@19.42.0, 784
#          icons, MIT); default: all six
#   env:   TRAJ_BUILD_DIR (default build/), TRIAL_DIR (downloads and results,
#          default a temporary folder, removed at the end)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
trajcore=${TRAJ_BUILD_DIR:-$root/build}/host/app/trajcore
[ -x "$trajcore" ] || { echo "trial_svg_icons.sh: no $trajcore (scripts/build.sh first)" >&2; exit 1; }
command -v npm > /dev/null || { echo "trial_svg_icons.sh: npm is needed to fetch the icon sets" >&2; exit 1; }
work=${TRIAL_DIR:-$(mktemp -d)}
[ -n "${TRIAL_DIR:-}" ] || trap 'rm -rf "$work"' EXIT
mkdir -p "$work"

# package@version and the folders of its icons inside the package
declare -A pkg=([simple-icons]="simple-icons@13.0.0" [bootstrap]="bootstrap-icons@1.13.2"
                [tabler]="@tabler/icons@3.52.0" [fontawesome]="@fortawesome/fontawesome-free@7.3.1"
                [mdi]="@mdi/svg@7.4.47" [octicons]="@primer/octicons@19.42.0")
declare -A dirs=([simple-icons]="icons" [bootstrap]="icons" [tabler]="icons/outline icons/filled"
                 [fontawesome]="svgs/solid svgs/regular svgs/brands" [mdi]="svg" [octicons]="build/svg")
sets="simple-icons bootstrap tabler fontawesome mdi octicons"

status=0
for set in "${@:-$sets}"; do
  for s in $set; do
    [ -n "${pkg[$s]:-}" ] || { echo "trial_svg_icons.sh: unknown set '$s' ($sets)" >&2; exit 1; }
    dest="$work/$s"
    mkdir -p "$dest"
    (cd "$dest" && npm pack --silent "${pkg[$s]}" > pack.txt && tar xzf "$(tail -n 1 pack.txt)")
    list="$dest/files.txt"
    : > "$list"
    for d in ${dirs[$s]}; do ls "$dest/package/$d"/*.svg >> "$list"; done
    refused="$dest/refused.txt"
    : > "$refused"
    start=$(date +%s.%N)
    while read -r f; do
      if ! out=$("$trajcore" plan "$f" -o "$dest/out.trj" 2>&1); then
        printf '%s: %s\n' "$(basename "$f")" "$(printf '%s\n' "$out" | grep -m1 'error' || printf '%s\n' "$out" | tail -n 1)" >> "$refused"
      fi
    done < "$list"
    rm -f "$dest/out.trj"
    secs=$(echo "$(date +%s.%N) - $start" | bc)
    n=$(wc -l < "$list")
    bad=$(wc -l < "$refused")
    printf '%-13s %-24s %5d icons, %5d planned, %d refused, %.0f s\n' "$s" "${pkg[$s]}" "$n" $((n - bad)) "$bad" "$secs"
    if [ "$bad" -gt 0 ]; then
      head -n 20 "$refused" | sed 's/^/    /'
      status=1
    fi
  done
done
exit $status
