// SPDX-License-Identifier: Apache-2.0
#include "input/path_json.hpp"

#include <filesystem>

#include <nlohmann/json.hpp>

#include "geometry/json_io.hpp"

namespace traj::input {

using plan::Path;
using plan::PlanError;

namespace {
Path path_from_json(const nlohmann::json& doc, const std::string& file);
}  // namespace

Path load_path(const std::string& file) {
  if (std::filesystem::is_directory(file)) throw PlanError(file + ": is a directory, not a path file");
  // every JSON error (syntax, truncation, a number out of the double range)
  // names file:line:column and the field
  nlohmann::json doc;
  try {
    doc = geo::load_json_file(file);
  } catch (const geo::GeometryError& e) {
    throw PlanError(e.what());
  }
  return path_from_json(doc, file);
}

Path parse_path(const std::string& text, const std::string& name) {
  nlohmann::json doc;
  try {
    doc = geo::parse_json_text(text, name);
  } catch (const geo::GeometryError& e) {
    throw PlanError(e.what());
  }
  return path_from_json(doc, name);
}

namespace {
Path path_from_json(const nlohmann::json& doc, const std::string& file) {
  Path p;
  try {
    if (doc.is_object() && doc.contains("curves")) {
      if (!doc["curves"].is_array() || doc["curves"].empty())
        throw PlanError(file + ": curves: must be a non-empty array of curves");
      for (size_t i = 0; i < doc["curves"].size(); ++i) {
        const std::string where = file + ": curves[" + std::to_string(i) + "]";
        p.add(geo::parse_curve(doc["curves"][i], where), where);
      }
    } else {
      p.add(geo::parse_curve(doc, file), file);
    }
  } catch (const geo::GeometryError& e) {
    throw PlanError(e.what());
  }
  return p;
}
}  // namespace

}  // namespace traj::input
