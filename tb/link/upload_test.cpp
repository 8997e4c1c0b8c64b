// trajcore upload's client against the loopback board over an in-process
// pipe, with faults in the byte path: the records the board plays are
// compared byte for byte with the stream file's (read by the stream reader):
// none lost, duplicated or reordered whenever the link recovers; a clear error
// and a board that holds still (a prefix of the job played) when it cannot.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

#include "input/raster.hpp"
#include "input/toolpath_file.hpp"
#include "job/toolpath_job.hpp"
#include "job/toolpath_stream.hpp"
#include "job/job.hpp"
#include "job/streaming.hpp"
#include "link/board_server.hpp"
#include "link/upload.hpp"
#include "stream/segment_stream.hpp"
#include "tmp_file.hpp"

namespace traj::link {
namespace {

// Time-scaling fields written into a stream header (as `trajcore plan
// --time-scale` writes them); scale_max 0: none.
struct ScaleHeader {
  double scale_max = 0;
  float rate = 0, accel = 0;
  double period = 0;  // the engine tick written (0: the machine's)
};

// A raster job of `pieces` pieces planned into a stream file once per size
// (and header).
const std::string& raster_stream(size_t pieces, const ScaleHeader& ts = {}) {
  static std::map<std::string, std::unique_ptr<test::TmpFile>> made;  // removed at exit
  const std::string key = std::to_string(pieces) + "_" + std::to_string(ts.scale_max) + "_" +
                          std::to_string(ts.rate) + "_" + std::to_string(ts.accel) + "_" + std::to_string(ts.period);
  auto it = made.find(key);
  if (it != made.end()) return it->second->path;
  auto file = std::make_unique<test::TmpFile>("traj_link_raster_" + std::to_string(made.size()) + "_" +
                                              std::to_string(pieces) + ".trj");
  const std::string& path = file->path;
  job::JobConfig cfg;
  input::RasterSource src(pieces);
  stream::Header h = cfg.machine.header();
  h.scale_max = ts.scale_max;
  h.scale_rate = ts.rate;
  h.scale_accel = ts.accel;
  if (ts.period > 0) h.period = ts.period;  // records count ticks: any tick period plays them
  stream::StreamWriter w(path, h);
  job::run_streaming(src, cfg, job::StreamOptions{}, job::write_to(w));
  w.finish();
  return (made[key] = std::move(file))->path;
}

std::vector<Bytes> file_records(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  stream::StreamReader r(in, path);
  std::vector<Bytes> out;
  stream::Record rec;
  while (r.next(rec)) out.push_back(r.raw());
  EXPECT_TRUE(r.complete()) << r.error();
  return out;
}

// A board with the time-scale unit as far as the host sees it: the loopback
// board behind a filter that takes CONFIG's time-scaling fields (recorded,
// then zeroed for the loopback), answers FEED itself (recorded; ACK, or NAK 4
// when told to), and reports in STATUS the S of the last FEED or CONFIG (0
// and the held flag while held).
class TimeScaleShim : public Board {
 public:
  explicit TimeScaleShim(LoopbackBoard& inner) : inner_(inner) {}
  void receive(const uint8_t* p, size_t n, Bytes& out) override {
    events_.clear();
    dec_.feed(p, n, events_);
    for (auto& e : events_) {
      if (!e.good) {
        const Bytes bad = {kFlag, 0x01, kFlag};  // a bad body: the board's NAK 1
        inner_.receive(bad.data(), bad.size(), out);
        continue;
      }
      Frame f = e.frame;
      if (f.type == Type::kFeed) {
        on_feed(f, out);
        continue;
      }
      if (f.type == Type::kConfig && f.payload.size() == kConfigBytes) on_config(f);
      const size_t from = out.size();
      const Bytes w = encode_frame(f);
      inner_.receive(w.data(), w.size(), out);
      patch_status(out, from);
    }
  }
  void advance(double now, Bytes& out) override {
    const size_t from = out.size();
    inner_.advance(now, out);
    patch_status(out, from);
  }
  void reset() override { inner_.reset(); }
  bool end_reached() const override { return inner_.end_reached(); }
  bool playing() const override { return inner_.playing(); }
  uint64_t stored_total() const override { return inner_.stored_total(); }

  std::vector<Config> configs() {
    std::lock_guard<std::mutex> l(m_);
    return configs_;
  }
  std::vector<Feed> feeds() {
    std::lock_guard<std::mutex> l(m_);
    return feeds_;
  }
  std::atomic<bool> refuse_feed{false};

