#include "link/frame.hpp"

#include <zlib.h>

namespace traj::link {

bool known_type(uint8_t t) {
  switch (static_cast<Type>(t)) {
    case Type::kReset: case Type::kConfig: case Type::kStart: case Type::kStop: case Type::kResume:
    case Type::kStatusReq: case Type::kFeed: case Type::kSegment: case Type::kEnd: case Type::kAck:
    case Type::kNak: case Type::kStatus:
      return true;
  }
  return false;
}

const char* type_name(Type t) {
  switch (t) {
    case Type::kReset: return "RESET";
    case Type::kConfig: return "CONFIG";
    case Type::kStart: return "START";
    case Type::kStop: return "STOP";
    case Type::kResume: return "RESUME";
    case Type::kStatusReq: return "STATUS_REQ";
    case Type::kFeed: return "FEED";
    case Type::kSegment: return "SEGMENT";
    case Type::kEnd: return "END";
    case Type::kAck: return "ACK";
    case Type::kNak: return "NAK";
    case Type::kStatus: return "STATUS";
  }
  return "?";
}

const char* nak_name(uint8_t reason) {
  switch (static_cast<NakReason>(reason)) {
    case NakReason::kBadFrame: return "bad frame";
    case NakReason::kOutOfOrder: return "out of order";
    case NakReason::kFifoFull: return "FIFO full";
    case NakReason::kBadContent: return "bad content";
    case NakReason::kPlaying: return "not allowed while playing";
  }
  return "unknown reason";
}

void put_u16(Bytes& b, uint16_t v) {
  b.push_back(v & 0xFF);
  b.push_back(v >> 8);
}
void put_u32(Bytes& b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back((v >> (8 * i)) & 0xFF);
}
uint32_t crc32(const uint8_t* p, size_t n) {
  return static_cast<uint32_t>(::crc32(::crc32(0L, Z_NULL, 0), p, static_cast<uInt>(n)));
}

uint32_t crc32_update(uint32_t crc, const uint8_t* p, size_t n) {
  return static_cast<uint32_t>(::crc32(crc, p, static_cast<uInt>(n)));
}

Bytes encode_frame(const Frame& f) {
  if (f.payload.size() > kMaxPayload) throw LinkError("frame payload of " + std::to_string(f.payload.size()) + " bytes");
  Bytes body;
  body.reserve(kHeaderBytes + f.payload.size() + kCrcBytes);
  body.push_back(static_cast<uint8_t>(f.type));
  body.push_back(0);
  put_u16(body, static_cast<uint16_t>(f.payload.size()));
  put_u32(body, f.seq);
  body.insert(body.end(), f.payload.begin(), f.payload.end());
  put_u32(body, crc32(body.data(), body.size()));
  Bytes w;
  w.reserve(body.size() + body.size() / 16 + 4);
  w.push_back(kFlag);
  for (uint8_t c : body) {
    if (c == kFlag || c == kEscape) {
      w.push_back(kEscape);
      w.push_back(c ^ kEscapeXor);
    } else {
      w.push_back(c);
    }
  }
  w.push_back(kFlag);
  return w;
}

std::string parse_body(const Bytes& b, Frame& f) {
  if (b.size() < kHeaderBytes + kCrcBytes) return "body of " + std::to_string(b.size()) + " bytes";
  const size_t len = get_u16(&b[2]);
  if (len > kMaxPayload) return "len " + std::to_string(len) + " > 2048";
  if (b.size() != kHeaderBytes + len + kCrcBytes)
    return "body of " + std::to_string(b.size()) + " bytes for len " + std::to_string(len);
  if (b[1] != 0) return "flags nonzero";
  if (crc32(b.data(), kHeaderBytes + len) != get_u32(&b[kHeaderBytes + len])) return "CRC mismatch";
  if (!known_type(b[0])) return "unknown type " + std::to_string(b[0]);
  f.type = static_cast<Type>(b[0]);
  f.seq = get_u32(&b[4]);
  f.payload.assign(b.begin() + kHeaderBytes, b.begin() + kHeaderBytes + len);
  return "";
}

FrameDecoder::Event FrameDecoder::finish_body() {
  Event e;
  if (bad_escape_) e.why = "0x7D followed by neither 0x5E nor 0x5D";
  else if (overlong_) e.why = "body longer than the longest frame";
  else if (escaped_) e.why = "body ends in 0x7D";
  else e.why = parse_body(body_, e.frame);
  e.good = e.why.empty();
  if (!e.good) ++bad_;
  body_.clear();
  escaped_ = bad_escape_ = overlong_ = false;
  return e;
}

void FrameDecoder::feed(const uint8_t* p, size_t n, std::vector<Event>& out) {
  constexpr size_t kLongest = kHeaderBytes + kMaxPayload + kCrcBytes;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t c = p[i];
    if (c == kFlag) {
      // bytes before the first flag are garbage of a frame whose start was lost
      if (in_body_ && (!body_.empty() || escaped_ || bad_escape_ || overlong_)) out.push_back(finish_body());
      in_body_ = true;
      body_.clear();
      escaped_ = bad_escape_ = overlong_ = false;
      continue;
    }
    if (!in_body_) continue;
    uint8_t v = c;
    if (escaped_) {
      escaped_ = false;
      if (c != (kFlag ^ kEscapeXor) && c != (kEscape ^ kEscapeXor)) bad_escape_ = true;
      v = c ^ kEscapeXor;
    } else if (c == kEscape) {
      escaped_ = true;
      continue;
    }
    if (body_.size() < kLongest) body_.push_back(v);
    else overlong_ = true;
  }
}

