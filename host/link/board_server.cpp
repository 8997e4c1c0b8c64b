#include "link/board_server.hpp"

#include <chrono>
#include <thread>

namespace traj::link {

double now_ms() {
  using namespace std::chrono;
  return duration<double, std::milli>(steady_clock::now().time_since_epoch()).count();
}

void ByteMangler::push(const uint8_t* p, size_t n, double now) {
  for (size_t i = 0; i < n; ++i) {
    uint8_t c = p[i];
    if (f_.drop > 0 && u_(rng_) < f_.drop) {
      ++dropped;
      continue;
    }
    if (f_.corrupt > 0 && u_(rng_) < f_.corrupt) {
      c ^= static_cast<uint8_t>(1u << (rng_() % 8));
      ++corrupted;
    }
    emit(c, now);
    if (f_.dup_frames <= 0) continue;
    if (c != kFlag) {
      frame_.push_back(c);
    } else {
      if (!frame_.empty() && u_(rng_) < f_.dup_frames) {
        emit(kFlag, now);
        for (uint8_t b : frame_) emit(b, now);
        emit(kFlag, now);
        ++duplicated;
      }
      frame_.clear();
    }
  }
}

size_t ByteMangler::pop(uint8_t* p, size_t n, double now) {
  size_t k = 0;
  while (k < n && !q_.empty() && q_.front().at <= now) {
    p[k++] = q_.front().c;
    q_.pop_front();
  }
  return k;
}

FaultyTransport::FaultyTransport(Transport& inner, const FaultOptions& f)
    : inner_(inner),
      f_(f),
      in_(f.to_board ? f : FaultOptions{}, f.seed * 2 + 1),
      out_(f.to_host ? f : FaultOptions{}, f.seed * 2 + 2) {}

void FaultyTransport::flush_out() {
  uint8_t buf[4096];
  for (size_t k; (k = out_.pop(buf, sizeof buf, now_ms())) > 0;) inner_.write(buf, k);
}

void FaultyTransport::write(const uint8_t* p, size_t n) {
  out_.push(p, n, now_ms());
  flush_out();
}

size_t FaultyTransport::read(uint8_t* p, size_t n, int timeout_ms) {
  flush_out();
  uint8_t buf[4096];
  const size_t k = inner_.read(buf, sizeof buf, in_.empty() ? timeout_ms : std::min(timeout_ms, 1));
  in_.push(buf, k, now_ms());
  flush_out();
  return in_.pop(p, n, now_ms());
}

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
