// SPDX-License-Identifier: Apache-2.0
// A synthetic toolpath of any length: a raster (boustrophedon) pocketing
// pattern of straight passes joined by 180-degree arcs (exact rational
// quadratic NURBS), tangent-continuous everywhere. Used by the streaming
// benchmark (a million pieces) and tests.
#pragma once
#include <cmath>
#include <string>

#include "input/curve_source.hpp"

namespace traj::input {

class RasterSource : public CurveSource {
 public:
  // `pieces` curves in all: passes of length `pass` (units) `step` apart,
  // going up `rows` rows and back down again (so it stays in a pocket of
  // pass x rows*step however long it runs).
  RasterSource(size_t pieces, double pass = 20.0, double step = 1.0, size_t rows = 1000)
      : n_(pieces), pass_(pass), step_(step), rows_(rows) {}
  bool next(geo::BSpline& out, std::string& where) override {
    if (i_ >= n_) return false;
    const size_t row = i_ / 2;
    const bool right = row % 2 == 0;  // pass direction
    const double y = row_y(row);
    if (i_ % 2 == 0) {
      Eigen::VectorXd a(2), b(2);
      a << (right ? 0.0 : pass_), y;
      b << (right ? pass_ : 0.0), y;
      out = geo::make_line(a, b);
    } else {
      // half circle from the end of this pass to the next row (up or down)
      const double y1 = row_y(row + 1);
      const bool up = y1 > y;
      const double r = step_ / 2;
      Eigen::Vector2d c(right ? pass_ : 0.0, 0.5 * (y + y1));
      if (right)
        out = up ? geo::make_arc(c, r, -M_PI / 2, M_PI / 2) : geo::make_arc(c, r, M_PI / 2, -M_PI / 2);
      else
        out = up ? geo::make_arc(c, r, 3 * M_PI / 2, M_PI / 2) : geo::make_arc(c, r, M_PI / 2, 3 * M_PI / 2);
    }
    where = "raster piece " + std::to_string(i_);
    ++i_;
    return true;
  }

 private:
  double row_y(size_t row) const {
    const size_t m = row % (2 * rows_);
    return step_ * static_cast<double>(m <= rows_ ? m : 2 * rows_ - m);
  }
  size_t n_, i_ = 0;
  double pass_, step_;
  size_t rows_;
};

}  // namespace traj::input
