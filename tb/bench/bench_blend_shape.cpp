// SPDX-License-Identifier: Apache-2.0
// Corner-blend shapes against the planner's speed bound: how fast could a
// line-line corner pass if its blend had another shape within the same
// tolerance?
//   usage: bench_blend_shape [--short | --cxx]
//     --short  one corner (90 degrees, long legs), fewer search steps (the
//              CTest test bench.short.blend_shape)
//     --cxx    prints the wide-blend shape table of host/corners/corners.cpp
//              (kWideShort, kWideLong): per turn 5..175 degrees, the shape of
//              least peak |d3x/ds3| at the largest size the tolerance allows,
//              for legs of 4 and of 16 tolerances (Nelder-Mead from several
//              starts, continued along the turns); about a minute
//
// For each turn and each length the blend may take from each leg, it prints
//   5pt:     the five-point blend (corners::blend_corners with
//            BlendOptions::wide off, on two segments whose share is that
//            length), its peak curvature and the lowest planner speed bound
//            along it (plan::speed_limit, the bound the profile follows:
//            limits (i) of bench_toolpaths, feed 100, 3000 mm/s^2, 60 000
//            mm/s^3, blend tolerance 0.045 mm);
//   chosen:  the planner speed bound along the blend corners::blend_corners
//            takes by default (a wide blend where it chooses one);
//   7pt:     the best symmetric seven-point clamped cubic B-spline found by a
//            seeded random search: P0, P1, P2 on the incoming line (G2 join
//            with curvature 0, as the five-point blend), P3 on the bisector,
//            at distance e from the corner, outward for e > 0, P4..P6 the
//            mirror image; accepted only when the corner is within the
//            tolerance of the curve and every curve point is within it of
//            the two legs (measured on 400 samples in the search, 4000 for
//            the row printed: dev_mm, corner);
//   v_gain:  7pt_v / 5pt_v;
//   r_band:  the radius of the circle tangent to the two outer edges of
//            the tolerance band and passing the tolerance from the corner,
//            over the junction-deviation circle's (tangent to the legs):
//            (1 + cos(theta/2)) / cos(theta/2).
// The search is a measurement of what a shape leaving the legs on the outer
// side of the band gains, not a proof of the optimum.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "corners/corners.hpp"
#include "geometry/bspline.hpp"
#include "input/toolpath.hpp"
#include "planner/planner.hpp"

using namespace traj;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTol = 0.045;  // the blend's share of bench_toolpaths' 0.05 mm

plan::Limits limits_i() {
  plan::Limits L;
  L.feed = 100;
  for (int a = 0; a < plan::kMaxAxes; ++a) {
    L.v_axis[a] = 100;
    L.a_axis[a] = 3000;
    L.j_axis[a] = 60000;
  }
  L.a_tan = L.a_cen = 3000;
  L.j_tan = L.j_cen = 60000;
  L.tol = 0.05;
  return L;
}

struct Measure {
  double v_min = 0, kappa_max = 0;
};

// Lowest planner speed bound and highest curvature over n samples of the curve.
Measure measure(const geo::BSpline& c, int n) {
  const plan::Limits L = limits_i();
  const plan::PlanOptions o;
  const double A_t = o.tan_a_share * L.a_tan;
  const double J_t = o.tan_j_share * std::min(L.j_tan, L.j_axis[0]);
  plan::Path p;
  p.add(c, "shape");
  Measure m{std::numeric_limits<double>::infinity(), 0};
  for (int i = 0; i <= n; ++i) {
    const double u = c.u_begin() + (c.u_end() - c.u_begin()) * i / n;
    const plan::Frame f = plan::frame_at(p, 0, u, 0);
    double A_loc = 0;  // the planner's own choice of the local tangential acceleration
    m.v_min = std::min(m.v_min, plan::speed_limit(f, L, o, A_t, J_t, 2, &A_loc));
    m.kappa_max = std::max(m.kappa_max, f.kappa);
  }
  return m;
}

