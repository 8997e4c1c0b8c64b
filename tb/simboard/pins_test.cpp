// SPDX-License-Identifier: Apache-2.0
// The simulated board's pin codecs against hand-built waveforms.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "board/step_decoder.hpp"
#include "board/uart_pins.hpp"
#include "test_seed.hpp"

namespace traj::board {
namespace {

// An 8N1 waveform built bit by bit from the definition, not from UartPinWriter.
std::vector<bool> waveform(const std::vector<uint8_t>& bytes, uint32_t cpb, uint32_t gap) {
  std::vector<bool> w(3 * cpb, true);
  for (uint8_t b : bytes) {
    std::vector<bool> bits{false};
    for (int i = 0; i < 8; ++i) bits.push_back((b >> i) & 1);
    bits.push_back(true);
    for (bool bit : bits) w.insert(w.end(), cpb, bit);
    w.insert(w.end(), gap, true);
  }
  w.insert(w.end(), 2 * cpb, true);
  return w;
}

std::vector<uint8_t> decode(const std::vector<bool>& w, uint32_t cpb, uint64_t* framing = nullptr) {
  UartPinReader r(cpb);
  std::vector<uint8_t> out;
  for (bool level : w)
    if (auto b = r.sample(level)) out.push_back(*b);
  if (framing) *framing = r.framing_errors();
  return out;
}

TEST(UartPins, ReaderDecodesTheDefinitionsWaveform) {
  std::mt19937 rng(static_cast<uint32_t>(test::test_seed(1)));
  for (uint32_t cpb : {4u, 12u, 13u, 48u}) {
    std::vector<uint8_t> bytes(200);
    for (auto& b : bytes) b = static_cast<uint8_t>(rng());
    EXPECT_EQ(decode(waveform(bytes, cpb, 0), cpb), bytes) << cpb;
    EXPECT_EQ(decode(waveform(bytes, cpb, cpb / 2 + 1), cpb), bytes) << cpb;
  }
}

TEST(UartPins, WriterMakesTheDefinitionsWaveform) {
  const std::vector<uint8_t> bytes{0x00, 0xFF, 0x7E, 0x7D, 0x55, 0xA5};
  for (uint32_t cpb : {4u, 25u}) {
    UartPinWriter w(cpb);
    for (uint8_t b : bytes) w.push(b);
    std::vector<bool> got(3 * cpb, true);  // the reference's leading idle
    while (!w.idle()) got.push_back(w.next());
    got.insert(got.end(), 2 * cpb, true);
    EXPECT_EQ(got, waveform(bytes, cpb, 0)) << cpb;
  }
}

TEST(UartPins, LowStopBitIsAFramingErrorAndTheNextByteStillDecodes) {
  const uint32_t cpb = 10;
  std::vector<bool> w = waveform({0x41, 0x42}, cpb, cpb);
  // Stop bit of the first byte: cycles [3cpb + 9cpb, 3cpb + 10cpb).
  for (uint32_t c = 12 * cpb; c < 13 * cpb; ++c) w[c] = false;
  uint64_t framing = 0;
  EXPECT_EQ(decode(w, cpb, &framing), std::vector<uint8_t>{0x42});
  EXPECT_EQ(framing, 1u);
}

TEST(UartPins, ShortGlitchIsNotAStartBit) {
  const uint32_t cpb = 16;
  std::vector<bool> w(10 * cpb, true);
  w[5] = w[6] = false;
  EXPECT_TRUE(decode(w, cpb).empty());
}

struct Pins {
  bool step, dir;
};

StepDecoder run(StepTiming t, const std::vector<Pins>& pins) {
  StepDecoder d(t);
  for (size_t c = 0; c < pins.size(); ++c) d.sample(c, pins[c].step, pins[c].dir);
  return d;
}

std::vector<Pins> pulses(bool dir, int n, int high, int low, int lead) {
  std::vector<Pins> p(lead, Pins{false, dir});
  for (int i = 0; i < n; ++i) {
    p.insert(p.end(), high, Pins{true, dir});
    p.insert(p.end(), low, Pins{false, dir});
  }
  return p;
}

TEST(StepDecoder, CountsSignedStepsAndKeepsEdgeTimes) {
  auto p = pulses(true, 5, 3, 3, 4);
  auto back = pulses(false, 2, 3, 3, 4);
  p.insert(p.end(), back.begin(), back.end());
  const StepDecoder d = run({3, 4}, p);
  EXPECT_EQ(d.position(), 3);
  ASSERT_EQ(d.edges().size(), 7u);
  EXPECT_EQ(d.edges()[0].cycle, 4u);
  EXPECT_EQ(d.edges()[1].cycle, 10u);
  EXPECT_TRUE(d.edges()[4].up);
  EXPECT_FALSE(d.edges()[5].up);
  EXPECT_EQ(d.violations(), 0u) << d.first_violation();
}

TEST(StepDecoder, FlagsShortPulsesAndDirectionSetupAndHold) {
  EXPECT_GT(run({3, 0}, pulses(true, 2, 2, 3, 4)).violations(), 0u);  // high 2 < 3
  EXPECT_GT(run({3, 0}, pulses(true, 2, 3, 2, 4)).violations(), 0u);  // low 2 < 3
  EXPECT_GT(run({1, 5}, pulses(true, 1, 2, 2, 2)).violations(), 0u);  // dir set 2 cycles before the edge
  auto hold = pulses(true, 1, 2, 1, 8);
  hold.push_back(Pins{false, false});  // dir flips 3 cycles after the edge
  EXPECT_GT(run({1, 5}, hold).violations(), 0u);
  EXPECT_EQ(run({1, 5}, pulses(true, 3, 2, 2, 8)).violations(), 0u);
}

}  // namespace
}  // namespace traj::board
