// SPDX-License-Identifier: Apache-2.0
// traj::geo umbrella header: B-spline/NURBS -> piecewise power basis, arc length, curvature split,
// reparameterisation by arc length. See host/geometry/README.md.
#pragma once
#include "geometry/arclength.hpp"
#include "geometry/bspline.hpp"
#include "geometry/curvature.hpp"
#include "geometry/curve.hpp"
#include "geometry/error.hpp"
#include "geometry/json_io.hpp"
#include "geometry/reparam.hpp"
