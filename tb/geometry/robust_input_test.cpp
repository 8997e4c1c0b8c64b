// Extreme curve input: refused fast with one message naming the field, or loaded correctly and fast.
// References: the fields named by the input itself, a long-double arc length computed here, knot
// insertion one knot at a time (Boehm) for the Bezier decomposition, the clock for the load time.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>
#include <string>

#include "geometry/geometry.hpp"

using namespace traj::geo;

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The message of loading `text` (a curve object) up to its arc length, or "" if it loads.
std::string load_error(const std::string& text) {
  try {
    const BSpline b = parse_curve(parse_json_text(text, "t.json"), "t.json");
    const Curve c(b, "t.json");
    const ArcLength al(c);
    if (!(al.total() > 0) || !std::isfinite(al.total())) return "bad length " + std::to_string(al.total());
  } catch (const GeometryError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(GeometryExtremeInput, RefusedFastNamingTheField) {
  struct Case {
    const char* text;
    const char* named;
  };
  const Case cases[] = {
      // found by a fuzzer: minutes of arc-length halving each
      {R"({"degree":2,"control_points":[[0,0],[1.7e308,10],[20,0]],"knots":[0,0,0,1,1,1]})",
       "control_points[1][0]: 1.7e+308 beyond"},
      {R"({"degree":2,"control_points":[[0,0],[10,10],[20,0],[30,5]],"knots":[0,0,0,1.1e-307,1,1,1]})",
       "knots: the span [0, 1.1e-307] is too short"},
      {R"({"degree":2,"rational":true,"control_points":[[0,0],[10,10],[20,0]],"weights":[1,1e12,1],"knots":[0,0,0,1,1,1]})",
       "weights[1]: 1e+12 is 1e+12 times weights[0]"},
      {R"({"degree":2,"control_points":[[0,0],[10,10],[20,0]],"knots":[1e-300,1e-300,1e-300,3e-300,3e-300,3e-300]})",
       "knots: the span [1e-300, 3e-300] is too short"},
      // a zero-length curve and "arc length -nan"
      {R"({"degree":2,"control_points":[[0,0],[10,10],[20,0]],"knots":[0,0,0,1e300,1e300,1e300]})",
       "knots[3]: 1e+300 beyond"},
      {R"({"degree":1,"control_points":[[0,0],[10,10]],"knots":[0,0,5e-324,5e-324]})", "knots: the span [0, 5e-324] is too short"},
      // shown as "degree: -1"
      {R"({"degree":18446744073709551615,"control_points":[[0,0],[10,10]],"knots":[0,0,1,1]})",
       "degree: 18446744073709551615 out of range"},
  };
  for (const Case& c : cases) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::string e = load_error(c.text);
    EXPECT_LT(seconds_since(t0), 2.0) << c.text;
    EXPECT_NE(e.find(std::string("t.json: ") + c.named), std::string::npos) << c.text << "\n-> " << e;
    EXPECT_EQ(e.find("nan"), std::string::npos) << e;
  }
}

// Just inside the bounds: loads, and a coordinate at the bound is no error.
TEST(GeometryExtremeInput, BoundsThemselvesAccepted) {
  EXPECT_EQ(load_error(R"({"degree":1,"control_points":[[0,0],[1e15,0]],"knots":[0,0,1,1]})"), "");
  EXPECT_EQ(load_error(R"({"degree":1,"control_points":[[0,0],[1,0]],"knots":[0,0,1e12,1e12]})"), "");
  EXPECT_EQ(load_error(R"({"degree":2,"rational":true,"control_points":[[0,0],[10,10],[20,0]],"weights":[1,1000,1],"knots":[0,0,0,1,1,1]})"), "");
}

// Conics with a large middle weight: the rational speed cancels (about ratio^2 ulp); the integration
// accepts differences at that noise level instead of halving for minutes, and stays accurate.
// Reference: the same conic's speed in long double (closed form of the rational quadratic),
// 3-point Gauss-Legendre on 200 000 panels graded towards the weight peak at t = 1/2.
TEST(GeometryExtremeInput, HighWeightConicLengthAgreesWithLongDouble) {
  for (const double w : {300.0, 1000.0}) {
    Eigen::MatrixXd P(3, 2);
    P << 0, 0, 10, 10, 20, 0;
    Eigen::VectorXd W(3);
    W << 1, w, 1;
    const Curve c(make_bezier(P, W));
    const auto t0 = std::chrono::steady_clock::now();
    const ArcLength al(c);
    EXPECT_LT(seconds_since(t0), 1.0);
    using LD = long double;
    auto speed = [&](LD t) {
      const LD b0 = (1 - t) * (1 - t), b1 = 2 * t * (1 - t), b2 = t * t, d0 = -2 * (1 - t), d1 = 2 - 4 * t, d2 = 2 * t;
      const LD Wt = b0 + w * b1 + b2, Wd = d0 + w * d1 + d2;
      const LD ax = w * b1 * 10 + b2 * 20, ay = w * b1 * 10, axd = w * d1 * 10 + d2 * 20, ayd = w * d1 * 10;
      const LD x = (axd * Wt - ax * Wd) / (Wt * Wt), y = (ayd * Wt - ay * Wd) / (Wt * Wt);
      return std::sqrt(x * x + y * y);
    };
    const int n = 200000;
    const LD gx[3] = {-0.774596669241483377035853079956L, 0, 0.774596669241483377035853079956L};
    const LD gw[3] = {5.0L / 9, 8.0L / 9, 5.0L / 9};
    LD ref = 0;
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        const LD v = (i + 0.5L + 0.5L * gx[k]) / n - 0.5L;  // t = 1/2 + 4 v^3, dt = 12 v^2 dv
        ref += gw[k] * speed(0.5L + 4 * v * v * v) * 12 * v * v / (2 * n);
      }
    EXPECT_NEAR(al.total(), static_cast<double>(ref), 1e-11 * static_cast<double>(ref)) << "weight " << w;
  }
}

