// trajcore hls: the board's host link, cycle-accurate model of rtl/traj_link.sv:
// UART receiver -> protocol (LINK.md) -> segment FIFO -> FD engine words, and
// the protocol's answers -> UART transmitter.
#pragma once
#include <cstdint>

#include "traj_link_proto.hpp"
#include "traj_seg_fifo.hpp"
#include "traj_uart_rx.hpp"
#include "traj_uart_tx.hpp"

namespace traj {

template <int ClkHz, int Baud, int Axes, int Degree, int Width, int ChunkWidth, int GuardBits, int FifoDepth,
          int MinTickPeriod, int ScaleWidth = 0, int CountRam = 0>
class Link {
 public:
  static constexpr int kOutWidth = Width - GuardBits;
  static constexpr int kHdrWords = ChunkWidth < 32 ? 32 / ChunkWidth : 1;
  static constexpr int kSegWords = kHdrWords + Axes * (Degree + 1) * Width / ChunkWidth;
  using Rx = UartRx<ClkHz, Baud>;
  using Tx = UartTx<ClkHz, Baud>;
  using Proto = LinkProto<Axes, Degree, Width, ChunkWidth, GuardBits, MinTickPeriod, ClkHz, ScaleWidth, CountRam>;
  using Fifo = SegFifo<ChunkWidth, kSegWords, FifoDepth>;
  static constexpr int kDiv = Rx::kDiv;
  static constexpr int kCap = Fifo::kCap;

  struct In {
    bool rst_n = true;
    bool rx = true;
    bool tready = false;
    bool tick = false, seg_start = false, underrun = false, tick_err = false;
    bool eng_tick = false;
    uint64_t sample[Axes] = {};
    uint32_t scale_s = 0, ahead = 0;
    uint16_t starved_count = 0;
    bool starved = false, held = false;
  };
  struct Out {
    bool tx;
    uint64_t tdata;
    bool tvalid;
    bool run;
    uint32_t tick_period;
    uint8_t step_shift[Axes];
    uint16_t pulse, setup;
    bool enable;
    uint32_t scale_m, scale_s_max, scale_override;
    uint8_t scale_shift;
    bool scale_auto, hold, stop, end, resume;
    bool stored;  // a record stored (committed to the FIFO), its K in stored_k
    uint32_t stored_k;
    bool cleared;  // the FIFO cleared (RESET)
  };

  Out outputs(const In& in) const {
    const Wires w = wires(in);
    Out o{};
    o.tx = w.tx.tx;
    o.tdata = w.fifo.tdata;
    o.tvalid = w.fifo.tvalid;
    o.run = w.proto.run;
    o.tick_period = w.proto.tick_period;
    for (int a = 0; a < Axes; ++a) o.step_shift[a] = w.proto.step_shift[a];
    o.pulse = w.proto.pulse;
    o.setup = w.proto.setup;
    o.enable = w.proto.enable;
    o.scale_m = w.proto.scale_m;
    o.scale_s_max = w.proto.scale_s_max;
    o.scale_override = w.proto.scale_override;
    o.scale_shift = w.proto.scale_shift;
    o.scale_auto = w.proto.scale_auto;
    o.hold = w.proto.hold;
    o.stop = w.proto.stop;
    o.end = w.proto.end;
    o.resume = w.proto.resume;
    o.stored = w.proto.fifo_commit;
    o.stored_k = w.proto.stored_k;
    o.cleared = w.proto.fifo_clear;
    return o;
  }

  void clock(const In& in) {
    const Wires w = wires(in);
    typename Rx::In ri;
    ri.rst_n = in.rst_n;
    ri.rx = in.rx;
    typename Fifo::In fi;
    fi.rst_n = in.rst_n;
    fi.wr = w.proto.fifo_wr;
    fi.wr_data = w.proto.fifo_wr_data;
    fi.commit = w.proto.fifo_commit;
    fi.rollback = w.proto.fifo_rollback;
    fi.clear = w.proto.fifo_clear;
    fi.release = w.proto.release;
    fi.tready = in.tready;
    typename Tx::In ti;
    ti.rst_n = in.rst_n;
    ti.tdata = w.proto.tx_tdata;
    ti.tvalid = w.proto.tx_tvalid;
    rx_.clock(ri);
    proto_.clock(w.pi);
    fifo_.clock(fi);
    tx_.clock(ti);
  }

  const Proto& proto() const { return proto_; }
  const Fifo& fifo() const { return fifo_; }

 private:
  struct Wires {
    typename Rx::Out rx;
    typename Tx::Out tx;
    typename Fifo::Out fifo;
    typename Proto::In pi;
    typename Proto::Out proto;
  };
  Wires wires(const In& in) const {
    Wires w{};
    w.rx = rx_.outputs();
    w.tx = tx_.outputs();
    w.fifo = fifo_.outputs();
    w.pi.rst_n = in.rst_n;
    w.pi.rx_data = w.rx.data;
    w.pi.rx_valid = w.rx.valid;
    w.pi.rx_err = w.rx.err;
    w.pi.tx_tready = w.tx.tready;
    w.pi.fifo_level = w.fifo.level;
    w.pi.fifo_credits = w.fifo.credits;
    w.pi.fifo_busy = w.fifo.busy;
    w.pi.tick = in.tick;
    w.pi.seg_start = in.seg_start;
    w.pi.underrun = in.underrun;
    w.pi.tick_err = in.tick_err;
    for (int a = 0; a < Axes; ++a) w.pi.sample[a] = in.sample[a];
    w.pi.eng_tick = in.eng_tick;
    w.pi.scale_s = in.scale_s;
    w.pi.ahead = in.ahead;
    w.pi.starved_count = in.starved_count;
    w.pi.starved = in.starved;
    w.pi.held = in.held;
    w.proto = proto_.outputs(w.pi);
    return w;
  }

  Rx rx_;
  Proto proto_;
  Fifo fifo_;
  Tx tx_;
};

}  // namespace traj
