// Curve files: the butterfly loads; every bad-input case gives one GeometryError naming the file and
// the field. Bad files are written to a temporary directory from the good one, one field broken each.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "geometry/geometry.hpp"
#include "test_util.hpp"

using namespace traj::geo;
using nlohmann::json;

namespace {

json good() {
  std::ifstream f(geotest::asset("butterfly_nurbs.json"));
  return json::parse(f);
}

std::string write_tmp(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "trajcore_geometry_test";
  std::filesystem::create_directories(dir);
  const auto p = dir / name;
  std::ofstream(p) << text;
  return p.string();
}

// Loads `doc` from a file called `name`; expects a GeometryError whose message contains every string
// in `parts` (file name first).
void expect_error(const std::string& name, const std::string& text, std::vector<std::string> parts) {
  const std::string path = write_tmp(name, text);
  try {
    (void)load_curve(path);
    ADD_FAILURE() << name << ": no error";
  } catch (const GeometryError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(name + ": ", 0), 0u) << m;
    for (const auto& p : parts) EXPECT_NE(m.find(p), std::string::npos) << "message '" << m << "' lacks '" << p << "'";
  }
}

}  // namespace

TEST(GeometryJson, ButterflyLoads) {
  const BSpline b = load_curve(geotest::asset("butterfly_nurbs.json"));
  EXPECT_EQ(b.degree, 3);
  EXPECT_EQ(b.n_ctrl(), 51);
  EXPECT_EQ(b.dim(), 2);
  EXPECT_TRUE(b.rational());
  EXPECT_EQ(b.knots.size(), 55);
  EXPECT_EQ(b.name, "butterfly");
  // Round trip through to_json.
  const BSpline c = parse_curve(to_json(b), "roundtrip");
  EXPECT_EQ((c.ctrl - b.ctrl).norm(), 0);
  EXPECT_EQ((c.knots - b.knots).norm(), 0);
}

TEST(GeometryJson, DecreasingKnot) {
  json j = good();
  j["knots"][12] = 0.3;
  j["knots"][11] = 0.4;  // knots[12] = 0.3 < previous 0.4
  expect_error("butterfly.json", j.dump(), {"knots[12]", "0.3 < previous 0.4", "non-decreasing"});
}

TEST(GeometryJson, WrongKnotCount) {
  json j = good();
  j["knots"].erase(j["knots"].begin() + 20);
  expect_error("short_knots.json", j.dump(), {"knots", "54 knots", "55"});
}

TEST(GeometryJson, NonPositiveWeight) {
  json j = good();
  j["weights"][7] = 0.0;
  expect_error("w0.json", j.dump(), {"weights[7]", "positive"});
  j["weights"][7] = -2.5;
  expect_error("wneg.json", j.dump(), {"weights[7]", "-2.5"});
}

TEST(GeometryJson, WeightCountAndMissing) {
  json j = good();
  j["weights"].erase(j["weights"].begin());
  expect_error("wcount.json", j.dump(), {"weights", "50 weights for 51"});
  j = good();
  j.erase("weights");
  expect_error("wmissing.json", j.dump(), {"weights", "missing"});
}

TEST(GeometryJson, DegreeOutOfRange) {
  json j = good();
  j["degree"] = 8;
  expect_error("deg8.json", j.dump(), {"degree", "8", "1..7"});
  j["degree"] = 0;
  expect_error("deg0.json", j.dump(), {"degree", "0"});
  j["degree"] = 2.5;
  expect_error("degf.json", j.dump(), {"degree", "integer"});
}

TEST(GeometryJson, NonFiniteAndNonNumbers) {
  // JSON has no NaN/Inf literals; 1e999 overflows in the parser (reported with the text), and a NaN
  // that reaches parse_curve from code is caught by field.
  std::string t = good().dump();
  const auto pos = t.find("56.082");
  ASSERT_NE(pos, std::string::npos);
  t.replace(pos, 6, "1e999");
  expect_error("inf.json", t, {"not valid JSON", "1e999"});
  json n = good();
  n["control_points"][2][0] = std::nan("");  // nlohmann stores NaN (dumps it as null)
  try {
    (void)parse_curve(n, "nan.json");
    ADD_FAILURE();
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("nan.json: control_points[2][0]: not a finite number"), std::string::npos)
        << e.what();
  }
  json j = good();
  j["knots"][5] = "x";
  expect_error("str.json", j.dump(), {"knots[5]", "number"});
}

TEST(GeometryJson, InconsistentDimensions) {
  json j = good();
  j["control_points"][9] = json::array({1.0, 2.0, 3.0});
  expect_error("dims.json", j.dump(), {"control_points[9]", "3 coordinates", "inconsistent"});
}

TEST(GeometryJson, TooFewPointsAndMissingFields) {
  json j = good();
  j.erase("knots");
  expect_error("noknots.json", j.dump(), {"knots", "missing"});
  json k;
  k["degree"] = 3;
  k["control_points"] = json::array({json::array({0.0, 0.0}), json::array({1.0, 0.0})});
  k["knots"] = json::array({0, 0, 0, 0, 1, 1});
  expect_error("few.json", k.dump(), {"control_points", "2 points", "degree 3"});
}

TEST(GeometryJson, NotJsonAndMissingFile) {
  expect_error("broken.json", "{\"degree\": 3, ", {"not valid JSON"});
  try {
    (void)load_curve("/nonexistent/dir/nothing.json");
    ADD_FAILURE();
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("nothing.json"), std::string::npos);
  }
}

TEST(GeometryJson, KnotMultiplicityTooHigh) {
  json j = good();
  for (int i = 20; i < 24; ++i) j["knots"][i] = 0.3649;  // 4 equal interior knots for degree 3
  expect_error("mult.json", j.dump(), {"knots[", "multiplicity"});
}
