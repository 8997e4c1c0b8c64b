// SPDX-License-Identifier: Apache-2.0
// traj::geo error type. Errors the user can cause (bad file, bad field, bad parameter) are
// reported by throwing GeometryError with one message naming the place (file, field, index).
#pragma once
#include <stdexcept>
#include <string>

namespace traj::geo {

class GeometryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace traj::geo