// The Bezier decomposition in one sweep equals inserting every interior knot up to multiplicity p,
// one knot at a time (Boehm), on random B-splines and NURBS with repeated knots.
TEST(GeometryExtremeInput, BezierPiecesEqualKnotInsertion) {
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> U(-10, 10), Wd(0.2, 5);
  int compared = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int p = 1 + static_cast<int>(rng() % 5), n = p + 1 + static_cast<int>(rng() % 12), dim = 2 + static_cast<int>(rng() % 2);
    BSpline b;
    b.degree = p;
    b.ctrl.resize(n, dim);
    for (int i = 0; i < n; ++i)
      for (int d = 0; d < dim; ++d) b.ctrl(i, d) = U(rng);
    if (trial % 2) {
      b.weights.resize(n);
      for (int i = 0; i < n; ++i) b.weights[i] = Wd(rng);
    }
    std::vector<double> inner;
    for (int i = 0; i < n - p - 1; ++i)  // repeats on purpose
      inner.push_back(std::clamp(std::round(U(rng) + 10) / 20, 1e-3, 1 - 1e-3));
    std::sort(inner.begin(), inner.end());
    // interior multiplicity up to p + 1 (a hodograph of a curve with a C0 knot has p + 1)
    for (int i = 0; i + p + 1 < static_cast<int>(inner.size()); ++i)
      if (inner[i] == inner[i + p + 1]) inner[i + p + 1] = std::nextafter(inner[i + p + 1], 2.0);
    b.knots.resize(n + p + 1);
    for (int i = 0; i <= p; ++i) b.knots[i] = 0, b.knots[n + i] = 1;
    for (size_t i = 0; i < inner.size(); ++i) b.knots[p + 1 + static_cast<int>(i)] = inner[i];
    std::sort(b.knots.data(), b.knots.data() + b.knots.size());
    bool bad = false;  // validate() refuses multiplicity p + 1; the decomposition takes it
    for (int i = 0; i + 1 < b.knots.size(); ++i) bad |= b.knots[i] > b.knots[i + 1];
    if (bad) continue;
    BSpline ref = b;
    for (int i = p + 1; i < n; ++i) {
      const double u = b.knots[i];
      int s = 0;
      for (int j = 0; j < ref.knots.size(); ++j) s += ref.knots[j] == u;
      if (s < p) ref = insert_knot(ref, u, p - s);
    }
    const Eigen::MatrixXd H = ref.homogeneous();
    std::vector<BezierPiece> want;
    for (int j = p; j < ref.n_ctrl(); ++j)
      if (ref.knots[j] < ref.knots[j + 1]) want.push_back({ref.knots[j], ref.knots[j + 1], H.middleRows(j - p, p + 1)});
    const std::vector<BezierPiece> got = bezier_pieces(b);
    ++compared;
    ASSERT_EQ(got.size(), want.size()) << "trial " << trial;
    for (size_t k = 0; k < got.size(); ++k) {
      EXPECT_EQ(got[k].u0, want[k].u0);
      EXPECT_EQ(got[k].u1, want[k].u1);
      EXPECT_LE((got[k].hom - want[k].hom).cwiseAbs().maxCoeff(), 1e-12 * (1 + want[k].hom.cwiseAbs().maxCoeff()))
          << "trial " << trial << " piece " << k;
    }
  }
  EXPECT_GT(compared, 150);
}

