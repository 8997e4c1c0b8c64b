// SPDX-License-Identifier: Apache-2.0
// A UART seen from outside the chip, one clock cycle at a time: the simulated
// board drives the core's RX pin bit by bit and decodes its TX pin, so the
// Verilated board top is exercised exactly as the FTDI chip would: 8N1, idle
// high, least significant bit first, clocks_per_bit cycles per bit.
//
// The decoder is written apart from the RTL's receiver on purpose (it
// checks the board's transmitter): it finds the start edge, samples each bit
// in its middle and reports a stop bit that is low as a framing error.
#pragma once
#include <cstdint>
#include <deque>
#include <optional>
#include <stdexcept>

namespace traj::board {

class UartPinWriter {
 public:
  explicit UartPinWriter(uint32_t clocks_per_bit) : cpb_(clocks_per_bit) {
    if (cpb_ < 4) throw std::invalid_argument("UART: fewer than 4 clocks per bit");
  }
  void push(uint8_t byte) { queue_.push_back(byte); }
  bool idle() const { return queue_.empty() && bit_ < 0; }
  size_t queued() const { return queue_.size(); }

  // The pin level for this cycle; advances one cycle.
  bool next() {
    if (bit_ < 0) {
      if (queue_.empty()) return true;
      shift_ = static_cast<uint16_t>(0x200u | (uint32_t{queue_.front()} << 1));  // start 0, data, stop 1
      queue_.pop_front();
      bit_ = 0;
      count_ = 0;
    }
    const bool level = (shift_ >> bit_) & 1u;
    if (++count_ == cpb_) {
      count_ = 0;
      if (++bit_ == 10) bit_ = -1;
    }
    return level;
  }

 private:
  uint32_t cpb_;
  std::deque<uint8_t> queue_;
  uint16_t shift_ = 0;
  int bit_ = -1;
  uint32_t count_ = 0;
};

class UartPinReader {
 public:
  explicit UartPinReader(uint32_t clocks_per_bit) : cpb_(clocks_per_bit) {
    if (cpb_ < 4) throw std::invalid_argument("UART: fewer than 4 clocks per bit");
  }
  uint64_t framing_errors() const { return framing_errors_; }

  // Samples the pin for one cycle; returns a byte when its stop bit is sampled.
  std::optional<uint8_t> sample(bool level) {
    if (!busy_) {
      if (prev_ && !level) {  // falling edge: the start bit begins this cycle
        busy_ = true;
        count_ = 0;
        bit_ = 0;
        shift_ = 0;
      }
      prev_ = level;
      return std::nullopt;
    }
    prev_ = level;
    // The middle of bit b is cpb·b + cpb/2 cycles after the start edge.
    if (++count_ != cpb_ * static_cast<uint32_t>(bit_) + cpb_ / 2) return std::nullopt;
    if (bit_ == 0) {
      if (level) busy_ = false;  // a glitch, not a start bit
      else ++bit_;
      return std::nullopt;
    }
    if (bit_ <= 8) {
      shift_ |= static_cast<uint8_t>(level ? 1u << (bit_ - 1) : 0u);
      ++bit_;
      return std::nullopt;
    }
    busy_ = false;
    if (!level) {
      ++framing_errors_;
      return std::nullopt;
    }
    return shift_;
  }

 private:
  uint32_t cpb_;
  bool prev_ = true, busy_ = false;
  uint32_t count_ = 0;
  int bit_ = 0;
  uint8_t shift_ = 0;
  uint64_t framing_errors_ = 0;
};

}  // namespace traj::board
