// SPDX-License-Identifier: Apache-2.0
// trajcore planner: from a curve to a jerk-limited, time-parameterised motion.
//
// Guarantee (checked, not assumed): on the planned trajectory no per-axis
// velocity, acceleration or jerk, no tangential acceleration or jerk, no
// centripetal acceleration or jerk exceeds its limit. How:
//   * tangential a and j come from the S-curve profile (profile.hpp) with
//     a_t <= A(s) <= A_t = tan_a_share a_tan and |j_t| <= J_t;
//   * per axis, x' = T v, x'' = K v^2 + T a_t, x''' = Q v^3 + 3 K v a_t + T j_t
//     (T = dC/ds, K = d2C/ds2, Q = d3C/ds3). The limits of each axis bound
//     the sums as they are, whatever the signs (no a-priori shares):
//       |T_a| v <= v_axis,
//       |K_a| v^2 + |T_a| A(s) <= a_axis,
//       |Q_a| v^3 + 3 |K_a| v A(s) + |T_a| J_t <= j_axis;
//   * centripetal: kappa v^2 <= a_cen; |Q| v^3 + 3 kappa v A(s) <= j_cen.
//   The acceleration and jerk sums fill axis_a_share, axis_j_share of the
//   limits (headroom for the grid and the fit). At each grid point the speed
//   bound takes the sums with A(s) at its floor (a_local_floor A_t), and A(s)
//   is what they leave at that speed (at most A_t): where the curvature is
//   high the coupling costs acceleration, not speed. Every block of the
//   profile then accelerates at most at the smallest A(s) inside it, and a
//   station is placed wherever A(s) has changed 4x since the last one, so
//   that a ramp on a nearly straight stretch does not take the small A(s) of
//   a tight turn at its end.
// These give a speed bound v_lim(s), evaluated on an arc-length grid that
// contains every curvature extremum and is refined where the curvature is high;
// stations are added until the profile is under v_lim at every grid point, and
// the result is verified at every tick (verify()).
//
// Curves meeting with a tangent break (angle > corner_tol), and C0 knots
// inside a curve, are passed at the corner speed: on the tick grid the
// velocity turns within one tick, so the speed is what keeps that turn's
// per-axis acceleration and jerk and its normal acceleration and jerk within
// the limits (corner_speed in planner.cpp): a stop in practice for a visible
// corner, the feed for a 1e-5 rad kink.
#pragma once
#include <Eigen/Dense>
#include <memory>
#include <string>
#include <vector>

#include "geometry/geometry.hpp"
#include "planner/arc_table.hpp"
#include "planner/profile.hpp"

