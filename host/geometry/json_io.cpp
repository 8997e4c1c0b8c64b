#include "geometry/json_io.hpp"

#include <cmath>
#include <fstream>

#include "geometry/error.hpp"

namespace traj::geo {

namespace {
[[noreturn]] void fail(const std::string& where, const std::string& what) { throw GeometryError(where + ": " + what); }

double number(const nlohmann::json& v, const std::string& where, const std::string& field) {
  if (!v.is_number()) fail(where, field + ": expected a number, got " + std::string(v.type_name()));
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(where, field + ": not a finite number");
  return d;
}
const nlohmann::json& member(const nlohmann::json& doc, const char* key, const std::string& where) {
  auto it = doc.find(key);
  if (it == doc.end()) fail(where, std::string(key) + ": missing");
  return *it;
}
}  // namespace

BSpline parse_curve(const nlohmann::json& doc, const std::string& where) {
  if (!doc.is_object()) fail(where, "top level: expected a JSON object");
  BSpline c;
  if (auto it = doc.find("name"); it != doc.end() && it->is_string()) c.name = it->get<std::string>();
  const auto& deg = member(doc, "degree", where);
  if (!deg.is_number_integer()) fail(where, "degree: expected an integer");
  const long long p = deg.get<long long>();
  if (p < 1 || p > kMaxDegree)
    fail(where, "degree: " + std::to_string(p) + " out of range 1.." + std::to_string(kMaxDegree));
  c.degree = static_cast<int>(p);

  bool rational = false;
  if (auto it = doc.find("rational"); it != doc.end()) {
    if (!it->is_boolean()) fail(where, "rational: expected true or false");
    rational = it->get<bool>();
  }

  const auto& cps = member(doc, "control_points", where);
  if (!cps.is_array() || cps.empty()) fail(where, "control_points: expected a non-empty array of points");
  const size_t n = cps.size();
  if (!cps[0].is_array() || cps[0].empty())
    fail(where, "control_points[0]: expected an array of coordinates");
  const size_t dim = cps[0].size();
  c.ctrl.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(dim));
  for (size_t i = 0; i < n; ++i) {
    const std::string fi = "control_points[" + std::to_string(i) + "]";
    if (!cps[i].is_array()) fail(where, fi + ": expected an array of coordinates");
    if (cps[i].size() != dim)
      fail(where, fi + ": " + std::to_string(cps[i].size()) + " coordinates, control_points[0] has " +
                      std::to_string(dim) + " (inconsistent dimensions)");
    for (size_t j = 0; j < dim; ++j)
      c.ctrl(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          number(cps[i][j], where, fi + "[" + std::to_string(j) + "]");
  }

  if (auto it = doc.find("weights"); it != doc.end() && !it->is_null()) {
    if (!it->is_array()) fail(where, "weights: expected an array of numbers");
    if (it->size() != n)
      fail(where, "weights: " + std::to_string(it->size()) + " weights for " + std::to_string(n) +
                      " control points");
    Eigen::VectorXd w(static_cast<Eigen::Index>(n));
    for (size_t i = 0; i < n; ++i) w[static_cast<Eigen::Index>(i)] = number((*it)[i], where, "weights[" + std::to_string(i) + "]");
    if (rational) c.weights = w;
    else
      for (size_t i = 0; i < n; ++i)
        if (w[static_cast<Eigen::Index>(i)] != 1.0)
          fail(where, "weights[" + std::to_string(i) + "]: non-unit weight but \"rational\" is false");
  } else if (rational) {
    fail(where, "weights: missing (\"rational\" is true)");
  }

  const auto& kn = member(doc, "knots", where);
  if (!kn.is_array()) fail(where, "knots: expected an array of numbers");
  c.knots.resize(static_cast<Eigen::Index>(kn.size()));
  for (size_t i = 0; i < kn.size(); ++i)
    c.knots[static_cast<Eigen::Index>(i)] = number(kn[i], where, "knots[" + std::to_string(i) + "]");

  validate(c, where);
  return c;
}

BSpline load_curve(const std::string& path) {
  const std::string where = path.substr(path.find_last_of('/') == std::string::npos ? 0 : path.find_last_of('/') + 1);
  std::ifstream f(path);
  if (!f) fail(path, "cannot open file");
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(f);
  } catch (const nlohmann::json::exception& e) {  // syntax error, or a number out of double range
    fail(where, std::string("not valid JSON (") + e.what() + ")");
  }
  return parse_curve(doc, where);
}

nlohmann::json to_json(const BSpline& c, const std::string& units) {
  nlohmann::json j;
  j["name"] = c.name;
  j["units"] = units;
  j["degree"] = c.degree;
  j["rational"] = c.rational();
  j["control_points"] = nlohmann::json::array();
  for (int i = 0; i < c.n_ctrl(); ++i) {
    nlohmann::json p = nlohmann::json::array();
    for (int d = 0; d < c.dim(); ++d) p.push_back(c.ctrl(i, d));
    j["control_points"].push_back(p);
  }
  if (c.rational()) j["weights"] = std::vector<double>(c.weights.data(), c.weights.data() + c.weights.size());
  j["knots"] = std::vector<double>(c.knots.data(), c.knots.data() + c.knots.size());
  return j;
}

}  // namespace traj::geo
