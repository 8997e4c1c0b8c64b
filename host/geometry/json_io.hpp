// SPDX-License-Identifier: Apache-2.0
// Curve files (the shared butterfly format):
//   { "name": str, "units": str, "degree": int, "rational": bool,
//     "control_points": [[x, y, ...], ...], "weights": [...] (required if rational), "knots": [...] }
// Every check names the file and the field, e.g.
//   butterfly.json: knots[12]: 0.3 < previous 0.4 (knot vector must be non-decreasing)
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "geometry/bspline.hpp"

namespace traj::geo {

// Reads and parses a JSON file. Every failure is one GeometryError naming the file and the place:
//   cannot open          "<name>: cannot open file"
//   syntax error, or a   "<name>:<line>:<column>: <field path>: <problem>", e.g.
//   number outside the     path.json:14:9: knots[12]: number overflow parsing '1e999' (beyond the double range)
//   double range (1e999)   path.json:40:1: control_points[50]: syntax error while parsing value - unexpected end of input; ...
// <line>:<column> (1-based; the column counts bytes) comes from the parser's byte offset: the first
// character of an overflowing number; for a syntax error the character at which the parser stopped
// (the unexpected character, the last character of an unexpected token, or the file's last character
// when the input ends too early). <field path> is the member or element
// being read (or expected next) when the parser stopped: object keys joined by '.', array indices in
// brackets ("curves[2].knots[5]"); it is left out at the top level and between an object's members. Any other nlohmann exception raised while reading (none is expected) becomes a
// GeometryError with the name and the field path too. `name` is the file's name in messages (default:
// `path` as given).
nlohmann::json load_json_file(const std::string& path, const std::string& name = {});
// The same for text already read: errors "<name>:<line>:<column>: <field path>: <problem>", lines
// counted from `first_line` (a JSON Lines reader passes the line's number in its file).
nlohmann::json parse_json_text(const std::string& text, const std::string& name, std::size_t first_line = 1);

// Reads and checks a curve file; throws GeometryError("<file name>: <field>: <problem>") (JSON errors
// from load_json_file: "<file name>:<line>:<column>: <field>: <problem>").
BSpline load_curve(const std::string& path);
// Same from an already parsed document; `where` names the source in messages. Every message names
// the field ("<where>: knots[5]: expected a number, got string"); an nlohmann exception raised while
// reading a field (none is expected: types are checked first) becomes a GeometryError naming it too.
BSpline parse_curve(const nlohmann::json& doc, const std::string& where);
// Writes a curve in the same format.
nlohmann::json to_json(const BSpline& c, const std::string& units = "mm");

}  // namespace traj::geo
