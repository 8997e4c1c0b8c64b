#include "fuzz_entries.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "input/dxf.hpp"
#include "input/gcode.hpp"
#include "input/jsonl_source.hpp"
#include "input/path_json.hpp"
#include "input/svg.hpp"
#include "link/board.hpp"
#include "link/frame.hpp"
#include "stream/segment_stream.hpp"

namespace traj::fuzz {

namespace {
[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz finding: %s\n", what.c_str());
  std::abort();
}

// A refusal is accepted if its message is short enough to be one error line.
void refused(const std::exception& e) {
  const std::string m = e.what();
  if (m.size() > kMaxMessage)
    finding("error message of " + std::to_string(m.size()) + " bytes: " + m.substr(0, 200) + " ...");
}

// Runs `read`, accepting a return or any std::runtime_error (the project's error classes).
template <class F>
int guarded(F&& read) {
  try {
    read();
  } catch (const std::runtime_error& e) {
    refused(e);
  }
  return 0;
}

std::string text(const uint8_t* data, std::size_t size) { return std::string(reinterpret_cast<const char*>(data), size); }
}  // namespace

int stream(const uint8_t* data, std::size_t size) {
  std::istringstream in(text(data, size));
  stream::StreamReader r(in, "fuzz.trj");
  stream::Record rec;
  while (r.next(rec)) {
    // An accepted record is the exact bytes its decoded form encodes to.
    if (stream::encode_record(r.header(), rec) != r.raw()) finding("record re-encodes to other bytes");
  }
  if (!r.complete() && r.error().empty()) finding("stream neither complete nor refused");
  if (r.error().size() > kMaxMessage) finding("stream error of " + std::to_string(r.error().size()) + " bytes");
  return 0;
}

int json(const uint8_t* data, std::size_t size) {
  return guarded([&] { input::parse_path(text(data, size), "fuzz.json"); });
}

int jsonl(const uint8_t* data, std::size_t size) {
  return guarded([&] {
    std::istringstream in(text(data, size));
    input::JsonlSource src(in, "fuzz.jsonl");
    geo::BSpline b;
    std::string where;
    while (src.next(b, where)) plan::PathCurve(b, where);  // the planner's loading: arc length, tables
  });
}

int gcode(const uint8_t* data, std::size_t size) {
  return guarded([&] {
    std::istringstream in(text(data, size));
    input::GcodeOptions opt;
    opt.axes = "XYZABCUV";  // every axis word a machine may have is read (8 axes: the core's)
    // what a table and --pause-as-stop open up is read too: G43 (with M6 or without), M0 and M60
    opt.tools = input::ToolTable{"fuzz.tbl", {{1, 40.5}, {2, -3.25}}};
    opt.pauses_as_stops = true;
    // Moves are read a block at a time, as the streamed planner reads them. A few bytes may be a
    // legitimate block of 100 000 pecks (seconds under the sanitizers): the reader's cost per move
    // is what is fuzzed, not the length of the program a file expands to, so reading stops after
    // kMaxGcodeMoves (the block that crosses it is read whole).
    input::GcodeReader reader(in, "fuzz.ngc", opt);
    input::Move m;
    for (std::size_t n = 0; n < kMaxGcodeMoves && reader.next(m); ++n) {
    }
  });
}

int svg(const uint8_t* data, std::size_t size) {
  return guarded([&] { input::parse_svg(text(data, size), "fuzz.svg"); });
}

int dxf(const uint8_t* data, std::size_t size) {
  // dxflib reads files only: one temporary file per process, rewritten for each input.
  static const std::string path = "/tmp/trajcore-fuzz-" + std::to_string(getpid()) + ".dxf";
  {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  const int r = guarded([&] { input::read_dxf(path); });
  std::remove(path.c_str());
  return r;
}

namespace {

std::vector<link::FrameDecoder::Event> frames_of(const link::Bytes& b) {
  link::FrameDecoder d;
  std::vector<link::FrameDecoder::Event> ev;
  d.feed(b.data(), b.size(), ev);
  return ev;
}

// A good frame decodes by its type (or is refused with a LinkError) and
// re-encodes to a frame that decodes to itself.
void check_good_frame(const link::Frame& f) {
  guarded([&] {
    switch (f.type) {
      case link::Type::kAck: link::decode_ack(f); break;
      case link::Type::kNak: link::decode_nak(f); break;
      case link::Type::kStatus: link::decode_status(f); break;
      case link::Type::kConfig: link::decode_config(f.payload); break;
      case link::Type::kFeed: link::decode_feed(f.payload); break;
      default: break;
    }
  });
  const auto again = frames_of(link::encode_frame(f));
  if (again.size() != 1 || !again[0].good || again[0].frame.type != f.type || again[0].frame.seq != f.seq ||
      again[0].frame.payload != f.payload)
    finding("a good frame does not re-encode to itself");
}

}  // namespace

int link(const uint8_t* data, std::size_t size) {
  const link::Bytes bytes(data, data + size);
  for (const auto& e : frames_of(bytes)) {
    if (e.good) check_good_frame(e.frame);
    else if (e.why.empty() || e.why.size() > kMaxMessage) finding("a bad body without a short reason");
  }
  // The loopback board takes the bytes as a host's: it must never throw
  // (a board answers garbage with NAK or silence), and every byte it sends
  // back is a good frame.
  link::BoardOptions bo;
  bo.fifo_segments = 4;
  bo.speed = 0;
  link::Bytes out;
  try {
    link::LoopbackBoard board(bo);
    board.receive(data, size, out);
    board.advance(1.0, out);
  } catch (const std::exception& e) {
    finding(std::string("the loopback board threw: ") + e.what());
  }
  for (const auto& e : frames_of(out))
    if (!e.good) finding("the board sent a bad frame: " + e.why);
  return 0;
}

const std::vector<Target>& targets() {
  static const std::vector<Target> t = {{"stream", stream}, {"json", json}, {"jsonl", jsonl},
                                        {"gcode", gcode},   {"svg", svg},   {"dxf", dxf},
                                        {"link", link}};
  return t;
}

}  // namespace traj::fuzz
