// A toolpath (G-code, SVG, DXF) streamed in bounded memory: the moves are read
// as the planning windows need curves (G-code a line at a time; SVG and DXF
// are read whole, then streamed), blended in chunks, and given to
// run_streaming with each move's speed and exact stop.
//
// Chunks. The corner blends of a chunk must be those of the whole toolpath,
// or at least as valid: a chunk of about `chunk` moves ends
//   * at a junction the blending leaves as it is whatever comes next (a rapid
//     on either side, or the end of an exact-stop move): the blends on both
//     sides are exactly those of the whole toolpath;
//   * else, after 2 `chunk` moves, inside the last feed move read, cut at its
//     parameter middle (geo::split_at: the same curve, a tangent- and
//     curvature-continuous join, which neither the blending nor the planner
//     sees as a corner). The corners next to the cut move then take at most
//     half of each half (a blend shortened to the half move's share, still
//     within the tolerance) and a run of corners ends at the cut.
// Speeds and stops as toolpath_plan gives them (its blend_toolpath and
// rapid_speed). The feed limit of the stream is the larger of the job's feed
// and the rapid speed (a whole toolpath takes the fastest move's speed, which
// a stream does not know in advance): a programmed feed above it runs at it.
#pragma once
#include <deque>
#include <memory>
#include <string>

#include "input/gcode.hpp"
#include "input/toolpath_file.hpp"
#include "job/streaming.hpp"
#include "job/toolpath_job.hpp"

namespace traj::job {

class ToolpathStream : public StreamSource {
 public:
  // A file (G-code read incrementally; SVG and DXF whole).
  ToolpathStream(const std::string& file, input::FileKind kind, const JobConfig& cfg, const ToolpathOptions& o = {},
                 size_t chunk = 256);
  // A toolpath in memory.
  ToolpathStream(input::Toolpath tp, const JobConfig& cfg, const ToolpathOptions& o = {}, size_t chunk = 256);

  bool next(StreamCurve& c) override;

  // The configuration to stream with: the feed limit above, and the fit's
  // share of the tolerance (1 - blend_share) when the corners are blended.
  const JobConfig& config() const { return cfg_; }

  struct Totals {
    size_t moves = 0, chunks = 0, split_moves = 0;  // moves read; chunks blended; moves cut between chunks
    size_t feed_curves = 0, rapid_curves = 0, stops = 0;
    size_t pauses = 0;  // program pauses (--pause-wait), each a pause record in the stream
    int corners_blended = 0, wide_blends = 0;
    double blend_deviation = 0;  // largest, mm
    size_t corner_stops = 0, faster_stops = 0;  // corners left as stops; of them, faster so
    size_t max_pending = 0;      // most moves held at once
  };
  const Totals& totals() const { return totals_; }
  const std::vector<std::string>& notes() const;

 private:
  bool read(input::Move& m);
  bool at_free_junction(size_t j) const;
  void blend_next_chunk();

  std::string file_;  // the file read (messages)
  std::unique_ptr<input::GcodeReader> reader_;
  input::Toolpath whole_;  // SVG, DXF, or a toolpath given in memory
  size_t whole_next_ = 0;
  int axes_ = 3;
  JobConfig job_cfg_, cfg_;
  ToolpathOptions opt_;
  double rapid_ = 0;
  size_t chunk_;
  bool ended_ = false;
  bool cut_inside_ = false;  // the last chunk ended inside a move: the next one starts at speed
  std::deque<input::Move> pending_;  // read, not yet blended
  size_t scanned_ = 1;               // junctions of pending_ below this were not free
  std::deque<StreamCurve> ready_;    // blended, not yet taken
  Totals totals_;
};

}  // namespace traj::job
