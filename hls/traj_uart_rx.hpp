// trajcore hls: UART receiver, 8N1, cycle-accurate model of rtl/traj_uart_rx.sv
// (contract and timing there).
#pragma once
#include <cstdint>

namespace traj {

template <int ClkHz, int Baud>
class UartRx {
 public:
  static constexpr int kDiv = (ClkHz + Baud / 2) / Baud;  // clocks per bit
  static constexpr int kHalf = kDiv / 2;
  static_assert(kDiv >= 8, "ClkHz/Baud must be at least 8 clocks per bit");
  static_assert((int64_t{ClkHz} - int64_t{kDiv} * Baud) * 50 <= int64_t{kDiv} * Baud &&
                    (int64_t{kDiv} * Baud - ClkHz) * 50 <= int64_t{kDiv} * Baud,
                "Baud is more than 2 percent away from ClkHz/Div");

  struct In {
    bool rst_n = true;
    bool rx = true;
  };
  struct Out {
    uint8_t data;
    bool valid;
    bool err;
  };

  Out outputs() const { return {shift_q_, valid_q_, err_q_}; }

  void clock(const In& in) {
    const bool sample = busy_q_ && cnt_q_ == 0;
    if (sample && bit_q_ >= 1 && bit_q_ <= 8) shift_q_ = static_cast<uint8_t>((shift_q_ >> 1) | (in.rx ? 0x80 : 0));
    if (!in.rst_n) {
      busy_q_ = false;
      bit_q_ = 0;
      cnt_q_ = 0;
      rx_q_ = false;
      valid_q_ = false;
      err_q_ = false;
      return;
    }
    const bool rx_prev = rx_q_;
    rx_q_ = in.rx;
    valid_q_ = false;
    err_q_ = false;
    if (!busy_q_) {
      if (rx_prev && !in.rx) {
        busy_q_ = true;
        bit_q_ = 0;
        cnt_q_ = kHalf - 1;
      }
    } else if (!sample) {
      --cnt_q_;
    } else {
      cnt_q_ = kDiv - 1;
      const int bit = bit_q_;
      bit_q_ = (bit_q_ + 1) & 15;
      if (bit == 0 && in.rx) {
        busy_q_ = false;  // start bit gone by its middle: a glitch
      } else if (bit == 9) {
        busy_q_ = false;
        valid_q_ = in.rx;
        err_q_ = !in.rx;
      }
    }
  }

 private:
  bool busy_q_ = false;
  int bit_q_ = 0;
  int cnt_q_ = 0;
  bool rx_q_ = false;
  uint8_t shift_q_ = 0;
  bool valid_q_ = false, err_q_ = false;
};

}  // namespace traj