 private:
  void on_config(Frame& f) {
    std::lock_guard<std::mutex> l(m_);
    configs_.push_back(decode_config(f.payload));
    s_ = configs_.back().scale_override;
    held_ = false;
    std::fill(f.payload.begin() + 24, f.payload.end(), 0);
  }
  void on_feed(const Frame& f, Bytes& out) {
    const Status s = inner_.status();
    if (refuse_feed) {
      const Bytes w = encode_frame(Type::kNak, s.next_seq, encode_nak({s.next_seq, 4, uint16_t(s.credits)}));
      out.insert(out.end(), w.begin(), w.end());
      return;
    }
    {
      std::lock_guard<std::mutex> l(m_);
      feeds_.push_back(decode_feed(f.payload));
      s_ = feeds_.back().override_s;
      held_ = feeds_.back().hold;
    }
    const Bytes w = encode_frame(Type::kAck, s.next_seq, encode_ack({s.next_seq, uint16_t(s.credits)}));
    out.insert(out.end(), w.begin(), w.end());
  }
  // The inner board's STATUS frames from `from` on, with S and the held flag.
  void patch_status(Bytes& out, size_t from) {
    std::vector<FrameDecoder::Event> ev;
    FrameDecoder d;
    d.feed(out.data() + from, out.size() - from, ev);
    Bytes again;
    for (auto& e : ev) {
      if (e.frame.type == Type::kStatus) {
        Status s = decode_status(e.frame);
        std::lock_guard<std::mutex> l(m_);
        s.scale_s = held_ ? 0 : s_;
        if (held_) s.flags |= status_flag::kHeld;
        e.frame.payload = encode_status(s);
      }
      const Bytes w = encode_frame(e.frame);
      again.insert(again.end(), w.begin(), w.end());
    }
    out.resize(from);
    out.insert(out.end(), again.begin(), again.end());
  }
  LoopbackBoard& inner_;
  FrameDecoder dec_;
  std::vector<FrameDecoder::Event> events_;
  std::mutex m_;
  std::vector<Config> configs_;
  std::vector<Feed> feeds_;
  uint32_t s_ = 0;
  bool held_ = false;
};

// The loopback board (or, with time_scale, the loopback board behind the
// TimeScaleShim) serving one end of an in-process pipe in its own thread.
class Rig {
 public:
  Rig(BoardOptions bo, FaultOptions fo, bool time_scale = false) : board_(bo), faults_(fo) {
    if (time_scale) shim_ = std::make_unique<TimeScaleShim>(board_);
    board_.on_played = [this](uint32_t, const Bytes& r) {
      std::lock_guard<std::mutex> l(m_);
      played_.push_back(r);
    };
    connect();
  }
  ~Rig() { disconnect(); }
  // A new tool: the old pipe closes, the board keeps its state.
  void connect() {
    disconnect();
    auto [host, dev] = make_pipe_pair();
    host_ = std::move(host);
    dev_ = std::move(dev);
    stop_ = false;
    Board& b = shim_ ? static_cast<Board&>(*shim_) : board_;
    thread_ = std::thread([this, &b] { serve(*dev_, b, stop_, faults_, stats_); });
  }
  void disconnect() {
    if (!thread_.joinable()) return;
    stop_ = true;
    thread_.join();
    host_.reset();
    dev_.reset();
  }
  Transport& port() { return *host_; }
  std::vector<Bytes> played() {
    std::lock_guard<std::mutex> l(m_);
    return played_;
  }
  const ServeStats& stats() const { return stats_; }
  LoopbackBoard& board() { return board_; }
  TimeScaleShim& shim() { return *shim_; }

