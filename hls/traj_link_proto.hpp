// trajcore hls: the host-link protocol of rtl/board/LINK.md, cycle-accurate
// model of rtl/traj_link_proto.sv (contract, frame handling and timing there).
#pragma once
#include <cstdint>

namespace traj {

// CRC-32 (zlib, reflected polynomial 0xEDB88320) of one byte, no final XOR.
inline uint32_t crc32_byte(uint32_t c, uint8_t d) {
  uint32_t r = c ^ d;
  for (int k = 0; k < 8; ++k) r = (r >> 1) ^ ((r & 1) ? 0xEDB88320u : 0u);
  return r;
}

template <int Axes, int Degree, int Width, int ChunkWidth, int GuardBits, int MinTickPeriod>
class LinkProto {
 public:
  static constexpr int kOutWidth = Width - GuardBits;
  static constexpr int kRegBytes = Axes * (Degree + 1) * Width / 8;
  static constexpr int kRecBytes = 16 + kRegBytes;
  static constexpr int kChunkB = ChunkWidth / 8;
  static constexpr int kStatLen = 40 + 8 * Axes;
  static constexpr int kCrcWordA = 3;
  static constexpr int kCrcWordS = 2 + kStatLen / 4;
  static constexpr uint32_t kResidue = 0xDEBB20E3u;
  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(Degree >= 1 && Degree <= 7, "Degree must be 1..7");
  static_assert(ChunkWidth == 16 || ChunkWidth == 32 || ChunkWidth == 64, "ChunkWidth must be 16, 32 or 64");
  static_assert(Width >= ChunkWidth && Width <= 128 && Width % ChunkWidth == 0, "Width");
  static_assert(kOutWidth >= 2 && kOutWidth <= 64, "OutWidth (Width - GuardBits) must be 2..64");
  static_assert(kRecBytes <= 2048, "the record exceeds 2048 bytes");

  enum : uint8_t {
    kReset = 0x01, kConfig = 0x02, kStart = 0x03, kStop = 0x04, kResume = 0x05, kStatReq = 0x06,
    kSegment = 0x10, kEnd = 0x11, kAck = 0x81, kNak = 0x82, kStatus = 0x83
  };

  struct In {
    bool rst_n = true;
    uint8_t rx_data = 0;
    bool rx_valid = false, rx_err = false;
    bool tx_tready = false;
    uint16_t fifo_level = 0, fifo_credits = 0;
    bool fifo_busy = false;
    bool tick = false, seg_start = false, underrun = false, tick_err = false;
    uint64_t sample[Axes] = {};  // OutWidth bits each
  };
  struct Out {
    uint8_t tx_tdata;
    bool tx_tvalid;
    bool fifo_wr;
    uint64_t fifo_wr_data;
    bool fifo_commit, fifo_rollback, fifo_clear, release;
    bool run;
    uint32_t tick_period;
    uint8_t step_shift[Axes];
    uint16_t pulse, setup;
    bool enable;
  };

  // Outputs of the cycle with inputs `in` (some are combinational in the inputs).
  Out outputs(const In& in) const {
    const Dec c = decode(in);
    Out o{};
    o.tx_tdata = c.tx_tdata;
    o.tx_tvalid = tx_state_q_ != kSIdle;
    o.fifo_wr = c.wbyte && c.wdone && wen_q_;
    o.fifo_wr_data = c.wword;
    o.fifo_commit = c.store;
    o.fifo_rollback = c.fend && !c.store;
    o.fifo_clear = c.do_reset;
    o.release = playing_q_ && !halt_q_ && !stop_q_ && !in.tick && !tick_d1_q_ && !tick_d2_q_ && !in.underrun;
    o.run = playing_q_ && !halt_q_;
    o.tick_period = cfg_tick_q_;
    for (int a = 0; a < Axes; ++a) o.step_shift[a] = cfg_shift_q_[a];
    o.pulse = cfg_pulse_q_;
    o.setup = cfg_setup_q_;
    o.enable = cfg_en_q_;
    return o;
  }

