// One entry function per reader that takes outside bytes. The libFuzzer targets (fuzz_main.cpp, built
// with clang -fsanitize=fuzzer,address,undefined by scripts/fuzz.sh) and the regression replay
// (regressions_test.cpp, the normal build) call the same functions.
//
// Each entry feeds the bytes to the reader and accepts every outcome the reader documents: the input
// read, or refused with one of the project's errors (all derived from std::runtime_error) whose
// message is short (a message longer than kMaxMessage aborts: an error line must not echo megabytes
// of input). Anything else escapes and is a finding: a crash, a sanitizer report, another exception,
// a hang (libFuzzer's -timeout), a stream record that does not re-encode to its own bytes.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace traj::fuzz {

constexpr std::size_t kMaxMessage = 1024;
constexpr std::size_t kMaxGcodeMoves = 100000;  // the G-code moves one input is read for (fuzz_entries.cpp)

int stream(const uint8_t* data, std::size_t size);  // StreamReader on the bytes (segment stream v3)
int json(const uint8_t* data, std::size_t size);    // JSON path: one curve or {"curves": [...]}
int jsonl(const uint8_t* data, std::size_t size);   // JSON Lines path
int gcode(const uint8_t* data, std::size_t size);   // G-code (RS274NGC subset), its first moves
int svg(const uint8_t* data, std::size_t size);     // SVG (tinyxml2)
int dxf(const uint8_t* data, std::size_t size);     // DXF (dxflib; through a temporary file)
int link(const uint8_t* data, std::size_t size);    // link frames (LINK.md) at both ends: the host's
                                                    // decoder, the loopback board taking them as a host's

struct Target {
  const char* name;
  int (*entry)(const uint8_t*, std::size_t);
};
// Every target, by the name of its folders (corpus/<name>, regressions/<name>, dict/<name>.dict).
const std::vector<Target>& targets();

}  // namespace traj::fuzz
