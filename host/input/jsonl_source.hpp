// SPDX-License-Identifier: Apache-2.0
// JSON Lines path files, read as a stream.
//
// Format (`*.jsonl`): one curve per line, each line a curve object of the
// shared butterfly format ({"degree": p, "knots": [...], "control_points":
// [[x, y(, z)], ...], optional "weights", "rational", "name", "units"}).
// Blank lines and lines whose first non-blank character is '#' are skipped.
// Consecutive curves must meet (the join check of load_path: check_join).
//
// JsonlSource reads the file with std::ifstream one line at a time and holds
// one line and the previous curve's end point, nothing else: with the
// streaming planner (run_streaming) memory is bounded by the window, not by
// the file. Every error is a PlanError naming "<file>:<line>" and the field:
//   path.jsonl:17: knots[3]: 0.2 < previous 0.5 (knot vector must be non-decreasing)
//   path.jsonl:17:31: knots[2]: number overflow parsing '1e999' (beyond the double range)
//   path.jsonl:18: starts 0.5 units away from the previous curve's end
// (a zero-length curve is refused by the planner with the same "<file>:<line>").
#pragma once
#include <Eigen/Dense>
#include <fstream>
#include <ostream>
#include <string>

#include "input/curve_source.hpp"
#include "planner/planner.hpp"

namespace traj::input {

class JsonlSource : public CurveSource {
 public:
  // Opens the file; PlanError "<file>: cannot open file" (or "is a directory").
  explicit JsonlSource(const std::string& file);
  // Reads `in` (kept alive by the caller), naming it `name` in messages: text already in memory.
  JsonlSource(std::istream& in, const std::string& name);
  bool next(geo::BSpline& out, std::string& where) override;
  size_t line() const { return line_; }      // lines read so far
  size_t curves() const { return curves_; }  // curves returned so far

 private:
  std::string file_;
  std::ifstream file_in_;
  std::istream& in_;
  std::string buf_;
  size_t line_ = 0, curves_ = 0;
  Eigen::VectorXd prev_end_;  // end point of the last curve returned
};

// True if `file` is to be read as JSON Lines: `format` is "jsonl", or it is
// empty and the name ends in ".jsonl". PlanError for any other `format` but
// "json".
bool is_jsonl(const std::string& file, const std::string& format = {});

// Writes every curve of `src` as one JSON Lines line (geo::to_json, compact);
// returns the number of curves. Used to produce large test files.
size_t write_jsonl(CurveSource& src, std::ostream& out, const std::string& units = "mm");

}  // namespace traj::input
