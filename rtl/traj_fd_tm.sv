// trajcore: time-multiplexed forward-difference sampling engine.
//
// Mirrors hls/traj_fd_tm.hpp cycle for cycle. The same segment word stream,
// tick contract, samples and status outputs as traj_fd_engine (the host's
// prediction is the same), with one ChunkWidth-bit adder for every register
// of every axis and the registers in one inferred block RAM:
//   * RAM word address {axis, chunk, register}: register i of axis a, chunk c
//     (c = 0 least significant) at (a << (ChB+RgB)) | (c << RgB) | i;
//   * a tick is one pass over Slots = Axes*Chunks*(Degree+1) RAM words in the
//     order axis, chunk, register (register fastest), one read per clock. At
//     the word of register i (i >= 1) the adder writes
//     r[i-1] <- r[i-1] + r[i] + carry[i-1] for that chunk: r[i-1] was read one
//     slot earlier, r[i] is still the old value (it is written one slot later),
//     so every register advances from the old values. The sum is written a
//     clock later (sum_q). carry[i-1] is the carry of register i-1 out of the
//     chunk below (0 for chunk 0), kept in a queue of Degree flops;
//   * the old r[0] chunks, read in the pass, are captured into the sample
//     register (the bits at GuardBits and above), so sample_o changes during
//     a pass and sample_valid_o pulses once the pass is done;
//   * the same r[0] chunks are written, whole, to a second RAM of
//     Axes*Chunks words (the sample RAM, word (a << ChB) | c: chunk c of axis
//     a's r[0], register bits c*ChunkWidth and up; the sample is the bits at
//     GuardBits and above) read through a registered port: sample_word_o is
//     the word at the sample_addr_i of the clock before. A consumer that
//     takes the samples a word at a time reads them there and leaves
//     sample_o open: synthesis then drops the Axes*OutWidth sample flops;
//     sample_we_o / sample_wd_o are those flops' write port (bit i of
//     sample_o takes bit i of sample_wd_o in a clock where bit i of
//     sample_we_o is high): a register outside built from them follows
//     sample_o exactly (traj_board shares one with the time-scale unit);
//   * segment words are written to the RAM as they arrive (stream order:
//     axis, register, chunk): the same field counters walk the RAM in the
//     load order and in the pass order;
//   * the pass of a segment's last tick reads the r[0] words only
//     (Axes*Chunks slots, no writes): the next segment replaces the
//     registers, and its load starts that much sooner.
//
// Timing (one tick with a segment active, tick_i high in cycle x; P = Slots,
// or Axes*Chunks for the last tick of a segment):
//   x+1          tick taken (run), read of the first slot
//   x+2 .. x+P+1 read data of the pass: writes, sample capture
//   x+P+2        sample_valid_o (and seg_done_o with the K-th sample)
// The next tick is taken at x+P+2 at the earliest (after the last tick, the
// next segment's load of Words words comes first). Ticks at least
// MinTickClocks = Axes*Chunks*(Degree+2) + HdrWords + 1 clocks apart never
// wait and never set tick_err (within a segment Slots + 1 is enough) while
// the stream delivers a word per clock when asked.
// sample_o holds from sample_valid_o until the next pass captures, i.e.
// until one clock after the next tick is taken; so do the sample RAM's words
// (a word is defined once a pass has written it: the RAM is not reset).
`default_nettype none
`include "traj_check.svh"