namespace traj::plan {

class PlanError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Axes a path may carry: X Y Z and A B C, U V W as a machine names them
// (input::AxisSet); the core takes up to 8.
constexpr int kMaxAxes = 8;
// Arc-length grid points one plan may hold (PlanOptions::max_grid_ds apart at
// most, closer where the curve turns): about 1.7 GB; a path needing more is
// refused naming the curve (split it: plan --window).
constexpr double kMaxGridPoints = 4e7;

struct Limits {
  double feed = 50;                        // commanded feed, units/s
  double v_axis[kMaxAxes] = {200, 200, 200, 200, 200, 200, 200, 200};
  double a_axis[kMaxAxes] = {2000, 2000, 2000, 2000, 2000, 2000, 2000, 2000};
  double j_axis[kMaxAxes] = {50000, 50000, 50000, 50000, 50000, 50000, 50000, 50000};
  double a_tan = 1000, j_tan = 20000;      // tangential
  double a_cen = 1000, j_cen = 50000;      // centripetal acceleration and its jerk
  double tol = 1e-3;                       // path tolerance (units): deviation of the output from the curve
  // The axes' letters in order, for messages and reports: the machine's
  // (input::AxisSet, e.g. "xyzac"); beyond them the rest of "xyzabcuvw".
  std::string axis_names = "xyzabcuv";
  std::string axis(int a) const { return std::string(1, axis_names.at(static_cast<size_t>(a))); }
  // The fastest the path of `dim` axes can move: the feed, or the axes'
  // velocity limits together where the feed is above them (a program's F
  // of millions of mm/min). Scales that follow the speed (the repairs'
  // floor, the report's moving ticks, the plot's colours) take it.
  double top_speed(int dim) const;
  // The slowest speed whose chords the feed figures cover (the report's feed
  // error, the fit's feed check): 1 % of the top speed.
  double feed_floor(int dim) const { return 1e-2 * top_speed(dim); }
  // Throws PlanError naming the field if any limit is non-positive or not finite.
  void validate() const;
};

// A speed cap over an arc-length interval (added by the job's repair loop
// where a tick-level check found a limit exceeded).
struct SpeedCap {
  double s0 = 0, s1 = 0, v = 0;
};
// How far an arc length along a path of the given length may be off by
// rounding (sums of curve lengths, a plan's s(t)): a few thousand ulps.
inline double arc_length_rounding(double length) { return 1e-12 * (length > 1 ? length : 1); }
// An exact stop at arc length s of a path of the given length (the end of
// a move): speed 0 over the rounding of s only, so that it holds the grid
// point of the junction and no other. Over 1e-9 of the length (11 µm on
// LinuxCNC's linuxcnc-logo.svg) it also held a grid point 4.6 µm past a
// stop, and the profile, at speed 0 at both ends of the stretch between,
// jumped over it.
inline SpeedCap stop_cap(double s, double length) {
  const double eps = arc_length_rounding(length);
  return {s - eps, s + eps, 0.0};
}

struct PlanOptions {
  double period = 1e-3;       // tick period h, s
  double corner_tol = 1e-6;   // tangent angle (rad) above which curves join with a stop
  // Headroom for the fit: the quintic through a bang-bang jerk profile
  // overshoots its jerk (up to ~1.5x), its acceleration a little. The plan
  // uses these shares of a_tan, j_tan and a_cen; the fit then checks the full
  // limits at the samples (segments.hpp), so these only set how often a fit
  // must be split or the plan slowed.
  double tan_a_share = 0.95, tan_j_share = 0.6, cen_a_share = 0.95;
  // Shortest jerk phase of a speed change, in ticks (profile.hpp: a smaller
  // change uses a lower jerk). A change whose phases are shorter than a tick
  // switches the jerk inside one tick, which no polynomial through the tick
  // samples follows within the limits; the repairs' slow-downs only make
  // such changes smaller and shorter (host/planner/README.md, "Short speed
  // changes").
  double jerk_phase_ticks = 2;
  // Straight moves between two stops are re-timed on the tick grid
  // (retime_moves_between_stops in planner.cpp): every jerk switch on a tick, so
  // that the polynomial of each tick reproduces the profile exactly and the
  // jerk may use axis_j_share of the limits instead of tan_j_share.
  bool align_straight_moves = true;
  // Curved moves between two stops on one curve are re-timed the same way
  // where the exact trajectory keeps every per-axis and centripetal sum
  // within its share at every half tick (retime_moves_between_stops).
  bool align_curved_moves = true;
  // A curved move between two stops whose cruise bound is low in a few
  // places only dips there instead of crawling from end to end (level_move
  // in planner.cpp), where that is faster and within the limits.
  bool align_level_moves = true;
  // Where a move between two stops is not re-timed as a whole, each block
  // of its profile between two stations is re-timed on the tick grid on its
  // own (retime_blocks in planner.cpp), where that is faster and within the
  // limits.
  bool align_blocks = true;
  // Plan time of the ticks: t = m period - tick_offset (m integer). A
  // streaming window whose plan starts between two ticks sets it.
  double tick_offset = 0;
  // Shares of each per-axis acceleration and jerk (and of j_cen) that the
  // sums of speed_limit may fill: headroom for the grid and the fit.
  double axis_a_share = 0.95, axis_j_share = 0.95;
  // Share of each per-axis velocity the speed bound may fill: a quintic fitted between ticks
  // overshoots a speed held exactly at the limit by ~1e-7 of it (a straight move along an axis whose
  // v_axis equals the feed would otherwise fail the fit and be capped far below).
  double axis_v_share = 0.999;
  // Share of the feed the plan may reach. Where the fit tick is coarser than
  // the engine's (job::Machine::fit_ticks) the chords between engine ticks
  // come close to the arcs of the plan, and the fitted polynomial's small
  // speed error along the path would take a plan at the feed above it.
  double feed_share = 1;
  // Corners (tangent breaks) are stops, not passed at the speed of a turn
  // within one tick. Where the fit tick is coarser than the engine's the
  // segments must end on engine ticks, and a turn at speed over a fit tick
  // reads as a large tangential jerk at the engine's (|x''_n|^2 / |x'| at the
  // almost vanishing corner speed): the machine stops there instead (the
  // corner speed was a stop in practice, a few um/s).
  bool corner_stops = false;
  // With corner_stops: the plan rests this long at each corner (seconds; 0:
  // none), so that engine ticks fall where it stands still and the segments
  // meet there at rest (fit_segments_fine).
  double corner_rest = 0;
  // Share of j_axis a curvature jump may take in the tick that steps the
  // acceleration (jump_speed in planner.cpp).
  double jump_j_share = 0.5;
  // Where the sums trade speed for tangential acceleration: the share of the
  // top speed (the one that leaves only a_local_floor) taken (speed_limit).
  double speed_share = 0.9;
  // Smallest local tangential acceleration, as a share of A_t (see the
  // header comment): below it the coupling lowers the speed instead.
  double a_local_floor = 0.05;
  // A(s) is first taken at v_lim(s); then a block that starts or ends at
  // rest takes what the sums leave at the speeds it can run at (A stored at
  // fractions of v_lim, v_lim capped there), and the faster of the two
  // profiles is kept (raise_accels in planner.cpp).
  bool accel_at_profile_speed = true;
  double max_grid_ds = 0.25;  // arc-length grid step, units
  double grid_turn = 0.02;    // grid step <= grid_turn / kappa (radians of turning per step)
  std::vector<SpeedCap> caps;
  double v_start = 0;                  // speed at the path start (a window continuing a committed plan)
  std::vector<double> force_stations;  // arc lengths that must be stations (acceleration 0 there)
  // Dwells (G4): at arc length s, where a cap of speed 0 stops the path, the
  // plan rests `seconds` (a piece at rest, Piece::dwell, after the stop).
  struct Dwell {
    double s = 0, seconds = 0;
  };
  std::vector<Dwell> dwells;
};

// A path: curves joined end to end (each a B-spline/NURBS/Bezier/line/arc).
// One curve of a path with what is derived from it alone (arc-length table,
// the arc lengths of its curvature extrema and inflections), built once and
// shared: a streaming window that re-plans a curve reuses it.
struct PathCurve {
  PathCurve(const geo::BSpline& spline, const std::string& where);  // checks axes and length
  std::unique_ptr<geo::Curve> curve;
  std::unique_ptr<geo::ArcLength> al;
  std::unique_ptr<ArcTable> table;  // fast arc-length inverse for marching (ticks, grid)
  std::string where;
  const std::vector<double>& split_s() const;  // s of geo::split_params, ascending (computed once)
  // s of the interior cusps (zero speed: the tangent turns back), ascending (computed once);
  // the planner stops there.
  const std::vector<double>& cusp_s() const;
  // Whether the curve starts (ends) with zero speed, to the cusps' 1e-7 (a
  // retracted handle): its curvature grows without bound there, so the
  // planner stops at that end.
  bool cusp_at_start() const { return cusp_start_; }
  bool cusp_at_end() const { return cusp_end_; }
 private:
  double speed_at(double u) const;  // |C'(u)|
  bool end_is_cusp(bool start) const;
  mutable std::vector<double> split_s_, cusp_s_;
  mutable bool split_done_ = false, cusp_done_ = false;
  bool cusp_start_ = false, cusp_end_ = false;
};

// The join check of Path::add (so of load_path and of every streaming window):
// the curve named `where`, starting at `start`, must have the axes of the
// previous curve (ending at `prev_end`) and start within 1e-9 * max(1, |prev_end|)
// units of that end. Throws PlanError("<where>: starts D units away from the
// previous curve's end") or PlanError("<where>: N axes, the path so far has M").
void check_join(const Eigen::VectorXd& prev_end, const Eigen::VectorXd& start, const std::string& where);

class Path {
 public:
  void add(const geo::BSpline& spline, const std::string& where);
  // Append a curve built before (shared, not copied); checks the join.
  void add(std::shared_ptr<const PathCurve> c);
  int dim() const { return dim_; }
  size_t size() const { return curves_.size(); }
  double length() const { return offsets_.empty() ? 0 : offsets_.back(); }
  const geo::Curve& curve(size_t i) const { return *curves_[i]->curve; }
  const geo::ArcLength& arclength(size_t i) const { return *curves_[i]->al; }
  const ArcTable& table(size_t i) const { return *curves_[i]->table; }
  const PathCurve& entry(size_t i) const { return *curves_[i]; }
  double offset(size_t i) const { return offsets_[i]; }  // s at the start of curve i
  size_t curve_at(double s) const;

