#include "link/transport.hpp"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <libserialport.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>

namespace traj::link {
namespace {

std::string errno_text(const std::string& what) { return what + ": " + std::strerror(errno); }

class FdTransport : public Transport {
 public:
  // drop_when_full: a pseudo-terminal master with no tool attached fills up;
  // bytes that do not fit are lost as on a UART nobody listens to.
  FdTransport(int fd, std::string name, bool drop_when_full = false)
      : fd_(fd), name_(std::move(name)), drop_(drop_when_full) {}
  ~FdTransport() override { ::close(fd_); }

  void write(const uint8_t* p, size_t n) override {
    while (n > 0) {
      const ssize_t k = ::write(fd_, p, n);
      if (k > 0) {
        p += k;
        n -= static_cast<size_t>(k);
        continue;
      }
      if (k < 0 && errno == EINTR) continue;
      if (k < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
        if (drop_) return;
        pollfd pf{fd_, POLLOUT, 0};
        if (::poll(&pf, 1, 2000) == 0) throw LinkError(name_ + ": write timed out");
        continue;
      }
      throw LinkError(errno_text(name_ + ": write"));
    }
  }

  size_t read(uint8_t* p, size_t n, int timeout_ms) override {
    pollfd pf{fd_, POLLIN, 0};
    int r;
    do r = ::poll(&pf, 1, timeout_ms);
    while (r < 0 && errno == EINTR);
    if (r < 0) throw LinkError(errno_text(name_ + ": poll"));
    if (r == 0) return 0;
    const ssize_t k = ::read(fd_, p, n);
    if (k > 0) return static_cast<size_t>(k);
    if (k < 0 && (errno == EINTR || errno == EAGAIN)) return 0;
    // A raw tty (VMIN 0) reads 0 bytes with nothing to read, not only at a
    // hang-up: only POLLHUP says the other end is gone.
    if (k == 0 && !(pf.revents & POLLHUP) && ::isatty(fd_)) return 0;
    if (k == 0) throw LinkError(name_ + ": closed by the other end");
    throw LinkError(errno_text(name_ + ": read"));
  }

  std::string name() const override { return name_; }

 private:
  int fd_;
  std::string name_;
  bool drop_;
};

void set_raw(int fd, const std::string& name) {
  termios t{};
  if (::tcgetattr(fd, &t) != 0) throw LinkError(errno_text(name + ": tcgetattr"));
  ::cfmakeraw(&t);
  if (::tcsetattr(fd, TCSANOW, &t) != 0) throw LinkError(errno_text(name + ": tcsetattr"));
}

class SerialTransport : public Transport {
 public:
  SerialTransport(const std::string& name, int baud) : name_(name) {
    check(sp_get_port_by_name(name.c_str(), &port_), "no such port");
    check(sp_open(port_, SP_MODE_READ_WRITE), "cannot open");
    check(sp_set_baudrate(port_, baud), "cannot set baud rate " + std::to_string(baud));
    check(sp_set_bits(port_, 8), "cannot set 8 data bits");
    check(sp_set_parity(port_, SP_PARITY_NONE), "cannot set no parity");
    check(sp_set_stopbits(port_, 1), "cannot set 1 stop bit");
    check(sp_set_flowcontrol(port_, SP_FLOWCONTROL_NONE), "cannot disable flow control");
  }
  ~SerialTransport() override {
    if (port_) {
      sp_close(port_);
      sp_free_port(port_);
    }
  }
  void write(const uint8_t* p, size_t n) override {
    const sp_return r = sp_blocking_write(port_, p, n, 5000);
    if (r < 0) check(r, "write failed");
    if (static_cast<size_t>(r) != n) throw LinkError(name_ + ": write timed out");
  }
  size_t read(uint8_t* p, size_t n, int timeout_ms) override {
    // libserialport: timeout 0 waits for ever; a poll is the non-blocking read
    const sp_return r = timeout_ms == 0 ? sp_nonblocking_read(port_, p, n)
                                        : sp_blocking_read_next(port_, p, n, timeout_ms < 0 ? 0u : unsigned(timeout_ms));
    if (r < 0) check(r, "read failed");
    return static_cast<size_t>(r);
  }
  std::string name() const override { return name_; }