module traj_fd_tm #(
  parameter int Axes          = 3,    // axes in lockstep, 1..8
  parameter int Degree        = 3,    // polynomial degree, 1..7 (Degree+1 registers per axis)
  parameter int Width         = 64,   // register width, multiple of ChunkWidth, <= 128
  parameter int ChunkWidth    = 16,   // adder, RAM and stream word width: 16 or 32
  parameter int GuardBits     = 32,   // register bits below the output LSB, 0..Width-2
  parameter int TickClocks    = 240,  // tick spacing the design uses (clocks), >= MinTickClocks
  // derived, do not override
  parameter int OutWidth      = Width - GuardBits,
  parameter int MinTickClocks = Axes * (Width / ChunkWidth) * (Degree + 2) + ((ChunkWidth < 32) ? 32 / ChunkWidth : 1) + 1,
  parameter int SampleAddrWidth = ($clog2(Axes) + $clog2(Width / ChunkWidth) > 0) ? $clog2(Axes) + $clog2(Width / ChunkWidth) : 1
) (
  input  logic                     clk_i,
  input  logic                     rst_ni,
  // segment word stream
  input  logic [ChunkWidth-1:0]    s_axis_tdata,
  input  logic                     s_axis_tvalid,
  output logic                     s_axis_tready,
  // servo strobe
  input  logic                     tick_i,
  // samples: axis a in sample_o[a*OutWidth +: OutWidth], two's complement
  output logic                     sample_valid_o,
  output logic [Axes*OutWidth-1:0] sample_o,
  output logic [Axes*OutWidth-1:0] sample_we_o,   // sample_o's write port (above)
  output logic [Axes*OutWidth-1:0] sample_wd_o,
  // sample RAM read port: word (axis << ChB) | chunk, one clock latency
  input  logic [SampleAddrWidth-1:0] sample_addr_i,
  output logic [ChunkWidth-1:0]    sample_word_o,
  output logic                     underrun_o,
  output logic                     seg_done_o,
  output logic                     tick_err_o
);

  localparam int Chunks     = Width / ChunkWidth;
  localparam int HdrWords   = (ChunkWidth < 32) ? 32 / ChunkWidth : 1;
  localparam int CountWidth = 32;
  localparam int AxB        = $clog2(Axes);        // address field widths
  localparam int ChB        = $clog2(Chunks);
  localparam int RgB        = $clog2(Degree + 1);
  localparam int AddrW      = AxB + ChB + RgB;      // >= 1 (Degree >= 1)
  localparam int AxW        = (AxB > 0) ? AxB : 1;  // counter widths
  localparam int ChW        = (ChB > 0) ? ChB : 1;

  // ---------------------------------------------------------------------
  // Elaboration-time parameter checks.
  // ---------------------------------------------------------------------
  `TRAJ_PARAM_CHECK(g_bad_axes, Axes >= 1 && Axes <= 8,
                    "traj_fd_tm: Axes must be 1..8")
  `TRAJ_PARAM_CHECK(g_bad_degree, Degree >= 1 && Degree <= 7,
                    "traj_fd_tm: Degree must be 1..7")
  `TRAJ_PARAM_CHECK(g_bad_chunk, ChunkWidth == 16 || ChunkWidth == 32,
                    "traj_fd_tm: ChunkWidth must be 16 or 32")
  `TRAJ_PARAM_CHECK(g_bad_width, Width >= ChunkWidth && Width <= 128 && Width % ChunkWidth == 0,
                    "traj_fd_tm: Width must be a multiple of ChunkWidth, at most 128")
  `TRAJ_PARAM_CHECK(g_bad_guard, GuardBits >= 0 && GuardBits <= Width - 2,
                    "traj_fd_tm: GuardBits must be 0..Width-2")
  `TRAJ_PARAM_CHECK(g_bad_outwidth, OutWidth == Width - GuardBits,
                    "traj_fd_tm: OutWidth is derived (Width-GuardBits); do not override it")
  `TRAJ_PARAM_CHECK(g_bad_mintick, MinTickClocks == Axes * Chunks * (Degree + 2) + HdrWords + 1,
                    "traj_fd_tm: MinTickClocks is derived (Axes*Chunks*(Degree+2)+HdrWords+1); do not override it")
  `TRAJ_PARAM_CHECK(g_bad_saddr, SampleAddrWidth == ((AxB + ChB > 0) ? AxB + ChB : 1),
                    "traj_fd_tm: SampleAddrWidth is derived (clog2(Axes)+clog2(Chunks), at least 1); do not override it")
  `TRAJ_PARAM_CHECK(g_bad_tick, TickClocks >= MinTickClocks,
                    "traj_fd_tm: TickClocks is below MinTickClocks = Axes*Chunks*(Degree+2)+HdrWords+1")

  // ---------------------------------------------------------------------
  // State. Datapath (mem, rd_q, prev_q, count_q, sample_q, slot copies) is
  // not reset.
  // ---------------------------------------------------------------------
  logic [ChunkWidth-1:0] rd_q;    // RAM read data: the word read last cycle
  logic [ChunkWidth-1:0] prev_q;  // the word read the cycle before (r[i-1])
  logic [Degree-1:0]     carry_q; // carries out of the previous chunk, in use order (see below)
  logic                  wpend_q;    // a pass's write is in flight (registered update write)
  logic [AddrW-1:0]      waddr_q;    // its address
  logic [ChunkWidth-1:0] sum_q;      // its data: the adder's sum
  logic [AxW-1:0]        a_q, ra_q;   // field counters; ra/rc/ri: the slot of rd_q
  logic [ChW-1:0]        c_q, rc_q;
  logic [RgB-1:0]        i_q, ri_q;
  logic [CountWidth-1:0] count_q;
  logic                  active_q, primed_q, last_tick_q;
  logic                  iss_q;      // a pass issues reads of slots 1..Slots-1
  logic                  busy_q;     // rd_q holds a word of a pass
  logic                  last1_q;    // rd_q holds the last word of a pass
  logic                  mid_q;      // a segment is partly loaded
  logic                  hdr_q;      // the next word is a header word
  logic                  hword_q;    // header word index (two header words at ChunkWidth 16)
  logic                  cnt_one_q;  // == (count_q == 1) while a segment is active (timing)
  logic                  tick_q, tick_in_q, tick_err_q;
  logic                  sample_valid_q, underrun_q, seg_done_q;
  logic [Axes*OutWidth-1:0] sample_q;

  // ---------------------------------------------------------------------
  // Control decode (mirrors FdTm::clock).
  // ---------------------------------------------------------------------
  logic ready, accept, header, load_shift, consume, run, walk, fast, step;
  logic i_wrap, c_wrap, a_wrap, at_last, at_wrap, hdr_last;
  logic tick_new, tick_held;
  // With one word per axis and register pair (Axes = 1, Chunks = 1,
  // Degree = 1) the next pass's first read is the word the last write of a
  // pass lands on: that pass waits a clock.
  localparam bit WaitWrite = (Axes == 1 && Chunks == 1 && Degree == 1);
  logic wr_wait;
  assign wr_wait = WaitWrite && wpend_q;

  assign tick_new   = tick_i && !tick_in_q;
  assign tick_held  = tick_i && tick_in_q;
  assign ready      = !active_q && !busy_q;
  assign accept     = s_axis_tvalid && ready;
  assign header     = accept && hdr_q;
  assign load_shift = accept && !hdr_q;
  assign consume    = tick_q && !busy_q && !wr_wait && !mid_q && !accept;
  // == consume && active_q: an active segment implies no load in progress
  assign run        = tick_q && active_q && !busy_q && !wr_wait;
  assign walk       = run || iss_q;       // a read of the pass is issued this cycle
  // the pass of a segment's last tick reads the r[0] words only (its sample):
  // the registers are not needed afterwards (the next segment replaces them)
  assign fast       = run ? cnt_one_q : (iss_q && last_tick_q);
  assign step       = walk || load_shift; // the field counters advance
  assign i_wrap     = (i_q == RgB'(Degree));
  assign c_wrap     = (32'(c_q) == Chunks - 1);
  assign a_wrap     = (32'(a_q) == Axes - 1);
  assign at_last    = (i_wrap || fast) && c_wrap && a_wrap;
  // the same for a load word: a load never walks (fast is 0), and the load's
  // decodes then stay off the pass's tick path (timing)
  assign at_wrap    = i_wrap && c_wrap && a_wrap;
  assign hdr_last   = (HdrWords == 1) || hword_q;

  // ---------------------------------------------------------------------
  // Field counters: the pass walks register, chunk, axis (register fastest);
  // the last tick's pass chunk, axis with register 0 only; the load walks
  // chunk, register, axis (the stream order).
  // ---------------------------------------------------------------------
  logic i_inc, c_inc;
  assign i_inc = walk ? !fast : c_wrap;
  assign c_inc = !walk || i_wrap || fast;

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      a_q <= '0;
      c_q <= '0;
      i_q <= '0;
    end else if (step) begin
      if (i_inc) i_q <= i_wrap ? '0 : i_q + 1'b1;
      if (c_inc) c_q <= c_wrap ? '0 : c_q + 1'b1;
      if ((i_wrap || fast) && c_wrap) a_q <= a_wrap ? '0 : a_q + 1'b1;
    end
  end

  // ---------------------------------------------------------------------
  // Register RAM, the shared chunk adder and the write port.
  // ---------------------------------------------------------------------
  function automatic logic [AddrW-1:0] addr(input logic [AxW-1:0] a, input logic [ChW-1:0] c,
                                            input logic [RgB-1:0] i);
    addr = (AddrW'(a) << (ChB + RgB)) | (AddrW'(c) << RgB) | AddrW'(i);
  endfunction

  logic [AddrW-1:0]      rd_addr, wr_addr;
  logic [ChunkWidth-1:0] wr_data;
  logic                  wr_en, upd_wr, carry_in;
  logic [ChunkWidth-1:0] sum;
  logic [RgB-1:0]        ri_m1;  // the register written at this slot: ri_q - 1

  assign ri_m1     = ri_q - 1'b1;
  assign carry_in  = carry_q[0];
  assign sum       = prev_q + rd_q + ChunkWidth'(carry_in);
  assign upd_wr    = busy_q && (ri_q != '0);
  assign rd_addr   = addr(a_q, c_q, i_q);
  // RAM write port: a load word at once, an update a clock after its slot
  // (the adder's carry chain ends at sum_q). They never meet: a load starts
  // only with no segment active, and a pass that writes never ends one.
  assign wr_en     = load_shift || wpend_q;
  assign wr_addr   = load_shift ? addr(a_q, c_q, i_q) : waddr_q;
  assign wr_data   = load_shift ? s_axis_tdata : sum_q;

  // An update lands one clock after its slot. A pass never reads a word it
  // has written, the next pass reads its first word (axis 0, chunk 0, r[0])
  // no sooner than the clock the last update lands (see wr_wait), and a pass
  // starts after the last load word: no read/write collision logic.
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      wpend_q <= 1'b0;
    end else begin
      wpend_q <= upd_wr;
    end
    waddr_q <= addr(ra_q, rc_q, ri_m1);
    sum_q   <= sum;
  end

  (* no_rw_check *) logic [ChunkWidth-1:0] mem [2**AddrW];
  always_ff @(posedge clk_i) begin
    if (wr_en) mem[wr_addr] <= wr_data;
    rd_q   <= mem[rd_addr];
    prev_q <= rd_q;
    ra_q   <= a_q;
    rc_q   <= c_q;
    ri_q   <= i_q;
  end

  // The carries form a queue: the slots of registers 1..Degree of a chunk
  // use the carries of registers 0..Degree-1 out of the previous chunk, in
  // that order (each slot pops the head: the adder's carry in is a flop),
  // and each slot's own carry out is pushed to the tail one clock later,
  // derived from flops (no path behind the carry chain): with the operands'
  // top bits a, b and the sum's top bit s, the carry out is a when a == b,
  // else !s. After the top chunk 0 is pushed, so every register starts the
  // next axis (and pass) with 0. A push in a clock that also pops lands one
  // place before the tail (the pop has moved the free place there).
  logic c_wrap_rd;  // rd_q holds a word of the top chunk
  logic pa_q, pb_q, top_q;  // the update in sum_q: operands' top bits, top chunk
  logic carry_late;         // its carry out
  assign c_wrap_rd  = (32'(rc_q) == Chunks - 1);
  assign carry_late = !top_q && ((pa_q == pb_q) ? pa_q : !sum_q[ChunkWidth-1]);
  always_ff @(posedge clk_i) begin
    pa_q  <= prev_q[ChunkWidth-1];
    pb_q  <= rd_q[ChunkWidth-1];
    top_q <= c_wrap_rd;
  end
  if (Degree == 1) begin : g_carry_one
    // a pop and a push never meet (a chunk's slots are register 0, then 1)
    always_ff @(posedge clk_i) begin
      if (!rst_ni) begin
        carry_q <= '0;
      end else if (wpend_q) begin
        carry_q <= carry_late;
      end
    end
  end else begin : g_carry_queue
    always_ff @(posedge clk_i) begin
      if (!rst_ni) begin
        carry_q <= '0;
      end else if (upd_wr) begin
        carry_q[Degree-2:0] <= carry_q[Degree-1:1];
        if (wpend_q) carry_q[Degree-2] <= carry_late;
      end else if (wpend_q) begin
        carry_q[Degree-1] <= carry_late;
      end
    end
  end

  // ---------------------------------------------------------------------
  // Sample capture: the old r[0] chunks, bits GuardBits and above.
  // ---------------------------------------------------------------------
  // The write port: bit p of axis a's sample is register bit GuardBits + p,
  // in chunk (GuardBits + p) / ChunkWidth; it takes rd_q's bit of that
  // position when the pass reads that chunk of that axis.
  logic cap;
  logic [Axes*OutWidth-1:0] sample_we, sample_wd;
  assign cap = busy_q && (ri_q == '0);
  for (genvar a = 0; a < Axes; a++) begin : g_out_axis
    for (genvar p = 0; p < OutWidth; p++) begin : g_out_bit
      localparam int Bit = GuardBits + p;  // register bit
      assign sample_we[a*OutWidth + p] = cap && 32'(ra_q) == a && 32'(rc_q) == Bit / ChunkWidth;
      assign sample_wd[a*OutWidth + p] = rd_q[Bit % ChunkWidth];
    end
  end
  always_ff @(posedge clk_i) begin
    for (int i = 0; i < Axes * OutWidth; i++)
      if (sample_we[i]) sample_q[i] <= sample_wd[i];
  end

  // Sample RAM: every r[0] chunk the pass reads (its own RAM, so that a
  // consumer reads the samples while the next pass runs in the register RAM).
  localparam int SaW = AxB + ChB;  // address bits in use (0: one word)
  logic [ChunkWidth-1:0] sample_word_q;
  logic [SampleAddrWidth-1:0] cap_addr;
  if (SaW > 0) begin : g_saddr
    assign cap_addr = SampleAddrWidth'((32'(ra_q) << ChB) | 32'(rc_q));
  end else begin : g_saddr_one
    assign cap_addr = '0;
  end
  (* no_rw_check, ram_style = "block" *) logic [ChunkWidth-1:0] smem [2**SampleAddrWidth];
  always_ff @(posedge clk_i) begin
    if (cap) smem[cap_addr] <= rd_q;
    sample_word_q <= smem[sample_addr_i];
  end

  // ---------------------------------------------------------------------
  // Control registers.
  // ---------------------------------------------------------------------
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      active_q       <= 1'b0;
      primed_q       <= 1'b0;
      mid_q          <= 1'b0;
      hdr_q          <= 1'b1;
      hword_q        <= 1'b0;
      iss_q          <= 1'b0;
      busy_q         <= 1'b0;
      last1_q        <= 1'b0;
      tick_q         <= 1'b0;
      tick_in_q      <= 1'b0;
      tick_err_q     <= 1'b0;
      sample_valid_q <= 1'b0;
      underrun_q     <= 1'b0;
      seg_done_q     <= 1'b0;
    end else begin
      // Segment load.
      if (header) begin
        mid_q   <= 1'b1;
        hword_q <= !hword_q && (HdrWords > 1);
        if (hdr_last) hdr_q <= 1'b0;
      end
      if (load_shift) begin
        if (at_wrap) begin
          mid_q    <= 1'b0;
          hdr_q    <= 1'b1;
          active_q <= !cnt_zero;
        end
      end
      // Pass sequencing.
      iss_q   <= walk && !at_last;
      busy_q  <= walk;
      last1_q <= walk && at_last;
      // (== walk && at_last && fast: run and iss_q never meet, and fast
      // makes at_last the chunk and axis wraps; written out for timing)
      if (((run && cnt_one_q) || (iss_q && last_tick_q)) && c_wrap && a_wrap) active_q <= 1'b0;
      // Tick handling.
      tick_in_q      <= tick_i;
      tick_q         <= (tick_q && !consume) || tick_new;
      tick_err_q     <= tick_err_q || (tick_new && tick_q && !consume) || tick_held;
      sample_valid_q <= (consume && !active_q && primed_q) || last1_q;
      // primed: a real sample has left since reset (a K = 0 segment emits
      // none), so an underrun repeats a sample that was output, never the
      // unreset register
      primed_q       <= primed_q || last1_q;
      underrun_q     <= consume && !active_q;
      seg_done_q     <= last1_q && last_tick_q;
    end
  end

  // Count: datapath, not reset.
  logic [CountWidth-1:0] count_hdr;  // count_q after taking one header word
  if (ChunkWidth < 32) begin : g_hdr_shift
    assign count_hdr = {s_axis_tdata, count_q[CountWidth-1:ChunkWidth]};
  end else begin : g_hdr_word
    assign count_hdr = s_axis_tdata[CountWidth-1:0];
  end

  // The count's decodes share one comparison of its upper bits: K = 0 and
  // K = 1 at the segment's last word, K = 2 at a tick.
  logic cnt_hi_zero, cnt_zero;
  assign cnt_hi_zero = (count_q[CountWidth-1:2] == '0);
  assign cnt_zero    = cnt_hi_zero && (count_q[1:0] == 2'd0);

  always_ff @(posedge clk_i) begin
    if (header) begin
      count_q   <= count_hdr;
    end else if (run) begin
      count_q   <= count_q - 1'b1;
      cnt_one_q <= cnt_hi_zero && (count_q[1:0] == 2'd2);
    end
    if (load_shift && at_wrap) begin
      cnt_one_q <= cnt_hi_zero && (count_q[1:0] == 2'd1);
    end
    if (run) begin
      last_tick_q <= cnt_one_q;
    end
  end

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Formal properties (yosys -formal): bounded model checking from reset and
  // temporal induction, run by scripts/formal.sh (the rtl.formal.* tests).
  // ---------------------------------------------------------------------
  logic f_past_valid = 1'b0;
  logic f_cnt_valid = 1'b0;  // count_q holds a value written by a header word
  logic f_emitted = 1'b0;    // a sample of an active segment has left since reset
  always_ff @(posedge clk_i) begin
    f_past_valid <= 1'b1;
    f_emitted <= rst_ni && (f_emitted || last1_q);
    if (header) f_cnt_valid <= 1'b1;
  end
  always_comb begin
    if (!f_past_valid) assume (!rst_ni);
  end
  // the slot index of the field counters (pass order) and of rd_q
  // (f_fslot, f_rfslot: the same in the last tick's pass, register 0 only)
  logic [31:0] f_slot, f_rslot, f_fslot, f_rfslot;
  assign f_fslot  = 32'(a_q) * Chunks + 32'(c_q);
  assign f_rfslot = 32'(ra_q) * Chunks + 32'(rc_q);
  assign f_slot   = f_fslot * (Degree + 1) + 32'(i_q);
  assign f_rslot  = f_rfslot * (Degree + 1) + 32'(ri_q);
  always_ff @(posedge clk_i) begin
    if (f_past_valid) begin
      // reset clears every control output and state
      if (!$past(rst_ni)) begin
        assert (!sample_valid_q && !underrun_q && !seg_done_q && !tick_err_q);
        assert (!active_q && !busy_q && !iss_q && !primed_q && !mid_q && hdr_q && !tick_q);
        assert (a_q == '0 && c_q == '0 && i_q == '0 && carry_q == '0);
      end
      // tick_err is sticky until reset
      if ($past(rst_ni) && $past(tick_err_q)) assert (tick_err_q);
      // tick contract: one strobe = one tick. tick_i high in two consecutive
      // cycles is one tick (no second pending tick) and sets tick_err.
      if ($past(rst_ni) && $past(tick_i) && $past(tick_in_q)) begin
        assert (tick_err_q);
        assert (tick_q == ($past(tick_q) && !$past(consume)));
      end
      if ($past(rst_ni) && $past(tick_i) && !$past(tick_in_q)) assert (tick_q);
      if ($past(rst_ni)) assert (tick_in_q == $past(tick_i));
      // the output moves only while a pass of an active segment captures
      // r[0]: underrun, idle, loading and reset hold it (no jump)
      if (!$past(cap)) assert (sample_q == $past(sample_q));
      // the sample RAM port: a word read twice at one address with no
      // capture between is the same word (only a pass's capture writes it)
      if ($past(f_past_valid) && $past(sample_addr_i) == $past(sample_addr_i, 2) && !$past(cap, 2))
        assert (sample_word_q == $past(sample_word_q));
      // a segment-done pulse comes with its sample, never with an underrun
      if (seg_done_q) assert (sample_valid_q && !underrun_q);
      if (underrun_q) assert (sample_valid_q == $past(primed_q));
      // a valid sample is one the engine has output since reset: never the
      // unreset sample register (e.g. after a K = 0 first segment)
      if (sample_valid_q) assert (f_emitted);
      // a pass takes Slots + 1 clocks from the tick taken to the sample
      if ($past(rst_ni) && $past(run)) assert (busy_q && f_rslot == 0);
    end
    if (f_past_valid) begin
      // registered decodes equal what they stand for (the timing fixes)
      if (active_q || busy_q) assert (cnt_one_q == (count_q == CountWidth'(1)));
      if (load_shift) assert (at_last == at_wrap);
      // state bounds and consistency
      assert (32'(a_q) < Axes && 32'(c_q) < Chunks && 32'(i_q) <= Degree);
      if (busy_q) assert (32'(ra_q) < Axes && 32'(rc_q) < Chunks && 32'(ri_q) <= Degree);
      if (HdrWords == 1 || !hdr_q || !mid_q) assert (!hword_q);
      if (iss_q) assert (busy_q && active_q);
      if (iss_q && !last_tick_q) assert (f_slot == f_rslot + 1);
      if (iss_q && last_tick_q) assert (i_q == '0 && ri_q == '0 && f_fslot == f_rfslot + 1);
      if (busy_q && !iss_q) assert (f_slot == 0 && last1_q);
      if (last1_q) assert (busy_q && !iss_q && 32'(ra_q) == Axes - 1 && 32'(rc_q) == Chunks - 1 &&
                           (last_tick_q ? ri_q == '0 : 32'(ri_q) == Degree));
      if (!busy_q) assert (!iss_q && !last1_q);
      if (!busy_q && !mid_q) assert (f_slot == 0);
      if (hdr_q && !busy_q) assert (f_slot == 0);
      if (!hdr_q) assert (mid_q);
      if (mid_q) assert (!active_q && !busy_q);
      if (active_q) assert (hdr_q);
      if (active_q && !busy_q) assert (count_q != '0);
      assert (s_axis_tready == (!active_q && !busy_q));
      // supporting invariants (make the properties inductive)
      if (busy_q) assert (f_cnt_valid && last_tick_q == (count_q == '0));
      if (active_q || primed_q || mid_q) assert (f_cnt_valid);
      // the carry queue (see the datapath): entries from below chunk 0 and
      // entries pushed in the top chunk are 0; the late push follows every
      // update slot; between passes the queue is clear
      if (busy_q && 32'(ri_q) >= 2) assert (wpend_q && top_q == c_wrap_rd);
      if (busy_q && ri_q == 1) assert (!wpend_q);
      if (busy_q && ri_q == '0 && wpend_q) assert (top_q == (rc_q == '0) && !last_tick_q);
      if (!busy_q && wpend_q) assert (top_q);
      if ((!busy_q && !wpend_q) || (busy_q && last_tick_q)) assert (carry_q == '0 && !wpend_q);
      for (int n = 0; n < Degree; n++) begin
        if (busy_q && rc_q == '0 && ri_q != '0 && n <= Degree - 32'(ri_q)) assert (!carry_q[n]);
        if (busy_q && rc_q == '0 && ri_q == '0 && (n < Degree - 1 || !wpend_q)) assert (!carry_q[n]);
        if (busy_q && c_wrap_rd && 32'(ri_q) >= 2 && n > Degree - 32'(ri_q) && n < Degree - 1)
          assert (!carry_q[n]);
        if (!busy_q && wpend_q && n < Degree - 1) assert (!carry_q[n]);
      end
      // the registered write port
      if ($past(rst_ni)) assert (wpend_q == $past(upd_wr));
      if (wpend_q) assert (!load_shift && active_q);
      assert (primed_q == f_emitted);
    end
  end
`endif

  assign s_axis_tready  = ready;
  assign sample_valid_o = sample_valid_q;
  assign sample_o       = sample_q;
  assign sample_we_o    = sample_we;
  assign sample_wd_o    = sample_wd;
  assign sample_word_o  = sample_word_q;
  assign underrun_o     = underrun_q;
  assign seg_done_o     = seg_done_q;
  assign tick_err_o     = tick_err_q;

endmodule

`default_nettype wire
