// trajcore hls: the host-link protocol of rtl/board/LINK.md, cycle-accurate
// model of rtl/traj_link_proto.sv (contract, frame handling and timing there).
#pragma once
#include <cstdint>

#include "traj_status_count.hpp"

namespace traj {

// CRC-32 (zlib, reflected polynomial 0xEDB88320) of one byte, no final XOR.
inline uint32_t crc32_byte(uint32_t c, uint8_t d) {
  uint32_t r = c ^ d;
  for (int k = 0; k < 8; ++k) r = (r >> 1) ^ ((r & 1) ? 0xEDB88320u : 0u);
  return r;
}

// ScaleWidth: SW of the board's time-scale unit (0: none; CONFIG's time
// scaling and FEED are refused). CountRam: the six STATUS counters in block
// RAM with one adder (the RTL's CountRam; its words come up to 6 clocks later).
template <int Axes, int Degree, int Width, int ChunkWidth, int GuardBits, int MinTickPeriod, int ClkHz,
          int ScaleWidth = 0, int CountRam = 0>
class LinkProto {
 public:
  static constexpr int kOutWidth = Width - GuardBits;
  static constexpr int kRegBytes = Axes * (Degree + 1) * Width / 8;
  static constexpr int kRecBytes = 16 + kRegBytes;
  static constexpr int kChunkB = ChunkWidth / 8;
  static constexpr int kStatLen = 48 + 8 * Axes;
  static constexpr int kCfgLen = 40, kFeedLen = 8;
  static constexpr int kCrcWordA = 3;
  static constexpr int kCrcWordS = 2 + kStatLen / 4;
  static constexpr uint32_t kResidue = 0xDEBB20E3u;
  static_assert(Axes >= 1 && Axes <= 8, "Axes must be 1..8");
  static_assert(Degree >= 1 && Degree <= 7, "Degree must be 1..7");
  static_assert(ChunkWidth == 16 || ChunkWidth == 32 || ChunkWidth == 64, "ChunkWidth must be 16, 32 or 64");
  static_assert(Width >= ChunkWidth && Width <= 128 && Width % ChunkWidth == 0, "Width");
  static_assert(kOutWidth >= 2 && kOutWidth <= 64, "OutWidth (Width - GuardBits) must be 2..64");
  static_assert(kRecBytes <= 2048, "the record exceeds 2048 bytes");
  static_assert(ClkHz >= 1, "ClkHz must be positive");
  static_assert(ScaleWidth == 0 || (ScaleWidth >= 4 && ScaleWidth <= 24), "ScaleWidth must be 0 or 4..24");
  static_assert(CountRam == 0 || CountRam == 1, "CountRam must be 0 or 1");

  enum : uint8_t {
    kReset = 0x01, kConfig = 0x02, kStart = 0x03, kStop = 0x04, kResume = 0x05, kStatReq = 0x06, kFeed = 0x07,
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
    bool eng_tick = false;       // the engine's tick (the servo tick without time scaling)
    uint64_t sample[Axes] = {};  // OutWidth bits each
    // time scaling, for STATUS
    uint32_t scale_s = 0, ahead = 0;
    uint16_t starved_count = 0;
    bool starved = false, held = false;
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
    // time scaling (CONFIG, FEED), the job's end, the K of a stored record
    uint32_t scale_m, scale_s_max, scale_override;
    uint8_t scale_shift;
    bool scale_auto, hold, stop, end, resume;
    uint32_t stored_k;  // with fifo_commit
  };

