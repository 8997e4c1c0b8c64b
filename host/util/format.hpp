// SPDX-License-Identifier: Apache-2.0
// Number formatting for messages and reports: one place, so every message
// prints a number the same way.
#pragma once
#include <string>

namespace traj::util {

// printf-style formatting of one double, e.g. fmt("%.4g", v).
std::string fmt(const char* printf_format, double v);

// printf-style formatting of a line (at most 511 bytes).
std::string strf(const char* printf_format, ...) __attribute__((format(printf, 1, 2)));

// "%g": six significant digits, the default for numbers in error messages.
inline std::string num(double v) { return fmt("%g", v); }

// The shortest text that reads back to the same double (0.3 prints as 0.3).
std::string shortest(double v);

// Text from an input file quoted in a message: at most `max` bytes, then "...".
inline std::string excerpt(const std::string& text, std::size_t max = 40) {
  return text.size() <= max ? text : text.substr(0, max) + "...";
}

}  // namespace traj::util