  void clock(const In& in) {
    const LinkProto q = *this;  // the registers at the start of the cycle (nonblocking reads)
    const Dec c = decode(in);
    const uint8_t d = c.d;
    const uint16_t p = c.p;

    // CONFIG shadow registers (datapath).
    if (c.dv && c.in_pay && is_cfg()) {
      if (p < 4) sh_tick_q_ = (sh_tick_q_ >> 8) | (uint32_t{d} << 24);
      else if (p < 8) sh_stat_q_ = (sh_stat_q_ >> 8) | (uint32_t{d} << 24);
      else if (p == 16 || p == 17) sh_pulse_q_ = static_cast<uint16_t>((sh_pulse_q_ >> 8) | (d << 8));
      else if (p == 18 || p == 19) sh_setup_q_ = static_cast<uint16_t>((sh_setup_q_ >> 8) | (d << 8));
      else if (p == 20) sh_en_q_ = d & 1;
      if (p >= 8 && p < 8 + Axes) sh_shift_q_[p - 8] = d & 63;
    }

    // Per-body flags and fields (datapath: set at the opening flag).
    const uint32_t crc_prev = crc_q_;
    seq_eq_q_ = q.seq_q_ == q.next_seq_q_;
    behind_q_ = ((q.seq_q_ - q.next_seq_q_) >> 31) != 0;
    len_ok_q_ = q.idx_q_ == ((q.len_q_ + 12) & 0xFFF);
    crc_ok_q_ = q.crc_q_ == kResidue;
    cbad_end_q_ = c.cbad_end;
    if (c.is_flag) {
      bad_q_ = false;
      cbad_q_ = false;
      kz_q_ = true;
      crc_q_ = 0xFFFFFFFFu;
      wb_q_ = 0;
    } else {
      if (in.rx_err || (in.rx_valid && esc_q_ && in.rx_data != 0x5E && in.rx_data != 0x5D)) bad_q_ = true;
      if (c.dv) {
        crc_q_ = crc32_byte(crc_prev, d);
        if (c.overlong) bad_q_ = true;
        switch (idx_q_) {
          case 0:
            type_q_ = d;
            if (!known(d)) bad_q_ = true;
            break;
          case 1:
            if (d != 0) bad_q_ = true;
            break;
          case 2:
            len_q_ = static_cast<uint16_t>((len_q_ & 0xF00) | d);
            break;
          case 3:
            len_q_ = static_cast<uint16_t>((len_q_ & 0xFF) | ((d & 15) << 8));
            if (d > 8 || (d == 8 && (len_q_ & 0xFF) != 0)) bad_q_ = true;
            break;
          case 4: case 5: case 6: case 7:
            seq_q_ = (seq_q_ >> 8) | (uint32_t{d} << 24);
            break;
          default:
            break;
        }
        if (c.in_pay && c.cbad_byte) cbad_q_ = true;
        if (c.in_pay && is_seg() && p >= 4 && p < 8 && d != 0) kz_q_ = false;
        if (c.wbyte) {
          asm_q_ = c.asm_d >> 8;
          wb_q_ = c.wdone ? 0 : wb_q_ + 1;
        }
      }
    }

    // Frame datapath of the answer side.
    const uint32_t tx_crc_d = crc32_byte(tx_crc_q_, c.tx_cur);
    if (tx_state_q_ == kSIdle) {
      tx_stat_q_ = !ans_pend_q_;
      tx_code_q_ = ans_code_q_;
      tx_idx_q_ = 0;
      tx_esc_q_ = false;
      tx_crc_q_ = 0xFFFFFFFFu;
      for (int a = 0; a < Axes; ++a) snap_q_[a] = in.sample[a] & out_mask();
    }
    const uint32_t word_next = next_word(in, c.tx_w_next, tx_crc_d);
    if (c.tx_first) tx_word_q_ = word_next;
    if (c.tx_hs && tx_state_q_ == kSBody) {
      if (c.tx_adv) {
        tx_esc_q_ = false;
        tx_crc_q_ = tx_crc_d;
        if ((tx_idx_q_ & 3) == 3) tx_word_q_ = word_next;
        tx_idx_q_ = static_cast<uint8_t>(tx_idx_q_ + 1);
      } else {
        tx_esc_q_ = true;
      }
    }

    if (!in.rst_n) {
      reset();
      return;
    }

    // Receive state.
    if (in.rx_valid) esc_q_ = c.is_esc;
    if (c.is_flag) {
      hunt_q_ = false;
      idx_q_ = 0;
      wen_q_ = false;
    } else if (c.dv) {
      if (idx_q_ == 8)
        wen_q_ = is_seg() && !q.bad_q_ && q.len_q_ == kRecBytes && q.seq_eq_q_ && in.fifo_credits != 0;
      if (idx_q_ != 0xFFF) ++idx_q_;
    }

    // Link, playback, configuration, counters.
    const bool stat_due = in.tick && cfg_stat_q_ != 0 && stat_cnt_q_ == 0;
    const bool tx_take_ans = tx_state_q_ == kSIdle && ans_pend_q_;
    const bool tx_take_stat = tx_state_q_ == kSIdle && !ans_pend_q_ && stat_pend_q_;
    const bool playing = playing_q_, halt = halt_q_, stop = stop_q_;
    tick_d2_q_ = tick_d1_q_;
    tick_d1_q_ = in.tick;
    if (c.store) ++next_seq_q_;
    if (c.do_reset) {
      next_seq_q_ = q.seq_q_;
      halt_q_ = stop_q_ = end_q_ = ended_q_ = false;
    }
    if (c.do_config) {
      cfg_tick_q_ = q.sh_tick_q_;
      cfg_stat_q_ = q.sh_stat_q_;
      for (int a = 0; a < Axes; ++a) cfg_shift_q_[a] = q.sh_shift_q_[a];
      cfg_pulse_q_ = q.sh_pulse_q_;
      cfg_setup_q_ = q.sh_setup_q_;
      cfg_en_q_ = q.sh_en_q_;
    }
    if (c.do_start && !halt) {
      playing_q_ = true;
      stop_q_ = false;
      ended_q_ = false;
    }
    if (c.do_stop) stop_q_ = playing;
    if (c.do_resume && halt) {
      halt_q_ = false;
      playing_q_ = true;
    }
    if (c.do_end) end_q_ = true;
    if (in.underrun && playing) {
      playing_q_ = false;
      stop_q_ = false;
      if (stop) {
      } else if (q.end_q_ && in.fifo_level == 0 && !in.fifo_busy) {
        ended_q_ = true;
      } else {
        halt_q_ = true;
        ++n_under_q_;
      }
    }
    if (in.seg_start) ++n_played_q_;
    if (in.tick && playing && !halt) ++n_ticks_q_;
    if (c.fend && !c.good) ++n_bad_q_;
    if (c.ooo) ++n_ooo_q_;
    if (in.rx_valid) ++n_bytes_q_;
    if (c.do_config) stat_cnt_q_ = q.sh_stat_q_ - 1;
    else if (in.tick && q.cfg_stat_q_ != 0) stat_cnt_q_ = stat_due ? q.cfg_stat_q_ - 1 : stat_cnt_q_ - 1;
    ans_pend_q_ = c.answer || (ans_pend_q_ && !tx_take_ans);
    if (c.answer) ans_code_q_ = c.code;
    stat_pend_q_ = c.want_stat || stat_due || (stat_pend_q_ && !tx_take_stat);

    // Answer state machine.
    switch (tx_state_q_) {
      case kSIdle:
        if (tx_take_ans || tx_take_stat) tx_state_q_ = kSOpen;
        break;
      case kSOpen:
        if (c.tx_hs) tx_state_q_ = kSBody;
        break;
      case kSBody:
        if (c.tx_adv && c.tx_last_byte) tx_state_q_ = kSClose;
        break;
      default:
        if (c.tx_hs) tx_state_q_ = kSIdle;
        break;
    }
  }