// 100 000 control points load (power basis, arc length) in seconds: the decomposition is linear
// (it used to copy the curve once per interior knot: 12 s at 10 000 points, minutes at 100 000).
// The time is printed; bench_load_points measures the growth.
TEST(GeometryExtremeInput, HundredThousandControlPointsLoadInSeconds) {
  const int n = 100000, p = 3;
  BSpline b;
  b.degree = p;
  b.ctrl.resize(n, 2);
  for (int i = 0; i < n; ++i) b.ctrl.row(i) << i * 0.1, std::sin(i * 0.01);
  b.knots.resize(n + p + 1);
  for (int i = 0; i < b.knots.size(); ++i) b.knots[i] = std::clamp(i - p, 0, n - p);
  const auto t0 = std::chrono::steady_clock::now();
  const Curve c(b);
  const ArcLength al(c);
  const double s = seconds_since(t0);
  std::printf("100000 control points: %zu spans, length %.6f, loaded in %.3f s\n", c.spans().size(), al.total(), s);
  EXPECT_EQ(c.spans().size(), static_cast<size_t>(n - p));
  EXPECT_LT(s, 30.0);
}

// Messages that echo input stay one line: a path 200 000 levels deep and a NUL byte.
TEST(GeometryJsonMessages, DeepNestingEchoClipped) {
  const std::string text(200000, '[');
  try {
    parse_json_text(text, "deep.json");
    FAIL() << "accepted";
  } catch (const GeometryError& e) {
    const std::string m = e.what();
    EXPECT_LT(m.size(), 1024u) << m.substr(0, 300);
    EXPECT_EQ(m.rfind("deep.json:1:", 0), 0u) << m.substr(0, 300);
  }
}

TEST(GeometryJsonMessages, NulByteAndWhatFollowsRefused) {
  const std::string curve = R"({"degree": 1, "control_points": [[0, 0], [10, 0]], "knots": [0, 0, 1, 1]})";
  const std::string text = curve + "\n" + std::string(1, '\0') + "garbage}}";
  EXPECT_NO_THROW(parse_json_text(curve + "\n", "ok.json"));
  try {
    parse_json_text(text, "nul.json");
    FAIL() << "accepted";
  } catch (const GeometryError& e) {
    EXPECT_EQ(std::string(e.what()), "nul.json:2:1: NUL byte (JSON text holds none)");
  }
}
