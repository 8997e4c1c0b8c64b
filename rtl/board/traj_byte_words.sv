// SPDX-License-Identifier: Apache-2.0
// trajcore: byte-to-word assembler at a board wrapper's pins: a registered
// byte port (byte_valid_i/byte_i, least significant byte first; byte_ready_o
// is back-pressure) in, an AXI4-Stream word out.
//
//   * Every pin is registered here, so nothing reaches the word consumer
//     combinationally from a pin.
//   * m_axis_tvalid is a flop: set when a word is complete, cleared by the
//     handshake, so the consumer's tready reaches nothing but that flop.
//   * byte_ready_o also covers the byte already in the pin register: a byte
//     taken at the pins is never dropped (the last byte of a word closes the
//     port until the word is handed over).
//   * user_i is side-band data (e.g. a segment kind) taken with every byte;
//     a word carries the user bits of its last byte. Tie it to '0 if unused:
//     synthesis then removes its flops.
// Control state (byte count, valid bits) is reset, the data registers are not.
`default_nettype none
`include "traj_check.svh"

module traj_byte_words #(
  parameter int WordWidth = 16,  // word width, a multiple of 8
  parameter int UserWidth = 1    // side-band bits per byte, >= 1
) (
  input  logic                 clk_i,
  input  logic                 rst_ni,        // synchronous
  input  logic [7:0]           byte_i,
  input  logic [UserWidth-1:0] user_i,
  input  logic                 byte_valid_i,
  output logic                 byte_ready_o,
  output logic [WordWidth-1:0] m_axis_tdata,
  output logic [UserWidth-1:0] m_axis_tuser,
  output logic                 m_axis_tvalid,
  input  logic                 m_axis_tready
);
  localparam int BytesPerWord = WordWidth / 8;
  // the byte count runs 0..BytesPerWord-1
  localparam int CountBits    = (BytesPerWord > 1) ? $clog2(BytesPerWord) : 1;
  localparam logic [CountBits-1:0] LastByte = CountBits'(BytesPerWord - 1);

  `TRAJ_PARAM_CHECK(g_bad_word, WordWidth >= 8 && WordWidth % 8 == 0,
                    "traj_byte_words: WordWidth must be a positive multiple of 8")
  `TRAJ_PARAM_CHECK(g_bad_user, UserWidth >= 1, "traj_byte_words: UserWidth must be >= 1")

  logic                 byte_valid_q, word_valid_q, last_in_flight;
  logic [7:0]           byte_q;
  logic [UserWidth-1:0] user_q, word_user_q;
  logic [WordWidth-1:0] word_q, word_d;
  logic [CountBits-1:0] nbytes_q;

  // the new byte enters at the top, earlier bytes move down
  if (BytesPerWord > 1) begin : g_shift
    assign word_d = {byte_q, word_q[WordWidth-1:8]};
  end else begin : g_one_byte
    assign word_d = byte_q;
  end

  assign last_in_flight = byte_valid_q && (nbytes_q == LastByte);
  assign byte_ready_o   = !word_valid_q && !last_in_flight;

  always_ff @(posedge clk_i) begin
    byte_q       <= byte_i;
    user_q       <= user_i;
    byte_valid_q <= byte_valid_i && byte_ready_o;
    if (!rst_ni) begin
      nbytes_q     <= '0;
      word_valid_q <= 1'b0;
      byte_valid_q <= 1'b0;
    end else if (word_valid_q) begin
      if (m_axis_tready) word_valid_q <= 1'b0;
    end else if (byte_valid_q) begin
      word_q      <= word_d;
      word_user_q <= user_q;
      if (nbytes_q == LastByte) begin
        nbytes_q     <= '0;
        word_valid_q <= 1'b1;
      end else begin
        nbytes_q <= nbytes_q + 1'b1;
      end
    end
  end

  assign m_axis_tdata  = word_q;
  assign m_axis_tuser  = word_user_q;
  assign m_axis_tvalid = word_valid_q;
endmodule

`default_nettype wire
