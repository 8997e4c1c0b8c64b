// trajcore: the host-link protocol of rtl/board/LINK.md on a byte stream,
// mirrored by hls/traj_link_proto.hpp cycle for cycle.
//
// Receive side, one byte per rx_valid_i (from traj_uart_rx):
//   * HDLC unstuffing: 0x7E ends a body and starts the next (empty bodies are
//     ignored; bytes before the first 0x7E after reset are ignored), 0x7D
//     escapes the next byte (XOR 0x20; anything but 0x5E/0x5D after it makes
//     the body bad), rx_err_i (framing error) makes the body bad.
//   * header, length, CRC-32 (byte-serial, zlib's; a good body leaves the
//     residue 0xDEBB20E3 in the register), command and content checks while
//     the bytes arrive; the verdict is taken at the closing 0x7E, in one cycle.
//   * a SEGMENT frame with seq == next_seq, the record size and a free slot
//     (decided at its first payload byte) writes K and the registers as engine
//     words into traj_seg_fifo as they arrive (tentative); the verdict commits
//     them (stored, next_seq + 1, ACK) or rolls them back (every other outcome).
//   * CONFIG and FEED payload bytes go to a shadow RAM (block RAM) as they
//     arrive; a good verdict copies them into the applied registers, a byte
//     per clock, each field whole at its last byte (below).
// Answer side: ACK/NAK (the latest verdict; one pending answer, a newer one
// replaces it: ACKs are cumulative) before STATUS (on STATUS_REQ or every
// status period in ticks), each a stuffed frame with its CRC, byte by byte to
// traj_uart_tx. Every u32 of a frame is read from the live state when its
// first byte is sent (no torn values); the samples are taken once, when the
// frame starts. With CountRam = 1 a counter's word is the count when the
// counter is next written back (below), at most 6 clocks after its first
// byte was due; the stream holds tvalid low until then.
// Playback: START sets playing; underrun_i while playing ends a STOP, or
// reaches the end (END received, FIFO empty and idle), or is an underrun
// (counted, halt until RESUME). release_o lets the FIFO start a segment:
// playing, no halt, no STOP (with time scaling a STOP is a hold: the data
// still goes to the engine), and no engine tick in this or the two previous
// cycles nor an underrun strobe now (underrun_i follows its tick by at most 2
// cycles, as the FD engine's underrun_o does): so no segment is handed to the
// engine after an underrun tick it could not serve. With time scaling the
// board gives underrun_i when a STOP has come to rest or the job's last
// sample is out (the engine itself never underruns then).
// Time scaling (scale_*_o, hold_o: CONFIG and FEED, LINK.md) is applied by
// the board's traj_time_scale; STATUS reports its state (scale_s_i, ...).
// Strobes (tick_i, eng_tick_i, seg_start_i, underrun_i, rx_valid_i, rx_err_i) are one
// cycle each, rx_valid_i at most every other cycle (the UART gives one per
// character); the tx stream holds its byte until tx_tready_i.
`default_nettype none
`include "traj_check.svh"

