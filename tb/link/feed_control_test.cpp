// Live feed control of `trajcore upload`: the control socket's text commands
// (parsed and run apart from any socket), the keys, a real Unix-domain socket
// in a temporary directory, and the keyboard's terminal mode on a
// pseudo-terminal.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <pty.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "link/feed_control.hpp"

namespace traj::link {
namespace {

// The upload client as the controls see it: sb 16, the plan's largest feed
// 150 %; set_feed refuses what the client refuses, and records what it sent.
class FakePort : public FeedPort {
 public:
  FakePort() {
    st_.scale_bits = 16;
    st_.s_max = 3 << 15;  // 1.5 in S units
    st_.max_percent = 150;
    st_.target_s = 1 << 16;
  }
  FeedState feed_state() const override { return st_; }
  void set_feed(double percent, bool hold) override {
    if (!(percent >= 0 && percent <= st_.max_percent)) throw FeedRefused("feed out of range");
    if (refuse_next) {
      refuse_next = false;
      throw FeedRefused("the board refuses FEED override 42");
    }
    st_.target_s = scale_of_percent(percent, st_.scale_bits, st_.s_max);
    st_.hold = hold;
    sent.push_back({percent, hold});
  }
  struct Sent {
    double percent;
    bool hold;
  };
  std::vector<Sent> sent;
  bool refuse_next = false;
  FeedState st_;
};

TEST(FeedControl, PercentToScale) {
  EXPECT_EQ(scale_of_percent(100, 16, 1 << 20), 65536);
  EXPECT_EQ(scale_of_percent(50, 16, 1 << 20), 32768);
  EXPECT_EQ(scale_of_percent(80, 19, 1 << 20), 419430);  // 0.8 * 524288 = 419430.4
  EXPECT_EQ(scale_of_percent(200, 16, 98304), 98304);    // at most s_max
  EXPECT_EQ(scale_of_percent(-5, 16, 98304), 0);
  EXPECT_DOUBLE_EQ(scale_percent(32768, 16), 50.0);
}

TEST(FeedControl, ParsesTheCommands) {
  using K = ControlCommand::Kind;
  auto feed = [](const std::string& l) {
    const ControlCommand c = parse_control_line(l);
    EXPECT_EQ(c.kind, K::kFeed) << l << ": " << c.error;
    return c.percent;
  };
  EXPECT_DOUBLE_EQ(feed("feed 80"), 80);
  EXPECT_DOUBLE_EQ(feed("  feed\t62.5 \r"), 62.5);
  EXPECT_DOUBLE_EQ(feed("feed 120%"), 120);
  EXPECT_DOUBLE_EQ(feed("feed 0 %"), 0);
  EXPECT_DOUBLE_EQ(feed("feed -3"), -3);  // parsed; the range is the port's to refuse
  EXPECT_EQ(parse_control_line("hold").kind, K::kHold);
  EXPECT_EQ(parse_control_line("resume\r").kind, K::kResume);
  EXPECT_EQ(parse_control_line(" status ").kind, K::kStatus);
  auto bad = [](const std::string& l, const std::string& says) {
    const ControlCommand c = parse_control_line(l);
    EXPECT_EQ(c.kind, K::kInvalid) << l;
    EXPECT_NE(c.error.find(says), std::string::npos) << l << ": " << c.error;
  };
  bad("feed", "needs a percent");
  bad("feed fast", "\"fast\" is not a percent");
  bad("feed 80x", "is not a percent");
  bad("feed 1e999", "is not a percent");
  bad("feed nan", "is not a percent");
  bad("hold now", "hold takes no argument");
  bad("status 1", "takes no argument");
  bad("FEED 80", "unknown command \"FEED\"");
  bad("stop", "unknown command \"stop\" (feed <percent>, hold, resume, status)");
  bad("", "empty line");
}

TEST(FeedControl, RunsTheCommandsOnThePort) {
  FakePort port;
  EXPECT_EQ(run_control_command(parse_control_line("feed 50"), port), "ok feed 50.00 %");
  EXPECT_EQ(port.st_.target_s, 32768);
  EXPECT_EQ(run_control_command(parse_control_line("hold"), port), "ok hold");
  EXPECT_TRUE(port.st_.hold);
  EXPECT_EQ(port.st_.target_s, 32768);  // hold keeps the override
  EXPECT_EQ(run_control_command(parse_control_line("feed 75"), port), "ok feed 75.00 %");
  EXPECT_TRUE(port.st_.hold);           // a new override keeps the hold
  EXPECT_EQ(run_control_command(parse_control_line("resume"), port), "ok resume");
  EXPECT_FALSE(port.st_.hold);
  ASSERT_EQ(port.sent.size(), 4u);
  EXPECT_DOUBLE_EQ(port.sent[3].percent, 75);
  EXPECT_EQ(run_control_command(parse_control_line("feed 151"), port), "error: feed out of range");
  port.refuse_next = true;
  EXPECT_EQ(run_control_command(parse_control_line("feed 10"), port), "error: the board refuses FEED override 42");
  EXPECT_EQ(port.sent.size(), 4u);
  EXPECT_EQ(run_control_command(parse_control_line("bogus"), port).rfind("error: unknown command", 0), 0u);
  // status: the effective feed from STATUS (S = 3/4 of 2^16), the target, the flags
  EXPECT_EQ(run_control_command(parse_control_line("status"), port), "ok feed ? (target 75.00 %), hold off");
  port.st_.have_status = true;
  port.st_.s = 49152;
  port.st_.held = true;
  port.st_.starved_holds = 2;
  EXPECT_EQ(run_control_command(parse_control_line("status"), port),
            "ok feed 75.00 % (target 75.00 %), hold off, held yes, starved no, starved holds 2");
}

TEST(FeedControl, Keys) {
  FakePort port;
  std::atomic<bool> stop{false};
  EXPECT_EQ(apply_key('h', port, stop), "hold (target 100.00 %)");
  EXPECT_TRUE(port.st_.hold);
  EXPECT_EQ(apply_key(' ', port, stop), "feed 100.00 %");
  EXPECT_FALSE(port.st_.hold);
  EXPECT_EQ(apply_key('+', port, stop), "feed 110.00 %");
  for (int i = 0; i < 8; ++i) apply_key('+', port, stop);
  EXPECT_EQ(port.st_.target_s, 3 << 15);  // at most the plan's 150 %
  EXPECT_EQ(apply_key('1', port, stop), "feed 100.00 %");
  for (int i = 0; i < 12; ++i) apply_key('-', port, stop);
  EXPECT_EQ(port.st_.target_s, 0);  // at least 0
  EXPECT_EQ(apply_key('x', port, stop), "");
  port.refuse_next = true;
  EXPECT_EQ(apply_key('1', port, stop), "the board refuses FEED override 42");
  EXPECT_FALSE(stop.load());
  EXPECT_EQ(apply_key('q', port, stop), "stop");
  EXPECT_TRUE(stop.load());
}

std::string temp_dir() {
  std::string d = (std::filesystem::temp_directory_path() / "traj_feed_XXXXXX").string();
  if (!::mkdtemp(d.data())) throw std::runtime_error("mkdtemp");
  return d;
}

int connect_to(const std::string& path) {
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::snprintf(a.sun_path, sizeof a.sun_path, "%s", path.c_str());
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  timeval tv{2, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  return fd;
}

// Polls the socket (as the upload's loop does) until `lines` answer lines came.
std::vector<std::string> answers(ControlSocket& sock, FeedPort& port, int fd, size_t lines) {
  std::string got;
  for (int i = 0; i < 400 && size_t(std::count(got.begin(), got.end(), '\n')) < lines; ++i) {
    sock.poll(port);
    char b[256];
    const ssize_t n = ::recv(fd, b, sizeof b, MSG_DONTWAIT);
    if (n > 0) got.append(b, size_t(n));
    else std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::vector<std::string> out;
  for (size_t at = 0, nl; (nl = got.find('\n', at)) != std::string::npos; at = nl + 1)
    out.push_back(got.substr(at, nl - at));
  return out;
}

TEST(FeedControl, UnixSocket) {
  const std::string dir = temp_dir();
  const std::string path = dir + "/feed.sock";
  FakePort port;
  {
    ControlSocket sock(path);
    struct stat st {};
    ASSERT_EQ(::lstat(path.c_str(), &st), 0);
    EXPECT_TRUE(S_ISSOCK(st.st_mode));
    // a second tool on the same path is refused while this one listens
    try {
      ControlSocket again(path);
      FAIL() << "a second control socket took a live path";
    } catch (const LinkError& e) {
      EXPECT_NE(std::string(e.what()).find("another process listens"), std::string::npos) << e.what();
    }
    const int a = connect_to(path), b = connect_to(path);
    ASSERT_GE(a, 0);
    ASSERT_GE(b, 0);
    const std::string cmds = "feed 50\nhol";  // a line in two pieces
    ASSERT_EQ(::send(a, cmds.data(), cmds.size(), 0), ssize_t(cmds.size()));
    EXPECT_EQ(answers(sock, port, a, 1), (std::vector<std::string>{"ok feed 50.00 %"}));
    ASSERT_EQ(::send(a, "d\nstatus\r\n", 10, 0), 10);
    ASSERT_EQ(::send(b, "feed 200\n", 9, 0), 9);
    EXPECT_EQ(answers(sock, port, a, 2),
              (std::vector<std::string>{"ok hold", "ok feed ? (target 50.00 %), hold on"}));
    EXPECT_EQ(answers(sock, port, b, 1), (std::vector<std::string>{"error: feed out of range"}));
    ::close(b);
    const std::string longer(300, 'x');
    ::send(a, longer.data(), longer.size(), 0);
    EXPECT_EQ(answers(sock, port, a, 1), (std::vector<std::string>{"error: a line longer than 256 bytes"}));
    ::close(a);
    sock.poll(port);
  }
  EXPECT_FALSE(std::filesystem::exists(path)) << "the socket was not removed";
  // a socket file left by a tool that died is replaced; another file is not
  {
    const int stale = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::snprintf(a.sun_path, sizeof a.sun_path, "%s", path.c_str());
    ASSERT_EQ(::bind(stale, reinterpret_cast<const sockaddr*>(&a), sizeof a), 0);
    ::close(stale);  // bound, never listened: nobody answers
    ControlSocket sock(path);
    const int c = connect_to(path);
    ASSERT_GE(c, 0);
    ::send(c, "resume\n", 7, 0);
    EXPECT_EQ(answers(sock, port, c, 1), (std::vector<std::string>{"ok resume"}));
    ::close(c);
  }
  std::ofstream(path) << "not a socket";
  EXPECT_THROW(ControlSocket{path}, LinkError);
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_THROW(ControlSocket{dir + "/" + std::string(120, 'p')}, LinkError);  // longer than sun_path
  std::filesystem::remove_all(dir);
}

// The keyboard on a pseudo-terminal: non-canonical without echo while it
// lives (signals stay on), keys act at once, the mode is restored after.
TEST(FeedControl, KeyboardModeIsRestored) {
  int master = -1, slave = -1;
  ASSERT_EQ(::openpty(&master, &slave, nullptr, nullptr, nullptr), 0);
  termios before{};
  ASSERT_EQ(::tcgetattr(slave, &before), 0);
  ASSERT_TRUE(before.c_lflag & ICANON);
  FakePort port;
  std::atomic<bool> stop{false};
  std::vector<std::string> said;
  {
    KeyboardControl keys(slave, stop, [&](const std::string& s) { said.push_back(s); });
    termios during{};
    ::tcgetattr(slave, &during);
    EXPECT_FALSE(during.c_lflag & ICANON);
    EXPECT_FALSE(during.c_lflag & ECHO);
    EXPECT_TRUE(during.c_lflag & ISIG);
    ASSERT_EQ(::write(master, "h+", 2), 2);  // no newline: taken without one
    for (int i = 0; i < 100 && said.size() < 2; ++i) {
      keys.poll(port);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  EXPECT_EQ(said, (std::vector<std::string>{"hold (target 100.00 %)", "hold (target 110.00 %)"}));
  termios after{};
  ASSERT_EQ(::tcgetattr(slave, &after), 0);
  EXPECT_EQ(after.c_lflag, before.c_lflag);
  EXPECT_EQ(after.c_cc[VMIN], before.c_cc[VMIN]);
  ::close(master);
  ::close(slave);
  const int not_a_tty = ::open("/dev/null", O_RDONLY);
  EXPECT_THROW(KeyboardControl(not_a_tty, stop, {}), LinkError);
  ::close(not_a_tty);
}

}  // namespace
}  // namespace traj::link
