// trajcore hls: segment FIFO, cycle-accurate model of rtl/traj_seg_fifo.sv
// (contract, memory and timing there). The RAM is a fixed array: Total words
// of ChunkWidth bits (at most 64).
#pragma once
#include <cstdint>

namespace traj {

template <int ChunkWidth, int SegWords, int Depth>
class SegFifo {
 public:
  static constexpr int kCap = Depth / SegWords;
  static constexpr int kTotal = kCap * SegWords;
  static_assert(ChunkWidth >= 8 && ChunkWidth <= 64, "ChunkWidth must be 8..64");
  static_assert(SegWords >= 2, "SegWords must be at least 2");
  static_assert(kCap >= 1 && kCap <= 65535, "Depth must hold 1..65535 segments");

  struct In {
    bool rst_n = true;
    bool wr = false;
    uint64_t wr_data = 0;
    bool commit = false, rollback = false, clear = false;
    bool release = false;
    bool tready = false;
  };
  struct Out {
    uint64_t tdata;
    bool tvalid;
    uint16_t level, credits;
    bool busy;
  };

  Out outputs() const {
    return {rdata_q_, out_valid_q_, stored_q_, static_cast<uint16_t>(kCap - stored_q_), rd_busy_q_};
  }

  void clock(const In& in) {
    const bool wr_take = in.wr && wr_cnt_q_ != SegWords && stored_q_ != kCap;
    const bool commit_ok = in.commit && wr_cnt_q_ == SegWords;
    const bool rewind = in.rollback || (in.commit && !commit_ok);
    const bool start = !rd_busy_q_ && stored_q_ != 0 && in.release && !in.clear;
    const bool issue = (rd_busy_q_ || start) && rd_cnt_q_ != SegWords && !wr_pend_q_ &&
                       (!out_valid_q_ || in.tready);
    const bool last_issue = issue && rd_cnt_q_ == SegWords - 1;
    const bool seg_end = out_valid_q_ && in.tready && rd_cnt_q_ == SegWords;
    const bool clear_ok = in.clear && !rd_busy_q_;

    // RAM and datapath (not reset).
    const int ram_addr = wr_pend_q_ ? wr_pend_addr_q_ : rd_addr_q_;
    if (wr_pend_q_) mem_[ram_addr] = wr_data_q_;
    else if (issue) rdata_q_ = mem_[ram_addr];
    if (wr_take) {
      wr_data_q_ = in.wr_data & word_mask();
      wr_pend_addr_q_ = wr_addr_q_;
    }
    if (!in.rst_n) {
      reset();
      return;
    }
    const int wr_base = wr_base_q_;
    wr_pend_q_ = wr_take;
    if (commit_ok) {
      wr_base_q_ = wr_addr_q_;
      wr_cnt_q_ = 0;
    } else if (rewind || clear_ok) {
      wr_addr_q_ = wr_base_q_;
      wr_cnt_q_ = 0;
    } else if (wr_take) {
      wr_addr_q_ = next_addr(wr_addr_q_);
      ++wr_cnt_q_;
    }
    if (clear_ok) rd_addr_q_ = wr_base;
    else if (issue) rd_addr_q_ = next_addr(rd_addr_q_);
    if (seg_end) {
      rd_busy_q_ = false;
      rd_cnt_q_ = 0;
    } else {
      if (start) rd_busy_q_ = true;
      if (issue) ++rd_cnt_q_;
    }
    out_valid_q_ = issue || (out_valid_q_ && !in.tready);
    if (clear_ok) stored_q_ = 0;
    else stored_q_ = static_cast<uint16_t>(stored_q_ + (commit_ok ? 1 : 0) - (last_issue ? 1 : 0));
  }

 private:
  static constexpr uint64_t word_mask() { return ChunkWidth >= 64 ? ~uint64_t{0} : (uint64_t{1} << ChunkWidth) - 1; }
  static int next_addr(int a) { return a == kTotal - 1 ? 0 : a + 1; }
  void reset() {
    wr_addr_q_ = wr_base_q_ = wr_cnt_q_ = 0;
    wr_pend_q_ = false;
    rd_addr_q_ = rd_cnt_q_ = 0;
    rd_busy_q_ = out_valid_q_ = false;
    stored_q_ = 0;
  }

  uint64_t mem_[kTotal] = {};
  int wr_addr_q_ = 0, wr_base_q_ = 0, wr_pend_addr_q_ = 0, rd_addr_q_ = 0;
  int wr_cnt_q_ = 0, rd_cnt_q_ = 0;
  bool wr_pend_q_ = false, rd_busy_q_ = false, out_valid_q_ = false;
  uint64_t wr_data_q_ = 0, rdata_q_ = 0;
  uint16_t stored_q_ = 0;
};

}  // namespace traj