Eigen::Vector2d point_on(const geo::BSpline& c, double u) {
  // de Boor on the clamped cubic (independent of the planner's evaluation)
  const int p = c.degree;
  int k = p;
  while (k + 1 < c.n_ctrl() && c.knots[k + 1] <= u) ++k;
  std::vector<Eigen::Vector2d> d;
  for (int j = 0; j <= p; ++j) d.push_back(c.ctrl.row(j + k - p).transpose());
  for (int r = 1; r <= p; ++r)
    for (int j = p; j >= r; --j) {
      const double a = (u - c.knots[j + k - p]) / (c.knots[j + 1 + k - r] - c.knots[j + k - p]);
      d[j] = (1 - a) * d[j - 1] + a * d[j];
    }
  return d[p];
}

double dist_segment(const Eigen::Vector2d& x, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - x).norm();
}

// Corner at the origin, incoming along +x, outgoing at angle `turn`:
// (the curve's largest distance from the legs, the corner's distance from the curve).
std::pair<double, double> deviations(const geo::BSpline& c, double turn, int n) {
  const Eigen::Vector2d a(-100, 0), v(0, 0), b(100 * std::cos(turn), 100 * std::sin(turn));
  double out = 0, corner = std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector2d> xs;
  for (int i = 0; i <= n; ++i) {
    const double u = std::min(c.u_begin() + (c.u_end() - c.u_begin()) * i / n, c.u_end() * (1 - 1e-15));
    const Eigen::Vector2d x = point_on(c, u);
    xs.push_back(x);
    out = std::max(out, std::min(dist_segment(x, a, v), dist_segment(x, v, b)));
    corner = std::min(corner, x.norm());
  }
  // the replaced legs' points to the curve (the corner is one of them)
  const Eigen::Vector2d p0 = c.ctrl.row(0).transpose(), p6 = c.ctrl.row(c.n_ctrl() - 1).transpose();
  for (int i = 0; i <= 32; ++i) {
    for (const Eigen::Vector2d& y : {Eigen::Vector2d(p0 * (1 - i / 32.0)), Eigen::Vector2d(p6 * (i / 32.0))}) {
      double m = std::numeric_limits<double>::infinity();
      for (const auto& x : xs) m = std::min(m, (x - y).norm());
      corner = std::max(corner, m);
    }
  }
  return {out, corner};
}

geo::BSpline seven_point(double turn, double l0, double l1, double l2, double e) {
  const Eigen::Vector2d t_out(std::cos(turn), std::sin(turn)), t_in(1, 0);
  const Eigen::Vector2d inward = (t_out - t_in).normalized();
  geo::BSpline c;
  c.degree = 3;
  c.ctrl.resize(7, 2);
  c.ctrl.row(0) = -l0 * t_in;
  c.ctrl.row(1) = -l1 * t_in;
  c.ctrl.row(2) = -l2 * t_in;
  c.ctrl.row(3) = -e * inward;
  c.ctrl.row(4) = l2 * t_out;
  c.ctrl.row(5) = l1 * t_out;
  c.ctrl.row(6) = l0 * t_out;
  c.knots.resize(11);
  c.knots << 0, 0, 0, 0, 0.25, 0.5, 0.75, 1, 1, 1, 1;
  return c;
}

// The product's blend of one corner whose legs allow `leg_share` mm each (five-point only, or as
// blend_corners chooses).
geo::BSpline product_blend(double turn, double leg_share, bool wide) {
  input::Toolpath tp;
  tp.axes = 2;
  const double leg = 2 * leg_share;  // BlendOptions::share = 1/2
  Eigen::VectorXd a(2), v(2), b(2);
  a << -leg, 0;
  v << 0, 0;
  b << leg * std::cos(turn), leg * std::sin(turn);
  for (auto [p, q] : {std::pair{a, v}, std::pair{v, b}}) {
    input::Move m;
    m.kind = input::Move::Kind::kFeed;
    m.curve = geo::make_line(p, q);
    m.feed = 100;
    m.where = "leg";
    tp.moves.push_back(m);
  }
  corners::BlendOptions o;
  o.wide = wide;
  const corners::BlendResult r = corners::blend_corners(tp, kTol, o);
  for (const auto& c : r.curves)
    if (c.curve.degree == 3) return c.curve;
  throw std::runtime_error("no blend");
}
geo::BSpline five_point(double turn, double leg_share) { return product_blend(turn, leg_share, false); }

struct Best {
  double v = -1, l0 = 0, l1 = 0, l2 = 0, e = 0;
};

