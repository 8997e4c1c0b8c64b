// SPDX-License-Identifier: Apache-2.0
// Curve files: the butterfly loads; every bad-input case gives one GeometryError naming the file and
// the field. Bad files are written to a temporary directory from the good one, one field broken each.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "geometry/geometry.hpp"
#include "tmp_file.hpp"
#include "test_util.hpp"

using namespace traj::geo;
using nlohmann::json;

namespace {

json good() {
  std::ifstream f(geotest::asset("butterfly_nurbs.json"));
  return json::parse(f);
}

std::string write_tmp(const std::string& name, const std::string& text) {
  static const traj::test::TmpDir dir("trajcore_geometry_test");
  return dir.write(name, text);
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
    EXPECT_EQ(m.rfind(name + ":", 0), 0u) << m;  // "name: field: ..." or "name:line:column: field: ..."
    for (const auto& p : parts) EXPECT_NE(m.find(p), std::string::npos) << "message '" << m << "' lacks '" << p << "'";
  }
}

// "line:column" (1-based, bytes) of text[pos], counted here independently of the library.
std::string line_col(const std::string& text, size_t pos) {
  size_t line = 1, start = 0;
  for (size_t i = 0; i < pos; ++i)
    if (text[i] == '\n') {
      line = line + 1;
      start = i + 1;
    }
  return std::to_string(line) + ":" + std::to_string(pos - start + 1);
}

// The butterfly as indented (multi-line) text with one value replaced by `literal`: the value at
// `ptr` is first set to a marker string, then the marker's text is replaced. Returns the text and the
// offset of the literal's first character.
std::pair<std::string, size_t> with_literal(const json::json_pointer& ptr, const std::string& literal) {
  json j = good();
  j[ptr] = "@@marker@@";
  std::string t = j.dump(2);
  const size_t pos = t.find("\"@@marker@@\"");
  t.replace(pos, 12, literal);
  return {t, pos};
}

// Message of the GeometryError that load_curve throws for `text` saved as `name` ("" if none).
std::string load_error(const std::string& name, const std::string& text) {
  try {
    (void)load_curve(write_tmp(name, text));
  } catch (const GeometryError& e) {
    return e.what();
  }
  return "";
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
  j["degree"] = 8;  // the butterfly is rational: 1..7
  expect_error("deg8.json", j.dump(), {"deg8.json: degree: 8 out of range 1..7 for a rational curve"});
  json b = j;
  b.erase("weights");
  b["rational"] = false;
  b["degree"] = 16;
  expect_error("deg16.json", b.dump(), {"deg16.json: degree: 16 out of range 1..15 ("});
  j["degree"] = 0;
  expect_error("deg0.json", j.dump(), {"degree", "0"});
  j["degree"] = 2.5;
  expect_error("degf.json", j.dump(), {"degree", "integer"});
}

TEST(GeometryJson, NonFiniteAndNonNumbers) {
  // JSON has no NaN/Inf literals; 1e999 overflows in the parser (see the Overflow* tests), and a NaN
  // that reaches parse_curve from code is caught by field.
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
  EXPECT_EQ(load_error("str.json", j.dump(2)), "str.json: knots[5]: expected a number, got string");
  j = good();
  j["control_points"][3] = json::array({1.0, true});
  EXPECT_EQ(load_error("bool.json", j.dump(2)), "bool.json: control_points[3][1]: expected a number, got boolean");
}

// A number beyond the double range (nlohmann: out_of_range 406) names the file, the line:column of
// the number's first character and the field.
TEST(GeometryJson, OverflowInControlPoint) {
  const auto [t, pos] = with_literal("/control_points/2/0"_json_pointer, "1e999");
  EXPECT_EQ(load_error("inf.json", t), "inf.json:" + line_col(t, pos) +
                                           ": control_points[2][0]: number overflow parsing '1e999' (beyond the double range)");
  const auto [t2, pos2] = with_literal("/control_points/50/1"_json_pointer, "-2.5e308");
  EXPECT_EQ(load_error("inf2.json", t2), "inf2.json:" + line_col(t2, pos2) +
                                             ": control_points[50][1]: number overflow parsing '-2.5e308' (beyond the double range)");
}

TEST(GeometryJson, OverflowInKnotAndWeight) {
  const auto [t, pos] = with_literal("/knots/12"_json_pointer, "1e999");
  EXPECT_EQ(load_error("knot.json", t),
            "knot.json:" + line_col(t, pos) + ": knots[12]: number overflow parsing '1e999' (beyond the double range)");
  const auto [t2, pos2] = with_literal("/weights/0"_json_pointer, "1E+400");
  EXPECT_EQ(load_error("w.json", t2),
            "w.json:" + line_col(t2, pos2) + ": weights[0]: number overflow parsing '1E+400' (beyond the double range)");
}

// Truncated file: the place is the last character read, the field the element expected there.
TEST(GeometryJson, TruncatedFile) {
  auto [t, pos] = with_literal("/knots/20"_json_pointer, "0");
  t.resize(pos);  // ends after "knots[19],\n    "
  const std::string m = load_error("trunc.json", t);
  EXPECT_EQ(m.rfind("trunc.json:" + line_col(t, t.size() - 1) + ": knots[20]: ", 0), 0u) << m;
  EXPECT_NE(m.find("unexpected end of input"), std::string::npos) << m;
  // Syntax errors inside the text: a missing comma, trailing content.
  std::string u = good().dump(2);
  const size_t c = u.find(",", u.find("\"knots\""));
  u.erase(c, 1);  // knots[0] and knots[1] without the comma
  const std::string m2 = load_error("comma.json", u);
  // The parser stops at the last character of the unexpected number (knots[1]'s text).
  const size_t last = u.find_first_of(",]", c) - 1;
  EXPECT_EQ(m2.rfind("comma.json:" + line_col(u, last) + ": knots[1]: syntax error", 0), 0u) << m2;
  const std::string v = good().dump() + "\n}";
  const std::string m3 = load_error("trailing.json", v);
  EXPECT_EQ(m3.rfind("trailing.json:2:1: syntax error", 0), 0u) << m3;
}

// load_json_file alone (the planner's multi-curve files): path as given, nested field paths.
TEST(GeometryJson, LoadJsonFileNamesNestedField) {
  const std::string text = "{\n  \"curves\": [\n    {\"degree\": 3},\n    {\"knots\": [0, 0.5, 3e400]}\n  ]\n}\n";
  const std::string path = write_tmp("multi.json", text);
  try {
    (void)load_json_file(path);
    ADD_FAILURE();
  } catch (const GeometryError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":" + line_col(text, text.find("3e400")) +
                                         ": curves[1].knots[2]: number overflow parsing '3e400' (beyond the double range)");
  }
  const json ok = load_json_file(write_tmp("ok.json", "{\"a\": [1, {\"b\": 2.5}]}"));
  EXPECT_EQ(ok["a"][1]["b"].get<double>(), 2.5);
  try {
    (void)load_json_file("/nonexistent/dir/x.json", "x.json");
    ADD_FAILURE();
  } catch (const GeometryError& e) {
    EXPECT_EQ(std::string(e.what()), "x.json: cannot open file /nonexistent/dir/x.json");
  }
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
  expect_error("broken.json", "{\"degree\": 3, ", {"broken.json:1:14: syntax error", "unexpected end of input"});
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