  // Model-only views for tests.
  uint32_t next_seq() const { return next_seq_q_; }
  bool playing() const { return playing_q_; }
  bool halted() const { return halt_q_; }
  bool ended() const { return ended_q_; }
  uint32_t bad_frames() const { return n_bad_q_; }
  uint32_t ooo_frames() const { return n_ooo_q_; }
  uint32_t underruns() const { return n_under_q_; }

 private:
  enum : int { kSIdle = 0, kSOpen = 1, kSBody = 2, kSClose = 3 };

  // Combinational decode of one cycle (the RTL's assigns and always_comb).
  struct Dec {
    bool is_flag, is_esc, dv;
    uint8_t d;
    uint16_t p;
    bool in_pay, overlong, wbyte, wdone, cbad_byte, cbad_end;
    uint64_t asm_d, wword;
    bool fend, good, store, answer, want_stat, ooo;
    bool do_reset, do_config, do_start, do_stop, do_resume, do_end;
    uint8_t code;
    bool tx_hs, tx_first, tx_adv, tx_last_byte;
    uint8_t tx_cur, tx_tdata;
    int tx_w_next;
  };

  static bool known(uint8_t t) {
    return t == kReset || t == kConfig || t == kStart || t == kStop || t == kResume || t == kStatReq ||
           t == kSegment || t == kEnd;
  }
  bool is_seg() const { return type_q_ == kSegment; }
  bool is_cfg() const { return type_q_ == kConfig; }
  static constexpr uint64_t out_mask() { return kOutWidth >= 64 ? ~uint64_t{0} : (uint64_t{1} << kOutWidth) - 1; }
  static constexpr uint64_t chunk_mask() {
    return ChunkWidth >= 64 ? ~uint64_t{0} : (uint64_t{1} << ChunkWidth) - 1;
  }