Bytes encode_config(const Config& c) {
  Bytes b;
  put_u32(b, c.tick_clocks);
  put_u32(b, c.status_ticks);
  b.insert(b.end(), c.step_shift, c.step_shift + 8);
  put_u16(b, c.pulse_clocks);
  put_u16(b, c.dir_setup_clocks);
  b.push_back(c.enable);
  b.insert(b.end(), c.reserved, c.reserved + 3);
  put_u32(b, c.scale_m);
  put_u32(b, c.scale_s_max);
  put_u32(b, c.scale_override);
  b.push_back(c.scale_shift);
  b.push_back(c.scale_flags);
  put_u16(b, c.scale_reserved);
  return b;
}

Config decode_config(const Bytes& p) {
  if (p.size() != kConfigBytes)
    throw LinkError("CONFIG payload of " + std::to_string(p.size()) + " bytes, not " + std::to_string(kConfigBytes));
  Config c;
  c.tick_clocks = get_u32(&p[0]);
  c.status_ticks = get_u32(&p[4]);
  for (int i = 0; i < 8; ++i) c.step_shift[i] = p[8 + i];
  c.pulse_clocks = get_u16(&p[16]);
  c.dir_setup_clocks = get_u16(&p[18]);
  c.enable = p[20];
  for (int i = 0; i < 3; ++i) c.reserved[i] = p[21 + i];
  c.scale_m = get_u32(&p[24]);
  c.scale_s_max = get_u32(&p[28]);
  c.scale_override = get_u32(&p[32]);
  c.scale_shift = p[36];
  c.scale_flags = p[37];
  c.scale_reserved = get_u16(&p[38]);
  return c;
}

Bytes encode_feed(const Feed& f) {
  Bytes b;
  put_u32(b, f.override_s);
  b.push_back(f.hold ? feed_flag::kHold : 0);
  b.insert(b.end(), 3, 0);
  return b;
}

Feed decode_feed(const Bytes& p) {
  if (p.size() != kFeedBytes)
    throw LinkError("FEED payload of " + std::to_string(p.size()) + " bytes, not " + std::to_string(kFeedBytes));
  if ((p[4] & ~feed_flag::kHold) != 0 || p[5] != 0 || p[6] != 0 || p[7] != 0)
    throw LinkError("FEED with reserved bits set (flags byte " + std::to_string(p[4]) + ")");
  return {get_u32(&p[0]), (p[4] & feed_flag::kHold) != 0};
}

Bytes encode_ack(const Ack& a) {
  Bytes b;
  put_u16(b, a.credits);
  put_u16(b, 0);
  return b;
}
Bytes encode_nak(const Nak& n) {
  Bytes b{n.reason, 0};
  put_u16(b, n.credits);
  return b;
}

Bytes encode_status(const Status& s) {
  Bytes b{s.axes, s.flags};
  put_u16(b, s.fifo_level);
  for (uint32_t v : {s.segments_played, s.ticks_played, s.underruns, s.bad_frames, s.out_of_order, s.bytes_received,
                     s.credits, s.clock_hz, s.scale_s, s.starved_holds, s.ticks_ahead})
    put_u32(b, v);
  for (int a = 0; a < s.axes; ++a) {
    const uint64_t v = static_cast<uint64_t>(a < static_cast<int>(s.sample.size()) ? s.sample[a] : 0);
    put_u32(b, static_cast<uint32_t>(v));
    put_u32(b, static_cast<uint32_t>(v >> 32));
  }
  return b;
}

namespace {
void expect(const Frame& f, Type t, size_t bytes) {
  if (f.type != t) throw LinkError(std::string("expected ") + type_name(t) + ", got " + type_name(f.type));
  if (f.payload.size() != bytes)
    throw LinkError(std::string(type_name(t)) + " payload of " + std::to_string(f.payload.size()) + " bytes, not " +
                    std::to_string(bytes));
}
}  // namespace

Ack decode_ack(const Frame& f) {
  expect(f, Type::kAck, 4);
  return {f.seq, get_u16(&f.payload[0])};
}

Nak decode_nak(const Frame& f) {
  expect(f, Type::kNak, 4);
  return {f.seq, f.payload[0], get_u16(&f.payload[2])};
}

Status decode_status(const Frame& f) {
  if (f.type != Type::kStatus || f.payload.size() < kStatusFixedBytes)
    throw LinkError("malformed STATUS frame (" + std::to_string(f.payload.size()) + " bytes, at least " +
                    std::to_string(kStatusFixedBytes) + ")");
  const uint8_t* p = f.payload.data();
  Status s;
  s.next_seq = f.seq;
  s.axes = p[0];
  expect(f, Type::kStatus, kStatusFixedBytes + 8 * size_t(s.axes));
  s.flags = p[1];
  s.fifo_level = get_u16(p + 2);
  s.segments_played = get_u32(p + 4);
  s.ticks_played = get_u32(p + 8);
  s.underruns = get_u32(p + 12);
  s.bad_frames = get_u32(p + 16);
  s.out_of_order = get_u32(p + 20);
  s.bytes_received = get_u32(p + 24);
  s.credits = get_u32(p + 28);
  s.clock_hz = get_u32(p + 32);
  s.scale_s = get_u32(p + 36);
  s.starved_holds = get_u32(p + 40);
  s.ticks_ahead = get_u32(p + 44);
  const uint8_t* q = p + kStatusFixedBytes;
  for (int a = 0; a < s.axes; ++a)
    s.sample.push_back(static_cast<int64_t>(get_u32(q + 8 * a) | uint64_t(get_u32(q + 4 + 8 * a)) << 32));
  return s;
}

}  // namespace traj::link