 private:
  void check(sp_return r, const std::string& what) {
    if (r == SP_OK) return;
    std::string why = what;
    if (r == SP_ERR_FAIL) {
      char* m = sp_last_error_message();
      why += std::string(" (") + (m ? m : "?") + ")";
      sp_free_error_message(m);
    }
    throw LinkError(name_ + ": " + why);
  }
  std::string name_;
  sp_port* port_ = nullptr;
};

std::unique_ptr<Transport> connect_tcp(const std::string& spec) {
  const std::string rest = spec.substr(4);
  const size_t colon = rest.rfind(':');
  if (colon == std::string::npos) throw LinkError(spec + ": expected tcp:HOST:PORT");
  const std::string host = rest.substr(0, colon), port = rest.substr(colon + 1);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  if (::getaddrinfo(host.c_str(), port.c_str(), &hints, &res) != 0) throw LinkError(spec + ": cannot resolve");
  int fd = -1;
  for (addrinfo* a = res; a && fd < 0; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype, a->ai_protocol);
    if (fd >= 0 && ::connect(fd, a->ai_addr, a->ai_addrlen) != 0) {
      ::close(fd);
      fd = -1;
    }
  }
  ::freeaddrinfo(res);
  if (fd < 0) throw LinkError(errno_text(spec + ": cannot connect"));
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  return std::make_unique<FdTransport>(fd, spec);
}

// One direction of an in-process pipe.
struct Channel {
  std::mutex m;
  std::condition_variable cv;
  std::deque<uint8_t> q;
  bool closed = false;
};

class PipeEnd : public Transport {
 public:
  PipeEnd(std::shared_ptr<Channel> in, std::shared_ptr<Channel> out, std::string name)
      : in_(std::move(in)), out_(std::move(out)), name_(std::move(name)) {}
  ~PipeEnd() override {
    for (auto* c : {in_.get(), out_.get()}) {
      std::lock_guard<std::mutex> l(c->m);
      c->closed = true;
      c->cv.notify_all();
    }
  }
  void write(const uint8_t* p, size_t n) override {
    std::lock_guard<std::mutex> l(out_->m);
    if (out_->closed) throw LinkError(name_ + ": closed by the other end");
    out_->q.insert(out_->q.end(), p, p + n);
    out_->cv.notify_all();
  }
  size_t read(uint8_t* p, size_t n, int timeout_ms) override {
    std::unique_lock<std::mutex> l(in_->m);
    auto ready = [&] { return !in_->q.empty() || in_->closed; };
    if (timeout_ms < 0) in_->cv.wait(l, ready);
    else in_->cv.wait_for(l, std::chrono::milliseconds(timeout_ms), ready);
    if (in_->q.empty()) {
      if (in_->closed) throw LinkError(name_ + ": closed by the other end");
      return 0;
    }
    const size_t k = std::min(n, in_->q.size());
    std::copy(in_->q.begin(), in_->q.begin() + static_cast<long>(k), p);
    in_->q.erase(in_->q.begin(), in_->q.begin() + static_cast<long>(k));
    return k;
  }
  std::string name() const override { return name_; }

 private:
  std::shared_ptr<Channel> in_, out_;
  std::string name_;
};

class PtyListener : public Listener {
 public:
  PtyListener() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0)
      throw LinkError(errno_text("cannot create a pseudo-terminal"));
    slave_name_ = ::ptsname(master_);
    // our own slave descriptor keeps the master readable while no tool has
    // the slave open, and sets the line raw (no echo, no line editing)
    slave_ = ::open(slave_name_.c_str(), O_RDWR | O_NOCTTY);
    if (slave_ < 0) throw LinkError(errno_text(slave_name_));
    set_raw(slave_, slave_name_);
    ::fcntl(master_, F_SETFL, ::fcntl(master_, F_GETFL) | O_NONBLOCK);
  }
  ~PtyListener() override {
    if (master_ >= 0) ::close(master_);
    ::close(slave_);
  }
  std::unique_ptr<Transport> accept(int timeout_ms) override {
    if (master_ < 0) {  // one connection: the pseudo-terminal serves every tool in turn
      if (timeout_ms < 0) for (;;) ::pause();
      ::usleep(static_cast<useconds_t>(timeout_ms) * 1000);
      return nullptr;
    }
    const int fd = master_;
    master_ = -1;
    return std::make_unique<FdTransport>(fd, "pty master of " + slave_name_, true);
  }
  std::string port_spec() const override { return slave_name_; }

 private:
  int master_ = -1, slave_ = -1;
  std::string slave_name_;
};

class TcpListener : public Listener {
 public:
  explicit TcpListener(int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd_ < 0) throw LinkError(errno_text("socket"));
    const int one = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<uint16_t>(port));
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(fd_, 4) != 0)
      throw LinkError(errno_text("tcp port " + std::to_string(port)));
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
  }
  ~TcpListener() override { ::close(fd_); }
  std::unique_ptr<Transport> accept(int timeout_ms) override {
    pollfd pf{fd_, POLLIN, 0};
    if (::poll(&pf, 1, timeout_ms) <= 0) return nullptr;
    const int c = ::accept(fd_, nullptr, nullptr);
    if (c < 0) return nullptr;
    const int one = 1;
    ::setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    return std::make_unique<FdTransport>(c, "tcp client on port " + std::to_string(port_));
  }
  std::string port_spec() const override { return "tcp:127.0.0.1:" + std::to_string(port_); }

 private:
  int fd_ = -1, port_ = 0;
};

}  // namespace

std::unique_ptr<Transport> fd_transport(int fd, const std::string& name) {
  return std::make_unique<FdTransport>(fd, name);
}

std::unique_ptr<Transport> open_port(const std::string& spec, int baud) {
  if (spec.rfind("tcp:", 0) == 0) return connect_tcp(spec);
  if (spec.rfind("/dev/pts/", 0) == 0) {
    const int fd = ::open(spec.c_str(), O_RDWR | O_NOCTTY);
    if (fd < 0) throw LinkError(errno_text(spec));
    set_raw(fd, spec);
    return std::make_unique<FdTransport>(fd, spec);
  }
  return std::make_unique<SerialTransport>(spec, baud);
}

std::pair<std::unique_ptr<Transport>, std::unique_ptr<Transport>> make_pipe_pair() {
  auto a = std::make_shared<Channel>(), b = std::make_shared<Channel>();
  return {std::make_unique<PipeEnd>(a, b, "pipe (host end)"), std::make_unique<PipeEnd>(b, a, "pipe (board end)")};
}

std::unique_ptr<Listener> listen_pty() { return std::make_unique<PtyListener>(); }
std::unique_ptr<Listener> listen_tcp(int port) { return std::make_unique<TcpListener>(port); }

}  // namespace traj::link
