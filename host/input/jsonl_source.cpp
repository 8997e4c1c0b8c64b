// SPDX-License-Identifier: Apache-2.0
#include "input/jsonl_source.hpp"

#include <filesystem>

#include "geometry/json_io.hpp"

namespace traj::input {

using plan::PlanError;

JsonlSource::JsonlSource(const std::string& file) : file_(file), in_(file_in_) {
  if (std::filesystem::is_directory(file)) throw PlanError(file + ": is a directory, not a path file");
  file_in_.open(file, std::ios::binary);
  if (!file_in_) throw PlanError(file + ": cannot open file");
}

JsonlSource::JsonlSource(std::istream& in, const std::string& name) : file_(name), in_(in) {}

bool JsonlSource::next(geo::BSpline& out, std::string& where) {
  while (std::getline(in_, buf_)) {
    ++line_;
    if (!buf_.empty() && buf_.back() == '\r') buf_.pop_back();  // CRLF files
    const size_t first = buf_.find_first_not_of(" \t");
    if (first == std::string::npos || buf_[first] == '#') continue;
    where = file_ + ":" + std::to_string(line_);
    try {
      // syntax errors and numbers beyond the double range: "<file>:<line>:<column>: <field>: ..."
      const nlohmann::json doc = geo::parse_json_text(buf_, file_, line_);
      out = geo::parse_curve(doc, where);  // "<file>:<line>: <field>: ..."
      const geo::Curve c(out, where);
      if (prev_end_.size() > 0) plan::check_join(prev_end_, c.point(c.u_begin()), where);
      prev_end_ = c.point(c.u_end());
    } catch (const geo::GeometryError& e) {
      throw PlanError(e.what());
    }
    ++curves_;
    return true;
  }
  if (in_.bad()) throw PlanError(file_ + ":" + std::to_string(line_ + 1) + ": read error");
  if (curves_ == 0) throw PlanError(file_ + ": no curves (a JSON Lines path holds one curve object per line)");
  return false;
}

bool is_jsonl(const std::string& file, const std::string& format) {
  if (format == "jsonl") return true;
  if (format == "json") return false;
  if (!format.empty()) throw PlanError("--format " + format + ": expected json or jsonl");
  return file.size() >= 6 && file.compare(file.size() - 6, 6, ".jsonl") == 0;
}

size_t write_jsonl(CurveSource& src, std::ostream& out, const std::string& units) {
  geo::BSpline b;
  std::string where;
  size_t n = 0;
  while (src.next(b, where)) {
    out << geo::to_json(b, units).dump() << '\n';
    ++n;
  }
  return n;
}

}  // namespace traj::input
