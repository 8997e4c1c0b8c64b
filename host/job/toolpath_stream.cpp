#include "job/toolpath_stream.hpp"

#include <algorithm>
#include <cmath>

#include "util/format.hpp"

namespace traj::job {

using plan::PlanError;

namespace {

JobConfig stream_config(const JobConfig& cfg, double rapid, const ToolpathOptions& o) {
  JobConfig c = cfg;
  c.limits.feed = std::max(cfg.limits.feed, rapid);
  if (o.blend) c.limits.tol = cfg.limits.tol * (1 - o.blend_share);
  return c;
}

}  // namespace

ToolpathStream::ToolpathStream(const std::string& file, input::FileKind kind, const JobConfig& cfg,
                               const ToolpathOptions& o, size_t chunk)
    : file_(file), job_cfg_(cfg), opt_(o), chunk_(std::max<size_t>(chunk, 2)) {
  if (kind == input::FileKind::kGcode) {
    reader_ = std::make_unique<input::GcodeReader>(file, o.gcode);
    axes_ = reader_->axes();
  } else {
    whole_ = input::read_toolpath(file, kind, o.gcode);
    axes_ = whole_.axes;
  }
  rapid_ = rapid_speed(cfg, axes_, o);
  cfg_ = stream_config(cfg, rapid_, o);
}

ToolpathStream::ToolpathStream(input::Toolpath tp, const JobConfig& cfg, const ToolpathOptions& o, size_t chunk)
    : whole_(std::move(tp)), axes_(whole_.axes), job_cfg_(cfg), opt_(o), chunk_(std::max<size_t>(chunk, 2)) {
  rapid_ = rapid_speed(cfg, axes_, o);
  cfg_ = stream_config(cfg, rapid_, o);
}

const std::vector<std::string>& ToolpathStream::notes() const { return reader_ ? reader_->notes() : whole_.notes; }

bool ToolpathStream::read(input::Move& m) {
  if (reader_) {
    if (reader_->next(m)) return true;
    if (totals_.moves == 0) throw input::InputError(input::no_moves(file_));
    return false;
  }
  if (whole_next_ >= whole_.moves.size()) return false;
  m = std::move(whole_.moves[whole_next_++]);
  return true;
}

// Junction j of pending_ (between moves j-1 and j): the blending leaves it as
// it is whatever the moves around it (corners::blend_corners: joins with a
// rapid, ends of exact-stop moves).
bool ToolpathStream::at_free_junction(size_t j) const {
  const auto rapid = input::Move::Kind::kRapid;
  return pending_[j - 1].kind == rapid || pending_[j].kind == rapid || pending_[j - 1].exact_stop;
}

void ToolpathStream::blend_next_chunk() {
  size_t cut = 0;  // moves to blend: pending_[0 .. cut)
  while (cut == 0) {
    for (; scanned_ < pending_.size(); ++scanned_)
      if (scanned_ >= chunk_ && at_free_junction(scanned_)) {
        cut = scanned_;
        break;
      }
    if (cut || ended_ || pending_.size() >= 2 * chunk_) break;
    input::Move m;
    if (read(m)) {
      ++totals_.moves;
      pending_.push_back(std::move(m));
      totals_.max_pending = std::max(totals_.max_pending, pending_.size());
    } else {
      ended_ = true;
    }
  }
  input::Toolpath part;
  part.axes = axes_;
  const bool starts_at_rest = !cut_inside_;
  cut_inside_ = false;
  if (cut == 0 && !ended_) {
    // no free junction: cut the last feed move read at its parameter middle
    size_t j = pending_.size() - 1;
    while (j > 0 && pending_[j].kind == input::Move::Kind::kRapid) --j;
    input::Move& m = pending_[j];
    if (m.kind == input::Move::Kind::kRapid) {
      cut = pending_.size();  // only rapids: every junction is free
    } else {
      auto halves = geo::split_at(m.curve, 0.5 * (m.curve.u_begin() + m.curve.u_end()));
      input::Move first = m;
      first.curve = std::move(halves.first);
      first.exact_stop = false;
      first.dwell = 0;
      first.pause = {};
      m.curve = std::move(halves.second);
      for (size_t i = 0; i < j; ++i) part.moves.push_back(std::move(pending_[i]));
      part.moves.push_back(std::move(first));
      pending_.erase(pending_.begin(), pending_.begin() + static_cast<long>(j));
      ++totals_.split_moves;
      cut_inside_ = true;
    }
  }
  if (part.moves.empty()) {
    if (cut == 0) cut = pending_.size();
    for (size_t i = 0; i < cut; ++i) part.moves.push_back(std::move(pending_[i]));
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<long>(cut));
  }
  scanned_ = 1;
  if (part.moves.empty()) return;
  ++totals_.chunks;
  ToolpathPlan stats;
  const input::Toolpath b =
      opt_.blend ? blend_toolpath(part, job_cfg_, opt_, stats, starts_at_rest, !cut_inside_) : part;
  totals_.corners_blended += stats.corners_blended;
  totals_.wide_blends += stats.wide_blends;
  totals_.blend_deviation = std::max(totals_.blend_deviation, stats.blend_deviation);
  totals_.corner_stops += stats.corner_stops;
  totals_.faster_stops += stats.faster_stops;
  for (const input::Move& m : b.moves) {
    StreamCurve c;
    c.curve = m.curve;
    c.where = m.where;
    const bool rapid = m.kind == input::Move::Kind::kRapid;
    const double v = rapid ? rapid_ : (m.feed > 0 ? m.feed : job_cfg_.limits.feed);
    if (!(v > 0) || !std::isfinite(v)) throw PlanError(m.where + ": feed " + util::num(v) + " mm/s must be positive");
    c.speed = std::min(v, cfg_.limits.feed);
    c.stop = m.exact_stop;
    c.dwell = m.dwell;
    const bool last = ended_ && pending_.empty() && &m == &b.moves.back();
    if (m.pause && !last) {  // a rest of kPauseRest fit ticks at least (mark_pauses)
      c.pause = m.pause;
      ++totals_.pauses;
      c.dwell = std::max(c.dwell, kPauseRest * cfg_.machine.fit_period());
    }
    (rapid ? totals_.rapid_curves : totals_.feed_curves)++;
    if (m.exact_stop && !last) ++totals_.stops;  // the path's end is a stop anyway (as toolpath_plan counts)
    ready_.push_back(std::move(c));
  }
}

bool ToolpathStream::next(StreamCurve& c) {
  while (ready_.empty()) {
    if (ended_ && pending_.empty()) return false;
    blend_next_chunk();
  }
  c = std::move(ready_.front());
  ready_.pop_front();
  return true;
}

}  // namespace traj::job
