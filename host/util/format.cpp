// SPDX-License-Identifier: Apache-2.0
#include "util/format.hpp"

#include <charconv>
#include <cstdarg>
#include <cstdio>

namespace traj::util {

std::string fmt(const char* printf_format, double v) {
  char b[64];
  std::snprintf(b, sizeof b, printf_format, v);
  return b;
}

std::string strf(const char* printf_format, ...) {
  char b[512];
  va_list ap;
  va_start(ap, printf_format);
  std::vsnprintf(b, sizeof b, printf_format, ap);
  va_end(ap);
  return b;
}

std::string shortest(double v) {
  char b[64];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return std::string(b, r.ptr);
}

}  // namespace traj::util