  // Outputs of the cycle with inputs `in` (some are combinational in the inputs).
  Out outputs(const In& in) const {
    const Dec c = decode(in);
    Out o{};
    o.tx_tdata = c.tx_tdata;
    o.tx_tvalid = tx_state_q_ != kSIdle && !tx_crcld_q_ && !cnt_wait();
    o.fifo_wr = c.wbyte && c.wdone && wen_q_;
    o.fifo_wr_data = c.wword;
    o.fifo_commit = v_.store;
    o.fifo_rollback = v_.fend && !v_.store;
    o.fifo_clear = v_.do_reset;
    o.release = playing_q_ && !halt_q_ && (!stop_q_ || cfg_m_q_ != 0) && !in.eng_tick && !tick_d1_q_ &&
                !tick_d2_q_ && !in.underrun;
    o.run = playing_q_ && !halt_q_;
    o.tick_period = cfg_tick_q_;
    for (int a = 0; a < Axes; ++a) o.step_shift[a] = cfg_shift_q_[a];
    o.pulse = cfg_pulse_q_;
    o.setup = cfg_setup_q_;
    o.enable = cfg_en_q_;
    o.scale_m = cfg_m_q_;
    o.scale_s_max = cfg_smax_q_;
    o.scale_override = cfg_ovr_q_;
    o.scale_shift = cfg_shl_q_;
    o.scale_auto = cfg_auto_q_;
    o.hold = hold_q_;
    o.stop = stop_q_;
    o.end = end_q_;
    o.resume = v_.do_resume;
    o.stored_k = sh_k_q_;
    return o;
  }

  void clock(const In& in) {
    const LinkProto q = *this;  // the registers at the start of the cycle (nonblocking reads)
    const Dec c = decode(in);
    const uint8_t d = c.d;

    // CONFIG's and FEED's payload bytes into the shadow RAM, the per-field flags
    // (the RTL's comment), a SEGMENT's K (datapath).
    const int p = (idx_q_ - 8) & 0xFFF, pb = p & 3;
    const bool first = pb == 0, d_nz = d != 0;
    const uint8_t min_byte = static_cast<uint8_t>(uint32_t(MinTickPeriod) >> (8 * pb));
    uint8_t wide_mask = 0;
    for (int b = 0; b < 8; ++b)
      if (8 * pb + b >= ScaleWidth) wide_mask = static_cast<uint8_t>(wide_mask | (1u << b));
    const bool wide = (d & wide_mask) != 0;
    if (c.dv && c.in_pay && ((is_cfg() && pd_.cfg) || (is_feed() && (pd_.ctick || pd_.p4))))
      sh_mem_[is_feed() ? 40 + (p & 7) : (p & 63)] = d;
    if (cp_act_q_) cp_rd_q_ = q.sh_mem_[cp_ra_q_];
    if (c.dv && c.in_pay && is_cfg()) {
      if (pd_.ctick) {
        tick_nz_q_ = d_nz || (!first && tick_nz_q_);
        tick_lt_q_ = d < min_byte || (d == min_byte && !first && tick_lt_q_);
      }
      if (pd_.cpulse) pulse_nz_q_ = d_nz || ((p & 1) && pulse_nz_q_);
      if (pd_.cm) {
        m_nz_q_ = d_nz || (!first && m_nz_q_);
        m_wide_q_ = wide || (!first && m_wide_q_);
      }
      if (pd_.csmax) {
        smax_nz_q_ = d_nz || (!first && smax_nz_q_);
        smax_wide_q_ = wide || (!first && smax_wide_q_);
      }
      if (pd_.cshl) shl_nz_q_ = d_nz;
      if (pd_.cfl) auto_q_ = d & 1;
    }
    // the override: CONFIG's and FEED's; a SEGMENT's K
    if (c.dv && c.in_pay && ((is_cfg() && pd_.covr) || (is_feed() && pd_.ctick))) {
      ovr_nz_q_ = d_nz || (!first && ovr_nz_q_);
      ovr_wide_q_ = wide || (!first && ovr_wide_q_);
    }
    if (c.dv && c.in_pay && is_seg() && pd_.k) sh_k_q_ = (sh_k_q_ >> 8) | (uint32_t{d} << 24);
    // the copy's datapath
    cp_wa_q_ = q.cp_ra_q_;
    if (q.cp_vld_q_) stg_q_ = (q.stg_q_ >> 8) | (uint32_t{q.cp_rd_q_} << 24);


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
      if (rxe_q_ || (rxv_q_ && esc_q_ && rxd_q_ != 0x5E && rxd_q_ != 0x5D)) bad_q_ = true;
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
        if (c.in_pay && is_seg() && pd_.k && d != 0) kz_q_ = false;
        if (c.wbyte) {
          asm_q_ = c.asm_d >> 8;
          wb_q_ = c.wdone ? 0 : wb_q_ + 1;
        }
      }
    }

