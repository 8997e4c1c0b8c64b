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

// Reads and checks a curve file; throws GeometryError("<file name>: <field>: <problem>").
BSpline load_curve(const std::string& path);
// Same from an already parsed document; `where` names the source in messages.
BSpline parse_curve(const nlohmann::json& doc, const std::string& where);
// Writes a curve in the same format.
nlohmann::json to_json(const BSpline& c, const std::string& units = "mm");

}  // namespace traj::geo
