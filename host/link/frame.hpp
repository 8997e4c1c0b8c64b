// The host link's frames (rtl/board/LINK.md): HDLC byte stuffing, the 8-byte
// header, zlib's CRC-32, a streaming decoder that resynchronises on the next
// 0x7E after any garbage, and the payloads of CONFIG, FEED, ACK, NAK and
// STATUS.
// One codec for both ends: the upload tool and the loopback board.
#pragma once
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace traj::link {

using Bytes = std::vector<uint8_t>;

class LinkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

constexpr uint8_t kFlag = 0x7E, kEscape = 0x7D, kEscapeXor = 0x20;
constexpr size_t kMaxPayload = 2048;
constexpr size_t kHeaderBytes = 8, kCrcBytes = 4;
// The core clock of the iCEBreaker top and the simulated board, and the
// loopback board's default; the HX8K top runs at 60 MHz. Each board reports
// its clock in STATUS, which `trajcore upload` uses.
constexpr double kDefaultBoardClockHz = 30e6;

enum class Type : uint8_t {
  kReset = 0x01,
  kConfig = 0x02,
  kStart = 0x03,
  kStop = 0x04,
  kResume = 0x05,
  kStatusReq = 0x06,
  kFeed = 0x07,
  kSegment = 0x10,
  kEnd = 0x11,
  kAck = 0x81,
  kNak = 0x82,
  kStatus = 0x83,
};
bool known_type(uint8_t t);
const char* type_name(Type t);

enum class NakReason : uint8_t { kBadFrame = 1, kOutOfOrder = 2, kFifoFull = 3, kBadContent = 4, kPlaying = 5 };
const char* nak_name(uint8_t reason);

struct Frame {
  Type type = Type::kStatusReq;
  uint32_t seq = 0;
  Bytes payload;
};

// The whole frame on the wire: 0x7E, stuffed body, 0x7E.
Bytes encode_frame(const Frame& f);
inline Bytes encode_frame(Type t, uint32_t seq, Bytes payload = {}) { return encode_frame({t, seq, std::move(payload)}); }

// Streaming decoder: feed any bytes; each complete body (between two 0x7E)
// becomes a good frame or a bad body; empty bodies are ignored.
class FrameDecoder {
 public:
  struct Event {
    bool good = false;
    Frame frame;           // good only
    std::string why;       // bad only: what was wrong
  };
  // Appends the events of these bytes to `out`.
  void feed(const uint8_t* p, size_t n, std::vector<Event>& out);
  uint64_t bad_bodies() const { return bad_; }

 private:
  Event finish_body();
  Bytes body_;
  bool escaped_ = false, bad_escape_ = false, overlong_ = false, in_body_ = false;
  uint64_t bad_ = 0;
};

// Checks an unstuffed body; on success fills `f` and returns "", otherwise why it is bad.
std::string parse_body(const Bytes& body, Frame& f);

// CONFIG payload, 40 bytes. With time scaling (scale_m != 0) the tick is the
// servo tick; s = S 2^-sb, s = 1 at S = 2^sb.
struct Config {
  uint32_t tick_clocks = 0;      // 0: external tick input
  uint32_t status_ticks = 0;     // 0: STATUS only on request
  uint8_t step_shift[8] = {};    // one step = 2^shift output LSB
  uint16_t pulse_clocks = 1;
  uint16_t dir_setup_clocks = 0;
  uint8_t enable = 1;
  uint8_t reserved[3] = {};
  uint32_t scale_m = 0;          // largest change of S per servo tick; 0: no time scaling (the rest must be 0)
  uint32_t scale_s_max = 0;      // S never exceeds it
  uint32_t scale_override = 0;   // the target S, as FEED sets it
  uint8_t scale_shift = 0;       // 32 - sb + p: 2^p engine ticks per servo tick at s = 1 (0..40)
  uint8_t scale_flags = 0;       // config_flag::kAutoResume; bits 1..7 reserved
  uint16_t scale_reserved = 0;
};
namespace config_flag {
constexpr uint8_t kAutoResume = 1;  // resume by itself after a starved hold
}
constexpr size_t kConfigBytes = 40;
Bytes encode_config(const Config& c);
// Throws LinkError if the payload is not 40 bytes.
Config decode_config(const Bytes& p);

// FEED payload, 8 bytes: feed override and hold, taken by the next servo tick.
struct Feed {
  uint32_t override_s = 0;  // the target S (as CONFIG's scale_override)
  bool hold = false;        // target 0: the machine stops on the path; clearing it resumes
};
constexpr size_t kFeedBytes = 8;
namespace feed_flag {
constexpr uint8_t kHold = 1;
}
Bytes encode_feed(const Feed& f);
// Throws LinkError if the payload is not 8 bytes or a reserved bit or byte is set.
Feed decode_feed(const Bytes& p);

struct Ack {
  uint32_t next_seq = 0;
  uint16_t credits = 0;
};
struct Nak {
  uint32_t next_seq = 0;
  uint8_t reason = 0;
  uint16_t credits = 0;
};

namespace status_flag {
constexpr uint8_t kPlaying = 1, kUnderrunHalt = 2, kEndReached = 4, kTickError = 8, kEnabled = 16, kFifoEmpty = 32,
                  kStarved = 64,  // time scaling: a starved hold (the data ahead did not cover a stop)
                  kHeld = 128;    // FEED hold or the hold pin
}

// STATUS payload, 48 + 8 axes bytes.
constexpr size_t kStatusFixedBytes = 48;
struct Status {
  uint32_t next_seq = 0;
  uint8_t axes = 0, flags = 0;
  uint16_t fifo_level = 0;
  uint32_t segments_played = 0, ticks_played = 0, underruns = 0, bad_frames = 0, out_of_order = 0, bytes_received = 0,
           credits = 0, clock_hz = 0;
  // time scaling (0 without): the current S, starved holds since reset (mod
  // 2^16), engine ticks stored beyond those played
  uint32_t scale_s = 0, starved_holds = 0, ticks_ahead = 0;
  std::vector<int64_t> sample;  // per axis, output LSB
};

Bytes encode_ack(const Ack& a);
Bytes encode_nak(const Nak& n);
Bytes encode_status(const Status& s);
// Decoders of board -> host frames; throw LinkError on a malformed payload.
Ack decode_ack(const Frame& f);
Nak decode_nak(const Frame& f);
Status decode_status(const Frame& f);

// Little-endian helpers shared by the link code.
inline uint32_t get_u32(const uint8_t* p) { return p[0] | p[1] << 8 | p[2] << 16 | uint32_t(p[3]) << 24; }
inline uint16_t get_u16(const uint8_t* p) { return uint16_t(p[0] | p[1] << 8); }
void put_u16(Bytes& b, uint16_t v);
void put_u32(Bytes& b, uint32_t v);
uint32_t crc32(const uint8_t* p, size_t n);
// Continues a CRC-32 over more bytes (crc32_update(0, ...) == crc32(...)).
uint32_t crc32_update(uint32_t crc, const uint8_t* p, size_t n);

// Sequence arithmetic modulo 2^32: a - b as a signed distance.
inline int32_t seq_diff(uint32_t a, uint32_t b) { return static_cast<int32_t>(a - b); }

}  // namespace traj::link