 private:
  LoopbackBoard board_;
  std::unique_ptr<TimeScaleShim> shim_;
  FaultOptions faults_;
  ServeStats stats_;
  std::unique_ptr<Transport> host_, dev_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::mutex m_;
  std::vector<Bytes> played_;
};

BoardOptions fast_board(size_t fifo = 16) {
  BoardOptions b;
  b.fifo_segments = fifo;
  b.speed = 0;  // unpaced
  return b;
}

UploadOptions tool() {
  UploadOptions o;
  o.timeout_ms = 30;
  o.max_retries = 40;
  return o;
}

UploadResult run(Rig& rig, const std::string& path, const UploadOptions& o = tool()) {
  RecordSource src(path);
  return upload(rig.port(), src, o);
}

TEST(Upload, CleanLinkPlaysEveryRecordOnce) {
  const auto& path = raster_stream(40);
  Rig rig(fast_board(), {});
  const auto r = run(rig, path);
  const auto want = file_records(path);
  EXPECT_GT(want.size(), 200u);  // several FIFO fills
  EXPECT_EQ(r.records, want.size());
  EXPECT_TRUE(rig.played() == want);
  EXPECT_EQ(r.progress.resends, 0u);
}

// --ahead N: the board never holds more than N segments beyond those it has
// started (as its own STATUS says), where the FIFO would take more; every
// record still played once.
TEST(Upload, AheadBoundsWhatTheBoardStoresBeyondWhatItPlays) {
  const auto& path = raster_stream(40);
  auto most_ahead = [&](size_t ahead) {
    BoardOptions bo = fast_board(64);
    bo.speed = 5;  // paced, so that the tool waits for the board (16 segments ahead: about 0.1 s)
    Rig rig(bo, {});
    RecordSource src(path);
    UploadOptions o = tool();
    o.ahead = ahead;
    o.status_period_s = 0.002;
    uint32_t most = 0;
    upload(rig.port(), src, o, [&](const UploadProgress& p) {
      if (p.have_status) most = std::max(most, p.status.next_seq - p.status.segments_played);
    });
    rig.disconnect();
    EXPECT_TRUE(rig.played() == file_records(path));
    return most;
  };
  EXPECT_LE(most_ahead(16), 16u);
  EXPECT_GT(most_ahead(0), 32u);  // without it the FIFO fills
}

struct FaultCase {
  const char* name;
  FaultOptions f;
};

void PrintTo(const FaultCase& c, std::ostream* os) { *os << c.name; }

class UploadFaults : public ::testing::TestWithParam<FaultCase> {};

TEST_P(UploadFaults, RecoversWithEveryRecordPlayedOnceInOrder) {
  const auto& path = raster_stream(40);
  FaultOptions f = GetParam().f;
  Rig rig(fast_board(), f);
  const auto r = run(rig, path);
  rig.disconnect();
  const auto want = file_records(path);
  const auto got = rig.played();
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) ASSERT_TRUE(got[i] == want[i]) << "record " << i;
  // the faults happened
  EXPECT_TRUE(f.corrupt == 0 || rig.stats().corrupted > 10);
  EXPECT_TRUE(f.drop == 0 || rig.stats().dropped > 10);
  EXPECT_TRUE(f.dup_frames == 0 || rig.stats().duplicated > 10);
  EXPECT_TRUE((f.corrupt == 0 && f.drop == 0) || r.progress.resends > 0);
}

FaultOptions faults(double corrupt, double drop, double dup, double delay, bool to_board = true,
                    bool to_host = true) {
  FaultOptions f;
  f.corrupt = corrupt;
  f.drop = drop;
  f.dup_frames = dup;
  f.delay_ms = delay;
  f.to_board = to_board;
  f.to_host = to_host;
  f.seed = 7;
  return f;
}

INSTANTIATE_TEST_SUITE_P(Link, UploadFaults,
                         ::testing::Values(FaultCase{"corrupt", faults(1e-3, 0, 0, 0)},
                                           FaultCase{"drop", faults(0, 1e-3, 0, 0)},
                                           FaultCase{"drop_answers", faults(0, 3e-3, 0, 0, false, true)},
                                           FaultCase{"duplicate", faults(0, 0, 0.2, 0)},
                                           FaultCase{"delay", faults(0, 0, 0, 3)},
                                           FaultCase{"all", faults(1e-3, 1e-3, 0.05, 1)}),
                         [](const auto& i) { return std::string(i.param.name); });

// A board reset mid-job: the tool stops with a message naming it; the board
// played a prefix of the job and nothing after the reset.
TEST(Upload, BoardResetMidJobStopsWithAClearError) {
  const auto& path = raster_stream(40);
  FaultOptions f;
  f.reset_after = 100;
  Rig rig(fast_board(), f);
  try {
    run(rig, path);
    FAIL() << "the upload went on after the board's reset";
  } catch (const UploadError& e) {
    EXPECT_NE(std::string(e.what()).find("reset mid-job"), std::string::npos) << e.what();
  }
  rig.disconnect();
  const auto want = file_records(path), got = rig.played();
  ASSERT_LE(got.size(), 100u);
  for (size_t i = 0; i < got.size(); ++i) ASSERT_TRUE(got[i] == want[i]) << "record " << i;
  EXPECT_FALSE(rig.board().playing());
}

TEST(Upload, DeadLinkGivesUpWithAClearError) {
  const auto& path = raster_stream(10);
  Rig rig(fast_board(), faults(0, 1.0, 0, 0));
  UploadOptions o = tool();
  o.max_retries = 5;
  try {
    run(rig, path, o);
    FAIL() << "an upload over a dead link succeeded";
  } catch (const UploadError& e) {
    EXPECT_NE(std::string(e.what()).find("no STATUS answer"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(rig.played().empty());
}

TEST(Upload, LinkDyingMidJobGivesUpAndTheBoardHolds) {
  const auto& path = raster_stream(40);
  FaultOptions f;
  f.cut_after = 120;
  Rig rig(fast_board(), f);
  UploadOptions o = tool();
  o.max_retries = 5;
  try {
    run(rig, path, o);
    FAIL() << "an upload over a dead link succeeded";
  } catch (const UploadError& e) {
    EXPECT_NE(std::string(e.what()).find("no answer from the board"), std::string::npos) << e.what();
  }
  rig.disconnect();
  const auto want = file_records(path), got = rig.played();
  ASSERT_LE(got.size(), 120u);
  for (size_t i = 0; i < got.size(); ++i) ASSERT_TRUE(got[i] == want[i]) << "record " << i;
}

// An upload of `path` interrupted (Ctrl-C: the interrupted flag) once 150
// records are stored; the message it ends with ("" if it did not fail).
std::string interrupted_upload(Rig& rig, const std::string& path) {
  std::atomic<bool> interrupted{false};
  UploadOptions o = tool();
  o.interrupted = &interrupted;
  RecordSource src(path);
  try {
    upload(rig.port(), src, o, [&](const UploadProgress& p) {
      if (p.acked >= 150) interrupted = true;
    });
  } catch (const UploadError& e) {
    return e.what();
  }
  ADD_FAILURE() << "the interrupted upload succeeded";
  return "";
}

// Ctrl-C (the interrupted flag): STOP, a message; a restarted tool with
// --resume continues from the board's next_seq: every record played once.
TEST(Upload, InterruptThenResumePlaysEveryRecordOnce) {
  const auto& path = raster_stream(40);
  Rig rig(fast_board(), {});
  {
    const std::string m = interrupted_upload(rig, path);
    EXPECT_NE(m.find("interrupted: STOP sent"), std::string::npos) << m;
  }
  const size_t before = rig.played().size();
  EXPECT_LT(before, file_records(path).size());
  rig.connect();  // the restarted tool
  UploadOptions again = tool();
  again.resume = true;
  const auto r = run(rig, path, again);
  EXPECT_GE(r.first_seq, 150u);
  rig.disconnect();
  EXPECT_TRUE(rig.played() == file_records(path));
}

// A tool that died without a word (kill -9): the board underran and holds;
// --resume refills, RESUMEs and finishes: every record played once.
TEST(Upload, KilledToolThenResumeAfterUnderrun) {
  const auto& path = raster_stream(40);
  BoardOptions bo = fast_board(64);
  bo.speed = 20;  // paced: the board runs dry while no tool feeds it (64 segments: ~0.1 s)
  Rig rig(bo, {});
  {
    // a tool that stores 60 records and starts the board, then vanishes
    RecordSource src(path);
    UploadOptions o = tool();
    o.prefill = 60;
    std::atomic<bool> die{false};
    o.interrupted = &die;
    struct Killed {};
    try {
      upload(rig.port(), src, o, [&](const UploadProgress& p) {
        if (p.have_status && (p.status.flags & status_flag::kPlaying)) throw Killed{};
      });
    } catch (const Killed&) {
    }
  }
  rig.disconnect();
  rig.connect();
  for (int i = 0; i < 200 && !(rig.board().status().flags & status_flag::kUnderrunHalt); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(rig.board().status().flags & status_flag::kUnderrunHalt);
  UploadOptions again = tool();
  again.resume = true;
  const auto r = run(rig, path, again);
  EXPECT_GT(r.first_seq, 0u);
  rig.disconnect();
  EXPECT_TRUE(rig.played() == file_records(path));
  EXPECT_EQ(rig.board().status().underruns, 1u);
}

}  // namespace
}  // namespace traj::link

namespace traj::link {
namespace {

// A board built for another record format refuses every segment (NAK 4): the
// tool names it instead of retrying for ever.
TEST(Upload, BoardOfAnotherFormatIsNamed) {
  const auto& path = raster_stream(10);
  BoardOptions bo = fast_board();
  bo.format.degree = 3;  // 160-byte records; the stream's are 232
  Rig rig(bo, {});
  try {
    run(rig, path);
    FAIL() << "a board of another record format took the job";
  } catch (const UploadError& e) {
    EXPECT_NE(std::string(e.what()).find("bad content"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(rig.played().empty());
}

// The tick period goes to the board in its own clocks, the clock it reports
// in STATUS: 1 ms at 60 MHz (the HX8K top) is 60000 clocks, pulse 2 us 120.
// A --clock-hz that disagrees with the board is refused before CONFIG.
TEST(Upload, TickPeriodInTheClockTheBoardReports) {
  const auto& path = raster_stream(10);
  BoardOptions bo = fast_board();
  bo.clock_hz = 60e6;
  {
    Rig rig(bo, {});
    run(rig, path);
    rig.disconnect();
    EXPECT_EQ(rig.board().config().tick_clocks, 60000u);
    EXPECT_EQ(rig.board().config().pulse_clocks, 120u);
    EXPECT_EQ(rig.played().size(), file_records(path).size());
  }
  Rig rig(bo, {});
  UploadOptions o = tool();
  o.clock_hz = 30e6;
  try {
    run(rig, path, o);
    FAIL() << "a --clock-hz that disagrees with the board was taken";
  } catch (const UploadError& e) {
    EXPECT_NE(std::string(e.what()).find("reports a core clock of 60000000"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(rig.played().empty());
}

// A board playing a job is not reset by a second upload without --resume.
TEST(Upload, PlayingBoardIsNotTakenOver) {
  const auto& path = raster_stream(40);
  BoardOptions bo = fast_board(64);
  bo.speed = 1;  // real time: the first job plays for minutes
  Rig rig(bo, {});
  {
    RecordSource src(path);
    UploadOptions o = tool();
    struct Gone {};
    try {
      upload(rig.port(), src, o, [&](const UploadProgress& p) {
        if (p.have_status && (p.status.flags & status_flag::kPlaying)) throw Gone{};
      });
    } catch (const Gone&) {
    }
  }
  rig.connect();
  try {
    run(rig, path);
    FAIL() << "a second upload took over a playing board";
  } catch (const UploadError& e) {
    EXPECT_NE(std::string(e.what()).find("the board is playing a job"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(rig.board().playing());
}

// A stream that breaks off mid-job (its writer died): the reader's message,
// and STOP: the board ends at a segment end, not by an underrun.
TEST(Upload, TruncatedStreamStopsTheBoard) {
  const auto& whole = raster_stream(40);
  const std::string cut = whole + ".cut";
  {
    std::ifstream in(whole, std::ios::binary);
    std::vector<char> b((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(cut, std::ios::binary).write(b.data(), 64 + 232 * 100 + 50);
  }
  BoardOptions bo = fast_board(64);
  bo.speed = 20;  // 100 records stream through in about 0.2 s; a segment lasts about 2 ms
  Rig rig(bo, {});
  try {
    run(rig, cut);
    FAIL() << "a truncated stream uploaded";
  } catch (const UploadError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("segment 100"), std::string::npos) << m;
    EXPECT_NE(m.find("STOP sent"), std::string::npos) << m;
  }
  std::filesystem::remove(cut);
  for (int i = 0; i < 300 && rig.board().playing(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const Status s = rig.board().status();
  EXPECT_FALSE(s.flags & status_flag::kPlaying);
  EXPECT_EQ(s.underruns, 0u);
  EXPECT_GT(s.fifo_level, 0);  // the rest of the FIFO is kept, not played
}

}  // namespace
}  // namespace traj::link

namespace traj::link {
namespace {

// ---- time scaling ------------------------------------------------------------

// Ramp bounds as `trajcore plan --time-scale 1.5` writes them, at an engine
// tick of 0.25 ms: at the default servo tick of 1 ms (2^2 engine ticks) the
// integer bounds are, by hand: scale bits 16 (2^-16 = 1.53e-5 <= accel H^2 =
// 2e-5 < 2^-15), m = floor(2 x 1e-3 x 2^16) = 131, S_max = 1.5 x 2^16 = 98304,
// shift = 32 - 16 + 2 = 18.
const ScaleHeader kScaled{1.5, 2.0f, 20.0f, 0.25e-3};

stream::Header scaled_header(double period = kScaled.period) {
  stream::Header h;
  h.period = period;
  h.scale_max = kScaled.scale_max;
  h.scale_rate = kScaled.rate;
  h.scale_accel = kScaled.accel;
  return h;
}

std::string setup_error(const stream::Header& h, const UploadOptions& o) {
  try {
    time_scale_setup(h, o);
  } catch (const UploadError& e) {
    return e.what();
  }
  return "";
}

TEST(TimeScaleSetup, FromTheHeaderAtTheDefaultServoTick) {
  const TimeScaleSetup t = time_scale_setup(scaled_header(), {});
  ASSERT_TRUE(t.on);
  EXPECT_DOUBLE_EQ(t.servo_period, 1e-3);
  EXPECT_EQ(t.p, 2);
  EXPECT_EQ(t.bounds.scale_bits, 16);
  EXPECT_EQ(t.bounds.m, 131);
  EXPECT_EQ(t.bounds.s_max, 98304);
  EXPECT_EQ(t.shift(), 18);
  EXPECT_EQ(t.override_s, 65536);  // 100 %
  Config c;
  t.apply(c);
  EXPECT_EQ(c.scale_m, 131u);
  EXPECT_EQ(c.scale_s_max, 98304u);
  EXPECT_EQ(c.scale_override, 65536u);
  EXPECT_EQ(c.scale_shift, 18);
  EXPECT_EQ(c.scale_flags, 1);  // auto-resume
  // the largest engine tick x 2^p within 1 ms, p >= 0
  EXPECT_DOUBLE_EQ(time_scale_setup(scaled_header(0.3e-3), {}).servo_period, 0.6e-3);
  EXPECT_DOUBLE_EQ(time_scale_setup(scaled_header(1e-3), {}).servo_period, 1e-3);
  const TimeScaleSetup slow = time_scale_setup(scaled_header(2e-3), {});
  EXPECT_DOUBLE_EQ(slow.servo_period, 2e-3);
  EXPECT_EQ(slow.p, 0);
}

TEST(TimeScaleSetup, Options) {
  UploadOptions o;
  o.servo_period_s = 0.5e-3;  // 2 engine ticks: scale bits 18 (2^-18 <= 20 x 0.25e-6 < 2^-17)
  o.feed_percent = 80;
  o.auto_resume = false;
  const TimeScaleSetup t = time_scale_setup(scaled_header(), o);
  EXPECT_EQ(t.p, 1);
  EXPECT_EQ(t.bounds.scale_bits, 18);
  EXPECT_EQ(t.bounds.m, 262);        // floor(2 x 0.5e-3 x 2^18 = 262.1)
  EXPECT_EQ(t.bounds.s_max, 393216);  // 1.5 x 2^18
  EXPECT_EQ(t.shift(), 15);
  EXPECT_EQ(t.override_s, 209715);  // round(0.8 x 2^18 = 209715.2)
  Config c;
  t.apply(c);
  EXPECT_EQ(c.scale_flags, 0);
  o = {};
  o.feed_percent = 150;
  EXPECT_EQ(time_scale_setup(scaled_header(), o).override_s, 98304);
  o.feed_percent = 0;
  EXPECT_EQ(time_scale_setup(scaled_header(), o).override_s, 0);
  // refused, naming the option
  o.feed_percent = 151;
  EXPECT_NE(setup_error(scaled_header(), o).find("--feed 151 %: the stream was planned for 0 .. 150 %"),
            std::string::npos)
      << setup_error(scaled_header(), o);
  // the header holds scale_max rounded down to 1/4096: up to that much more is S_max
  o.feed_percent = 150.02;
  EXPECT_EQ(time_scale_setup(scaled_header(), o).override_s, 98304);
  o.feed_percent = 150.03;
  EXPECT_NE(setup_error(scaled_header(), o).find("--feed 150.03 %"), std::string::npos);
  o.feed_percent = -1;
  EXPECT_NE(setup_error(scaled_header(), o).find("--feed -1"), std::string::npos);
  o = {};
  for (double bad : {0.75e-3, 0.125e-3, 1.0001e-3}) {
    o.servo_period_s = bad;
    EXPECT_NE(setup_error(scaled_header(), o).find("is not the engine tick (0.00025 s"), std::string::npos)
        << setup_error(scaled_header(), o);
  }
  // bounds the unit cannot take: a jerk step below 2^-40 per servo tick
  stream::Header h = scaled_header();
  h.scale_accel = 1e-9f;
  EXPECT_NE(setup_error(h, {}).find("scale bits"), std::string::npos) << setup_error(h, {});
  EXPECT_NE(setup_error(h, {}).find("--servo-period"), std::string::npos);
}

TEST(TimeScaleSetup, OptionsRefusedWithoutTimeScaling) {
  stream::Header h;  // scale_max 0
  const TimeScaleSetup t = time_scale_setup(h, {});
  EXPECT_FALSE(t.on);
  EXPECT_DOUBLE_EQ(t.servo_period, h.period);
  Config c;
  t.apply(c);
  EXPECT_EQ(encode_config(c), encode_config(Config{}));
  FeedControls none;
  const std::pair<const char*, std::function<void(UploadOptions&)>> cases[] = {
      {"--feed", [](UploadOptions& o) { o.feed_percent = 100; }},
      {"--servo-period", [](UploadOptions& o) { o.servo_period_s = 1e-3; }},
      {"--no-auto-resume", [](UploadOptions& o) { o.auto_resume = false; }},
      {"--control", [&](UploadOptions& o) { o.feed_control = &none; }},
  };
  for (const auto& [name, set] : cases) {
    UploadOptions o;
    set(o);
    const std::string e = setup_error(h, o);
    EXPECT_NE(e.find(name), std::string::npos) << e;
    EXPECT_NE(e.find("the stream was planned without --time-scale"), std::string::npos) << e;
  }
}

// The loopback board has no time-scale unit: its NAK 4 to the CONFIG is
// reported with the values, nothing is played.
TEST(Upload, TimeScaledStreamOnABoardWithoutTheUnitIsNamed) {
  const auto& path = raster_stream(10, kScaled);
  Rig rig(fast_board(), {});
  try {
    run(rig, path);
    FAIL() << "a board without the time-scale unit took a time-scaled job";
  } catch (const UploadError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("refuses CONFIG as bad content"), std::string::npos) << m;
    EXPECT_NE(m.find("m 131, S_max 98304, override 65536, shift 18"), std::string::npos) << m;
    EXPECT_NE(m.find("without the time-scale unit"), std::string::npos) << m;
  }
  EXPECT_TRUE(rig.played().empty());
  EXPECT_EQ(rig.board().status().fifo_level, 0);
}

TEST(Upload, TimeScalingOptionsAreRefusedBeforeTheBoardIsTouched) {
  const auto& path = raster_stream(10);
  Rig rig(fast_board(), {});
  UploadOptions o = tool();
  o.feed_percent = 80;
  try {
    run(rig, path, o);
    FAIL() << "--feed was taken for a stream without time scaling";
  } catch (const UploadError& e) {
    EXPECT_NE(std::string(e.what()).find("--feed: the stream was planned without --time-scale"), std::string::npos)
        << e.what();
  }
  rig.disconnect();
  EXPECT_EQ(rig.board().status().bytes_received, 0u);
}

// A servo tick too short for the board's time-scale unit is refused before
// CONFIG, naming the shortest that fits. At 0.25 ms (one engine tick, 7500
// clocks at 30 MHz) the integer bounds are, by hand: scale bits 20 (2^-20 <=
// 20 x (0.25e-3)^2 = 1.25e-6), m = floor(2 x 0.25e-3 x 2^20) = 524, S_max =
// 1.5 x 2^20: a stop may take 3 x 524 + (S_max + 524^2 + 523) / 524 + 4 =
// 5102 S-curve steps of 4 clocks, beyond 7500. At 0.5 ms (scale bits 18,
// m 262, S_max 393216) it is 2553 steps, about 10 700 clocks of 15 000.
TEST(Upload, ServoTickTheUnitCannotFinishIsRefused) {
  const auto& path = raster_stream(10, kScaled);
  Rig rig(fast_board(), {}, true);
  UploadOptions o = tool();
  o.servo_period_s = 0.25e-3;
  try {
    run(rig, path, o);
    FAIL() << "a 0.25 ms servo tick was taken";
  } catch (const UploadError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("the servo tick of 250 us is 7500 clocks at 30 MHz, but the board's time-scale unit may need up to"),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("a simulated stop of up to 5102 S-curve steps"), std::string::npos) << m;
    EXPECT_NE(m.find("give --servo-period 0.0005 s or longer"), std::string::npos) << m;
  }
  rig.disconnect();
  EXPECT_TRUE(rig.shim().configs().empty());
  EXPECT_TRUE(rig.played().empty());

  // The check is at the clock the board reports: at 120 MHz the same tick is
  // 30 000 clocks, enough.
  BoardOptions fast = fast_board();
  fast.clock_hz = 120e6;
  Rig quick(fast, {}, true);
  run(quick, path, o);
  quick.disconnect();
  ASSERT_EQ(quick.shim().configs().size(), 1u);
  EXPECT_EQ(quick.shim().configs()[0].tick_clocks, 30000u);
  EXPECT_TRUE(quick.played() == file_records(path));
}

// A scripted operator: each step runs once its condition holds, in order.
class Script : public FeedControl {
 public:
  struct Step {
    std::function<bool(const FeedState&)> when;
    std::function<void(FeedPort&)> act;
  };
  std::vector<Step> steps;
  size_t done = 0;
  std::vector<std::string> refused;
  void poll(FeedPort& port) override {
    if (done >= steps.size() || !steps[done].when(port.feed_state())) return;
    try {
      steps[done].act(port);
    } catch (const FeedRefused& e) {
      refused.push_back(e.what());
    }
    ++done;
  }
};

// Paced so that the feed changes land while the job plays, with a FIFO deep
// enough (64 records, about 0.2 s at 10x real time) that a host slowed by the
// sanitizers and a parallel test run does not underrun it.
BoardOptions paced_board() {
  BoardOptions bo = fast_board(64);
  bo.speed = 10;  // 450 records in about 1.6 s; the board's STATUS every 10 ms
  return bo;
}

// CONFIG carries the servo tick and the time-scaling fields; feed changes
// while playing go out as FEED (each acknowledged), the board's S and held
// flag come back in the progress; every record is played once, in order.
TEST(Upload, TimeScaledJobWithLiveFeedChanges) {
  const auto& path = raster_stream(40, kScaled);
  Rig rig(paced_board(), {}, true);
  Script op;
  std::vector<FeedState> seen;
  op.steps = {
      {[](const FeedState& f) { return f.have_status; }, [](FeedPort& p) { p.set_feed(50, false); }},
      {[](const FeedState& f) { return f.s == 32768; }, [](FeedPort& p) { p.set_feed(50, true); }},
      {[](const FeedState& f) { return f.held; }, [](FeedPort& p) { p.set_feed(151, false); }},
      {[](const FeedState&) { return true; }, [](FeedPort& p) { p.set_feed(120, false); }},
  };
  UploadOptions o = tool();
  o.feed_control = &op;
  RecordSource src(path);
  const auto r = upload(rig.port(), src, o, [&](const UploadProgress& p) { seen.push_back(p.feed); });
  rig.disconnect();
  EXPECT_TRUE(rig.played() == file_records(path));
  ASSERT_EQ(op.done, op.steps.size());
  ASSERT_EQ(op.refused.size(), 1u);
  EXPECT_NE(op.refused[0].find("feed 151 %: the stream was planned for 0 .. 150 %"), std::string::npos)
      << op.refused[0];
  const auto configs = rig.shim().configs();
  ASSERT_EQ(configs.size(), 1u);
  const Config& c = configs[0];
  EXPECT_EQ(c.tick_clocks, 30000u);  // the servo tick, 1 ms at 30 MHz
  EXPECT_EQ(c.status_ticks, 100u);   // 0.1 s in servo ticks
  EXPECT_EQ(c.scale_m, 131u);
  EXPECT_EQ(c.scale_s_max, 98304u);
  EXPECT_EQ(c.scale_override, 65536u);
  EXPECT_EQ(c.scale_shift, 18);
  EXPECT_EQ(c.scale_flags, config_flag::kAutoResume);
  const auto feeds = rig.shim().feeds();
  ASSERT_EQ(feeds.size(), 3u);
  EXPECT_EQ(feeds[0].override_s, 32768u);
  EXPECT_FALSE(feeds[0].hold);
  EXPECT_EQ(feeds[1].override_s, 32768u);
  EXPECT_TRUE(feeds[1].hold);
  EXPECT_EQ(feeds[2].override_s, 78643u);  // round(1.2 x 2^16 = 78643.2)
  EXPECT_FALSE(feeds[2].hold);
  EXPECT_TRUE(r.progress.time_scaling);
  EXPECT_EQ(r.progress.feed.target_s, 78643);
  EXPECT_FALSE(r.progress.feed.hold);
  EXPECT_NEAR(r.progress.feed.effective_percent(), 120.0, 1e-3);
  EXPECT_TRUE(std::any_of(seen.begin(), seen.end(), [](const FeedState& f) { return f.held && f.s == 0; }));
}

// A FEED the board refuses (NAK 4) is named with its value; the job goes on.
TEST(Upload, FeedRefusedByTheBoardIsNamedAndTheJobGoesOn) {
  const auto& path = raster_stream(10, kScaled);
  Rig rig(fast_board(), {}, true);
  rig.shim().refuse_feed = true;
  Script op;
  op.steps = {{[](const FeedState&) { return true; }, [](FeedPort& p) { p.set_feed(50, false); }}};
  UploadOptions o = tool();
  o.feed_control = &op;
  RecordSource src(path);
  const auto r = upload(rig.port(), src, o);
  rig.disconnect();
  ASSERT_EQ(op.refused.size(), 1u);
  EXPECT_NE(op.refused[0].find("the board refuses FEED override 32768 (50 %): bad content"), std::string::npos)
      << op.refused[0];
  EXPECT_EQ(r.progress.feed.target_s, 65536);  // unchanged
  EXPECT_TRUE(rig.played() == file_records(path));
}

// Ctrl-C with time scaling: STOP is a hold on the path, the message says so;
// --resume sends the feed it starts with (--feed) and plays the rest once.
TEST(Upload, InterruptWithTimeScalingThenResume) {
  const auto& path = raster_stream(40, kScaled);
  Rig rig(fast_board(), {}, true);
  {
    const std::string m = interrupted_upload(rig, path);
    EXPECT_NE(m.find("interrupted: STOP sent and acknowledged; the board holds"), std::string::npos) << m;
    EXPECT_NE(m.find("stops on the path"), std::string::npos) << m;
    EXPECT_NE(m.find("START (`--resume`) continues"), std::string::npos) << m;
  }
  EXPECT_TRUE(rig.shim().feeds().empty());
  rig.connect();
  UploadOptions again = tool();
  again.resume = true;
  again.feed_percent = 70;
  const auto r = run(rig, path, again);
  EXPECT_GE(r.first_seq, 150u);
  rig.disconnect();
  EXPECT_TRUE(rig.played() == file_records(path));
  const auto feeds = rig.shim().feeds();
  ASSERT_EQ(feeds.size(), 1u);
  EXPECT_EQ(feeds[0].override_s, 45875u);  // round(0.7 x 2^16 = 45875.2)
  EXPECT_FALSE(feeds[0].hold);
}

// --resume with a time-scaled stream on a board whose job has no time
// scaling (the loopback board): its NAK 4 to the FEED is named.
TEST(Upload, ResumeWithTimeScalingOnABoardWithoutItIsNamed) {
  Rig rig(fast_board(), {});
  std::atomic<bool> interrupted{false};
  UploadOptions o = tool();
  o.interrupted = &interrupted;
  {
    RecordSource src(raster_stream(40));
    EXPECT_THROW(upload(rig.port(), src, o, [&](const UploadProgress& p) { interrupted = p.acked >= 150; }),
                 UploadError);
  }
  const size_t before = rig.played().size();
  rig.connect();
  UploadOptions again = tool();
  again.resume = true;
  try {
    run(rig, raster_stream(40, kScaled), again);
    FAIL() << "a time-scaled --resume went on without the board's FEED";
  } catch (const UploadError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("the board refuses FEED override 65536 (100 %): bad content"), std::string::npos) << m;
    EXPECT_NE(m.find("--resume of a time-scaled job"), std::string::npos) << m;
  }
  rig.disconnect();
  EXPECT_EQ(rig.played().size(), before);
}

// ---- program pauses ------------------------------------------------------

// A G-code program with two program pauses (M0 and M60), read with
// --pause-wait and planned as `trajcore plan` does, whole or streamed in
// windows of 4 curves, into a stream file.
const std::string& pause_stream(bool streamed) {
  static test::TmpFile files[2] = {test::TmpFile("traj_link_pauses.trj"), test::TmpFile("traj_link_pauses_w4.trj")};
  static bool made[2] = {false, false};
  const std::string& path = files[streamed].path;
  if (made[streamed]) return path;
  test::TmpFile prog("traj_link_pauses.ngc");
  prog.write("G21 G90 G17\nG1 X10 F600\nM0 (tool change)\nG1 X10 Y10\nG1 X20 Y10\nM60\nG1 X0 Y0\nM2\n");
  input::GcodeOptions go;
  go.pauses_wait = true;
  const input::Toolpath tp = input::read_toolpath(prog.path, input::FileKind::kGcode, go);
  job::JobConfig cfg;
  if (streamed) {
    job::ToolpathStream src(tp, cfg);
    job::StreamOptions so;
    so.window = 4;
    so.commit = 2;
    stream::StreamWriter w(path, cfg.machine.header());
    job::run_streaming(src, src.config(), so, job::write_to(w));
    w.finish();
  } else {
    const job::ToolpathPlan tpp = job::toolpath_plan(tp, cfg);
    const job::JobResult res = job::run_job(tpp.path, tpp.cfg);
    stream::write_file(path, res.header, job::records_of(res), job::pauses_of(res));
  }
  made[streamed] = true;
  return path;
}

// The position step from the last sample of record `before - 1` (the one the
// board holds while it waits) to the first of record `before`, in units,
// from the exact registers: r1 after K - 1 ticks, sum C(K-1, i) r[i+1].
double step_at(const stream::ReadResult& rd, size_t before, int axis) {
  const stream::Record& r = rd.records.at(before - 1);
  const auto& reg = r.regs.at(static_cast<size_t>(axis));
  mpz_class d = 0, c = 1;  // C(K-1, i)
  const unsigned long n = r.ticks - 1;
  for (size_t i = 0; i + 1 < reg.size(); ++i) {
    d += c * reg[i + 1];
    c = c * static_cast<unsigned long>(n - i) / static_cast<unsigned long>(i + 1);
  }
  return std::ldexp(d.get_d(), -(rd.header.frac_bits + rd.header.guard_bits));
}

// The stream holds both pauses where the machine rests (the step from the
// held sample to the next is below 1e-9 mm, where the feed moves 0.01 mm a
// tick); the board plays up to each and holds there, stores nothing beyond
// it, until the operator says go; then every record is played once, and the
// two underruns of the pauses are no failure.
class UploadPauses : public ::testing::TestWithParam<bool> {};  // streamed

TEST_P(UploadPauses, HoldTheBoardAtRestUntilTheOperatorSaysGo) {
  const std::string& path = pause_stream(GetParam());
  const stream::ReadResult rd = stream::read_file(path);
  ASSERT_TRUE(rd.complete) << rd.error;
  ASSERT_EQ(rd.pauses.size(), 2u);
  EXPECT_EQ(rd.pauses[0].line, 3u);
  EXPECT_EQ(rd.pauses[1].line, 6u);
  for (const auto& p : rd.pauses)
    for (int a = 0; a < rd.header.axes; ++a) EXPECT_LT(std::fabs(step_at(rd, p.before, a)), 1e-9) << p.before;

  BoardOptions bo = fast_board(64);
  bo.speed = 20;  // paced: an unpaced board plays only when its FIFO fills
  Rig rig(bo, {});
  RecordSource src(path);
  UploadOptions o = tool();
  o.status_period_s = 0.01;
  Status latest;
  std::vector<std::pair<uint32_t, int>> asked;  // link seq, calls
  o.pause_confirmed = [&](const PauseAt& p) {
    EXPECT_EQ(latest.segments_played, p.link_seq);
    EXPECT_EQ(latest.next_seq, p.link_seq);
    EXPECT_TRUE(latest.flags & status_flag::kUnderrunHalt);
    EXPECT_EQ(rig.played().size(), p.link_seq);
    if (asked.empty() || asked.back().first != p.link_seq) asked.push_back({p.link_seq, 0});
    return ++asked.back().second >= 10;  // about 0.2 s of waiting
  };
  const auto r = upload(rig.port(), src, o, [&](const UploadProgress& p) {
    if (p.have_status) latest = p.status;
  });
  rig.disconnect();
  ASSERT_EQ(asked.size(), 2u);
  EXPECT_EQ(asked[0].first, rd.pauses[0].before);
  EXPECT_EQ(asked[1].first, rd.pauses[1].before);
  EXPECT_EQ(r.progress.pauses, 2u);
  EXPECT_EQ(r.progress.status.underruns, 2u);
  EXPECT_TRUE(rig.played() == file_records(path));
}

INSTANTIATE_TEST_SUITE_P(WholeAndStreamed, UploadPauses, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? "Streamed" : "Whole"; });

// With no one to confirm, the tool stops at the first pause, the board
// holding there at rest, and says so; --resume then waits at the same pause.
TEST(Upload, ProgramPauseWithNoOneToConfirmIsNamed) {
  const std::string& path = pause_stream(false);
  const stream::ReadResult rd = stream::read_file(path);
  BoardOptions bo = fast_board(64);
  bo.speed = 20;
  Rig rig(bo, {});
  try {
    run(rig, path);
    FAIL() << "went past a pause with no one to confirm it";
  } catch (const UploadError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("holds at rest at the program pause at line 3 and no one is here to confirm it"),
              std::string::npos) << m;
  }
  EXPECT_EQ(rig.played().size(), rd.pauses.at(0).before);
  rig.connect();
  UploadOptions again = tool();
  again.resume = true;
  int calls = 0;
  again.pause_confirmed = [&](const PauseAt& p) {
    EXPECT_EQ(rig.played().size(), p.link_seq);
    return ++calls % 3 == 0;
  };
  run(rig, path, again);
  rig.disconnect();
  EXPECT_EQ(calls, 6);
  EXPECT_TRUE(rig.played() == file_records(path));
}

}  // namespace
}  // namespace traj::link