    const Position pd_next = position(q.idx_q_, q.len_q_);

    // Frame datapath of the answer side.
    const uint32_t tx_crc_d = crc32_byte(tx_crc_q_, c.tx_cur);
    if (tx_state_q_ == kSIdle) {
      tx_stat_q_ = !ans_pend_q_;
      tx_code_q_ = ans_code_q_;
      tx_idx_q_ = 0;
      tx_esc_q_ = false;
      tx_crc_q_ = 0xFFFFFFFFu;
      tx_w_q_ = 0;
      for (int a = 0; a < Axes; ++a) snap_q_[a] = in.sample[a] & out_mask();
    }
    const bool tx_crc_next = tx_w_q_ == (tx_stat_q_ ? kCrcWordS : kCrcWordA);
    const uint32_t word_next = next_word(in, tx_w_q_);
    if (c.tx_load && !tx_crc_next) tx_word_q_ = word_next;
    if (c.tx_load) tx_w_q_ = (tx_w_q_ + 1) & 63;
    if (tx_crcld_q_) tx_word_q_ = ~tx_crc_q_;
    // the STATUS counters in block RAM: a counter's word when it is written back
    if (CountRam != 0) {
      const auto cn = cnt_.outputs();
      if (cn.ld) tx_word_q_ = cn.sum;
      typename StatusCount<6>::In ci;
      ci.rst_n = in.rst_n;
      ci.ev = count_events(in, q);
      ci.want = c.tx_load && q.tx_stat_q_ && q.tx_w_q_ >= 3 && q.tx_w_q_ <= 8;
      ci.k = (q.tx_w_q_ - 3) & 7;
      cnt_.clock(ci);
    }
    if (c.tx_hs && tx_state_q_ == kSBody) {
      if (c.tx_adv) {
        tx_esc_q_ = false;
        tx_crc_q_ = tx_crc_d;
        tx_idx_q_ = static_cast<uint8_t>(tx_idx_q_ + 1);
      } else {
        tx_esc_q_ = true;
      }
    }

    pd_ = pd_next;
    rxd_q_ = in.rx_data;
    rxv_q_ = in.rx_valid;
    rxe_q_ = in.rx_err;
    if (!in.rst_n) {
      reset();
      return;
    }
    const Dec v = v_;  // the verdict registered at the previous flag acts in this cycle
    v_ = c;

