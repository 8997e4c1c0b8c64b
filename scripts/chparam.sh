#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Prints the Yosys command that overrides parameters of a top,
# "chparam -set Name Value ... TOP;" (nothing without overrides), for the
# synthesis, bitstream and formal scripts; exits non-zero, naming it, for an
# argument that is not Name=Value.
#   usage: scripts/chparam.sh TOP [Name=Value ...]
set -euo pipefail
top=${1:?usage: chparam.sh TOP [Name=Value ...]}
shift
[ $# -gt 0 ] || exit 0
sets=""
for p in "$@"; do
  [[ $p == *=* ]] || { echo "chparam.sh: parameter '$p' is not Name=Value" >&2; exit 1; }
  sets+=" -set ${p%%=*} ${p#*=}"
done
echo "chparam$sets $top;"
