// Live feed control while `trajcore upload` plays a time-scaled stream: the
// feed override and hold an operator changes (the keyboard, a control
// socket), sent as FEED frames (rtl/board/LINK.md) by the upload client.
//
// The upload client is a FeedPort; the controls are FeedControls it polls
// every turn of its loops (one thread: a control's command runs inside the
// poll, FEED and its ACK included).
#pragma once
#include <termios.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "link/frame.hpp"

namespace traj::link {

// s = S 2^-sb in percent, and the S of a percent (rounded, at most s_max).
inline double scale_percent(int64_t s, int scale_bits) { return 100.0 * std::ldexp(double(s), -scale_bits); }
int64_t scale_of_percent(double percent, int scale_bits, int64_t s_max);

// The feed as the tool sent it and as the board's latest STATUS reports it.
struct FeedState {
  int scale_bits = 0;          // sb: s = S 2^-sb
  int64_t s_max = 0;           // the largest target S
  double max_percent = 100;    // the stream's scale_max (its header), %: the largest feed asked for
  int64_t target_s = 0;        // the override sent (CONFIG, FEED)
  bool hold = false;           // the hold bit sent
  bool have_status = false;    // the board fields below are from a STATUS
  int64_t s = 0;               // the board's S
  bool held = false, starved = false;  // STATUS flags: held (FEED or the hold pin), starved hold
  uint32_t starved_holds = 0;

  double target_percent() const { return scale_percent(target_s, scale_bits); }
  double effective_percent() const { return scale_percent(s, scale_bits); }
};

// One line: "feed 79.99 % (target 80.00 %), hold off, held no, starved no, starved holds 0".
std::string describe_feed(const FeedState& f);

// A feed change refused (out of range, or NAK 4 from the board): the upload
// goes on; the control that asked reports it.
class FeedRefused : public LinkError {
 public:
  using LinkError::LinkError;
};

// The upload client as the controls see it.
class FeedPort {
 public:
  virtual ~FeedPort() = default;
  virtual FeedState feed_state() const = 0;
  // Sends FEED (target in % of the planned speed, hold) and waits for its
  // ACK. Throws FeedRefused for a percent outside 0 .. max_percent or a NAK 4
  // (the message names the value); other failures (no answer) end the upload.
  virtual void set_feed(double percent, bool hold) = 0;
};

class FeedControl {
 public:
  virtual ~FeedControl() = default;
  // Takes what arrived (non-blocking) and runs it on `port`.
  virtual void poll(FeedPort& port) = 0;
};

// ---- the control socket's text protocol --------------------------------

struct ControlCommand {
  enum class Kind { kInvalid, kFeed, kHold, kResume, kStatus };
  Kind kind = Kind::kInvalid;
  double percent = 0;  // kFeed
  std::string error;   // kInvalid: why
};
// One line (without its newline; a trailing '\r' and surrounding blanks are
// ignored): "feed <percent>" (a trailing '%' allowed), "hold", "resume", "status".
ControlCommand parse_control_line(const std::string& line);
// Runs a command: the answer line without its newline, "ok ..." or "error: ...".
std::string run_control_command(const ControlCommand& c, FeedPort& port);

// A Unix-domain stream socket at `path` (created; removed by the destructor)
// taking command lines from any number of clients, one answer line each.
class ControlSocket : public FeedControl {
 public:
  // Throws LinkError if the path is taken (by a file, or a socket another
  // process listens on; a stale socket is replaced) or the socket fails.
  explicit ControlSocket(const std::string& path);
  ~ControlSocket() override;
  ControlSocket(const ControlSocket&) = delete;
  ControlSocket& operator=(const ControlSocket&) = delete;
  void poll(FeedPort& port) override;
  const std::string& path() const { return path_; }

 private:
  struct Client {
    int fd = -1;
    std::string in;
  };
  bool serve(Client& c, FeedPort& port);  // false: close it
  std::string path_;
  int fd_ = -1;
  std::vector<Client> clients_;
};

// ---- the keyboard ------------------------------------------------------

// One key: 'h' or ' ' toggles hold, '+' / '-' the override by 10 % (within
// 0 .. max), '1' 100 % (at most max), 'q' sets `interrupt` (as Ctrl-C).
// Returns what it did ("" for other keys); a refused change says why.
std::string apply_key(char key, FeedPort& port, std::atomic<bool>& interrupt);

// Keys from a terminal in non-canonical mode without echo (signals stay on:
// Ctrl-C is SIGINT); the destructor restores the terminal's mode.
class KeyboardControl : public FeedControl {
 public:
  // `say` shows what a key did. Throws LinkError if `fd` is not a terminal.
  KeyboardControl(int fd, std::atomic<bool>& interrupt, std::function<void(const std::string&)> say);
  ~KeyboardControl() override;
  KeyboardControl(const KeyboardControl&) = delete;
  KeyboardControl& operator=(const KeyboardControl&) = delete;
  void poll(FeedPort& port) override;
  static const char* help() { return "keys: h or space hold/resume, + / - feed +/-10 %, 1 feed 100 %, q stop"; }

 private:
  int fd_;
  std::atomic<bool>& interrupt_;
  std::function<void(const std::string&)> say_;
  struct termios saved_ {};  // the terminal's mode, restored by the destructor
  bool open_ = true;
};

// Several controls polled in turn.
class FeedControls : public FeedControl {
 public:
  void add(std::unique_ptr<FeedControl> c) { all_.push_back(std::move(c)); }
  bool empty() const { return all_.empty(); }
  void poll(FeedPort& port) override {
    for (auto& c : all_) c->poll(port);
  }

 private:
  std::vector<std::unique_ptr<FeedControl>> all_;
};

}  // namespace traj::link