module traj_link_proto #(
  parameter int Axes          = 3,    // 1..8
  parameter int Degree        = 3,    // FD degree, 1..7
  parameter int Width         = 64,   // FD register width (bits, multiple of ChunkWidth)
  parameter int ChunkWidth    = 16,   // engine word width: 16, 32 or 64
  parameter int GuardBits     = 32,   // FD guard bits: OutWidth = Width - GuardBits <= 64
  parameter int MinTickPeriod = 256,  // smallest CONFIG tick period in clocks (0 = external is allowed)
  parameter int ClkHz         = 48_000_000,  // clk_i in Hz, reported in STATUS (the host's clocks -> seconds)
  parameter int ScaleWidth    = 0,    // SW of the board's time-scale unit (0: none, time scaling and FEED refused)
  parameter int SnapRam       = 0,    // 1: the STATUS snapshot of the samples in block RAM (traj_hold_ram), not flops
  parameter int CountRam      = 0,    // 1: the six STATUS counters in block RAM, one adder for all (below)
  // derived, do not override
  parameter int OutWidth      = Width - GuardBits
) (
  input  logic                     clk_i,
  input  logic                     rst_ni,
  // bytes from the UART receiver
  input  logic [7:0]               rx_data_i,
  input  logic                     rx_valid_i,
  input  logic                     rx_err_i,
  // bytes to the UART transmitter
  output logic [7:0]               tx_tdata_o,
  output logic                     tx_tvalid_o,
  input  logic                     tx_tready_i,
  // segment FIFO
  output logic                     fifo_wr_o,
  output logic [ChunkWidth-1:0]    fifo_wr_data_o,
  output logic                     fifo_commit_o,
  output logic                     fifo_rollback_o,
  output logic                     fifo_clear_o,
  output logic                     release_o,
  input  logic [15:0]              fifo_level_i,
  input  logic [15:0]              fifo_credits_i,
  input  logic                     fifo_busy_i,
  // board
  input  logic                     tick_i,
  input  logic                     eng_tick_i,     // the engine's tick (tick_i without time scaling)
  input  logic                     seg_start_i,
  input  logic                     underrun_i,
  input  logic                     tick_err_i,
  input  logic [Axes*OutWidth-1:0] sample_i,
  // time scaling, for STATUS
  input  logic [31:0]              scale_s_i,
  input  logic [15:0]              starved_count_i,
  input  logic [31:0]              ahead_i,
  input  logic                     starved_i,
  input  logic                     held_i,
  output logic                     run_o,
  output logic [31:0]              tick_period_o,
  output logic [Axes*6-1:0]        step_shift_o,
  output logic [15:0]              pulse_o,
  output logic [15:0]              setup_o,
  output logic                     enable_o,
  // time scaling (CONFIG, FEED), STOP, the job's end (END taken), RESUME (a
  // strobe), the K of a stored record (with fifo_commit_o)
  output logic [31:0]              scale_m_o,
  output logic [31:0]              scale_s_max_o,
  output logic [31:0]              scale_override_o,
  output logic [5:0]               scale_shift_o,
  output logic                     scale_auto_o,
  output logic                     hold_o,
  output logic                     stop_o,
  output logic                     end_o,
  output logic                     resume_o,
  output logic [31:0]              stored_k_o
);

  localparam int RegBytes  = Axes * (Degree + 1) * Width / 8;
  localparam int RecBytes  = 16 + RegBytes;                  // SEGMENT payload
  localparam int ChunkB    = ChunkWidth / 8;
  localparam int StatLen   = 48 + 8 * Axes;                  // STATUS payload
  localparam int CfgLen    = 40;                             // CONFIG payload
  localparam int FeedLen   = 8;                              // FEED payload
  localparam int CrcWordA  = 3;                              // ACK/NAK: last body word
  localparam int CrcWordS  = 2 + StatLen / 4;                // STATUS: last body word
  localparam logic [31:0] Residue = 32'hDEBB20E3;

  // frame types
  localparam logic [7:0] TReset = 8'h01, TConfig = 8'h02, TStart = 8'h03, TStop = 8'h04;
  localparam logic [7:0] TResume = 8'h05, TStatReq = 8'h06, TFeed = 8'h07, TSegment = 8'h10, TEnd = 8'h11;
  localparam logic [7:0] TAck = 8'h81, TNak = 8'h82, TStatus = 8'h83;

  `TRAJ_PARAM_CHECK(g_bad_axes, Axes >= 1 && Axes <= 8, "traj_link_proto: Axes must be 1..8")
  `TRAJ_PARAM_CHECK(g_bad_degree, Degree >= 1 && Degree <= 7, "traj_link_proto: Degree must be 1..7")
  `TRAJ_PARAM_CHECK(g_bad_chunk, ChunkWidth == 16 || ChunkWidth == 32 || ChunkWidth == 64,
                    "traj_link_proto: ChunkWidth must be 16, 32 or 64")
  `TRAJ_PARAM_CHECK(g_bad_width, Width >= ChunkWidth && Width <= 128 && Width % ChunkWidth == 0,
                    "traj_link_proto: Width must be a multiple of ChunkWidth, at most 128")
  `TRAJ_PARAM_CHECK(g_bad_out, OutWidth >= 2 && OutWidth <= 64,
                    "traj_link_proto: OutWidth (Width - GuardBits) must be 2..64")
  `TRAJ_PARAM_CHECK(g_bad_rec, RecBytes <= 2048, "traj_link_proto: the record exceeds 2048 bytes")
  `TRAJ_PARAM_CHECK(g_bad_clk, ClkHz >= 1, "traj_link_proto: ClkHz must be positive")
  `TRAJ_PARAM_CHECK(g_bad_snap, SnapRam == 0 || SnapRam == 1, "traj_link_proto: SnapRam must be 0 or 1")
  `TRAJ_PARAM_CHECK(g_bad_count, CountRam == 0 || CountRam == 1, "traj_link_proto: CountRam must be 0 or 1")
  `TRAJ_PARAM_CHECK(g_bad_scale, ScaleWidth == 0 || (ScaleWidth >= 4 && ScaleWidth <= 24),
                    "traj_link_proto: ScaleWidth must be 0 or 4..24")
  `TRAJ_PARAM_CHECK(g_bad_derived, OutWidth == Width - GuardBits,
                    "traj_link_proto: OutWidth is derived; do not override it")

  // CRC-32 (zlib, reflected polynomial 0xEDB88320) of one byte, no final XOR.
  function automatic logic [31:0] crc8(input logic [31:0] c, input logic [7:0] d);
    logic [31:0] r;
    r = c ^ {24'h0, d};
    for (int k = 0; k < 8; k++) r = (r >> 1) ^ (r[0] ? 32'hEDB88320 : 32'h0);
    crc8 = r;
  endfunction

  // -------------------------------------------------------------------
  // Receive: unstuffing and body bytes.
  // -------------------------------------------------------------------
  logic        hunt_q, esc_q, bad_q, cbad_q, kz_q, wen_q;
  logic [11:0] idx_q, len_q;
  logic [7:0]  type_q;
  logic [31:0] seq_q, crc_q;
  logic [ChunkWidth-9:0] asm_q;  // the bytes of the word so far, top-aligned (the last byte completes it)
  logic [3:0]  wb_q;

  // The received byte and its decodes, registered (timing): the byte is
  // handled one cycle after the UART delivers it.
  logic [7:0] rxd_q;
  logic       rxv_q, rxe_q, rx7e_q, rx7d_q, rxesc_ok_q;
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      rxv_q <= 1'b0;
      rxe_q <= 1'b0;
    end else begin
      rxv_q <= rx_valid_i;
      rxe_q <= rx_err_i;
    end
    rxd_q      <= rx_data_i;
    rx7e_q     <= (rx_data_i == 8'h7E);
    rx7d_q     <= (rx_data_i == 8'h7D);
    rxesc_ok_q <= (rx_data_i == 8'h5E) || (rx_data_i == 8'h5D);
  end

  logic       is_flag, is_esc, dv;
  logic [7:0] d;
  assign is_flag = rxv_q && rx7e_q;
  assign is_esc  = rxv_q && !rx7e_q && !esc_q && rx7d_q;
  assign dv      = rxv_q && !rx7e_q && !is_esc && !hunt_q;
  assign d       = esc_q ? (rxd_q ^ 8'h20) : rxd_q;

  // Decodes of the position in the body, registered (timing): a byte at
  // cycle t sees the position after every earlier byte, since bytes come at
  // most every other cycle. p = idx - 8 is the payload offset. Comparisons
  // with a constant as logic (traj_ge_const: no carry chain).
  `include "traj_ge_const.svh"
  logic [11:0] p;
  logic        in_pay;    // a payload byte
  logic        overlong;  // past the CRC
  logic        pd_pay_q, pd_over_q, pd_k_q, pd_reg_q, pd_p0_q, pd_p13_q, pd_pseq_q;
  logic        pd_ctick_q, pd_cshift_q, pd_cpulse_q, pd_cen_q, pd_cres_q;
  logic        pd_cm_q, pd_csmax_q, pd_covr_q, pd_cshl_q, pd_cfl_q, pd_p4_q, pd_fres_q, pd_cscale_q, pd_cfg_q;
  assign p        = idx_q - 12'd8;
  function automatic logic p_in(input logic [11:0] x, input int lo, input int hi);  // lo <= x < hi
    p_in = traj_ge_const(32'(x), 32'(lo)) && !traj_ge_const(32'(x), 32'(hi));
  endfunction
  assign in_pay   = pd_pay_q;
  assign overlong = pd_over_q;
  always_ff @(posedge clk_i) begin
    pd_pay_q    <= traj_ge_const(32'(idx_q), 32'd8) && (p < len_q);
    pd_over_q   <= traj_ge_const(32'(idx_q), 32'd8) && (p >= len_q + 12'd4);
    pd_k_q      <= p_in(p, 4, 8);
    pd_reg_q    <= p_in(p, 12, RecBytes - 4);
    pd_p0_q     <= (p == 12'd0);
    pd_p13_q    <= p_in(p, 1, 4);
    pd_pseq_q   <= p_in(p, 8, 12);
    pd_ctick_q  <= p_in(p, 0, 4);
    pd_cshift_q <= p_in(p, 8, 8 + Axes);
    pd_cpulse_q <= (p == 12'd16) || (p == 12'd17);
    pd_cen_q    <= (p == 12'd20);
    pd_cres_q   <= p_in(p, 21, 24) || (p == 12'd38) || (p == 12'd39);
    pd_cm_q     <= p_in(p, 24, 28);
    pd_csmax_q  <= p_in(p, 28, 32);
    pd_covr_q   <= p_in(p, 32, 36);
    pd_cshl_q   <= (p == 12'd36);
    pd_cfl_q    <= (p == 12'd37);
    pd_p4_q     <= (p == 12'd4);
    pd_fres_q   <= p_in(p, 5, 8);
    pd_cscale_q <= p_in(p, 24, 40);
    pd_cfg_q    <= p_in(p, 0, 40);
  end

  logic known;
  always_comb begin
    case (d)
      TReset, TConfig, TStart, TStop, TResume, TStatReq, TFeed, TSegment, TEnd: known = 1'b1;
      default: known = 1'b0;
    endcase
  end

  logic is_seg, is_cfg, is_feed;
  assign is_seg  = (type_q == TSegment);
  assign is_cfg  = (type_q == TConfig);
  assign is_feed = (type_q == TFeed);

  // SEGMENT payload bytes that carry engine words: K and the registers.
  logic wbyte, wdone;
  logic [ChunkWidth-1:0] asm_d, wword;
  assign wbyte = dv && in_pay && is_seg && (pd_k_q || pd_reg_q);
  assign asm_d = {d, asm_q};
  if (ChunkWidth > 32) begin : g_khalf
    // K is half an engine word: the header word is K, zero-extended.
    logic pd_p7_q;  // the last byte of K comes next (registered, as the other decodes)
    always_ff @(posedge clk_i) pd_p7_q <= (p == 12'd7);
    assign wdone = (32'(wb_q) == ChunkB - 1) || pd_p7_q;
    assign wword = pd_p7_q ? {{(ChunkWidth-32){1'b0}}, asm_d[ChunkWidth-1 -: 32]} : asm_d;
  end else begin : g_kwhole
    assign wdone = (32'(wb_q) == ChunkB - 1);
    assign wword = asm_d;
  end

  // content check of one payload byte
  logic cbad_byte;
  logic [7:0] seq_byte;
  assign seq_byte = seq_q[8*idx_q[1:0] +: 8];  // byte p - 8 of seq (p[1:0] == idx[1:0])
  // An OR of the field checks, not a priority chain (timing: the byte's
  // compares in parallel). The fields of a type are disjoint byte ranges,
  // except without the unit, where bytes 24..39 must be 0 (pd_cscale_q): the
  // checks it overlaps (reserved: != 0; shift: > 40; flags: > 1) then flag
  // no byte that != 0 does not.
  logic d_zero, d_gt1, d_gt40, d_gt63;
  assign d_zero = (d == 8'd0);
  assign d_gt1  = (d[7:1] != 7'd0);
  assign d_gt40 = (d > 8'd40);
  assign d_gt63 = (d[7:6] != 2'd0);
  always_comb begin
    cbad_byte = (is_seg && ((pd_p0_q && d != 8'd1) || (pd_p13_q && !d_zero) || (pd_pseq_q && d != seq_byte))) ||
                (is_cfg && ((pd_cshift_q && d_gt63) || (pd_cen_q && d_gt1) || (pd_cres_q && !d_zero) ||
                            (ScaleWidth == 0 && pd_cscale_q && !d_zero) ||  // no unit: no time scaling
                            (pd_cshl_q && d_gt40) || (pd_cfl_q && d_gt1))) ||
                (is_feed && ((pd_p4_q && d_gt1) || (pd_fres_q && !d_zero)));
  end

  // CONFIG's and FEED's payload bytes go to a shadow RAM as they arrive (CONFIG
  // byte p at address p, p < 40; FEED byte p at 40 + p, p < 5); a good frame's
  // verdict copies them into the live registers, a byte per clock (the copy,
  // below). The checks a CONFIG or FEED verdict needs are flags kept per field
  // while the bytes arrive: every byte of a field comes in the same frame
  // (a good frame has the length of its type), so each field's first byte
  // sets them afresh and the later ones add to them.
  logic       sh_we;
  logic [5:0] sh_wa;
  assign sh_we = dv && in_pay && ((is_cfg && pd_cfg_q) || (is_feed && (pd_ctick_q || pd_p4_q)));
  assign sh_wa = is_feed ? 6'd40 + 6'(p[2:0]) : p[5:0];

  // per-field flags: nonzero (nz), below MinTickPeriod (tick_lt), a bit at or
  // above ScaleWidth (wide); the byte's index in its field is p[1:0]
  logic pulse_nz_q, tick_nz_q, tick_lt_q, m_nz_q, smax_nz_q, ovr_nz_q, shl_nz_q, auto_q;
  logic m_wide_q, smax_wide_q, ovr_wide_q;
  logic [31:0] sh_k_q;
  logic [7:0] min_byte, wide_mask;
  logic       first;  // the field's first byte
  logic       d_nz;
  assign min_byte = 8'(32'(MinTickPeriod) >> (8 * p[1:0]));
  assign first    = (p[1:0] == 2'd0);
  assign d_nz     = (d != 8'd0);
  localparam logic [31:0] WideBits = ~((32'd1 << ScaleWidth) - 1);  // bits at or above ScaleWidth
  assign wide_mask = WideBits[8*p[1:0] +: 8];
  always_ff @(posedge clk_i) begin
    if (dv && in_pay && is_cfg) begin
      if (pd_ctick_q) begin
        tick_nz_q <= d_nz || (!first && tick_nz_q);
        tick_lt_q <= (d < min_byte) || ((d == min_byte) && !first && tick_lt_q);
      end
      if (pd_cpulse_q) pulse_nz_q <= d_nz || (p[0] && pulse_nz_q);
      if (pd_cm_q) begin
        m_nz_q   <= d_nz || (!first && m_nz_q);
        m_wide_q <= ((d & wide_mask) != '0) || (!first && m_wide_q);
      end
      if (pd_csmax_q) begin
        smax_nz_q   <= d_nz || (!first && smax_nz_q);
        smax_wide_q <= ((d & wide_mask) != '0) || (!first && smax_wide_q);
      end
      if (pd_cshl_q) shl_nz_q <= d_nz;
      if (pd_cfl_q) auto_q <= d[0];
    end
    // the override: CONFIG's and FEED's; a SEGMENT's K
    if (dv && in_pay && ((is_cfg && pd_covr_q) || (is_feed && pd_ctick_q))) begin
      ovr_nz_q   <= d_nz || (!first && ovr_nz_q);
      ovr_wide_q <= ((d & wide_mask) != '0) || (!first && ovr_wide_q);
    end
    if (dv && in_pay && is_seg && pd_k_q) sh_k_q <= {d, sh_k_q[31:8]};
  end

  // a time-scaling value the unit cannot hold (bits at or above ScaleWidth)
  function automatic logic too_wide(input logic wide);
    too_wide = (ScaleWidth == 0) || wide;
  endfunction

  // -------------------------------------------------------------------
  // Verdict at the closing flag.
  // -------------------------------------------------------------------
  logic        fend, good, cbad_end, playing_busy;
  logic [31:0] next_seq_q;
  /* verilator lint_off UNUSEDSIGNAL */
  logic [31:0] diff;  // seq - next_seq: only its sign is read (seq behind next_seq)
  /* verilator lint_on UNUSEDSIGNAL */
  // Comparisons of the body so far, registered (timing): rx_valid_i comes at
  // most every other cycle, so at a flag they describe every byte before it.
  logic        seq_eq_q;   // seq == next_seq
  logic        behind_q;   // seq below next_seq (mod 2^32): a re-send
  logic        len_ok_q;   // idx == 12 + len
  logic        crc_ok_q;   // the CRC residue of a good body
  logic        cbad_end_q; // the length or a whole field is wrong for the type (cbad_end)
  logic [2:0]  code;      // 0 ACK, 1..5 NAK reason
  logic        answer, store, want_stat, do_reset, do_config, do_start, do_stop, do_resume, do_end, do_feed, ooo;
  logic        playing_q, halt_q, stop_q, end_q, ended_q;

  assign fend         = is_flag && !hunt_q && (idx_q != '0);
  assign good         = !bad_q && !esc_q && len_ok_q && crc_ok_q;
  assign diff         = seq_q - next_seq_q;
  assign playing_busy = playing_q || fifo_busy_i;
  always_comb begin
    case (type_q)
      TSegment: cbad_end = (len_q != 12'(RecBytes)) || kz_q;
      TConfig:  cbad_end = (len_q != 12'(CfgLen)) || !pulse_nz_q || (tick_nz_q && tick_lt_q)
                        || (ScaleWidth != 0
                            && (!m_nz_q ? (smax_nz_q || ovr_nz_q || shl_nz_q || auto_q)
                                        : (too_wide(m_wide_q) || too_wide(smax_wide_q) || too_wide(ovr_wide_q))));
      TFeed:    cbad_end = (len_q != 12'(FeedLen)) || too_wide(ovr_wide_q);
      default:  cbad_end = (len_q != '0);
    endcase
  end

  always_comb begin
    code = 3'd0; answer = 1'b0; store = 1'b0; want_stat = 1'b0; ooo = 1'b0;
    do_reset = 1'b0; do_config = 1'b0; do_start = 1'b0; do_stop = 1'b0; do_resume = 1'b0; do_end = 1'b0;
    do_feed = 1'b0;
    if (fend) begin
      answer = 1'b1;
      if (!good) code = 3'd1;
      else if (cbad_q || cbad_end_q) code = 3'd4;
      else begin
        case (type_q)
          TReset:   if (playing_busy) code = 3'd5; else do_reset = 1'b1;
          TConfig:  if (playing_busy) code = 3'd5; else do_config = 1'b1;
          TStart:   do_start = 1'b1;
          TStop:    do_stop = 1'b1;
          TResume:  do_resume = 1'b1;
          TFeed:    do_feed = 1'b1;
          TStatReq: begin answer = 1'b0; want_stat = 1'b1; end
          TSegment:
            if (seq_eq_q) begin
              if (wen_q) store = 1'b1; else code = 3'd3;
            end else if (!behind_q) begin
              code = 3'd2; ooo = 1'b1;
            end
          default:  // TEnd
            if (seq_eq_q) do_end = 1'b1; else begin code = 3'd2; ooo = 1'b1; end
        endcase
      end
    end
  end

  // The verdict acts one cycle after the flag (timing), from registers: the
  // body's registers it reads (seq, the CONFIG flags) hold, since the next
  // byte comes two cycles after the flag at the earliest.
  logic       v_answer_q, v_store_q, v_want_stat_q, v_ooo_q, v_bad_q, v_fend_q;
  logic       v_reset_q, v_config_q, v_start_q, v_stop_q, v_resume_q, v_end_q, v_feed_q;
  logic [2:0] v_code_q;
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      v_answer_q <= 1'b0; v_store_q <= 1'b0; v_want_stat_q <= 1'b0; v_ooo_q <= 1'b0;
      v_bad_q    <= 1'b0; v_fend_q  <= 1'b0; v_reset_q     <= 1'b0; v_config_q <= 1'b0;
      v_start_q  <= 1'b0; v_stop_q  <= 1'b0; v_resume_q    <= 1'b0; v_end_q    <= 1'b0;
      v_feed_q   <= 1'b0; v_code_q  <= '0;
    end else begin
      v_answer_q <= answer; v_store_q <= store; v_want_stat_q <= want_stat; v_ooo_q <= ooo;
      v_bad_q    <= fend && !good; v_fend_q <= fend; v_reset_q <= do_reset; v_config_q <= do_config;
      v_start_q  <= do_start; v_stop_q <= do_stop; v_resume_q <= do_resume; v_end_q <= do_end;
      v_feed_q   <= do_feed; v_code_q <= code;
    end
  end

  // -------------------------------------------------------------------
  // Receive state.
  // -------------------------------------------------------------------
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      hunt_q <= 1'b1;
      esc_q  <= 1'b0;
      idx_q  <= '0;
      wen_q  <= 1'b0;
    end else begin
      if (rxv_q) esc_q <= is_esc;
      if (is_flag) begin
        hunt_q <= 1'b0;
        idx_q  <= '0;
        wen_q  <= 1'b0;
      end else if (dv) begin
        if (idx_q != 12'hFFF) idx_q <= idx_q + 1'b1;
        if (idx_q == 12'd8)
          wen_q <= is_seg && !bad_q && (len_q == 12'(RecBytes)) && seq_eq_q && (fifo_credits_i != '0);
      end
    end
  end

  // Per-body flags and fields: set at the opening flag, so not reset.
  always_ff @(posedge clk_i) begin
    seq_eq_q <= (seq_q == next_seq_q);
    behind_q <= diff[31];
    len_ok_q <= (idx_q == len_q + 12'd12);
    crc_ok_q <= (crc_q == Residue);
    cbad_end_q <= cbad_end;
    if (is_flag) begin
      bad_q  <= 1'b0;
      cbad_q <= 1'b0;
      kz_q   <= 1'b1;
      crc_q  <= 32'hFFFFFFFF;
      wb_q   <= '0;
    end else begin
      if (rxe_q || (rxv_q && esc_q && !rxesc_ok_q)) bad_q <= 1'b1;
      if (dv) begin
        crc_q <= crc8(crc_q, d);
        if (overlong) bad_q <= 1'b1;
        case (idx_q)
          12'd0: begin type_q <= d; if (!known) bad_q <= 1'b1; end
          12'd1: if (d != 8'd0) bad_q <= 1'b1;
          12'd2: len_q[7:0] <= d;
          12'd3: begin
            len_q[11:8] <= d[3:0];
            if (d > 8'd8 || (d == 8'd8 && len_q[7:0] != 8'd0)) bad_q <= 1'b1;
          end
          12'd4, 12'd5, 12'd6, 12'd7: seq_q <= {d, seq_q[31:8]};
          default: ;
        endcase
        if (in_pay && cbad_byte) cbad_q <= 1'b1;
        if (in_pay && is_seg && pd_k_q && d != 8'd0) kz_q <= 1'b0;
        if (wbyte) begin
          asm_q <= asm_d[ChunkWidth-1:8];
          wb_q  <= wdone ? 4'd0 : wb_q + 1'b1;
        end
      end
    end
  end

  // -------------------------------------------------------------------
  // Link, playback and configuration state; counters.
  // -------------------------------------------------------------------
  logic [31:0]       cfg_tick_q, cfg_stat_q, stat_cnt_q;
  logic [Axes*6-1:0] cfg_shift_q;
  logic [15:0]       cfg_pulse_q, cfg_setup_q;
  logic              cfg_en_q;
  logic [31:0]       cfg_m_q, cfg_smax_q, cfg_ovr_q;
  logic [5:0]        cfg_shl_q;
  logic              cfg_auto_q, hold_q;
  logic [5:0]        cnt_ev;    // this clock's counter events: {bytes, ooo, bad, under, ticks, played}
  logic [31:0]       cnt_word;  // the counter word tx_w_q asks for (CountRam = 0)
  logic              cnt_wait;  // the answer side waits for a counter word (CountRam = 1)
  logic              cnt_ld;    // cnt_sum is that word: load it
  logic [31:0]       cnt_sum;
  logic              ans_pend_q, stat_pend_q, tick_d1_q, tick_d2_q;
  logic [2:0]        ans_code_q;
  logic              tx_take_ans, tx_take_stat, stat_due;

  // The shadow RAM (block RAM) and the copy. A good CONFIG's verdict copies
  // addresses 0..37, a good FEED's 40..44: each byte is read in one clock
  // (cp_rd_q) and applied in the next, shifted into stg_q; a field is written
  // whole at its last byte ({byte, stg_q} or, for the override, from stg_q at
  // the byte after it, with the shift or the hold). The copy reads address
  // a (or 40 + a) a + 2 clocks after the closing flag; the next frame's byte
  // for that address is at least its ninth after the flag, 2 (9 + a) clocks
  // at the earliest (bytes at most every other clock): no address is read
  // and written in the same clock. A copy (39 clocks at most) ends before the
  // next one starts: a FEED, the shortest frame that starts one, is 21 bytes.
  (* ram_style = "block", no_rw_check *) logic [7:0] sh_mem [0:63];
  logic        cp_act_q, cp_vld_q;
  logic [5:0]  cp_ra_q, cp_wa_q;  // the address read; the address of cp_rd_q
  logic [7:0]  cp_rd_q;
  logic [31:0] stg_q;
  logic [31:0] cp_word;           // the field ending with this byte
  always_ff @(posedge clk_i) begin
    if (sh_we) sh_mem[sh_wa] <= d;
    if (cp_act_q) cp_rd_q <= sh_mem[cp_ra_q];
  end
  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      cp_act_q <= 1'b0;
      cp_vld_q <= 1'b0;
    end else begin
      if (v_config_q || v_feed_q) begin
        cp_act_q <= 1'b1;
        cp_ra_q  <= v_feed_q ? 6'd40 : 6'd0;
      end else if (cp_act_q) begin
        cp_ra_q <= cp_ra_q + 1'b1;
        if (cp_ra_q == 6'd37 || cp_ra_q == 6'd44) cp_act_q <= 1'b0;
      end
      cp_vld_q <= cp_act_q;
    end
    cp_wa_q <= cp_ra_q;
    if (cp_vld_q) stg_q <= {cp_rd_q, stg_q[31:8]};
  end
  assign cp_word = {cp_rd_q, stg_q[31:8]};

  // Time scaling's configuration (CONFIG's and FEED's fields, FEED's hold).
  // Without a unit (ScaleWidth = 0) CONFIG refuses any nonzero time-scaling
  // byte and FEED is refused, so they stay 0: constants, and the flags that
  // would check them go unused.
  if (ScaleWidth != 0) begin : g_scale_cfg
    always_ff @(posedge clk_i) begin
      if (!rst_ni) begin
        cfg_m_q    <= '0;
        cfg_smax_q <= '0;
        cfg_ovr_q  <= '0;
        cfg_shl_q  <= '0;
        cfg_auto_q <= 1'b0;
        hold_q     <= 1'b0;
      end else if (cp_vld_q) begin
        case (cp_wa_q)
          6'd27: cfg_m_q    <= cp_word;
          6'd31: cfg_smax_q <= cp_word;
          6'd36: begin cfg_ovr_q <= stg_q; cfg_shl_q <= cp_rd_q[5:0]; end
          6'd37: cfg_auto_q <= cp_rd_q[0];
          6'd44: begin cfg_ovr_q <= stg_q; hold_q <= cp_rd_q[0]; end
          default: ;
        endcase
      end
    end
  end else begin : g_no_scale_cfg
    assign cfg_m_q    = '0;
    assign cfg_smax_q = '0;
    assign cfg_ovr_q  = '0;
    assign cfg_shl_q  = '0;
    assign cfg_auto_q = 1'b0;
    assign hold_q     = 1'b0;
    /* verilator lint_off UNUSEDSIGNAL */
    logic unused_sh;
    assign unused_sh = ^{m_nz_q, smax_nz_q, ovr_nz_q, shl_nz_q, auto_q, m_wide_q, smax_wide_q, ovr_wide_q,
                         stg_q[7:0]};
    /* verilator lint_on UNUSEDSIGNAL */
  end

  // stat_cnt_q: the tick of the period this one is (1 after CONFIG and after
  // each periodic STATUS; counted only while the period is not 0); the
  // STATUS is due at the tick that reaches the period: an incrementer and a
  // compare of two registers, with the loads of 1 a flop's set/reset (a
  // countdown needs a multiplexer per bit to load the period)
  assign stat_due = tick_i && (cfg_stat_q != '0) && (stat_cnt_q == cfg_stat_q);

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      next_seq_q  <= '0;
      playing_q   <= 1'b0;
      halt_q      <= 1'b0;
      stop_q      <= 1'b0;
      end_q       <= 1'b0;
      ended_q     <= 1'b0;
      cfg_tick_q  <= '0;
      cfg_stat_q  <= '0;
      cfg_shift_q <= '0;
      cfg_pulse_q <= 16'd1;
      cfg_setup_q <= '0;
      cfg_en_q    <= 1'b0;
      stat_cnt_q  <= '0;
      ans_pend_q  <= 1'b0;
      ans_code_q  <= '0;
      stat_pend_q <= 1'b0;
      tick_d1_q   <= 1'b0;
      tick_d2_q   <= 1'b0;
    end else begin
      tick_d1_q <= eng_tick_i;
      tick_d2_q <= tick_d1_q;
      // verdicts
      if (v_store_q) next_seq_q <= next_seq_q + 1'b1;
      if (v_reset_q) begin
        next_seq_q <= seq_q;
        halt_q     <= 1'b0;
        stop_q     <= 1'b0;
        end_q      <= 1'b0;
        ended_q    <= 1'b0;
      end
      // CONFIG's fields, from the copy
      if (cp_vld_q) begin
        if (cp_wa_q == 6'd3) cfg_tick_q <= cp_word;
        if (cp_wa_q == 6'd7) cfg_stat_q <= cp_word;
        for (int a = 0; a < Axes; a++)
          if (cp_wa_q == 6'(8 + a)) cfg_shift_q[a*6 +: 6] <= cp_rd_q[5:0];
        if (cp_wa_q == 6'd17) cfg_pulse_q <= cp_word[31:16];
        if (cp_wa_q == 6'd19) cfg_setup_q <= cp_word[31:16];
        if (cp_wa_q == 6'd20) cfg_en_q <= cp_rd_q[0];
      end
      if (v_start_q && !halt_q) begin
        playing_q <= 1'b1;
        stop_q    <= 1'b0;
        ended_q   <= 1'b0;
      end
      if (v_stop_q) stop_q <= playing_q;
      if (v_resume_q && halt_q) begin
        halt_q    <= 1'b0;
        playing_q <= 1'b1;
      end
      if (v_end_q) end_q <= 1'b1;
      // playback: an engine tick found no segment
      if (underrun_i && playing_q) begin
        playing_q <= 1'b0;
        stop_q    <= 1'b0;
        if (stop_q) begin
          // STOP reached the end of the current segment
        end else if (end_q && fifo_level_i == '0 && !fifo_busy_i) begin
          ended_q <= 1'b1;
        end else begin
          halt_q    <= 1'b1;  // an underrun: counted (cnt_ev)
        end
      end
      // status period in ticks
      if ((cp_vld_q && cp_wa_q == 6'd7) || stat_due) stat_cnt_q <= 32'd1;
      else if (tick_i && cfg_stat_q != '0) stat_cnt_q <= stat_cnt_q + 1'b1;
      // answers
      ans_pend_q  <= v_answer_q || (ans_pend_q && !tx_take_ans);
      if (v_answer_q) ans_code_q <= v_code_q;
      stat_pend_q <= v_want_stat_q || stat_due || (stat_pend_q && !tx_take_stat);
    end
  end

  // -------------------------------------------------------------------
  // Answer side: frame builder, word by word, byte-stuffed.
  // -------------------------------------------------------------------
  localparam logic [1:0] SIdle = 2'd0, SOpen = 2'd1, SBody = 2'd2, SClose = 2'd3;
  logic [1:0]  tx_state_q;
  logic        tx_stat_q;   // the frame is a STATUS (else ACK/NAK)
  logic [2:0]  tx_code_q;   // ACK/NAK code of the frame
  logic [7:0]  tx_idx_q;    // body byte
  logic        tx_esc_q;    // the escape byte 0x7D was sent; the XORed byte follows
  logic [31:0] tx_crc_q, tx_word_q;
  logic [Axes*OutWidth-1:0] snap_q;  // the samples as the frame started (STATUS words 14..)

  logic [5:0]  tx_w_q;      // the body word loaded next
  logic        tx_crcld_q;  // the CRC word is loaded this cycle (from tx_crc_q, off the byte path)
  logic       tx_hs, tx_first, tx_need_esc, tx_adv, tx_last_byte, tx_load, tx_crc_next;
  logic [7:0] tx_cur;
  logic [31:0] tx_crc_d, word_next;

  assign tx_take_ans  = (tx_state_q == SIdle) && ans_pend_q;
  assign tx_take_stat = (tx_state_q == SIdle) && !ans_pend_q && stat_pend_q;
  assign tx_hs        = tx_tvalid_o && tx_tready_i;
  assign tx_cur       = tx_word_q[8*tx_idx_q[1:0] +: 8];
  assign tx_need_esc  = (tx_cur == 8'h7E) || (tx_cur == 8'h7D);
  assign tx_adv       = tx_hs && (tx_state_q == SBody) && (tx_esc_q || !tx_need_esc);
  assign tx_crc_d     = crc8(tx_crc_q, tx_cur);
  assign tx_first     = tx_hs && (tx_state_q == SOpen);
  // a word is loaded after the opening flag and after each word's last byte
  assign tx_load      = tx_first || (tx_adv && tx_idx_q[1:0] == 2'd3);
  assign tx_crc_next  = tx_w_q == (tx_stat_q ? 6'(CrcWordS) : 6'(CrcWordA));
  assign tx_last_byte = tx_idx_q == (tx_stat_q ? 8'(4 * CrcWordS + 3) : 8'(4 * CrcWordA + 3));

  // the body word tx_w_next of the frame being sent
  logic [Axes*32-1:0] samp_lo, samp_hi;  // sample a sign-extended to 64 bits, halves
  for (genvar a = 0; a < Axes; a++) begin : g_samp
    logic [63:0] s64;
    if (OutWidth < 64) begin : g_ext
      assign s64 = {{(64-OutWidth){snap_q[a*OutWidth+OutWidth-1]}}, snap_q[a*OutWidth +: OutWidth]};
    end else begin : g_full
      assign s64 = snap_q[a*OutWidth +: 64];
    end
    assign samp_lo[a*32 +: 32] = s64[31:0];
    assign samp_hi[a*32 +: 32] = s64[63:32];
  end
  logic [7:0] flags;
  assign flags = {held_i, starved_i, fifo_level_i == '0, cfg_en_q, tick_err_i, ended_q, halt_q, playing_q};
  always_comb begin
    word_next = '0;
    if (tx_w_q == 6'd0) begin
      word_next = tx_stat_q ? {16'(StatLen), 8'h00, TStatus}
                            : {16'd4, 8'h00, (tx_code_q == '0) ? TAck : TNak};
    end else if (tx_w_q == 6'd1) begin
      word_next = next_seq_q;
    end else if (!tx_stat_q) begin
      word_next = (tx_code_q == '0) ? {16'h0, fifo_credits_i} : {fifo_credits_i, 8'h00, 5'h0, tx_code_q};
    end else begin
      case (tx_w_q)
        6'd2:  word_next = {fifo_level_i, flags, 8'(Axes)};
        6'd3, 6'd4, 6'd5, 6'd6, 6'd7, 6'd8: word_next = cnt_word;
        6'd9:  word_next = {16'h0, fifo_credits_i};
        6'd10: word_next = 32'(ClkHz);
        6'd11: word_next = scale_s_i;
        6'd12: word_next = {16'h0, starved_count_i};
        6'd13: word_next = ahead_i;
        default: begin
          for (int a = 0; a < Axes; a++) begin
            if (tx_w_q == 6'(14 + 2 * a)) word_next = samp_lo[a*32 +: 32];
            if (tx_w_q == 6'(15 + 2 * a)) word_next = samp_hi[a*32 +: 32];
          end
        end
      endcase
    end
  end

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      tx_state_q <= SIdle;
      tx_crcld_q <= 1'b0;
    end else begin
      tx_crcld_q <= tx_load && tx_crc_next;
      case (tx_state_q)
        SIdle:  if (tx_take_ans || tx_take_stat) tx_state_q <= SOpen;
        SOpen:  if (tx_hs) tx_state_q <= SBody;
        SBody:  if (tx_adv && tx_last_byte) tx_state_q <= SClose;
        default: if (tx_hs) tx_state_q <= SIdle;
      endcase
    end
  end

  // The snapshot of the samples, taken while no frame is sent. In block RAM
  // it reads the last idle clock's samples one clock after the frame starts
  // (traj_hold_ram), long before the first sample word (word 14) is loaded.
  if (SnapRam != 0) begin : g_snap_ram
    traj_hold_ram #(.Width(Axes * OutWidth)) u_snap (
      .clk_i, .we_i(tx_state_q == SIdle), .data_i(sample_i), .data_o(snap_q)
    );
  end else begin : g_snap_flops
    always_ff @(posedge clk_i) begin
      if (tx_state_q == SIdle) snap_q <= sample_i;
    end
  end

  // Frame datapath: loaded when a frame starts, so not reset.
  always_ff @(posedge clk_i) begin
    if (tx_state_q == SIdle) begin
      tx_stat_q <= !ans_pend_q;
      tx_code_q <= ans_code_q;
      tx_idx_q  <= '0;
      tx_esc_q  <= 1'b0;
      tx_crc_q  <= 32'hFFFFFFFF;
      tx_w_q    <= '0;
    end
    if (tx_load && !tx_crc_next) tx_word_q <= word_next;
    if (cnt_ld) tx_word_q <= cnt_sum;
    if (tx_load) tx_w_q <= tx_w_q + 1'b1;
    if (tx_crcld_q) tx_word_q <= ~tx_crc_q;
    if (tx_hs && tx_state_q == SBody) begin
      if (tx_adv) begin
        tx_esc_q <= 1'b0;
        tx_crc_q <= tx_crc_d;
        tx_idx_q <= tx_idx_q + 1'b1;
      end else begin
        tx_esc_q <= 1'b1;
      end
    end
  end

  // -------------------------------------------------------------------
  // STATUS counters (words 3..8): played, ticks, underruns, bad frames,
  // out-of-order frames, bytes.
  // -------------------------------------------------------------------
  assign cnt_ev = {rxv_q, v_ooo_q, v_bad_q,
                   underrun_i && playing_q && !stop_q && !(end_q && fifo_level_i == '0 && !fifo_busy_i),
                   tick_i && playing_q && !halt_q, seg_start_i};
  if (CountRam == 0) begin : g_cnt_flops
    logic [31:0] n_played_q, n_ticks_q, n_under_q, n_bad_q, n_ooo_q, n_bytes_q;
    always_ff @(posedge clk_i) begin
      if (!rst_ni) begin
        n_played_q <= '0;
        n_ticks_q  <= '0;
        n_under_q  <= '0;
        n_bad_q    <= '0;
        n_ooo_q    <= '0;
        n_bytes_q  <= '0;
      end else begin
        if (cnt_ev[0]) n_played_q <= n_played_q + 1'b1;
        if (cnt_ev[1]) n_ticks_q  <= n_ticks_q + 1'b1;
        if (cnt_ev[2]) n_under_q  <= n_under_q + 1'b1;
        if (cnt_ev[3]) n_bad_q    <= n_bad_q + 1'b1;
        if (cnt_ev[4]) n_ooo_q    <= n_ooo_q + 1'b1;
        if (cnt_ev[5]) n_bytes_q  <= n_bytes_q + 1'b1;
      end
    end
    always_comb begin
      case (tx_w_q)
        6'd4:    cnt_word = n_ticks_q;
        6'd5:    cnt_word = n_under_q;
        6'd6:    cnt_word = n_bad_q;
        6'd7:    cnt_word = n_ooo_q;
        6'd8:    cnt_word = n_bytes_q;
        default: cnt_word = n_played_q;
      endcase
    end
    assign cnt_wait = 1'b0;
    assign cnt_ld   = 1'b0;
    assign cnt_sum  = '0;
  end else begin : g_cnt_ram
    // in block RAM, one adder for all (traj_status_count): a counter's word
    // waits (tvalid low) for the counter's next write, 1 to 6 clocks
    traj_status_count #(.N(6)) u_count (
      .clk_i, .rst_ni, .ev_i(cnt_ev),
      .want_i(tx_load && tx_stat_q && tx_w_q >= 6'd3 && tx_w_q <= 6'd8), .k_i(3'(tx_w_q - 6'd3)),
      .wait_o(cnt_wait), .ld_o(cnt_ld), .sum_o(cnt_sum)
    );
    assign cnt_word = '0;
  end

  always_comb begin
    case (tx_state_q)
      SBody:   tx_tdata_o = tx_esc_q ? (tx_cur ^ 8'h20) : (tx_need_esc ? 8'h7D : tx_cur);
      default: tx_tdata_o = 8'h7E;
    endcase
  end
  assign tx_tvalid_o = (tx_state_q != SIdle) && !tx_crcld_q && !cnt_wait;

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Formal properties of the framing (scripts/formal.sh, rtl.formal.*):
  // a FIFO commit comes only from a good SEGMENT frame whose seq is next_seq
  // and whose words all went to the FIFO (exactly SegWords of them), and it
  // advances next_seq by one; next_seq moves only so or by RESET. So the
  // stored-segment count equals the ACKed records, none is stored twice or
  // skipped, and nothing of a bad frame is committed (the FIFO rolls back
  // every other verdict: traj_seg_fifo's properties).
  // ---------------------------------------------------------------------
  localparam int SegWords = ((ChunkWidth < 32) ? 32 / ChunkWidth : 1) + RegBytes / ChunkB;
  logic        f_past_valid = 1'b0;
  logic [11:0] f_wr;        // FIFO words written since the last flag
  logic        f_dv_q;      // a body byte was taken in the previous cycle
  logic        f_rx_q;      // a byte (or flag) was handled in the previous cycle, or reset
  logic        f_in_q;      // rx_valid_i in the previous cycle
  logic [31:0] f_seq0;      // next_seq after the last reset or RESET
  logic [31:0] f_ns_q;      // next_seq in the previous cycle (seq_eq_q follows a change a cycle later)
  logic [31:0] f_stores;    // commits since then
  always_ff @(posedge clk_i) begin
    f_past_valid <= 1'b1;
    f_dv_q <= dv;
    f_rx_q <= rxv_q || !rst_ni;
    f_in_q <= rx_valid_i;
    f_ns_q <= next_seq_q;
    if (is_flag) f_wr <= '0;
    else if (fifo_wr_o) f_wr <= f_wr + 1'b1;
    if (!rst_ni) begin
      f_seq0   <= '0;
      f_stores <= '0;
    end else if (v_reset_q) begin
      f_seq0   <= seq_q;
      f_stores <= '0;
    end else if (fifo_commit_o) begin
      f_stores <= f_stores + 1'b1;
    end
  end
  // the UART gives at most one byte every other cycle
  always_comb begin
    if (!f_past_valid) assume (!rst_ni);
    if (f_past_valid && f_in_q) assume (!rx_valid_i);
  end
  // words a writing frame has produced after idx_q body bytes
  int f_p, f_bytes;
  assign f_p     = 32'(idx_q) - 8;
  assign f_bytes = ((f_p > 8) ? 4 : (f_p > 4) ? f_p - 4 : 0)
                 + ((f_p > RecBytes - 4) ? RegBytes : (f_p > 12) ? f_p - 12 : 0);
  always_ff @(posedge clk_i) begin
    if (f_past_valid && rst_ni) begin
      // the registered comparisons describe the body when no byte came last cycle
      if (!f_rx_q) begin
        assert (len_ok_q == (idx_q == len_q + 12'd12));
        assert (cbad_end_q == cbad_end);
        if (next_seq_q == f_ns_q) assert (seq_eq_q == (seq_q == next_seq_q));
        assert (pd_pay_q == ((idx_q >= 12'd8) && (p < len_q)));
        assert (pd_k_q == ((p >= 12'd4) && (p < 12'd8)));
        assert (pd_reg_q == ((p >= 12'd12) && (p < 12'(RecBytes - 4))));
      end
      if (!hunt_q && idx_q == '0) assert (f_wr == '0 && wb_q == '0 && !wen_q);
      assert (32'(idx_q) <= 4095);
      // words written so far: all K and register bytes of a writing frame
      if (!hunt_q && ChunkWidth <= 32) begin
        assert (f_wr == (wen_q ? 12'(f_bytes >> $clog2(ChunkB)) : 12'd0));
        if (wen_q) assert (32'(wb_q) == (f_bytes & (ChunkB - 1)));
      end
      if (wen_q) assert (is_seg && len_q == 12'(RecBytes) && 32'(idx_q) > 8);
      // a store: a good SEGMENT, seq == next_seq, all its words written
      if (store) begin
        assert (fend && good && is_seg && seq_eq_q && wen_q);
        if (ChunkWidth <= 32) assert (f_wr == 12'(SegWords));
      end
      if (fifo_commit_o) assert (!fifo_rollback_o && !fifo_clear_o);
      if (fifo_commit_o || fifo_rollback_o || fifo_clear_o) assert (!fifo_wr_o);
      // the count of stored records since the last RESET is next_seq's advance
      assert (next_seq_q == f_seq0 + f_stores);
    end
    if (f_past_valid && rst_ni && $past(rst_ni)) begin
      // the FIFO commits exactly the stores, one cycle later
      assert (fifo_commit_o == $past(store));
      if ($past(fifo_commit_o)) assert (next_seq_q == $past(next_seq_q) + 1);
      else if (!$past(fifo_clear_o)) assert (next_seq_q == $past(next_seq_q));
    end
    // reachability (scripts/formal.sh's cover run): a bound that reaches a
    // commit has checked the properties above through a whole good SEGMENT
    // frame, one that reaches a second commit through the frame after it
    if (f_past_valid && rst_ni) cover (fifo_commit_o);
    if (f_past_valid && rst_ni) cover (fifo_commit_o && f_stores == 32'd1);
  end
`endif

  // -------------------------------------------------------------------
  // Outputs.
  // -------------------------------------------------------------------
  assign fifo_wr_o       = wbyte && wdone && wen_q;
  assign fifo_wr_data_o  = wword;
  assign fifo_commit_o   = v_store_q;
  assign fifo_rollback_o = v_fend_q && !v_store_q;
  assign fifo_clear_o    = v_reset_q;
  // with time scaling STOP is a hold: the engine keeps its data while it stops
  assign release_o       = playing_q && !halt_q && (!stop_q || cfg_m_q != '0)
                        && !eng_tick_i && !tick_d1_q && !tick_d2_q && !underrun_i;
  assign run_o           = playing_q && !halt_q;
  assign tick_period_o   = cfg_tick_q;
  assign step_shift_o    = cfg_shift_q;
  assign pulse_o         = cfg_pulse_q;
  assign setup_o         = cfg_setup_q;
  assign enable_o        = cfg_en_q;
  assign scale_m_o        = cfg_m_q;
  assign scale_s_max_o    = cfg_smax_q;
  assign scale_override_o = cfg_ovr_q;
  assign scale_shift_o    = cfg_shl_q;
  assign scale_auto_o     = cfg_auto_q;
  assign hold_o           = hold_q;
  assign stop_o           = stop_q;
  assign end_o            = end_q;
  assign resume_o         = v_resume_q;
  assign stored_k_o       = sh_k_q;

endmodule

`default_nettype wire
