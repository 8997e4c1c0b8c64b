// SPDX-License-Identifier: Apache-2.0
// JSON path files: one curve object (the butterfly format: degree, knots,
// control_points, optional weights) or {"curves": [curve, ...]} whose curves
// meet end to end. Every error is a plan::PlanError naming file:line:column
// (syntax, a number beyond the double range) or the file and the field.
#pragma once
#include <string>

#include "planner/planner.hpp"

namespace traj::input {

plan::Path load_path(const std::string& file);
// The same for JSON text already in memory, named `name` in messages.
plan::Path parse_path(const std::string& text, const std::string& name);

}  // namespace traj::input
