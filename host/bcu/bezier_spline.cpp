// SPDX-License-Identifier: Apache-2.0
#include "bcu/bezier_spline.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "bcu/bcu_compiler.hpp"

namespace traj::bcu {
namespace {

double bern(int i, double t) {
  const double u = 1.0 - t;
  switch (i) {
    case 0: return u * u * u;
    case 1: return 3 * u * u * t;
    case 2: return 3 * u * t * t;
    default: return t * t * t;
  }
}

}  // namespace

std::vector<BezierSegment> c1_spline(const Eigen::MatrixXd& p, double lambda, double mu) {
  if (p.rows() < 4) {
    std::ostringstream m;
    m << "traj::bcu::c1_spline: needs at least 4 points (P_0..P_{N+1}, N >= 2), got " << p.rows();
    throw std::invalid_argument(m.str());
  }
  if (p.cols() < 1) throw std::invalid_argument("traj::bcu::c1_spline: points have no axis");
  for (int r = 0; r < p.rows(); ++r)
    for (int c = 0; c < p.cols(); ++c)
      if (!std::isfinite(p(r, c))) {
        std::ostringstream m;
        m << "traj::bcu::c1_spline: point P_" << r << " axis " << c << " is "
          << (std::isnan(p(r, c)) ? "NaN" : "infinite");
        throw std::invalid_argument(m.str());
      }
  for (double v : {lambda, mu})
    if (!(v > 0.0 && v <= 1.0)) {
      std::ostringstream m;
      m << "traj::bcu::c1_spline: tension " << (v == lambda ? "lambda" : "mu") << " = " << v
        << " out of range (0, 1]";
      throw std::invalid_argument(m.str());
    }
  const int n = static_cast<int>(p.rows()) - 2;  // P_1..P_N
  std::vector<BezierSegment> out;
  for (int i = 1; i <= n - 1; ++i) {
    BezierSegment s(4, p.cols());
    s.row(0) = p.row(i);
    s.row(1) = p.row(i) + lambda * (p.row(i + 1) - p.row(i - 1));
    s.row(2) = p.row(i + 1) - mu * (p.row(i + 2) - p.row(i));
    s.row(3) = p.row(i + 1);
    out.push_back(s);
  }
  return out;
}

Eigen::VectorXd eval_segment(const BezierSegment& s, double t) {
  Eigen::VectorXd v(s.cols());
  for (int a = 0; a < s.cols(); ++a) {
    const double b[4] = {s(0, a), s(1, a), s(2, a), s(3, a)};
    v(a) = de_casteljau(b, t);
  }
  return v;
}

Eigen::VectorXd eval_derivative(const BezierSegment& s, double t) {
  // derivative of a cubic Bezier: quadratic Bezier on 3 (b_{k+1} - b_k)
  const double u = 1.0 - t;
  Eigen::VectorXd v(s.cols());
  for (int a = 0; a < s.cols(); ++a) {
    const double d0 = 3 * (s(1, a) - s(0, a)), d1 = 3 * (s(2, a) - s(1, a)),
                 d2 = 3 * (s(3, a) - s(2, a));
    v(a) = u * u * d0 + 2 * u * t * d1 + t * t * d2;
  }
  return v;
}

Eigen::VectorXd eval_eq13(const Eigen::MatrixXd& p, int i, double lambda, double mu, double t) {
  const double bz0 = bern(0, t) + bern(1, t) + mu * bern(2, t);
  const double bz1 = lambda * bern(1, t) + bern(2, t) + bern(3, t);
  Eigen::VectorXd v = p.row(i).transpose() * bz0 + p.row(i + 1).transpose() * bz1;
  v -= lambda * bern(1, t) * p.row(i - 1).transpose();
  v -= mu * bern(2, t) * p.row(i + 2).transpose();
  return v;
}

}  // namespace traj::bcu
