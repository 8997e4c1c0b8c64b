// A synthetic toolpath of any length: a raster (boustrophedon) pocketing
// pattern of straight passes joined by 180-degree arcs (exact rational
// quadratic NURBS), tangent-continuous everywhere. Used by the streaming
// benchmark (a million pieces) and tests.
#pragma once
#include <cmath>
#include <string>

#include "planner/streaming.hpp"

namespace traj::plan {

class RasterSource : public CurveSource {
 public:
  // `pieces` curves in all: passes of length `pass` (units) `step` apart.
  RasterSource(size_t pieces, double pass = 20.0, double step = 1.0) : n_(pieces), pass_(pass), step_(step) {}
  bool next(geo::BSpline& out, std::string& where) override {
    if (i_ >= n_) return false;
    const size_t row = i_ / 2;
    const bool right = row % 2 == 0;  // pass direction
    const double y = row * step_;
    if (i_ % 2 == 0) {
      Eigen::VectorXd a(2), b(2);
      a << (right ? 0.0 : pass_), y;
      b << (right ? pass_ : 0.0), y;
      out = geo::make_line(a, b);
    } else {
      // half circle from the end of this pass up to the next row
      const double r = step_ / 2;
      Eigen::Vector2d c(right ? pass_ : 0.0, y + r);
      out = right ? geo::make_arc(c, r, -M_PI / 2, M_PI / 2) : geo::make_arc(c, r, 3 * M_PI / 2, M_PI / 2);
    }
    where = "raster piece " + std::to_string(i_);
    ++i_;
    return true;
  }

 private:
  size_t n_, i_ = 0;
  double pass_, step_;
};

}  // namespace traj::plan