  Dec decode(const In& in) const {
    Dec c{};
    c.is_flag = in.rx_valid && in.rx_data == 0x7E;
    c.is_esc = in.rx_valid && !c.is_flag && !esc_q_ && in.rx_data == 0x7D;
    c.dv = in.rx_valid && !c.is_flag && !c.is_esc && !hunt_q_;
    c.d = esc_q_ ? static_cast<uint8_t>(in.rx_data ^ 0x20) : in.rx_data;
    c.p = static_cast<uint16_t>((idx_q_ - 8) & 0xFFF);
    c.in_pay = idx_q_ >= 8 && c.p < len_q_;
    c.overlong = idx_q_ >= 8 && c.p >= ((len_q_ + 4) & 0xFFF);
    const uint16_t p = c.p;
    const uint8_t d = c.d;
    c.wbyte = c.dv && c.in_pay && is_seg() && ((p >= 4 && p < 8) || (p >= 12 && p < kRecBytes - 4));
    c.asm_d = ((uint64_t{d} << (ChunkWidth - 8)) | asm_q_) & chunk_mask();
    if (ChunkWidth > 32) {
      c.wdone = wb_q_ == kChunkB - 1 || p == 7;
      c.wword = p == 7 ? (c.asm_d >> (ChunkWidth - 32)) & 0xFFFFFFFFull : c.asm_d;
    } else {
      c.wdone = wb_q_ == kChunkB - 1;
      c.wword = c.asm_d;
    }
    const uint8_t seq_byte = static_cast<uint8_t>(seq_q_ >> (8 * (p & 3)));
    c.cbad_byte = false;
    if (is_seg()) {
      if (p == 0) c.cbad_byte = d != 1;
      else if (p < 4) c.cbad_byte = d != 0;
      else if (p >= 8 && p < 12) c.cbad_byte = d != seq_byte;
    } else if (is_cfg()) {
      if (p >= 8 && p < 8 + Axes) c.cbad_byte = d > 63;
      else if (p == 20) c.cbad_byte = d > 1;
      else if (p > 20) c.cbad_byte = d != 0;
    }

    // verdict
    c.fend = c.is_flag && !hunt_q_ && idx_q_ != 0;
    c.good = !bad_q_ && !esc_q_ && len_ok_q_ && crc_ok_q_;
    const bool playing_busy = playing_q_ || in.fifo_busy;
    bool& cbad_end = c.cbad_end;
    switch (type_q_) {
      case kSegment:
        cbad_end = len_q_ != kRecBytes || kz_q_;
        break;
      case kConfig:
        cbad_end = len_q_ != 24 || sh_pulse_q_ == 0 || (sh_tick_q_ != 0 && sh_tick_q_ < uint32_t(MinTickPeriod));
        break;
      default:
        cbad_end = len_q_ != 0;
        break;
    }
    if (c.fend) {
      c.answer = true;
      if (!c.good) c.code = 1;
      else if (cbad_q_ || cbad_end_q_) c.code = 4;
      else {
        switch (type_q_) {
          case kReset:
            if (playing_busy) c.code = 5; else c.do_reset = true;
            break;
          case kConfig:
            if (playing_busy) c.code = 5; else c.do_config = true;
            break;
          case kStart: c.do_start = true; break;
          case kStop: c.do_stop = true; break;
          case kResume: c.do_resume = true; break;
          case kStatReq:
            c.answer = false;
            c.want_stat = true;
            break;
          case kSegment:
            if (seq_eq_q_) {
              if (wen_q_) c.store = true; else c.code = 3;
            } else if (!behind_q_) {
              c.code = 2;
              c.ooo = true;
            }
            break;
          default:
            if (seq_eq_q_) c.do_end = true;
            else {
              c.code = 2;
              c.ooo = true;
            }
            break;
        }
      }
    }

    // answer side
    c.tx_hs = tx_state_q_ != kSIdle && in.tx_tready;
    c.tx_cur = static_cast<uint8_t>(tx_word_q_ >> (8 * (tx_idx_q_ & 3)));
    const bool need_esc = c.tx_cur == 0x7E || c.tx_cur == 0x7D;
    c.tx_adv = c.tx_hs && tx_state_q_ == kSBody && (tx_esc_q_ || !need_esc);
    c.tx_first = c.tx_hs && tx_state_q_ == kSOpen;
    c.tx_w_next = c.tx_first ? 0 : ((tx_idx_q_ >> 2) + 1) & 63;
    c.tx_last_byte = tx_idx_q_ == (tx_stat_q_ ? 4 * kCrcWordS + 3 : 4 * kCrcWordA + 3);
    c.tx_tdata = tx_state_q_ == kSBody ? (tx_esc_q_ ? static_cast<uint8_t>(c.tx_cur ^ 0x20)
                                                    : (need_esc ? uint8_t{0x7D} : c.tx_cur))
                                       : uint8_t{0x7E};
    return c;
  }

