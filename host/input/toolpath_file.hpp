// SPDX-License-Identifier: Apache-2.0
// Reads a toolpath file by its kind: G-code (.ngc .nc .gcode .tap .cnc),
// SVG (.svg) or DXF (.dxf). JSON and JSON Lines paths are curves without
// moves (path_json.hpp, jsonl_source.hpp).
#pragma once
#include <string>

#include "input/gcode.hpp"
#include "input/toolpath.hpp"

namespace traj::input {

enum class FileKind { kJson, kJsonl, kGcode, kSvg, kDxf };

// The kind of `file` by `format` ("json", "jsonl", "gcode", "svg", "dxf") or,
// if `format` is empty, by the name's ending (JSON for any other ending);
// InputError for an unknown `format`.
FileKind file_kind(const std::string& file, const std::string& format = {});
bool is_toolpath(FileKind k);

// read_gcode (with `gcode`), read_svg or read_dxf by kind (InputError for JSON kinds, and for a
// G-code program that makes no move: no_moves).
Toolpath read_toolpath(const std::string& file, FileKind kind, const GcodeOptions& gcode = {});
std::string no_moves(const std::string& file);

}  // namespace traj::input
