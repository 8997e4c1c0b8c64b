// trajcore upload's client against the loopback board over an in-process
// pipe, with faults in the byte path: the records the board plays are
// compared byte for byte with the stream file's (read by the stream reader):
// none lost, duplicated or reordered whenever the link recovers; a clear error
// and a board that holds still (a prefix of the job played) when it cannot.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "input/raster.hpp"
#include "job/streaming.hpp"
#include "link/board_server.hpp"
#include "link/upload.hpp"
#include "stream/segment_stream.hpp"

namespace traj::link {
namespace {

// A raster job of `pieces` pieces planned into a stream file once per size.
const std::string& raster_stream(size_t pieces) {
  static std::map<size_t, std::string> made;
  auto it = made.find(pieces);
  if (it != made.end()) return it->second;
  const std::string path =
      (std::filesystem::temp_directory_path() / ("traj_link_raster_" + std::to_string(pieces) + "_" +
                                                 std::to_string(::getpid()) + ".trj"))
          .string();
  job::JobConfig cfg;
  input::RasterSource src(pieces);
  stream::StreamWriter w(path, cfg.machine.header());
  job::run_streaming(src, cfg, job::StreamOptions{},
                     [&](const fd::Compiled& c, const plan::TimeSegment&) { w.add({c.ticks, c.regs}); });
  w.finish();
  return made[pieces] = path;
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

// The loopback board serving one end of an in-process pipe in its own thread.
class Rig {
 public:
  Rig(BoardOptions bo, FaultOptions fo) : board_(bo), faults_(fo) {
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
    thread_ = std::thread([this] { serve(*dev_, board_, stop_, faults_, stats_); });
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

 private:
  LoopbackBoard board_;
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

// Ctrl-C (the interrupted flag): STOP, a message; a restarted tool with
// --resume continues from the board's next_seq: every record played once.
TEST(Upload, InterruptThenResumePlaysEveryRecordOnce) {
  const auto& path = raster_stream(40);
  Rig rig(fast_board(), {});
  std::atomic<bool> interrupted{false};
  UploadOptions o = tool();
  o.interrupted = &interrupted;
  {
    RecordSource src(path);
    try {
      upload(rig.port(), src, o, [&](const UploadProgress& p) {
        if (p.acked >= 150) interrupted = true;
      });
      FAIL() << "the interrupted upload succeeded";
    } catch (const UploadError& e) {
      EXPECT_NE(std::string(e.what()).find("interrupted: STOP sent"), std::string::npos) << e.what();
    }
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
  bo.speed = 50;  // paced: the board runs dry while no tool feeds it (64 segments: ~40 ms)
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
  BoardOptions bo = fast_board(32);
  bo.speed = 20;  // 100 records stream through in about 0.1 s; a segment lasts about 2 ms
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