  uint32_t next_word(const In& in, int w, uint32_t tx_crc_d) const {
    if (w == 0)
      return tx_stat_q_ ? (uint32_t(kStatLen) << 16) | kStatus
                        : (4u << 16) | (tx_code_q_ == 0 ? kAck : kNak);
    if (w == 1) return next_seq_q_;
    if (w == (tx_stat_q_ ? kCrcWordS : kCrcWordA)) return ~tx_crc_d;
    if (!tx_stat_q_)
      return tx_code_q_ == 0 ? uint32_t{in.fifo_credits} : (uint32_t{in.fifo_credits} << 16) | tx_code_q_;
    switch (w) {
      case 2: {
        const uint32_t flags = (playing_q_ ? 1u : 0u) | (halt_q_ ? 2u : 0u) | (ended_q_ ? 4u : 0u) |
                               (in.tick_err ? 8u : 0u) | (cfg_en_q_ ? 16u : 0u) | (in.fifo_level == 0 ? 32u : 0u);
        return (uint32_t{in.fifo_level} << 16) | (flags << 8) | uint32_t(Axes);
      }
      case 3: return n_played_q_;
      case 4: return n_ticks_q_;
      case 5: return n_under_q_;
      case 6: return n_bad_q_;
      case 7: return n_ooo_q_;
      case 8: return n_bytes_q_;
      case 9: return in.fifo_credits;
      case 10: case 11: return 0;
      default: {
        for (int a = 0; a < Axes; ++a) {
          uint64_t s = snap_q_[a];
          if (kOutWidth < 64 && ((s >> (kOutWidth - 1)) & 1)) s |= ~out_mask();
          if (w == 12 + 2 * a) return static_cast<uint32_t>(s);
          if (w == 13 + 2 * a) return static_cast<uint32_t>(s >> 32);
        }
        return 0;
      }
    }
  }

