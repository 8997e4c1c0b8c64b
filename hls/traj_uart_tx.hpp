// trajcore hls: UART transmitter, 8N1, cycle-accurate model of rtl/traj_uart_tx.sv
// (contract and timing there).
#pragma once
#include <cstdint>

namespace traj {

template <int ClkHz, int Baud>
class UartTx {
 public:
  static constexpr int kDiv = (ClkHz + Baud / 2) / Baud;  // clocks per bit
  static_assert(kDiv >= 8, "ClkHz/Baud must be at least 8 clocks per bit");

  struct In {
    bool rst_n = true;
    uint8_t tdata = 0;
    bool tvalid = false;
  };
  struct Out {
    bool tready;
    bool tx;
  };

  Out outputs() const { return {!busy_q_, tx_q_}; }

  void clock(const In& in) {
    const bool accept = in.tvalid && !busy_q_;
    const bool shift = busy_q_ && cnt_q_ == 0 && left_q_ != 0;
    const uint16_t shift_prev = shift_q_;
    if (accept) shift_q_ = static_cast<uint16_t>(0x100 | in.tdata);
    else if (shift) shift_q_ = static_cast<uint16_t>(0x100 | (shift_q_ >> 1));
    if (!in.rst_n) {
      busy_q_ = false;
      left_q_ = 0;
      cnt_q_ = 0;
      tx_q_ = true;
      return;
    }
    if (accept) {
      busy_q_ = true;
      left_q_ = 9;
      cnt_q_ = kDiv - 1;
      tx_q_ = false;
    } else if (busy_q_) {
      if (cnt_q_ != 0) {
        --cnt_q_;
      } else if (left_q_ == 0) {
        busy_q_ = false;
      } else {
        cnt_q_ = kDiv - 1;
        --left_q_;
        tx_q_ = (shift_prev & 1) != 0;
      }
    }
  }

 private:
  bool busy_q_ = false;
  int left_q_ = 0;
  int cnt_q_ = 0;
  uint16_t shift_q_ = 0;
  bool tx_q_ = true;
};

}  // namespace traj
