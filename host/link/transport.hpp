// Byte transports of the host link, behind one interface: a serial port
// (libserialport), a file descriptor (pseudo-terminal, TCP socket), and an
// in-process pipe for tests. Frames are the caller's business (frame.hpp).
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "link/frame.hpp"

namespace traj::link {

class Transport {
 public:
  virtual ~Transport() = default;
  // Writes all bytes; throws LinkError if the port fails or the peer is gone.
  virtual void write(const uint8_t* p, size_t n) = 0;
  // Reads what is there, waiting at most timeout_ms for the first byte;
  // returns 0 on timeout; throws LinkError if the port fails or the peer closed.
  virtual size_t read(uint8_t* p, size_t n, int timeout_ms) = 0;
  virtual std::string name() const = 0;

  void write(const Bytes& b) { write(b.data(), b.size()); }
};

// Opens the host side of a link: "tcp:HOST:PORT" (a TCP socket), "/dev/pts/N"
// (a pseudo-terminal, raw), any other name a serial port through libserialport
// at `baud` 8N1 without flow control.
std::unique_ptr<Transport> open_port(const std::string& spec, int baud);

// A connected pair of in-process byte pipes: what one end writes the other reads.
std::pair<std::unique_ptr<Transport>, std::unique_ptr<Transport>> make_pipe_pair();

// A transport over a file descriptor it owns (a socket or a tty set raw).
std::unique_ptr<Transport> fd_transport(int fd, const std::string& name);

// The board side: a pseudo-terminal whose slave the tool opens, or a TCP
// listener; accept() waits for the next tool (a restarted tool reconnects).
class Listener {
 public:
  virtual ~Listener() = default;
  // The next connection; nullptr after timeout_ms (< 0: wait forever).
  virtual std::unique_ptr<Transport> accept(int timeout_ms) = 0;
  // What the tool passes as --port.
  virtual std::string port_spec() const = 0;
};
// A pseudo-terminal pair; the master stays open across tools.
std::unique_ptr<Listener> listen_pty();
// A TCP listener on 127.0.0.1 (port 0: any free port).
std::unique_ptr<Listener> listen_tcp(int port);

}  // namespace traj::link
