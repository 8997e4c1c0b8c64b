// trajcore: narrow-pin wrapper of traj_bcu_gen for iCE40 synthesis and
// place-and-route measurements (same pin-out as traj_fd_synth_top).
//
// The generator's segment stream is ChunkWidth bits wide and its sample bus is
// Axes*OutWidth bits: more pins than an SG48 package has. This wrapper
//   * assembles stream words from bytes (byte_valid_i/byte_i, LS byte first;
//     byte_ready_o is back-pressure),
//   * registers the servo strobe and the reset,
//   * XOR-folds every sample bit into an 8-bit register so that no generator
//     output can be optimised away, and registers the status flags.
// Everything is registered at the pins, so the measured Fmax is the core's.
`default_nettype none
`include "traj_check.svh"

module traj_bcu_synth_top #(
  parameter int Axes       = 3,   // axes in lockstep
  parameter int ChunkWidth = 16,  // stream word width, multiple of 8
  parameter int CtrlWidth  = 40,  // control value width
  parameter int GuardBits  = 9,   // control bits below the output LSB
  parameter int OutWidth   = 32,  // sample width
  parameter int MaxDepth   = 12   // largest depth (K = 4096)
) (
  input  logic       clk_i,
  input  logic       rst_ni,
  input  logic [7:0] byte_i,
  input  logic       byte_valid_i,
  output logic       byte_ready_o,
  input  logic       tick_i,
  output logic [7:0] fold_o,
  output logic       sample_valid_o,
  output logic       underrun_o,
  output logic       seg_done_o,
  output logic       tick_err_o
);
  localparam int BytesPerWord = ChunkWidth / 8;
  localparam int NbBits       = $clog2(BytesPerWord + 1);

  `TRAJ_PARAM_CHECK(g_bad_chunk8, ChunkWidth % 8 == 0,
                    "traj_bcu_synth_top: ChunkWidth must be a multiple of 8")

  logic                     rst_nq, tick_q, byte_valid_q;
  logic [7:0]               byte_q;
  logic [ChunkWidth-1:0]    word_q;
  logic [NbBits-1:0]        nbytes_q;
  logic                     word_valid, word_ready;
  logic                     sample_valid, underrun, seg_done, tick_err;
  logic [Axes*OutWidth-1:0] sample;
  logic [7:0]               fold_q, fold_d;
  logic                     sample_valid_q, underrun_q, seg_done_q, tick_err_q;

  // Byte -> word assembly. tvalid is a flop (set when a word is complete,
  // cleared by the handshake), so the engine's tready reaches nothing but that
  // flop. byte_ready_o also covers the byte already in byte_q: a byte taken at
  // the pins is never dropped (the last byte of a word closes the port until
  // the word is handed over).
  logic word_valid_q, last_in_flight;
  assign word_valid     = word_valid_q;
  assign last_in_flight = byte_valid_q && (nbytes_q == NbBits'(BytesPerWord - 1));
  assign byte_ready_o   = !word_valid_q && !last_in_flight;

  always_ff @(posedge clk_i) begin
    rst_nq       <= rst_ni;
    tick_q       <= tick_i;
    byte_q       <= byte_i;
    byte_valid_q <= byte_valid_i && byte_ready_o;
    if (!rst_nq) begin
      nbytes_q     <= '0;
      word_valid_q <= 1'b0;
      byte_valid_q <= 1'b0;
    end else if (word_valid_q) begin
      if (word_ready) word_valid_q <= 1'b0;
    end else if (byte_valid_q) begin
      word_q      <= {byte_q, word_q[ChunkWidth-1:8]};
      if (nbytes_q == NbBits'(BytesPerWord - 1)) begin
        nbytes_q     <= '0;
        word_valid_q <= 1'b1;
      end else begin
        nbytes_q <= nbytes_q + 1'b1;
      end
    end
  end

  traj_bcu_gen #(
    .Axes(Axes), .ChunkWidth(ChunkWidth), .CtrlWidth(CtrlWidth), .GuardBits(GuardBits),
    .OutWidth(OutWidth), .MaxDepth(MaxDepth)
  ) u_gen (
    .clk_i, .rst_ni(rst_nq),
    .s_axis_tdata(word_q), .s_axis_tvalid(word_valid), .s_axis_tready(word_ready),
    .tick_i(tick_q),
    .sample_valid_o(sample_valid), .sample_o(sample),
    .underrun_o(underrun), .seg_done_o(seg_done), .tick_err_o(tick_err)
  );

  // XOR-fold the sample bus into 8 bits.
  always_comb begin
    fold_d = fold_q;
    for (int b = 0; b < Axes * OutWidth; b++) fold_d[b % 8] = fold_d[b % 8] ^ sample[b];
  end

  always_ff @(posedge clk_i) begin
    if (sample_valid) fold_q <= fold_d;
    sample_valid_q <= sample_valid;
    underrun_q     <= underrun;
    seg_done_q     <= seg_done;
    tick_err_q     <= tick_err;
  end

  assign fold_o         = fold_q;
  assign sample_valid_o = sample_valid_q;
  assign underrun_o     = underrun_q;
  assign seg_done_o     = seg_done_q;
  assign tick_err_o     = tick_err_q;
endmodule

`default_nettype wire
