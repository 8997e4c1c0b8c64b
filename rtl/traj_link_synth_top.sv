// trajcore: synthesis wrapper of traj_link for scripts/synth.sh (place and
// route figures with few pins): the engine-side buses are folded onto single
// pins and the sample bus is a shift register fed from one pin, so nothing is
// optimised away and every input and output is registered.
`default_nettype none

module traj_link_synth_top #(
  parameter int ClkHz         = 48_000_000,
  parameter int Baud          = 1_000_000,
  parameter int Axes          = 3,
  parameter int Degree        = 3,
  parameter int Width         = 64,
  parameter int ChunkWidth    = 16,
  parameter int GuardBits     = 32,
  parameter int FifoDepth     = 4096,
  parameter int MinTickPeriod = 256
) (
  input  logic clk_i,
  input  logic rst_ni,
  input  logic rx_i,
  output logic tx_o,
  input  logic tready_i,
  input  logic tick_i,
  input  logic seg_start_i,
  input  logic underrun_i,
  input  logic tick_err_i,
  input  logic sample_bit_i,
  output logic tdata_o,   // XOR of the word
  output logic tvalid_o,
  output logic run_o,
  output logic cfg_o      // XOR of the configuration outputs
);

  localparam int OutWidth = Width - GuardBits;

  logic rst_nq, rx_q, tready_q, tick_q, seg_start_q, underrun_q, tick_err_q;
  logic [Axes*OutWidth-1:0] sample_q;
  logic [ChunkWidth-1:0] tdata;
  logic tvalid, run, enable, tx;
  logic [31:0] tick_period;
  logic [Axes*6-1:0] step_shift;
  logic [15:0] pulse, setup;

  always_ff @(posedge clk_i) begin
    rst_nq      <= rst_ni;
    rx_q        <= rx_i;
    tready_q    <= tready_i;
    tick_q      <= tick_i;
    seg_start_q <= seg_start_i;
    underrun_q  <= underrun_i;
    tick_err_q  <= tick_err_i;
    sample_q    <= {sample_q[Axes*OutWidth-2:0], sample_bit_i};
    tdata_o     <= ^tdata;
    tvalid_o    <= tvalid;
    run_o       <= run;
    tx_o        <= tx;
    cfg_o       <= ^{tick_period, step_shift, pulse, setup, enable};
  end

  traj_link #(
    .ClkHz(ClkHz), .Baud(Baud), .Axes(Axes), .Degree(Degree), .Width(Width), .ChunkWidth(ChunkWidth),
    .GuardBits(GuardBits), .FifoDepth(FifoDepth), .MinTickPeriod(MinTickPeriod)
  ) u_link (
    .clk_i, .rst_ni(rst_nq), .rx_i(rx_q), .tx_o(tx),
    .m_axis_tdata(tdata), .m_axis_tvalid(tvalid), .m_axis_tready(tready_q),
    .tick_i(tick_q), .seg_start_i(seg_start_q), .underrun_i(underrun_q), .tick_err_i(tick_err_q),
    .sample_i(sample_q), .run_o(run), .tick_period_o(tick_period), .step_shift_o(step_shift),
    .pulse_o(pulse), .setup_o(setup), .enable_o(enable)
  );

endmodule

`default_nettype wire