 private:
  int dim_ = 0;
  std::vector<std::shared_ptr<const PathCurve>> curves_;
  std::vector<double> offsets_;  // size() + 1 entries
};

// Geometry at one arc length: position and derivatives with respect to s.
struct Frame {
  double s = 0, u = 0;
  size_t curve = 0;
  double C[kMaxAxes] = {}, T[kMaxAxes] = {}, K[kMaxAxes] = {}, Q[kMaxAxes] = {};
  double kappa = 0, q_norm = 0;
  double sig[3] = {0, 0, 0};  // parametric speed |C'(u)| and its first two u-derivatives
};

// Frame at curve parameter u of curve i (s given for bookkeeping); `span`, if
// known (>= 0), is the power-basis span to evaluate (saves the span search).
Frame frame_at(const Path& p, size_t curve, double u, double s, int span = -1);

struct Plan {
  std::vector<Piece> pieces;  // s(t), from t = 0 to duration()
  std::vector<Station> stations;
  double length = 0;
  double duration() const { return pieces.empty() ? 0 : pieces.back().t0 + pieces.back().T; }
  int grid_points = 0, refinements = 0;
  // Frames evaluated by the exact checks of the moves re-timed on the tick
  // grid (step 5 of host/planner/README.md): the re-timing's work.
  long long check_frames = 0;
  double A_t = 0, J_t = 0;    // effective tangential limits used (A_t: the largest; blocks may use less)
};

// Speed bound at a frame (see the header comment) with the coupling terms
// bounded by a tangential acceleration A_t; with A_loc, the local tangential
// acceleration chosen there is returned in *A_loc and used for the coupling.
double speed_limit(const Frame& f, const Limits& L, const PlanOptions& o, double A_t, double J_t, int dim,
                   double* A_loc = nullptr);

// The searches of earlier plans for the re-timing of curved moves between
// stops (README.md, step 5, "Work"), for later plans of the same path with
// the same limits and options but for `caps`, `force_stations` and
// `tick_offset`: the
// repair rounds of job::plan_and_fit, each of which plans the whole path
// again with a few more caps. Such a search depends on its move's ends, its
// speed bound and the time the move took as planned (max_T); a later plan
// takes an earlier search's result where the ends and the bound are the same
// and every comparison that search made against max_T comes out the same for
// the new one, so the plan is the one the search would give.
class RetimeMemo {
 public:
  RetimeMemo();
  ~RetimeMemo();
  RetimeMemo(const RetimeMemo&) = delete;
  RetimeMemo& operator=(const RetimeMemo&) = delete;
  long long reused = 0, searched = 0;  // moves taken from here, and searched

