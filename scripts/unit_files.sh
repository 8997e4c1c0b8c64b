#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Prints the RTL files of one unit (absolute paths, elaboration order) from the
# unit table rtl/units.txt; exits non-zero for a unit the table does not name.
#   usage: scripts/unit_files.sh UNIT
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
unit=${1:?usage: unit_files.sh UNIT}
files=$(awk -v u="$unit" -v d="$root/rtl" '$1 == u { for (i = 2; i <= NF; i++) printf "%s/%s ", d, $i }' \
        "$root/rtl/units.txt")
if [ -z "$files" ]; then
  echo "unit_files.sh: no unit '$unit' in $root/rtl/units.txt (units: $(awk '!/^#/ && NF {printf "%s ", $1}' "$root/rtl/units.txt"))" >&2
  exit 1
fi
echo "$files"