    // Receive state.
    if (q.rxv_q_) esc_q_ = c.is_esc;
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
    const bool stat_due = in.tick && cfg_stat_q_ != 0 && stat_cnt_q_ == cfg_stat_q_;
    const bool tx_take_ans = tx_state_q_ == kSIdle && ans_pend_q_;
    const bool tx_take_stat = tx_state_q_ == kSIdle && !ans_pend_q_ && stat_pend_q_;
    const bool playing = playing_q_, halt = halt_q_, stop = stop_q_;
    tick_d2_q_ = tick_d1_q_;
    tick_d1_q_ = in.eng_tick;
    if (v.store) ++next_seq_q_;
    if (v.do_reset) {
      next_seq_q_ = q.seq_q_;
      halt_q_ = stop_q_ = end_q_ = ended_q_ = false;
    }
    // the copy of a good CONFIG's or FEED's bytes into the live registers
    if (v.do_config || v.do_feed) {
      cp_act_q_ = true;
      cp_ra_q_ = v.do_feed ? 40 : 0;
    } else if (q.cp_act_q_) {
      cp_ra_q_ = (q.cp_ra_q_ + 1) & 63;
      if (q.cp_ra_q_ == 37 || q.cp_ra_q_ == 44) cp_act_q_ = false;
    }
    cp_vld_q_ = q.cp_act_q_;
    const uint32_t cp_word = (q.stg_q_ >> 8) | (uint32_t{q.cp_rd_q_} << 24);
    if (q.cp_vld_q_) {
      const int wa = q.cp_wa_q_;
      const uint8_t b = q.cp_rd_q_;
      if (wa == 3) cfg_tick_q_ = cp_word;
      if (wa == 7) cfg_stat_q_ = cp_word;
      for (int a = 0; a < Axes; ++a)
        if (wa == 8 + a) cfg_shift_q_[a] = b & 63;
      if (wa == 17) cfg_pulse_q_ = static_cast<uint16_t>(cp_word >> 16);
      if (wa == 19) cfg_setup_q_ = static_cast<uint16_t>(cp_word >> 16);
      if (wa == 20) cfg_en_q_ = b & 1;
      if (ScaleWidth != 0) {  // without a unit they stay 0 (the RTL's constants)
        if (wa == 27) cfg_m_q_ = cp_word;
        if (wa == 31) cfg_smax_q_ = cp_word;
        if (wa == 36) {
          cfg_ovr_q_ = q.stg_q_;
          cfg_shl_q_ = b & 63;
        }
        if (wa == 37) cfg_auto_q_ = b & 1;
        if (wa == 44) {
          cfg_ovr_q_ = q.stg_q_;
          hold_q_ = b & 1;
        }
      }
    }
    if (v.do_start && !halt) {
      playing_q_ = true;
      stop_q_ = false;
      ended_q_ = false;
    }
    if (v.do_stop) stop_q_ = playing;
    if (v.do_resume && halt) {
      halt_q_ = false;
      playing_q_ = true;
    }
    if (v.do_end) end_q_ = true;
    if (in.underrun && playing) {
      playing_q_ = false;
      stop_q_ = false;
      if (stop) {
      } else if (q.end_q_ && in.fifo_level == 0 && !in.fifo_busy) {
        ended_q_ = true;
      } else {
        halt_q_ = true;  // an underrun: counted (count_events)
      }
    }
    const uint8_t ev = count_events(in, q);
    uint32_t* const counters[6] = {&n_played_q_, &n_ticks_q_, &n_under_q_, &n_bad_q_, &n_ooo_q_, &n_bytes_q_};
    for (int k = 0; k < 6; ++k)
      if ((ev >> k) & 1) ++*counters[k];
    if ((q.cp_vld_q_ && q.cp_wa_q_ == 7) || stat_due) stat_cnt_q_ = 1;
    else if (in.tick && q.cfg_stat_q_ != 0) ++stat_cnt_q_;
    ans_pend_q_ = v.answer || (ans_pend_q_ && !tx_take_ans);
    if (v.answer) ans_code_q_ = v.code;
    stat_pend_q_ = v.want_stat || stat_due || (stat_pend_q_ && !tx_take_stat);

    // Answer state machine.
    tx_crcld_q_ = c.tx_load && tx_crc_next;
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

  // Registered decodes of the position in the body (the RTL's pd_*_q).
  struct Position {
    bool pay, over, k, reg, p0, p13, pseq, p7, ctick, cshift, cpulse, cen, cres;
    bool cm, csmax, covr, cshl, cfl, p4, fres, cscale, cfg;
  };
  static Position position(uint16_t idx, uint16_t len) {
    const int p = (idx - 8) & 0xFFF;
    Position r{};
    r.pay = idx >= 8 && p < len;
    r.over = idx >= 8 && p >= ((len + 4) & 0xFFF);
    r.k = p >= 4 && p < 8;
    r.reg = p >= 12 && p < kRecBytes - 4;
    r.p0 = p == 0;
    r.p13 = p >= 1 && p < 4;
    r.pseq = p >= 8 && p < 12;
    r.p7 = p == 7;
    r.ctick = p < 4;
    r.cshift = p >= 8 && p < 8 + Axes;
    r.cpulse = p == 16 || p == 17;
    r.cen = p == 20;
    r.cres = (p > 20 && p < 24) || p == 38 || p == 39;
    r.cm = p >= 24 && p < 28;
    r.csmax = p >= 28 && p < 32;
    r.covr = p >= 32 && p < 36;
    r.cshl = p == 36;
    r.cfl = p == 37;
    r.p4 = p == 4;
    r.fres = p >= 5 && p < 8;
    r.cscale = p >= 24 && p < 40;
    r.cfg = p < 40;
    return r;
  }

