// SPDX-License-Identifier: Apache-2.0
// A path read one curve at a time: what every input reader gives the
// streaming planner (job/streaming.hpp), so that memory is bounded by the
// planning window, not by the file.
#pragma once
#include <string>

#include "geometry/bspline.hpp"

namespace traj::input {

class CurveSource {
 public:
  virtual ~CurveSource() = default;
  // Next curve and where it comes from (for messages); false at the end of the path.
  virtual bool next(geo::BSpline& out, std::string& where) = 0;
};

}  // namespace traj::input
