#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Install, idempotently, every Debian package trajcore needs.
# Safe to run repeatedly; skips apt entirely when everything is already present.
set -euo pipefail

PKGS=(
  build-essential cmake ninja-build pkg-config
  verilator iverilog yosys nextpnr-ice40 fpga-icestorm z3
  libeigen3-dev libgtest-dev libgmock-dev
  libcli11-dev nlohmann-json3-dev libgmp-dev zlib1g-dev
  valgrind
  libtinyxml2-dev libdxflib-dev
  libserialport-dev  # serial ports of the upload tool (host/link)
  libgoogle-perftools-dev  # tcmalloc, the allocator of trajcore and the benchmarks (CMakeLists.txt, TRAJ_TCMALLOC)
  socat  # a client of the upload tool's control socket (tb/simboard, README)
  linuxcnc-uspace  # rs274, LinuxCNC's interpreter: the oracle of the G-code cross-check (tb/input)
  clang libclang-rt-14-dev  # libFuzzer and the sanitizer runtimes of the fuzz targets (tb/fuzz, scripts/fuzz.sh)
)

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PKGS[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "setup: done"