  // Combinational decode of one cycle (the RTL's assigns and always_comb).
  struct Dec {
    bool is_flag, is_esc, dv;
    uint8_t d;
    bool in_pay, overlong, wbyte, wdone, cbad_byte, cbad_end;
    uint64_t asm_d, wword;
    bool fend, good, store, answer, want_stat, ooo;
    bool do_reset, do_config, do_start, do_stop, do_resume, do_end, do_feed;
    uint8_t code;
    bool tx_hs, tx_first, tx_adv, tx_last_byte;
    uint8_t tx_cur, tx_tdata;
    bool tx_load;
  };

  static bool known(uint8_t t) {
    return t == kReset || t == kConfig || t == kStart || t == kStop || t == kResume || t == kStatReq ||
           t == kFeed || t == kSegment || t == kEnd;
  }
  bool is_seg() const { return type_q_ == kSegment; }
  bool is_cfg() const { return type_q_ == kConfig; }
  bool is_feed() const { return type_q_ == kFeed; }
  // a time-scaling value the unit cannot hold (bits at or above ScaleWidth)
  static bool too_wide(bool wide) { return ScaleWidth == 0 || wide; }
  static constexpr uint64_t out_mask() { return kOutWidth >= 64 ? ~uint64_t{0} : (uint64_t{1} << kOutWidth) - 1; }
  static constexpr uint64_t chunk_mask() {
    return ChunkWidth >= 64 ? ~uint64_t{0} : (uint64_t{1} << ChunkWidth) - 1;
  }

