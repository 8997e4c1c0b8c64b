#include "link/feed_control.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace traj::link {

int64_t scale_of_percent(double percent, int scale_bits, int64_t s_max) {
  const double s = std::round(percent / 100.0 * std::ldexp(1.0, scale_bits));
  if (!(s > 0)) return 0;
  return s >= double(s_max) ? s_max : static_cast<int64_t>(s);
}

namespace {

std::string percent_text(double p) {
  char b[64];
  std::snprintf(b, sizeof b, "%.2f %%", p);
  return b;
}

}  // namespace

std::string describe_feed(const FeedState& f) {
  std::string s = "feed " + (f.have_status ? percent_text(f.effective_percent()) : std::string("?")) + " (target " +
                  percent_text(f.target_percent()) + "), hold " + (f.hold ? "on" : "off");
  if (f.have_status)
    s += std::string(", held ") + (f.held ? "yes" : "no") + ", starved " + (f.starved ? "yes" : "no") +
         ", starved holds " + std::to_string(f.starved_holds);
  return s;
}

// ---- the control socket's text protocol --------------------------------

namespace {

constexpr const char* kBlank = " \t\r\n";
constexpr const char* kCommands = "feed <percent>, hold, resume, status";

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(kBlank);
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(kBlank) - a + 1);
}

ControlCommand invalid(std::string why) {
  ControlCommand c;
  c.error = std::move(why);
  return c;
}

ControlCommand of_kind(ControlCommand::Kind k) {
  ControlCommand c;
  c.kind = k;
  return c;
}

// "80", "80.5", "80 %", "80%": a finite number, nothing else.
bool parse_percent(std::string s, double& out) {
  if (!s.empty() && s.back() == '%') s = trim(s.substr(0, s.size() - 1));
  if (s.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (errno != 0 || end != s.c_str() + s.size() || !std::isfinite(v)) return false;
  out = v;
  return true;
}

}  // namespace

ControlCommand parse_control_line(const std::string& line) {
  const std::string t = trim(line);
  const size_t sp = t.find_first_of(kBlank);
  const std::string word = t.substr(0, sp);
  const std::string rest = sp == std::string::npos ? "" : trim(t.substr(sp));
  using K = ControlCommand::Kind;
  if (word == "feed") {
    if (rest.empty()) return invalid("feed needs a percent (feed 80)");
    ControlCommand c = of_kind(K::kFeed);
    if (!parse_percent(rest, c.percent)) return invalid("feed: \"" + rest + "\" is not a percent (feed 80)");
    return c;
  }
  const K k = word == "hold" ? K::kHold : word == "resume" ? K::kResume : word == "status" ? K::kStatus : K::kInvalid;
  if (k == K::kInvalid)
    return invalid(t.empty() ? std::string("empty line (") + kCommands + ")"
                             : "unknown command \"" + word + "\" (" + kCommands + ")");
  if (!rest.empty()) return invalid(word + " takes no argument");
  return of_kind(k);
}

std::string run_control_command(const ControlCommand& c, FeedPort& port) {
  using K = ControlCommand::Kind;
  const FeedState f = port.feed_state();
  try {
    switch (c.kind) {
      case K::kInvalid:
        return "error: " + c.error;
      case K::kFeed:
        port.set_feed(c.percent, f.hold);
        return "ok feed " + percent_text(port.feed_state().target_percent());
      case K::kHold:
        port.set_feed(f.target_percent(), true);
        return "ok hold";
      case K::kResume:
        port.set_feed(f.target_percent(), false);
        return "ok resume";
      case K::kStatus:
        return "ok " + describe_feed(f);
    }
  } catch (const FeedRefused& e) {
    return std::string("error: ") + e.what();
  }
  return "error: ?";
}

// ---- the control socket --------------------------------------------------

namespace {

constexpr size_t kLongestLine = 256;

[[noreturn]] void socket_error(const std::string& path, const std::string& what) {
  throw LinkError("--control " + path + ": " + what + (errno ? std::string(": ") + std::strerror(errno) : ""));
}

sockaddr_un socket_address(const std::string& path) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof a.sun_path) {
    errno = 0;
    socket_error(path, "a socket path of 1.." + std::to_string(sizeof a.sun_path - 1) + " bytes");
  }
  std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
  return a;
}

// A socket file left by a tool that died is replaced; one a live process
// listens on, or any other file, is not.
void clear_stale_socket(const std::string& path, const sockaddr_un& a) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return;
  errno = 0;
  if (!S_ISSOCK(st.st_mode)) socket_error(path, "exists and is not a socket");
  const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const bool live = probe >= 0 && ::connect(probe, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  if (probe >= 0) ::close(probe);
  errno = 0;
  if (live) socket_error(path, "another process listens on it");
  ::unlink(path.c_str());
}

bool send_line(int fd, const std::string& s) {
  const std::string line = s + "\n";
  return ::send(fd, line.data(), line.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(line.size());
}

}  // namespace