Best search(double turn, double leg_share, int steps) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(0, 1);
  std::normal_distribution<double> gauss(0, 1);
  Best best;
  const double lmax = leg_share;
  for (int it = 0; it < steps; ++it) {
    double l0, l1, l2, e;
    if (best.v < 0 || uni(rng) < 0.2) {
      l0 = lmax * (0.05 + 0.95 * uni(rng));
      l1 = l0 * (0.3 + 0.65 * uni(rng));
      l2 = l1 * 0.95 * uni(rng);
      e = kTol * (-1 + 7 * uni(rng));
    } else {
      l0 = best.l0 * (1 + 0.05 * gauss(rng));
      l1 = best.l1 * (1 + 0.05 * gauss(rng));
      l2 = best.l2 * (1 + 0.05 * gauss(rng));
      e = best.e + 0.2 * kTol * gauss(rng);
    }
    if (!(lmax >= l0 && l0 > l1 && l1 > l2 && l2 >= 0)) continue;
    const geo::BSpline c = seven_point(turn, l0, l1, l2, e);
    const auto [out, corner] = deviations(c, turn, 400);
    if (out > kTol || corner > kTol) continue;
    const double v = measure(c, 200).v_min;
    if (v > best.v) best = {v, l0, l1, l2, e};
  }
  return best;
}

// Largest |d^3 x / ds^3| (the planner's q_norm: the jerk per v^3 of a pass at constant speed) over n samples.
double q_max(const geo::BSpline& c, int n) {
  plan::Path p;
  p.add(c, "shape");
  double q = 0;
  for (int i = 0; i <= n; ++i) q = std::max(q, plan::frame_at(p, 0, c.u_begin() + (c.u_end() - c.u_begin()) * i / n, 0).q_norm);
  return q;
}

// Normalised shape (l0 = 1): x = (logit l1/l0, logit l2/l1, e/l0).
struct Shape {
  double r1, r2, eps;
};
Shape shape_of(const double* x) {
  auto sig = [](double z) { return 1 / (1 + std::exp(-z)); };
  return {sig(x[0]), sig(x[1]), x[2]};
}
// Scale-free cost of a shape at turn `turn` with legs allowing lambda tolerances: the peak |Q| at the
// largest scale the tolerance and the legs allow (Q scales as 1/l0^2).
double cost(const Shape& sh, double turn, double lambda, double* l0_out = nullptr) {
  const geo::BSpline c = seven_point(turn, 1, sh.r1, sh.r1 * sh.r2, sh.eps);
  const auto [out, corner] = deviations(c, turn, 300);
  const double D = std::max(out, corner);
  const double l0 = std::min(1 / D, lambda);
  if (l0_out) *l0_out = l0;
  return q_max(c, 150) / (l0 * l0);
}

// Nelder-Mead from a few starts.
std::array<double, 3> g_last{};  // the last optimum (continuation along the turns)
bool g_have_last = false;
Shape optimise(double turn, double lambda, double* l0_out) {
  std::vector<std::array<double, 3>> starts = {{1.5, 0.5, 0.0}, {2.0, 0.0, 0.1}, {1.0, 0.0, -0.1}, {2.5, 1.5, 0.05}};
  if (g_have_last) starts.push_back(g_last);
  double best = INFINITY;
  std::array<double, 3> bx{};
  for (const auto& s0 : starts) {
    std::array<std::array<double, 3>, 4> v;
    std::array<double, 4> f;
    for (int i = 0; i < 4; ++i) {
      v[i] = s0;
      if (i > 0) v[i][i - 1] += (i == 3 ? 0.05 : 0.5);
      f[i] = cost(shape_of(v[i].data()), turn, lambda);
    }
    for (int it = 0; it < 300; ++it) {
      std::array<int, 4> o{0, 1, 2, 3};
      std::sort(o.begin(), o.end(), [&](int a, int b) { return f[a] < f[b]; });
      auto vv = v;
      auto ff = f;
      for (int i = 0; i < 4; ++i) v[i] = vv[o[i]], f[i] = ff[o[i]];
      std::array<double, 3> c{};
      for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) c[k] += v[i][k] / 3;
      auto at = [&](double t) {
        std::array<double, 3> x;
        for (int k = 0; k < 3; ++k) x[k] = c[k] + t * (v[3][k] - c[k]);
        return x;
      };
      const auto xr = at(-1);
      const double fr = cost(shape_of(xr.data()), turn, lambda);
      if (fr < f[0]) {
        const auto xe = at(-2);
        const double fe = cost(shape_of(xe.data()), turn, lambda);
        if (fe < fr) v[3] = xe, f[3] = fe;
        else v[3] = xr, f[3] = fr;
      } else if (fr < f[2]) {
        v[3] = xr, f[3] = fr;
      } else {
        const auto xc = at(0.5);
        const double fc = cost(shape_of(xc.data()), turn, lambda);
        if (fc < f[3]) v[3] = xc, f[3] = fc;
        else
          for (int i = 1; i < 4; ++i) {
            for (int k = 0; k < 3; ++k) v[i][k] = v[0][k] + 0.5 * (v[i][k] - v[0][k]);
            f[i] = cost(shape_of(v[i].data()), turn, lambda);
          }
      }
    }
    for (int i = 0; i < 4; ++i)
      if (f[i] < best) best = f[i], bx = v[i];
  }
  cost(shape_of(bx.data()), turn, lambda, l0_out);
  g_last = bx;
  g_have_last = true;
  return shape_of(bx.data());
}

}  // namespace

