// SPDX-License-Identifier: Apache-2.0
// trajcore: narrow-pin wrapper of the time-scale unit behind the
// time-multiplexed FD engine (traj_fd_tm -> traj_time_scale, the unit reading
// the samples through the engine's sample RAM port), for iCE40 synthesis and
// place-and-route measurements of the pair a board would carry. Stream words from bytes (traj_byte_words), the configuration
// (m, s_max, override, shift, hold, auto_resume, end, avail) from a serial
// shift register (cfg_i, cfg_en_i: so that none of it is a constant), the
// servo strobe and the reset registered, the output samples XOR-folded into
// 8 pins with the status registered (traj_sample_fold).
`default_nettype none
`include "traj_check.svh"

module traj_time_scale_synth_top #(
  parameter int Axes       = 3,
  parameter int Degree     = 5,
  parameter int Width      = 96,
  parameter int ChunkWidth = 16,
  parameter int GuardBits  = 48,
  parameter int SW         = 16
) (
  input  logic       clk_i,
  input  logic       rst_ni,
  input  logic [7:0] byte_i,
  input  logic       byte_valid_i,
  output logic       byte_ready_o,
  input  logic       tick_i,
  input  logic       cfg_i,
  input  logic       cfg_en_i,
  output logic [7:0] fold_o,
  output logic       sample_valid_o,
  output logic       underrun_o,
  output logic       seg_done_o,
  output logic       tick_err_o
);
  localparam int OutWidth = Width - GuardBits;
  localparam int CfgW     = 3 * SW + 6 + 3 + 32;
  localparam int AxB      = $clog2(Axes);
  localparam int ChB      = $clog2(Width / ChunkWidth);
  localparam int WB       = $clog2(OutWidth / ChunkWidth);
  localparam int TsAddrW  = (AxB + WB > 0) ? AxB + WB : 1;

  `TRAJ_PARAM_CHECK(g_bad_guard, GuardBits % ChunkWidth == 0,
                    "traj_time_scale_synth_top: GuardBits must be a multiple of ChunkWidth (the unit reads whole words)")

  logic                     rst_nq, tick_q;
  logic [CfgW-1:0]          cfg_q;
  logic [ChunkWidth-1:0]    word;
  logic                     word_valid, word_ready;
  logic                     eng_tick, eng_valid, underrun, seg_done, eng_err;
  logic [Axes*OutWidth-1:0] sample;
  logic                     sample_valid, ts_err;
  logic [ChunkWidth-1:0]    sample_word;
  logic [TsAddrW-1:0]       ts_addr;
  /* verilator lint_off UNUSEDSIGNAL */
  logic                     word_user;
  logic [Axes*OutWidth-1:0] eng_sample;  // read through the sample RAM port instead
  logic [Axes*OutWidth-1:0] eng_we, eng_wd;
  logic                     out_shift, out_bit;  // (the unit's own sample flops)
  logic [SW-1:0]            s;
  logic                     starved, busy;
  logic [15:0]              starved_count;
  /* verilator lint_on UNUSEDSIGNAL */
  localparam int SaW = (AxB + ChB > 0) ? AxB + ChB : 1;
  logic [SaW-1:0]           sample_addr;
  // the unit's word {axis, w}: chunk GuardBits/ChunkWidth + w of the axis
  logic [31:0]              ax, w;
  assign ax          = (AxB > 0) ? 32'(ts_addr) >> WB : 32'd0;
  assign w           = (WB > 0) ? 32'(ts_addr) & ((32'd1 << WB) - 32'd1) : 32'd0;
  assign sample_addr = SaW'((ax << ChB) | (32'(GuardBits / ChunkWidth) + w));

  always_ff @(posedge clk_i) begin
    rst_nq <= rst_ni;
    tick_q <= tick_i;
    if (cfg_en_i) cfg_q <= {cfg_q[CfgW-2:0], cfg_i};
  end

  traj_byte_words #(.WordWidth(ChunkWidth), .UserWidth(1)) u_bytes (
    .clk_i, .rst_ni(rst_nq),
    .byte_i, .user_i(1'b0), .byte_valid_i, .byte_ready_o,
    .m_axis_tdata(word), .m_axis_tuser(word_user), .m_axis_tvalid(word_valid),
    .m_axis_tready(word_ready)
  );

  traj_fd_tm #(
    .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth), .GuardBits(GuardBits)
  ) u_engine (
    .clk_i, .rst_ni(rst_nq),
    .s_axis_tdata(word), .s_axis_tvalid(word_valid), .s_axis_tready(word_ready),
    .tick_i(eng_tick),
    .sample_valid_o(eng_valid), .sample_o(eng_sample), .sample_we_o(eng_we), .sample_wd_o(eng_wd),
    .sample_addr_i(sample_addr), .sample_word_o(sample_word),
    .underrun_o(underrun), .seg_done_o(seg_done), .tick_err_o(eng_err)
  );

  traj_time_scale #(.Axes(Axes), .OutWidth(OutWidth), .SW(SW), .WordWidth(ChunkWidth)) u_scale (
    .clk_i, .rst_ni(rst_nq), .tick_i(tick_q),
    .m_i(cfg_q[0 +: SW]), .s_max_i(cfg_q[SW +: SW]), .override_i(cfg_q[2*SW +: SW]),
    .shift_i(cfg_q[3*SW +: 6]), .hold_i(cfg_q[3*SW+6]), .auto_resume_i(cfg_q[3*SW+7]),
    .end_i(cfg_q[3*SW+8]), .avail_i(cfg_q[3*SW+9 +: 32]),
    .eng_tick_o(eng_tick), .eng_valid_i(eng_valid), .eng_addr_o(ts_addr), .eng_word_i(sample_word),
    .sample_valid_o(sample_valid), .sample_o(sample), .out_shift_o(out_shift), .out_bit_o(out_bit),
    .s_o(s), .starved_o(starved),
    .starved_count_o(starved_count), .busy_o(busy), .err_o(ts_err)
  );

  traj_sample_fold #(.SampleWidth(Axes * OutWidth)) u_fold (
    .clk_i,
    .sample_valid_i(sample_valid), .sample_i(sample),
    .underrun_i(underrun), .seg_done_i(seg_done), .tick_err_i(eng_err || ts_err),
    .fold_o, .sample_valid_o, .underrun_o, .seg_done_o, .tick_err_o
  );
endmodule

`default_nettype wire