  struct Searches;  // planner.cpp
  std::unique_ptr<Searches> searches;
  const Path* path = nullptr;  // the path it holds searches of
};

// retimed (optional): searches of earlier plans of the same path, limits and
// options but for caps, force_stations and tick_offset; this plan's are added.
Plan plan_path(const Path& p, const Limits& L, const PlanOptions& o, RetimeMemo* retimed = nullptr);

// Kinematic state along the path at time t.
struct PathState {
  double s, v, a, j;
};
PathState state_at(const Plan& plan, double t, int* hint = nullptr);

// Per-tick samples of the planned trajectory: position and time derivatives.
struct TickSample {
  double t, s, v, a, j;  // path (t: the tick's time, k h)
  double tp;             // the plan's own time of the tick
  double u;
  size_t curve;
  int span;  // power-basis span of the curve that holds u
  double x[kMaxAxes], dx[kMaxAxes], ddx[kMaxAxes], dddx[kMaxAxes];
  double a_cen, j_cen_geo;  // centripetal acceleration kappa v^2, jerk bound |Q| v^3 + 3 kappa v |a|
};
// Where a search for the plan's piece, curve and arc-length table piece
// starts (any values are correct; nearby ones are fast).
struct SampleHints {
  int piece = 0, table = 0;
  size_t curve = static_cast<size_t>(-1);
};
// The plan at its time tp (t: the sample's tick time, kept as given).
TickSample sample_plan(const Path& p, const Plan& plan, double tp, double t, SampleHints& hints);
std::vector<TickSample> sample_ticks(const Path& p, const Plan& plan, double period);
// The same into `out` (cleared first; its storage is kept: a caller that
// samples round after round holds one buffer, not two at a time).
void sample_ticks(const Path& p, const Plan& plan, double period, std::vector<TickSample>& out);
// Ticks k_first..k_last (global indices) of a plan that starts at global time
// k_origin h + t_offset: tick k is at plan time (k - k_origin) h - t_offset
// (clamped to the plan). A streaming caller keeps t_offset below a tick and
// the tick count in k_origin, so the plan time of a tick keeps full double
// precision however long the path runs (k h alone loses it past 2^25 ticks).
std::vector<TickSample> sample_ticks_range(const Path& p, const Plan& plan, double period, double t_offset,
                                           long long k_first, long long k_last);
// The same, appended to `out` (whose storage a caller can reuse window after
// window: no allocation, no page faults once it has grown; it grows with an
// eighth of room, untouched until used, so that a round a little longer than
// the last does not move it).
void append_ticks_range(const Path& p, const Plan& plan, double period, double t_offset, long long k_first,
                        long long k_last, std::vector<TickSample>& out, long long k_origin = 0);

struct Peaks {
  double v_axis[kMaxAxes] = {}, a_axis[kMaxAxes] = {}, j_axis[kMaxAxes] = {};
  double feed = 0, a_tan = 0, j_tan = 0, a_cen = 0, j_cen = 0;
};
Peaks peaks_of(const std::vector<TickSample>& ts, int dim);
// Largest ratio of a kinematic quantity at one tick to its limit.
double tick_ratio(const TickSample& t, const Limits& L, int dim);
// Largest ratio of a peak to its limit (<= 1 means every limit holds).
double worst_ratio(const Peaks& pk, const Limits& L, int dim, std::string* which = nullptr);

}  // namespace traj::plan
