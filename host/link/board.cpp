#include "link/board.hpp"

#include <algorithm>
#include <cmath>

namespace traj::link {

LoopbackBoard::LoopbackBoard(const BoardOptions& o) : o_(o) { reset(); }

void LoopbackBoard::reset() {
  dec_ = FrameDecoder();
  fifo_.clear();
  next_seq_ = seq_playing_ = 0;
  configured_ = playing_ = halted_ = stop_req_ = end_marked_ = end_reached_ = in_segment_ = false;
  cfg_ = Config();
  left_in_segment_ = 0;
  tick_budget_ = 0;
  next_status_tick_ = 0;
  st_ = Status();
  st_.axes = static_cast<uint8_t>(o_.format.axes);
  st_.sample.assign(static_cast<size_t>(o_.format.axes), 0);
}

uint16_t LoopbackBoard::credits() const {
  return static_cast<uint16_t>(std::min<size_t>(o_.fifo_segments - fifo_.size(), 0xFFFF));
}

void LoopbackBoard::ack(Bytes& out) const {
  const Bytes f = encode_frame(Type::kAck, next_seq_, encode_ack({next_seq_, credits()}));
  out.insert(out.end(), f.begin(), f.end());
}

void LoopbackBoard::nak(NakReason r, Bytes& out) const {
  const Bytes f =
      encode_frame(Type::kNak, next_seq_, encode_nak({next_seq_, static_cast<uint8_t>(r), credits()}));
  out.insert(out.end(), f.begin(), f.end());
}

Status LoopbackBoard::status() const {
  Status s = st_;
  s.clock_hz = static_cast<uint32_t>(std::lround(o_.clock_hz));
  s.next_seq = next_seq_;
  s.flags = static_cast<uint8_t>((playing_ ? status_flag::kPlaying : 0) | (halted_ ? status_flag::kUnderrunHalt : 0) |
                                 (end_reached_ ? status_flag::kEndReached : 0) |
                                 (configured_ && cfg_.enable ? status_flag::kEnabled : 0) |
                                 (fifo_.empty() ? status_flag::kFifoEmpty : 0));
  s.fifo_level = static_cast<uint16_t>(fifo_.size());
  s.credits = credits();
  return s;
}

void LoopbackBoard::receive(const uint8_t* p, size_t n, Bytes& out) {
  st_.bytes_received += static_cast<uint32_t>(n);
  events_.clear();
  dec_.feed(p, n, events_);
  for (const auto& e : events_) {
    if (e.good && static_cast<uint8_t>(e.frame.type) < 0x80) {
      on_frame(e.frame, out);
    } else {  // a bad body, or a board-to-host type sent to the board
      ++st_.bad_frames;
      nak(NakReason::kBadFrame, out);
    }
  }
}

void LoopbackBoard::on_frame(const Frame& f, Bytes& out) {
  switch (f.type) {
    case Type::kReset:
      if (playing_) return nak(NakReason::kPlaying, out);
      fifo_.clear();
      halted_ = end_marked_ = end_reached_ = stop_req_ = in_segment_ = false;
      left_in_segment_ = 0;
      next_seq_ = f.seq;
      return ack(out);
    case Type::kConfig: {
      if (f.payload.size() != kConfigBytes || !config_good(decode_config(f.payload)))
        return nak(NakReason::kBadContent, out);
      if (playing_) return nak(NakReason::kPlaying, out);
      cfg_ = decode_config(f.payload);
      configured_ = true;
      next_status_tick_ = st_.ticks_played + cfg_.status_ticks;
      return ack(out);
    }
    case Type::kStart:
      if (!halted_ && !end_reached_) playing_ = true;
      stop_req_ = false;
      return ack(out);
    case Type::kStop:
      if (in_segment_) stop_req_ = true;
      else playing_ = false;
      return ack(out);
    case Type::kResume:
      if (halted_) {
        halted_ = false;
        playing_ = true;
      }
      return ack(out);
    case Type::kFeed:  // a build without the time-scale unit
      return nak(NakReason::kBadContent, out);
    case Type::kStatusReq: {
      const Bytes s = encode_frame(Type::kStatus, next_seq_, encode_status(status()));
      out.insert(out.end(), s.begin(), s.end());
      return;
    }
    case Type::kSegment:
      return on_segment(f, out);
    case Type::kEnd:
      if (f.seq != next_seq_) {
        ++st_.out_of_order;
        return nak(NakReason::kOutOfOrder, out);
      }
      end_marked_ = true;
      return ack(out);
    default:
      ++st_.bad_frames;
      return nak(NakReason::kBadFrame, out);
  }
}

// A build without the time-scale unit: time scaling (m != 0) is refused, and
// m = 0 needs bytes 28..39 zero.
bool LoopbackBoard::config_good(const Config& c) const {
  bool ok = c.tick_clocks == 0 || c.tick_clocks >= o_.min_tick_clocks;
  for (int a = 0; a < 8; ++a) ok = ok && c.step_shift[a] <= 63;
  ok = ok && c.pulse_clocks >= 1 && c.reserved[0] == 0 && c.reserved[1] == 0 && c.reserved[2] == 0;
  return ok && c.scale_m == 0 && c.scale_s_max == 0 && c.scale_override == 0 && c.scale_shift == 0 &&
         c.scale_flags == 0 && c.scale_reserved == 0;
}

bool LoopbackBoard::content_good(const Frame& f) const {
  const Bytes& r = f.payload;
  return r.size() == o_.format.record_bytes() && r[0] == 1 && r[1] == 0 && r[2] == 0 && r[3] == 0 &&
         get_u32(&r[8]) == f.seq && get_u32(&r[4]) != 0;
}

void LoopbackBoard::on_segment(const Frame& f, Bytes& out) {
  const int32_t d = seq_diff(f.seq, next_seq_);
  if (d < 0) return ack(out);  // a re-send of a stored record: the ACK heals a lost one
  if (d > 0) {
    ++st_.out_of_order;
    return nak(NakReason::kOutOfOrder, out);
  }
  if (!content_good(f)) return nak(NakReason::kBadContent, out);
  if (fifo_.size() >= o_.fifo_segments) return nak(NakReason::kFifoFull, out);
  fifo_.push_back(f.payload);
  ++next_seq_;
  ++stored_total_;
  ack(out);
}

int64_t LoopbackBoard::start_sample(const Bytes& rec, int axis) const {
  const BoardFormat& F = o_.format;
  const size_t wb = size_t(F.width / 8);
  const size_t at = 12 + size_t(axis) * size_t(F.degree + 1) * wb;
  unsigned __int128 u = 0;
  for (size_t i = 0; i < wb && i < 16; ++i) u |= static_cast<unsigned __int128>(rec[at + i]) << (8 * i);
  if (F.width < 128 && (rec[at + wb - 1] & 0x80)) u |= ~static_cast<unsigned __int128>(0) << F.width;  // sign
  return static_cast<int64_t>(static_cast<__int128>(u) >> F.guard);
}

void LoopbackBoard::start_next_segment() {
  const Bytes& rec = fifo_.front();
  seq_playing_ = get_u32(&rec[8]);
  left_in_segment_ = get_u32(&rec[4]);
  for (int a = 0; a < o_.format.axes; ++a) st_.sample[static_cast<size_t>(a)] = start_sample(rec, a);
  if (on_played) on_played(seq_playing_, rec);
  fifo_.pop_front();
  in_segment_ = true;
  ++st_.segments_played;
}

// At a segment end: the stop, the next segment, the end of the job, or an
// underrun (hold position, halt until RESUME). True if a segment started.
bool LoopbackBoard::at_boundary() {
  if (stop_req_) {
    playing_ = stop_req_ = false;
    return false;
  }
  if (!fifo_.empty()) {
    start_next_segment();
    return true;
  }
  playing_ = false;
  if (end_marked_) {
    end_reached_ = true;
  } else {
    ++st_.underruns;
    halted_ = true;
  }
  return false;
}

void LoopbackBoard::play_ticks(uint64_t ticks) {
  while (playing_) {
    if (!in_segment_ && !at_boundary()) return;
    if (ticks == 0) return;
    const uint64_t k = std::min(ticks, left_in_segment_);
    ticks -= k;
    left_in_segment_ -= k;
    st_.ticks_played += static_cast<uint32_t>(k);
    if (left_in_segment_ == 0) in_segment_ = false;
  }
}

// Time in steps of whole segments: a full FIFO plays its older half, END or
// STOP plays to the end; otherwise time stands still (no underrun).
void LoopbackBoard::play_unpaced() {
  size_t n = fifo_.size() >= o_.fifo_segments ? std::max<size_t>(1, o_.fifo_segments / 2) : 0;
  while (playing_) {
    if (in_segment_) {
      st_.ticks_played += static_cast<uint32_t>(left_in_segment_);
      left_in_segment_ = 0;
      in_segment_ = false;
    }
    if (!end_marked_ && !stop_req_ && (n == 0 || fifo_.empty())) return;
    if (!at_boundary()) return;
    if (n > 0) --n;
  }
}

void LoopbackBoard::advance(double now, Bytes& out) {
  const double dt = last_time_ < 0 ? 0 : now - last_time_;
  last_time_ = now;
  if (playing_) {
    if (o_.speed <= 0) {
      play_unpaced();
    } else {
      const double tick_s = cfg_.tick_clocks ? cfg_.tick_clocks / o_.clock_hz : 1e-3;
      tick_budget_ += dt * o_.speed / tick_s;
      const double whole = std::floor(tick_budget_);
      tick_budget_ -= whole;
      play_ticks(static_cast<uint64_t>(whole));
    }
  } else {
    tick_budget_ = 0;
  }
  if (configured_ && cfg_.status_ticks && st_.ticks_played >= next_status_tick_) {
    next_status_tick_ = st_.ticks_played + cfg_.status_ticks;
    const Bytes s = encode_frame(Type::kStatus, next_seq_, encode_status(status()));
    out.insert(out.end(), s.begin(), s.end());
  }
}

}  // namespace traj::link
