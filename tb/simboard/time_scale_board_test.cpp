// SPDX-License-Identifier: Apache-2.0
// Time scaling on the simulated board (rtl/traj_board.sv with its
// traj_time_scale, Verilated): feed override and feed hold over the link
// (FEED), a hold from the board's pin, and starvation (the host stops
// sending for a while), each at random servo ticks of the butterfly and of a
// G1 polyline with blended corners. A small sender in this file plays the
// role of the upload tool, in board time, so that every run is reproducible
// from its seed. Checked on the board's own output samples (one per servo
// tick, the step generator's input), apart from the code that plans and the
// unit's reference:
//   * on the path: every sample lies on the polyline through the unscaled
//     trajectory's engine samples (the host's exact prediction), within
//     2 LSB per axis, at a position that never goes back and advances by at
//     most s_max engine ticks per engine tick: the same points, re-timed;
//   * limits: per-axis velocity, acceleration and jerk from the samples'
//     differences at the servo tick <= 1.00 x the machine's limits (the plan
//     keeps 70 % / 40 % of them, the ramp bounds the rest);
//   * no underrun, no tick error; a starved hold is counted and resumes;
//     a hold comes to rest (S = 0, the output still) and resumes from there;
//   * the job ends on its last sample (nothing lost) with the end reported.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <sstream>

#include "board/sim_board.hpp"
#include "board/step_check.hpp"
#include "input/gcode.hpp"
#include "job/toolpath_job.hpp"
#include "link/frame.hpp"
#include "link/record_source.hpp"
#include "link/upload.hpp"
#include "stream/segment_stream.hpp"
#include "test_seed.hpp"
#include "timescale/scaled_butterfly.hpp"

