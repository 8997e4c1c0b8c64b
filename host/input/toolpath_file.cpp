// SPDX-License-Identifier: Apache-2.0
#include "input/toolpath_file.hpp"

#include <algorithm>
#include <cctype>

#include "input/dxf.hpp"
#include "input/gcode.hpp"
#include "input/svg.hpp"

namespace traj::input {
namespace {

std::string lower_extension(const std::string& file) {
  const size_t dot = file.find_last_of('.');
  const size_t slash = file.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return {};
  std::string e = file.substr(dot + 1);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

}  // namespace

FileKind file_kind(const std::string& file, const std::string& format) {
  const std::string k = format.empty() ? lower_extension(file) : format;
  if (k == "json") return FileKind::kJson;
  if (k == "jsonl") return FileKind::kJsonl;
  if (k == "ngc" || k == "nc" || k == "gcode" || k == "tap" || k == "cnc") return FileKind::kGcode;
  if (k == "svg") return FileKind::kSvg;
  if (k == "dxf") return FileKind::kDxf;
  if (!format.empty()) throw InputError("--format " + format + ": expected json, jsonl, gcode, svg or dxf");
  return FileKind::kJson;  // any other name: a JSON path (its reader names what is wrong)
}

bool is_toolpath(FileKind k) { return k == FileKind::kGcode || k == FileKind::kSvg || k == FileKind::kDxf; }

std::string no_moves(const std::string& file) {
  return file + ": the program makes no move (no G0, G1, G2, G3, G5 or canned cycle): nothing to plan";
}

Toolpath read_toolpath(const std::string& file, FileKind kind, const GcodeOptions& gcode) {
  switch (kind) {
    case FileKind::kGcode: {
      Toolpath tp = read_gcode(file, gcode);
      if (tp.moves.empty()) throw InputError(no_moves(file));
      return tp;
    }
    case FileKind::kSvg: return read_svg(file);
    case FileKind::kDxf: return read_dxf(file);
    default: throw InputError(file + ": not a toolpath file (JSON paths are curves: load_path)");
  }
}

}  // namespace traj::input