  void reset() {
    hunt_q_ = true;
    esc_q_ = false;
    idx_q_ = 0;
    wen_q_ = false;
    next_seq_q_ = 0;
    playing_q_ = halt_q_ = stop_q_ = end_q_ = ended_q_ = false;
    cfg_tick_q_ = cfg_stat_q_ = 0;
    for (int a = 0; a < Axes; ++a) cfg_shift_q_[a] = 0;
    cfg_pulse_q_ = 1;
    cfg_setup_q_ = 0;
    cfg_en_q_ = false;
    stat_cnt_q_ = 0;
    n_played_q_ = n_ticks_q_ = n_under_q_ = n_bad_q_ = n_ooo_q_ = n_bytes_q_ = 0;
    ans_pend_q_ = false;
    ans_code_q_ = 0;
    stat_pend_q_ = false;
    tick_d1_q_ = tick_d2_q_ = false;
    tx_state_q_ = kSIdle;
  }

  // receive
  bool hunt_q_ = true, esc_q_ = false, bad_q_ = false, cbad_q_ = false, kz_q_ = false, wen_q_ = false;
  bool seq_eq_q_ = false, behind_q_ = false, len_ok_q_ = false, crc_ok_q_ = false, cbad_end_q_ = false;
  uint16_t idx_q_ = 0, len_q_ = 0;
  uint8_t type_q_ = 0;
  uint32_t seq_q_ = 0, crc_q_ = 0;
  uint64_t asm_q_ = 0;
  int wb_q_ = 0;
  uint32_t sh_tick_q_ = 0, sh_stat_q_ = 0;
  uint8_t sh_shift_q_[Axes] = {};
  uint16_t sh_pulse_q_ = 0, sh_setup_q_ = 0;
  bool sh_en_q_ = false;
  // link, playback, configuration, counters
  uint32_t next_seq_q_ = 0;
  bool playing_q_ = false, halt_q_ = false, stop_q_ = false, end_q_ = false, ended_q_ = false;
  uint32_t cfg_tick_q_ = 0, cfg_stat_q_ = 0, stat_cnt_q_ = 0;
  uint8_t cfg_shift_q_[Axes] = {};
  uint16_t cfg_pulse_q_ = 1, cfg_setup_q_ = 0;
  bool cfg_en_q_ = false;
  uint32_t n_played_q_ = 0, n_ticks_q_ = 0, n_under_q_ = 0, n_bad_q_ = 0, n_ooo_q_ = 0, n_bytes_q_ = 0;
  bool ans_pend_q_ = false, stat_pend_q_ = false, tick_d1_q_ = false, tick_d2_q_ = false;
  uint8_t ans_code_q_ = 0;
  // answer side
  int tx_state_q_ = kSIdle;
  bool tx_stat_q_ = false, tx_esc_q_ = false;
  uint8_t tx_code_q_ = 0, tx_idx_q_ = 0;
  uint32_t tx_crc_q_ = 0, tx_word_q_ = 0;
  uint64_t snap_q_[Axes] = {};
};

}  // namespace traj