namespace traj {
namespace {

using board::BoardBuild;
using board::SimulatedBoard;

constexpr double kServo = 1e-3;  // servo tick, s
constexpr int kP = 3;            // 2^3 engine ticks of 125 us per servo tick
constexpr double kEngineTick = kServo / (1 << kP);
constexpr double kSMax = 1.2;

// What happens when, in servo ticks after START.
struct Event {
  enum Kind { kOverride, kFeedHold, kPinHold, kStarve } kind;
  uint64_t at, length;  // hold and starve: for `length` servo ticks
  double value = 0;     // override: the new s
};

struct Run {
  std::vector<int64_t> out;  // output samples, 3 per servo tick
  std::vector<link::Status> statuses;
  link::Status last;
  bool ended = false;
  uint64_t servo_ticks = 0;
  uint64_t unit_busy_max = 0, engine_answer_max = 0;  // clocks (SimulatedBoard)
};

// The stream of `p` with its time-scaling fields, written where the link's
// record source reads it.
std::string write_stream(ScaledPlan& p, const timescale::RampBounds& rb, const std::string& name) {
  p.res.header.scale_max = std::floor(kSMax * stream::kScaleMaxUnit) / stream::kScaleMaxUnit;
  p.res.header.scale_rate = static_cast<float>(rb.rate);
  p.res.header.scale_accel = static_cast<float>(rb.accel);
  const std::string path = (std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + ".trj")).string();
  stream::write_file(path, p.res.header, job::records_of(p.res));
  return path;
}

// Plays `stream_path` on a simulated board with the events, as the upload
// tool would (RESET, CONFIG with time scaling, records kept `ahead_ticks`
// engine ticks ahead of the board, START, END), in board time.
Run play(const std::string& stream_path, const timescale::IntBounds& ib, const std::vector<Event>& events,
         uint64_t ahead_ticks) {
  SimulatedBoard b;
  b.keep_samples(true);
  link::FrameDecoder dec;
  Run r;
  uint32_t acked = 0;
  link::Bytes out;
  auto send = [&](link::Type t, uint32_t seq, const link::Bytes& payload = {}) {
    const link::Bytes f = link::encode_frame(t, seq, payload);
    b.receive(f.data(), f.size(), out);
  };
  auto step = [&](uint64_t cycles) {
    out.clear();
    b.run(cycles, out);
    std::vector<link::FrameDecoder::Event> ev;
    dec.feed(out.data(), out.size(), ev);
    for (const auto& e : ev) {
      ASSERT_TRUE(e.good) << e.why;
      const link::Frame& f = e.frame;
      if (f.type == link::Type::kNak) FAIL() << "NAK " << int(link::decode_nak(f).reason) << " at seq " << f.seq;
      if (f.type == link::Type::kAck) acked = f.seq;
      if (f.type == link::Type::kStatus) {
        r.last = link::decode_status(f);
        acked = f.seq;
        r.statuses.push_back(r.last);
      }
    }
  };
  const uint64_t clocks = std::llround(kServo * BoardBuild::kClkHz);
  send(link::Type::kReset, 0);
  step(20000);
  link::Config c;
  c.tick_clocks = static_cast<uint32_t>(clocks);
  c.status_ticks = 5;
  for (int a = 0; a < 8; ++a) c.step_shift[a] = 26;
  c.pulse_clocks = 30;
  c.dir_setup_clocks = 60;
  c.enable = 1;
  c.scale_m = static_cast<uint32_t>(ib.m);
  c.scale_s_max = static_cast<uint32_t>(ib.s_max);
  c.scale_override = 1u << ib.scale_bits;
  c.scale_shift = static_cast<uint8_t>(32 - ib.scale_bits + kP);
  c.scale_flags = link::config_flag::kAutoResume;
  send(link::Type::kConfig, 0, link::encode_config(c));
  step(20000);

  link::RecordSource src(stream_path, 0);
  link::Bytes rec;
  uint32_t sent = 0;
  bool more = true, end_sent = false;
  uint64_t ahead_known = 0;  // engine ticks ahead, from the last STATUS
  auto feed = [&](double s, bool hold) {
    link::Feed f;
    f.override_s = static_cast<uint32_t>(std::llround(std::ldexp(s, ib.scale_bits)));
    f.hold = hold;
    send(link::Type::kFeed, 0, link::encode_feed(f));
  };
  // prefill: one second of motion, then START
  uint64_t queued = 0;
  while (more && queued < ahead_ticks && (more = src.next(rec))) {
    send(link::Type::kSegment, sent++, rec);
    queued += link::get_u32(&rec[4]);
    step(4000);
  }
  send(link::Type::kStart, 0);
  uint64_t tick = 0;
  bool feed_hold = false;
  double override_s = 1;
  const uint64_t limit_ticks = 120000;
  while (tick < limit_ticks) {
    // the events of this servo tick
    bool starving = false;
    for (const Event& e : events) {
      const bool in = tick >= e.at && tick < e.at + e.length;
      switch (e.kind) {
        case Event::kOverride:
          if (tick == e.at) feed(override_s = e.value, feed_hold);
          break;
        case Event::kFeedHold:
          if (tick == e.at) feed(override_s, feed_hold = true);
          if (tick == e.at + e.length) feed(override_s, feed_hold = false);
          break;
        case Event::kPinHold:
          if (tick == e.at) b.set_hold_pin(true);
          if (tick == e.at + e.length) b.set_hold_pin(false);
          break;
        case Event::kStarve:
          starving = starving || in;
          break;
      }
    }
    // keep the board `ahead_ticks` engine ticks ahead (by its STATUS; the
    // records in flight count as sent), unless starving it
    ahead_known = r.last.ticks_ahead;
    if (!starving && more && acked == sent && ahead_known < ahead_ticks) {
      if ((more = src.next(rec))) send(link::Type::kSegment, sent++, rec);
    }
    if (!more && !end_sent && acked == sent) {
      send(link::Type::kEnd, sent);
      end_sent = true;
    }
    // after END, ask: the periodic STATUS stops with the ticks
    if (end_sent && tick % 50 == 0) send(link::Type::kStatusReq, 0);
    step(clocks);
    ++tick;
    if (r.last.flags & link::status_flag::kEndReached) break;
  }
  EXPECT_LT(tick, limit_ticks) << "the job did not end";
  b.drain();
  r.ended = (r.last.flags & link::status_flag::kEndReached) != 0;
  r.out = b.samples();
  r.servo_ticks = b.sample_cycles().size();
  r.unit_busy_max = b.unit_busy_max();
  r.engine_answer_max = b.engine_answer_max();
  std::printf("  the unit busy at most %llu clocks of a servo tick, the engine's answer at most %llu clocks\n",
              static_cast<unsigned long long>(r.unit_busy_max), static_cast<unsigned long long>(r.engine_answer_max));
  return r;
}

const char* const kQuantity[3] = {"velocity", "acceleration", "jerk"};

// The largest share of each per-axis limit (velocity, acceleration, jerk)
// in the output's differences at the servo tick.
std::array<double, 3> worst_of_limits(const ScaledPlan& p, const Run& r) {
  std::array<double, 3> worst{0, 0, 0};
  const uint64_t m = r.out.size() / 3;
  const double H = kServo;
  for (uint64_t t = 3; t < m; ++t)
    for (int a = 0; a < 3; ++a) {
      auto x = [&](uint64_t k) { return static_cast<double>(r.out[3 * k + a]) * p.lsb; };
      const double d1 = x(t) - x(t - 1), d2 = d1 - (x(t - 1) - x(t - 2)), d3 = d2 - (x(t - 1) - 2 * x(t - 2) + x(t - 3));
      worst[0] = std::max(worst[0], std::fabs(d1) / H / p.limits[a].v);
      worst[1] = std::max(worst[1], std::fabs(d2) / (H * H) / p.limits[a].a);
      worst[2] = std::max(worst[2], std::fabs(d3) / (H * H * H) / p.limits[a].j);
    }
  for (int i = 0; i < 3; ++i) std::printf("  %s: %.3f of the limit at most\n", kQuantity[i], worst[i]);
  return worst;
}

// The checks above, on the run's output against the unscaled engine samples.
void check(const ScaledPlan& p, const timescale::IntBounds& ib, const Run& r, const std::vector<Event>& events) {
  ASSERT_TRUE(r.ended);
  EXPECT_EQ(r.last.underruns, 0u);
  EXPECT_EQ(r.last.flags & (link::status_flag::kTickError | link::status_flag::kUnderrunHalt), 0);
  const uint64_t m = r.out.size() / 3;
  ASSERT_GT(m, 10u);
  // on the path (2 LSB: the engine samples' rounding and the interpolation's
  // floor), at most s_max 2^p engine ticks per servo tick, ending on the last sample
  const board::PathCheck pc = board::check_on_path(p.samples, r.out, 3, 2.0, kSMax * (1 << kP));
  std::printf("  %s", board::describe(pc).c_str());
  EXPECT_TRUE(pc.ok()) << pc.first_problem;
  // limits at the servo tick
  const std::array<double, 3> worst = worst_of_limits(p, r);
  for (int i2 = 0; i2 < 3; ++i2) EXPECT_LE(worst[i2], 1.0) << kQuantity[i2];
  // holds come to rest (S = 0) and resume; starvation is counted
  const bool starve =
      std::any_of(events.begin(), events.end(), [](const Event& e) { return e.kind == Event::kStarve; });
  bool starved_flag = false;
  uint32_t s_max_seen = 0;
  for (const link::Status& s : r.statuses) {
    starved_flag = starved_flag || (s.flags & link::status_flag::kStarved);
    s_max_seen = std::max(s_max_seen, s.scale_s);
  }
  EXPECT_LE(s_max_seen, ib.s_max);
  // each hold is at rest (S = 0, held) by its end; STATUS counts servo ticks
  // from START as the events do
  for (const Event& e : events) {
    if (e.kind != Event::kFeedHold && e.kind != Event::kPinHold) continue;
    bool rest = false;
    for (const link::Status& s : r.statuses)
      if (s.ticks_played >= e.at && s.ticks_played < e.at + e.length && s.scale_s == 0 &&
          (s.flags & link::status_flag::kHeld))
        rest = true;
    EXPECT_TRUE(rest) << "the hold at servo tick " << e.at << " did not come to rest";
  }
  if (starve) {
    EXPECT_GE(r.last.starved_holds, 1u);
    EXPECT_TRUE(starved_flag);
  }
  std::printf("  %llu servo ticks, %u starved holds, largest S %u (s %.3f)\n",
              static_cast<unsigned long long>(r.servo_ticks), r.last.starved_holds, s_max_seen,
              std::ldexp(static_cast<double>(s_max_seen), -ib.scale_bits));
}

// The host's clock bounds (what `trajcore upload` checks a servo tick
// against) hold on the board's RTL: the engine's answer to a tick, and the
// unit's work in a servo tick.
void check_clocks(const ScaledPlan& p, const timescale::IntBounds& ib, const Run& r) {
  const fd::Format f = p.res.header.format();
  const int engine = link::board_engine_clocks(f);
  const uint64_t unit = timescale::unit_tick_clocks(ib, kP, f.axes, engine);
  std::printf("  bounds: the engine's answer %d clocks, the unit's servo tick %llu clocks\n", engine,
              static_cast<unsigned long long>(unit));
  EXPECT_LE(r.engine_answer_max, static_cast<uint64_t>(engine));
  EXPECT_LE(r.unit_busy_max, unit);
  EXPECT_GT(r.unit_busy_max, 0u);
}

// Random event ticks over the motion (the unscaled duration in servo ticks).
std::vector<Event> random_events(std::mt19937_64& rng, uint64_t motion_ticks) {
  auto at = [&](double lo, double hi) {
    return static_cast<uint64_t>(motion_ticks * (lo + (hi - lo) * std::uniform_real_distribution<double>(0, 1)(rng)));
  };
  std::vector<Event> e;
  e.push_back({Event::kOverride, at(0.05, 0.15), 0, 1.2});
  e.push_back({Event::kFeedHold, at(0.2, 0.3), 900, 0});
  e.push_back({Event::kOverride, at(0.35, 0.45), 0, 0.5});
  e.push_back({Event::kPinHold, at(0.5, 0.6), 900, 0});
  e.push_back({Event::kOverride, at(0.62, 0.65), 0, 1.0});
  e.push_back({Event::kStarve, at(0.7, 0.8), 2500, 0});
  for (const Event& x : e)
    std::printf("  event %d at servo tick %llu for %llu (%g)\n", x.kind, static_cast<unsigned long long>(x.at),
                static_cast<unsigned long long>(x.length), x.value);
  return e;
}

// ramp_gain_log2 > 0: ramps 2^gain faster than the bounds (the jerk step of
// s that much larger), which must break a limit while the path still holds.
void run_case(ScaledPlan p, const std::string& name, uint64_t seed, int ramp_gain_log2 = 0) {
  std::mt19937_64 rng(seed);
  const timescale::OutputError err{kEngineTick, kServo, p.lsb};
  const timescale::RampBounds rb = timescale::derive_ramp_bounds(p.peaks, p.limits, kSMax, err);
  timescale::IntBounds ib = timescale::integer_bounds(rb, kServo);
  if (ramp_gain_log2 > 0) {
    ib.scale_bits -= ramp_gain_log2;
    ib.s_max = static_cast<int64_t>(std::floor(std::ldexp(kSMax, ib.scale_bits)));
  }
  std::printf("  ramp bounds: |ds/dt| <= %.4g /s, |d2s/dt2| <= %.4g /s^2; scale bits %d, m %lld, S_max %lld\n", rb.rate,
              rb.accel, ib.scale_bits, static_cast<long long>(ib.m), static_cast<long long>(ib.s_max));
  const std::string path = write_stream(p, rb, name);
  const uint64_t motion_ticks = p.n >> kP;
  if (ramp_gain_log2 > 0) {
    const std::vector<Event> events{{Event::kOverride, motion_ticks / 5, 0, 0.5},
                                    {Event::kFeedHold, motion_ticks / 2, 300, 0}};
    const Run r = play(path, ib, events, 8 * 1000);
    std::filesystem::remove(path);
    check_clocks(p, ib, r);
    const board::PathCheck pc = board::check_on_path(p.samples, r.out, 3, 2.0, kSMax * (1 << kP));
    EXPECT_TRUE(pc.ok()) << pc.first_problem;
    const std::array<double, 3> worst = worst_of_limits(p, r);
    EXPECT_GT(std::max(worst[1], worst[2]), 1.0) << "ramps " << (1 << ramp_gain_log2)
                                                  << " times faster than the bounds kept every limit";
    return;
  }
  const std::vector<Event> events = random_events(rng, motion_ticks);
  // 1 s of motion ahead (twice the longest stop and more, so that a starved
  // hold resumes once the data is back): a starvation of 2.5 s empties it
  const Run r = play(path, ib, events, 8 * 1000);
  std::filesystem::remove(path);
  check_clocks(p, ib, r);
  check(p, ib, r, events);
}

TEST(SimBoardTimeScale, ButterflyHoldOverrideStarvation) {
  ScaledPlan p = scaled_plan(butterfly_path(), job::JobConfig{}, kEngineTick, 96);
  run_case(std::move(p), "butterfly", test::test_seed(16));
}

// a zigzag of G1 moves, its corners blended (G64 P0.01)
ScaledPlan zigzag() {
  std::istringstream g(
      "G21 G90 G64 P0.01 F3000\nG1 X0 Y0\nG1 X20 Y5\nG1 X5 Y15\nG1 X30 Y20\nG1 X10 Y35\nG1 X40 Y40\nG1 X0 Y45\n"
      "G1 X25 Y60\nM2\n");
  const input::Toolpath tp = input::read_gcode(g, "zigzag.ngc");
  const job::ToolpathPlan tpp = job::toolpath_plan(tp, job::JobConfig{});
  return scaled_plan(tpp.path, tpp.cfg, kEngineTick, 96);
}

TEST(SimBoardTimeScale, G1PolylineHoldOverrideStarvation) { run_case(zigzag(), "zigzag", test::test_seed(17)); }

// The limit check can fail: the board's ramps 16 times faster than the
// bounds (an override and a hold) break the acceleration or jerk limit.
TEST(SimBoardTimeScale, RampsFasterThanTheBoundsBreakALimit) { run_case(zigzag(), "zigzag_fast", 18, 4); }

// board::check_on_path where the path comes back onto itself: x out to 1000 LSB and back
// (engine samples 10 LSB apart, y 0), outputs 9.5 engine ticks apart, interpolated with floor
// as the unit does. Near the turn an output matches a place on the way out and one on the way
// back; the check follows the one its last advance predicts (outline_2d.ngc under an override
// failed so on the simulated board: "output sample 10823 is not on the path"). An output 3 LSB
// off the path, or one that goes back, is still found.
TEST(SimBoardTimeScale, OnPathCheckFollowsAPathThatComesBack) {
  std::vector<int64_t> engine;
  for (int k = 0; k <= 100; ++k) engine.insert(engine.end(), {10 * k, 0, 0});
  for (int k = 99; k >= 0; --k) engine.insert(engine.end(), {10 * k, 0, 0});
  const int64_t n = static_cast<int64_t>(engine.size() / 3);
  auto at = [&](int64_t q) {  // position q / 16 engine ticks, floor-interpolated per axis
    const int64_t k = std::min(q / 16, n - 1), f = q % 16;
    const int64_t y0 = engine[3 * k], y1 = k + 1 < n ? engine[3 * (k + 1)] : y0;
    const int64_t d = (y1 - y0) * f;
    return std::array<int64_t, 3>{y0 + (d >= 0 ? d / 16 : -((-d + 15) / 16)), 0, 0};
  };
  std::vector<int64_t> out;
  for (int64_t q = 0; q < 16 * (n - 1); q += 152) {  // 9.5 engine ticks
    const auto p = at(q);
    out.insert(out.end(), p.begin(), p.end());
  }
  out.insert(out.end(), {0, 0, 0});
  const board::PathCheck ok = board::check_on_path(engine, out, 3, 2.0, 9.6);
  EXPECT_TRUE(ok.ok()) << ok.first_problem;
  EXPECT_NEAR(ok.largest_advance, 9.5, 1e-9);
  std::vector<int64_t> off = out;
  ASSERT_EQ(out.size(), 3u * 23);
  off.at(3 * 11 + 1) += 3;  // just past the turn
  const std::string off_problem = board::check_on_path(engine, off, 3, 2.0, 9.6).first_problem;
  EXPECT_NE(off_problem.find("output sample 11 is not on the path"), std::string::npos) << off_problem;
  std::vector<int64_t> back = out;
  std::copy(out.begin() + 3 * 5, out.begin() + 3 * 6, back.begin() + 3 * 6);  // sample 6 repeats sample 5's place... 
  std::copy(out.begin() + 3 * 4, out.begin() + 3 * 5, back.begin() + 3 * 7);  // ...and sample 7 goes back to 4's
  EXPECT_NE(board::check_on_path(engine, back, 3, 2.0, 9.6).first_problem.find("output sample 7 is not on the path"),
            std::string::npos);
  // A rest of 40 engine samples: every one matches an output there; none more than 9.6 ahead
  // of the last output may be taken (the sim_timescale CLI run failed so: "advanced 9.998").
  std::vector<int64_t> rest;
  for (int k = 0; k <= 50; ++k) rest.insert(rest.end(), {7 * k, 0, 0});
  for (int k = 0; k < 40; ++k) rest.insert(rest.end(), {350, 0, 0});
  for (int k = 51; k <= 100; ++k) rest.insert(rest.end(), {7 * k, 0, 0});
  std::vector<int64_t> rest_out;
  const int64_t rn = static_cast<int64_t>(rest.size() / 3);
  for (int64_t q = 0; q < 16 * (rn - 1); q += 153) {  // 9.5625 engine ticks
    const int64_t k = q / 16, f = q % 16, y0 = rest[3 * k], y1 = rest[3 * (k + 1)];
    rest_out.insert(rest_out.end(), {y0 + (y1 - y0) * f / 16, 0, 0});
  }
  rest_out.insert(rest_out.end(), rest.end() - 3, rest.end());
  const board::PathCheck at_rest = board::check_on_path(rest, rest_out, 3, 2.0, 9.6);
  EXPECT_TRUE(at_rest.ok()) << at_rest.first_problem;
  EXPECT_LE(at_rest.largest_advance, 9.6 + 0.01);
}

// A stop at a 90 degree corner: the engine samples crowd at the vertex (a cubic slow-down to it and
// speed-up from it), so outputs there match many places, and one guess per output can fall behind and
// then find the next output more than max_advance ahead (outline_2d.ngc with a corner stop failed so:
// "the output advanced 9.795 engine ticks"). The check keeps every place until later outputs decide.
TEST(SimBoardTimeScale, OnPathCheckThroughACornerStop) {
  std::vector<int64_t> engine;
  const int half = 40;
  for (int k = 0; k <= half; ++k) {
    const double u = 1.0 - double(k) / half;
    engine.insert(engine.end(), {std::llround(1000 * (1 - u * u * u)), 0, 0});
  }
  for (int k = 1; k <= half; ++k) {
    const double u = double(k) / half;
    engine.insert(engine.end(), {1000, std::llround(1000 * u * u * u), 0});
  }
  const int64_t n = static_cast<int64_t>(engine.size() / 3);
  for (const int64_t step : {150, 151, 152, 153}) {  // 9.375 .. 9.5625 engine ticks (at most 9.6)
    std::vector<int64_t> out;
    for (int64_t q = 0; q < 16 * (n - 1); q += step) {
      const int64_t k = q / 16, f = q % 16;
      for (int a = 0; a < 3; ++a) {
        const int64_t y0 = engine[3 * k + a], y1 = engine[3 * (k + 1) + a], d = (y1 - y0) * f;
        out.push_back(y0 + (d >= 0 ? d / 16 : -((-d + 15) / 16)));
      }
    }
    out.insert(out.end(), engine.end() - 3, engine.end());
    const board::PathCheck c = board::check_on_path(engine, out, 3, 2.0, 9.6);
    EXPECT_TRUE(c.ok()) << "outputs " << step / 16.0 << " engine ticks apart: " << c.first_problem;
    EXPECT_LE(c.largest_advance, 9.61) << step;
  }
}

}  // namespace
}  // namespace traj