ControlSocket::ControlSocket(const std::string& path) : path_(path) {
  const sockaddr_un a = socket_address(path);
  clear_stale_socket(path, a);
  fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) socket_error(path, "socket");
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0 || ::listen(fd_, 8) != 0) {
    const int e = errno;
    ::close(fd_);
    errno = e;
    socket_error(path, "cannot listen");
  }
}

ControlSocket::~ControlSocket() {
  for (auto& c : clients_) ::close(c.fd);
  ::close(fd_);
  ::unlink(path_.c_str());
}

void ControlSocket::poll(FeedPort& port) {
  for (;;) {
    const int c = ::accept4(fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (c < 0) break;
    clients_.push_back({c, {}});
  }
  for (size_t i = 0; i < clients_.size();) {
    if (serve(clients_[i], port)) {
      ++i;
    } else {
      ::close(clients_[i].fd);
      clients_.erase(clients_.begin() + static_cast<long>(i));
    }
  }
}

// Reads what the client sent and answers each whole line; false when it
// closed, failed, or sent a line longer than any command.
bool ControlSocket::serve(Client& c, FeedPort& port) {
  char buf[512];
  for (;;) {
    const ssize_t n = ::recv(c.fd, buf, sizeof buf, 0);
    if (n == 0) return false;
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      if (errno == EINTR) continue;
      return false;
    }
    c.in.append(buf, static_cast<size_t>(n));
    for (size_t nl; (nl = c.in.find('\n')) != std::string::npos;) {
      const std::string line = c.in.substr(0, nl);
      c.in.erase(0, nl + 1);
      if (!send_line(c.fd, run_control_command(parse_control_line(line), port))) return false;
    }
    if (c.in.size() > kLongestLine) {
      send_line(c.fd, "error: a line longer than " + std::to_string(kLongestLine) + " bytes");
      return false;
    }
  }
  return true;
}

// ---- the keyboard ------------------------------------------------------

std::string apply_key(char key, FeedPort& port, std::atomic<bool>& interrupt) {
  const FeedState f = port.feed_state();
  auto set = [&](double percent, bool hold) -> std::string {
    try {
      port.set_feed(percent, hold);
    } catch (const FeedRefused& e) {
      return e.what();
    }
    const FeedState g = port.feed_state();
    return g.hold ? "hold (target " + percent_text(g.target_percent()) + ")"
                  : "feed " + percent_text(g.target_percent());
  };
  auto within = [&](double p) { return std::clamp(p, 0.0, f.max_percent); };
  switch (key) {
    case 'h': case 'H': case ' ':
      return set(f.target_percent(), !f.hold);
    case '+': case '=':
      return set(within(f.target_percent() + 10), f.hold);
    case '-': case '_':
      return set(within(f.target_percent() - 10), f.hold);
    case '1':
      return set(within(100), f.hold);
    case 'q': case 'Q':
      interrupt.store(true);
      return "stop";
    default:
      return "";
  }
}

KeyboardControl::KeyboardControl(int fd, std::atomic<bool>& interrupt, std::function<void(const std::string&)> say)
    : fd_(fd), interrupt_(interrupt), say_(std::move(say)) {
  if (!::isatty(fd) || ::tcgetattr(fd, &saved_) != 0) throw LinkError("the keyboard: not a terminal");
  struct termios raw = saved_;
  raw.c_lflag &= static_cast<tcflag_t>(~(ICANON | ECHO));  // ISIG stays: Ctrl-C is SIGINT
  raw.c_cc[VMIN] = 1;
  raw.c_cc[VTIME] = 0;
  if (::tcsetattr(fd, TCSANOW, &raw) != 0) throw LinkError("the keyboard: cannot set the terminal's mode");
}

// SIGTTOU blocked: a process the shell put in the background (Ctrl-Z, bg)
// restores the mode instead of being stopped by it.
KeyboardControl::~KeyboardControl() {
  sigset_t ttou, old;
  sigemptyset(&ttou);
  sigaddset(&ttou, SIGTTOU);
  pthread_sigmask(SIG_BLOCK, &ttou, &old);
  ::tcsetattr(fd_, TCSANOW, &saved_);
  pthread_sigmask(SIG_SETMASK, &old, nullptr);
}

void KeyboardControl::poll(FeedPort& port) {
  // in the background of its controlling terminal a read would stop the
  // process (SIGTTIN); tcgetpgrp fails on a terminal that is not the controlling one
  const pid_t fg = ::tcgetpgrp(fd_);
  if (fg != -1 && fg != ::getpgrp()) return;
  while (open_) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 0) <= 0 || !(p.revents & (POLLIN | POLLHUP))) return;
    char keys[64];
    const ssize_t n = ::read(fd_, keys, sizeof keys);
    if (n <= 0) {
      open_ = n < 0 && errno == EINTR;  // end of input: no more keys
      return;
    }
    for (ssize_t i = 0; i < n; ++i) {
      const std::string what = apply_key(keys[i], port, interrupt_);
      if (!what.empty() && say_) say_(what);
    }
  }
}

}  // namespace traj::link