int main(int argc, char** argv) {
  const bool short_run = argc > 1 && std::strcmp(argv[1], "--short") == 0;
  if (argc > 1 && std::strcmp(argv[1], "--cxx") == 0) {
    // the shape table of host/corners (wide_shapes.inc): per turn 5..175 degrees, the optimum for legs of
    // 4 tolerances, 16 tolerances and without a leg limit
    for (double lambda : {4.0, 16.0, 1e9}) {
      g_have_last = false;
      for (int deg = 5; deg <= 175; deg += 5) {
        double l0 = 0;
        const Shape sh = optimise(deg * kPi / 180, lambda, &l0);
        std::printf("    {%3d, %.0e, %.4f, %.4f, %+.4f},  // l0 %.2f tol\n", deg, lambda, sh.r1, sh.r2, sh.eps, l0);
      }
    }
    return 0;
  }
  const std::vector<double> turns = short_run ? std::vector<double>{90} : std::vector<double>{30, 60, 90, 120, 150};
  const std::vector<double> legs = short_run ? std::vector<double>{2.0} : std::vector<double>{2.0, 0.5, 0.25};
  const int steps = short_run ? 400 : (std::getenv("STEPS") ? std::atoi(std::getenv("STEPS")) : 3000);
  std::printf("corner blends at tolerance %.3f mm, planner speed bound of limits (i) (feed 100, a 3000, j 60000)\n",
              kTol);
  std::printf("%6s %6s | %9s %9s %9s | %9s %9s %7s %6s %6s %7s %9s %9s | %6s %6s\n", "turn", "leg_mm", "5pt_kmax",
              "5pt_v", "chosen_v", "7pt_kmax", "7pt_v", "l0_mm", "l1/l0", "l2/l0", "e/tol", "dev_mm", "corner", "v_gain",
              "r_band");
  int bad = 0;
  for (double deg : turns)
    for (double leg : legs) {
      const double turn = deg * kPi / 180;
      const geo::BSpline five = five_point(turn, leg);
      const Measure m5 = measure(five, 4000);
      const Measure mc = measure(product_blend(turn, leg, true), 4000);
      const Best b = search(turn, leg, steps);
      if (b.v < 0) {
        std::printf("%6.0f %6.2f | no seven-point shape found\n", deg, leg);
        ++bad;
        continue;
      }
      const geo::BSpline seven = seven_point(turn, b.l0, b.l1, b.l2, b.e);
      const Measure m7 = measure(seven, 4000);
      const auto [out, corner] = deviations(seven, turn, 4000);
      const double c = std::cos(turn / 2);
      std::printf("%6.0f %6.2f | %9.3f %9.2f %9.2f | %9.3f %9.2f %7.3f %6.3f %6.3f %7.2f %9.5f %9.5f | %6.2f %6.2f\n",
                  deg, leg, m5.kappa_max, m5.v_min, mc.v_min, m7.kappa_max, m7.v_min, b.l0, b.l1 / b.l0, b.l2 / b.l0,
                  b.e / kTol, out, corner, m7.v_min / m5.v_min, (1 + c) / c);
      if (out > kTol * (1 + 1e-9) || corner > kTol * (1 + 1e-9)) ++bad;
    }
  return bad == 0 ? 0 : 1;
}
