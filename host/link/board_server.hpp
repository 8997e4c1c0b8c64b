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

double now_ms();

// Serves a board on `t` until `stop` is set, the other end closes (a closed
// transport returns normally), or, with end_idle_s > 0, the job's end was
// reached and the tool has been silent for end_idle_s. Resets the board
// mid-job if asked (once per FaultOptions, counted in `stats`). Board: the
// loopback board (LoopbackBoard) or the simulated board
// (board::SimulatedBoard): receive(p, n, out), advance(now_s, out), reset(),
// stored_total(), end_reached().
template <class Board>
void serve(Transport& t, Board& board, const std::atomic<bool>& stop, const FaultOptions& f,
           ServeStats& stats, double end_idle_s) {
  std::unique_ptr<FaultyTransport> faulty;
  if (f.any_bytes()) faulty = std::make_unique<FaultyTransport>(t, f);
  Transport& port = faulty ? static_cast<Transport&>(*faulty) : t;
  uint8_t buf[4096];
  Bytes out;
  double last_rx = now_ms();
  auto count_faults = [&] {
    if (!faulty) return;
    stats.corrupted = faulty->to_board().corrupted + faulty->to_host().corrupted;
    stats.dropped = faulty->to_board().dropped + faulty->to_host().dropped;
    stats.duplicated = faulty->to_board().duplicated + faulty->to_host().duplicated;
  };
  try {
    while (!stop.load()) {
      const size_t n = port.read(buf, sizeof buf, board.playing() ? 0 : 1);  // a playing board runs on
      out.clear();
      const bool cut = f.cut_after && board.stored_total() >= f.cut_after;
      if (n && !cut) {
        board.receive(buf, n, out);
        last_rx = now_ms();
      }
      if (f.reset_after && stats.resets == 0 && board.stored_total() >= f.reset_after) {
        board.reset();
        ++stats.resets;
      }
      if (end_idle_s > 0 && board.end_reached() && now_ms() - last_rx > end_idle_s * 1e3) break;
      board.advance(now_ms() * 1e-3, out);
      if (!out.empty() && !cut) port.write(out);
    }
  } catch (const LinkError&) {
    // the tool closed its end: the board keeps its state for the next one
  }
  count_faults();
}

}  // namespace traj::link
