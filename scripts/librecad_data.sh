# SPDX-License-Identifier: Apache-2.0
# Sourced by the trial scripts: LibreCAD's parts library (Debian's
# librecad-data), downloaded with apt (not installed) into $1 and unpacked
# there; writes the sorted list of its DXF files to $2 and prints the
# package's name and the count.
librecad_dxf_list() {
  local work=$1 list=$2 deb
  (cd "$work" && ls librecad-data_*.deb > /dev/null 2>&1 || apt-get download librecad-data > /dev/null 2>&1) ||
    { echo "$(basename "$0"): apt-get download librecad-data failed (no network or no Debian sources?)" >&2; return 1; }
  deb=$(ls "$work"/librecad-data_*.deb | head -n 1)
  dpkg-deb -x "$deb" "$work/x"
  find "$work/x" -iname '*.dxf' | sort > "$list"
  echo "$(basename "$deb"): $(wc -l < "$list") DXF files"
}