  Dec decode(const In& in) const {
    Dec c{};
    c.is_flag = rxv_q_ && rxd_q_ == 0x7E;
    c.is_esc = rxv_q_ && !c.is_flag && !esc_q_ && rxd_q_ == 0x7D;
    c.dv = rxv_q_ && !c.is_flag && !c.is_esc && !hunt_q_;
    c.d = esc_q_ ? static_cast<uint8_t>(rxd_q_ ^ 0x20) : rxd_q_;
    c.in_pay = pd_.pay;
    c.overlong = pd_.over;
    const uint8_t d = c.d;
    c.wbyte = c.dv && c.in_pay && is_seg() && (pd_.k || pd_.reg);
    c.asm_d = ((uint64_t{d} << (ChunkWidth - 8)) | asm_q_) & chunk_mask();
    if (ChunkWidth > 32) {
      c.wdone = wb_q_ == kChunkB - 1 || pd_.p7;
      c.wword = pd_.p7 ? (c.asm_d >> (ChunkWidth - 32)) & 0xFFFFFFFFull : c.asm_d;
    } else {
      c.wdone = wb_q_ == kChunkB - 1;
      c.wword = c.asm_d;
    }
    const uint8_t seq_byte = static_cast<uint8_t>(seq_q_ >> (8 * (idx_q_ & 3)));
    c.cbad_byte = false;
    if (is_seg()) {
      if (pd_.p0) c.cbad_byte = d != 1;
      else if (pd_.p13) c.cbad_byte = d != 0;
      else if (pd_.pseq) c.cbad_byte = d != seq_byte;
    } else if (is_cfg()) {
      if (pd_.cshift) c.cbad_byte = d > 63;
      else if (pd_.cen) c.cbad_byte = d > 1;
      else if (pd_.cres) c.cbad_byte = d != 0;
      else if (ScaleWidth == 0 && pd_.cscale) c.cbad_byte = d != 0;  // no unit: no time scaling
      else if (pd_.cshl) c.cbad_byte = d > 40;
      else if (pd_.cfl) c.cbad_byte = d > 1;
    } else if (is_feed()) {
      if (pd_.p4) c.cbad_byte = d > 1;
      else if (pd_.fres) c.cbad_byte = d != 0;
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
        cbad_end = len_q_ != kCfgLen || !pulse_nz_q_ || (tick_nz_q_ && tick_lt_q_) ||
                   (ScaleWidth != 0 &&
                    (!m_nz_q_ ? (smax_nz_q_ || ovr_nz_q_ || shl_nz_q_ || auto_q_)
                              : (too_wide(m_wide_q_) || too_wide(smax_wide_q_) || too_wide(ovr_wide_q_))));
        break;
      case kFeed:
        cbad_end = len_q_ != kFeedLen || too_wide(ovr_wide_q_);
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
          case kFeed: c.do_feed = true; break;
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
    c.tx_hs = tx_state_q_ != kSIdle && !tx_crcld_q_ && !cnt_wait() && in.tx_tready;
    c.tx_cur = static_cast<uint8_t>(tx_word_q_ >> (8 * (tx_idx_q_ & 3)));
    const bool need_esc = c.tx_cur == 0x7E || c.tx_cur == 0x7D;
    c.tx_adv = c.tx_hs && tx_state_q_ == kSBody && (tx_esc_q_ || !need_esc);
    c.tx_first = c.tx_hs && tx_state_q_ == kSOpen;
    c.tx_load = c.tx_first || (c.tx_adv && (tx_idx_q_ & 3) == 3);
    c.tx_last_byte = tx_idx_q_ == (tx_stat_q_ ? 4 * kCrcWordS + 3 : 4 * kCrcWordA + 3);
    c.tx_tdata = tx_state_q_ == kSBody ? (tx_esc_q_ ? static_cast<uint8_t>(c.tx_cur ^ 0x20)
                                                    : (need_esc ? uint8_t{0x7D} : c.tx_cur))
                                       : uint8_t{0x7E};
    return c;
  }

  bool cnt_wait() const { return CountRam != 0 && cnt_.outputs().wait; }
  // the counters' events of this cycle, from the registers at its start (q):
  // played, ticks, underruns, bad frames, out-of-order frames, bytes
  static uint8_t count_events(const In& in, const LinkProto& q) {
    const bool under = in.underrun && q.playing_q_ && !q.stop_q_ && !(q.end_q_ && in.fifo_level == 0 && !in.fifo_busy);
    return static_cast<uint8_t>((in.seg_start ? 1 : 0) | ((in.tick && q.playing_q_ && !q.halt_q_) ? 2 : 0) |
                                (under ? 4 : 0) | ((q.v_.fend && !q.v_.good) ? 8 : 0) | (q.v_.ooo ? 16 : 0) |
                                (q.rxv_q_ ? 32 : 0));
  }

  uint32_t next_word(const In& in, int w) const {
    if (w == 0)
      return tx_stat_q_ ? (uint32_t(kStatLen) << 16) | kStatus
                        : (4u << 16) | (tx_code_q_ == 0 ? kAck : kNak);
    if (w == 1) return next_seq_q_;
    if (!tx_stat_q_)
      return tx_code_q_ == 0 ? uint32_t{in.fifo_credits} : (uint32_t{in.fifo_credits} << 16) | tx_code_q_;
    switch (w) {
      case 2: {
        const uint32_t flags = (playing_q_ ? 1u : 0u) | (halt_q_ ? 2u : 0u) | (ended_q_ ? 4u : 0u) |
                               (in.tick_err ? 8u : 0u) | (cfg_en_q_ ? 16u : 0u) | (in.fifo_level == 0 ? 32u : 0u) |
                               (in.starved ? 64u : 0u) | (in.held ? 128u : 0u);
        return (uint32_t{in.fifo_level} << 16) | (flags << 8) | uint32_t(Axes);
      }
      case 3: return n_played_q_;
      case 4: return n_ticks_q_;
      case 5: return n_under_q_;
      case 6: return n_bad_q_;
      case 7: return n_ooo_q_;
      case 8: return n_bytes_q_;
      case 9: return in.fifo_credits;
      case 10: return uint32_t(ClkHz);
      case 11: return in.scale_s;
      case 12: return in.starved_count;
      case 13: return in.ahead;
      default: {
        for (int a = 0; a < Axes; ++a) {
          uint64_t s = snap_q_[a];
          if (kOutWidth < 64 && ((s >> (kOutWidth - 1)) & 1)) s |= ~out_mask();
          if (w == 14 + 2 * a) return static_cast<uint32_t>(s);
          if (w == 15 + 2 * a) return static_cast<uint32_t>(s >> 32);
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
    cfg_m_q_ = cfg_smax_q_ = cfg_ovr_q_ = 0;
    cfg_shl_q_ = 0;
    cfg_auto_q_ = hold_q_ = false;
    cp_act_q_ = cp_vld_q_ = false;
    stat_cnt_q_ = 0;
    n_played_q_ = n_ticks_q_ = n_under_q_ = n_bad_q_ = n_ooo_q_ = n_bytes_q_ = 0;
    ans_pend_q_ = false;
    ans_code_q_ = 0;
    stat_pend_q_ = false;
    tick_d1_q_ = tick_d2_q_ = false;
    tx_state_q_ = kSIdle;
    tx_crcld_q_ = false;
    v_ = Dec{};
    rxv_q_ = rxe_q_ = false;
  }

  // receive
  bool hunt_q_ = true, esc_q_ = false, bad_q_ = false, cbad_q_ = false, kz_q_ = false, wen_q_ = false;
  Position pd_ = {};
  uint8_t rxd_q_ = 0;  // the received byte, registered (the RTL also registers its compares)
  bool rxv_q_ = false, rxe_q_ = false;
  Dec v_ = {};  // the registered verdict (the RTL's v_*_q; only its verdict fields are read)
  bool seq_eq_q_ = false, behind_q_ = false, len_ok_q_ = false, crc_ok_q_ = false, cbad_end_q_ = false;
  uint16_t idx_q_ = 0, len_q_ = 0;
  uint8_t type_q_ = 0;
  uint32_t seq_q_ = 0, crc_q_ = 0;
  uint64_t asm_q_ = 0;
  int wb_q_ = 0;
  // CONFIG's and FEED's bytes (block RAM), the per-field flags, the copy, a SEGMENT's K
  uint8_t sh_mem_[64] = {};
  bool tick_nz_q_ = false, tick_lt_q_ = false, pulse_nz_q_ = false, m_nz_q_ = false, smax_nz_q_ = false;
  bool ovr_nz_q_ = false, shl_nz_q_ = false, auto_q_ = false, m_wide_q_ = false, smax_wide_q_ = false;
  bool ovr_wide_q_ = false;
  bool cp_act_q_ = false, cp_vld_q_ = false;
  int cp_ra_q_ = 0, cp_wa_q_ = 0;
  uint8_t cp_rd_q_ = 0;
  uint32_t stg_q_ = 0;
  uint32_t sh_k_q_ = 0;
  // link, playback, configuration, counters
  uint32_t next_seq_q_ = 0;
  bool playing_q_ = false, halt_q_ = false, stop_q_ = false, end_q_ = false, ended_q_ = false;
  uint32_t cfg_tick_q_ = 0, cfg_stat_q_ = 0, stat_cnt_q_ = 0;
  uint8_t cfg_shift_q_[Axes] = {};
  uint16_t cfg_pulse_q_ = 1, cfg_setup_q_ = 0;
  bool cfg_en_q_ = false;
  uint32_t cfg_m_q_ = 0, cfg_smax_q_ = 0, cfg_ovr_q_ = 0;
  uint8_t cfg_shl_q_ = 0;
  bool cfg_auto_q_ = false, hold_q_ = false;
  // the counters (with CountRam = 1 the RTL keeps them in block RAM, cnt_; these stay as the model's views)
  uint32_t n_played_q_ = 0, n_ticks_q_ = 0, n_under_q_ = 0, n_bad_q_ = 0, n_ooo_q_ = 0, n_bytes_q_ = 0;
  StatusCount<6> cnt_;  // CountRam = 1: the counters in block RAM (the RTL's u_count)
  bool ans_pend_q_ = false, stat_pend_q_ = false, tick_d1_q_ = false, tick_d2_q_ = false;
  uint8_t ans_code_q_ = 0;
  // answer side
  int tx_state_q_ = kSIdle;
  bool tx_stat_q_ = false, tx_esc_q_ = false;
  uint8_t tx_code_q_ = 0, tx_idx_q_ = 0;
  int tx_w_q_ = 0;
  bool tx_crcld_q_ = false;
  uint32_t tx_crc_q_ = 0, tx_word_q_ = 0;
  uint64_t snap_q_[Axes] = {};
};

}  // namespace traj
