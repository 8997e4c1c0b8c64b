// Serving the loopback board on a transport, with fault injection in the byte
// path between the tool and the board (both directions): corrupted bytes,
// dropped bytes, duplicated frames, delays, and a board reset mid-job.
#pragma once
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <random>

#include "link/board.hpp"
#include "link/transport.hpp"

namespace traj::link {

struct FaultOptions {
  double corrupt = 0;        // probability per byte of a flipped bit
  double drop = 0;           // probability per byte of its loss
  double dup_frames = 0;     // probability per frame of it arriving twice
  double delay_ms = 0;       // every byte arrives this late
  bool to_board = true, to_host = true;  // which directions the faults hit
  uint64_t reset_after = 0;  // a board reset once this many segments were stored (0: none)
  uint64_t cut_after = 0;    // the link goes dead (every byte lost) once this many were stored (0: never)
  uint64_t seed = 1;
  bool any_bytes() const { return corrupt > 0 || drop > 0 || dup_frames > 0 || delay_ms > 0; }
};

// One direction's faults, applied to the bytes passing through.
class ByteMangler {
 public:
  ByteMangler(const FaultOptions& f, uint64_t seed) : f_(f), rng_(seed) {}
  void push(const uint8_t* p, size_t n, double now_ms);
  // The bytes whose time has come.
  size_t pop(uint8_t* p, size_t n, double now_ms);
  bool empty() const { return q_.empty(); }
  uint64_t corrupted = 0, dropped = 0, duplicated = 0;

 private:
  void emit(uint8_t c, double now_ms) { q_.push_back({now_ms + f_.delay_ms, c}); }
  FaultOptions f_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> u_{0.0, 1.0};
  std::vector<uint8_t> frame_;  // the frame being passed, for duplication
  struct Timed {
    double at;
    uint8_t c;
  };
  std::deque<Timed> q_;
};

// A transport whose bytes pass through a ByteMangler each way.
class FaultyTransport : public Transport {
 public:
  FaultyTransport(Transport& inner, const FaultOptions& f);
  void write(const uint8_t* p, size_t n) override;
  size_t read(uint8_t* p, size_t n, int timeout_ms) override;
  std::string name() const override { return inner_.name() + " (faults injected)"; }
  ByteMangler& to_board() { return in_; }
  ByteMangler& to_host() { return out_; }

 private:
  void flush_out();
  Transport& inner_;
  FaultOptions f_;
  ByteMangler in_, out_;
};

struct ServeStats {
  uint64_t corrupted = 0, dropped = 0, duplicated = 0, resets = 0;
};

// Serves the board on `t` until `stop` is set, the other end closes (a closed
// transport returns normally), or, with end_idle_s > 0, the job's end was
// reached and the tool has been silent for end_idle_s. Resets the board
// mid-job if asked (once per FaultOptions, counted in `stats`).
void serve(Transport& t, Board& board, const std::atomic<bool>& stop, const FaultOptions& f,
           ServeStats& stats, double end_idle_s = 0);

double now_ms();

}  // namespace traj::link
