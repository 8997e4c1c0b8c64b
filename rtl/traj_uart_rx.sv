// trajcore: UART receiver, 8N1, mirrored by hls/traj_uart_rx.hpp cycle for cycle.
//
// Contract:
//   * rx_i is already synchronised to clk_i (the board top's two-flop
//     synchroniser); this unit adds no metastability protection.
//   * Div = round(ClkHz/Baud) clocks per bit, at least 8 (checked at
//     elaboration, with the rate error within 2 percent).
//   * A start bit is a falling edge of rx_i (rx_i low after a high cycle); it
//     is confirmed by a sample in the middle of the start bit, so a low glitch
//     shorter than half a bit is rejected. Data bits (LSB first) and the stop
//     bit are sampled one bit time apart from there, in their middles.
//   * valid_o (one cycle) with data_o when the stop bit is high; err_o (one
//     cycle) when it is low (framing error: the byte is dropped). The receiver
//     is ready for the next start edge from the middle of the stop bit on; after
//     a framing error it waits for rx_i high first (a held break reads as one
//     error, not a stream of zero bytes).
//   * data_o holds from one valid_o to the next.
`default_nettype none
`include "traj_check.svh"

module traj_uart_rx #(
  parameter int ClkHz = 48_000_000,  // clk_i frequency in Hz
  parameter int Baud  = 1_000_000,   // bit rate
  // derived, do not override
  parameter int Div   = (ClkHz + Baud / 2) / Baud  // clocks per bit
) (
  input  logic       clk_i,
  input  logic       rst_ni,
  input  logic       rx_i,     // synchronised serial input, idle high
  output logic [7:0] data_o,
  output logic       valid_o,  // one cycle per good byte
  output logic       err_o     // one cycle per framing error
);

  localparam int CntWidth = $clog2(Div);
  localparam int Half     = Div / 2;

  `TRAJ_PARAM_CHECK(g_bad_div, Div >= 8,
                    "traj_uart_rx: ClkHz/Baud must be at least 8 clocks per bit")
  `TRAJ_PARAM_CHECK(g_bad_rate, (ClkHz - Div * Baud) * 50 <= Div * Baud
                    && (Div * Baud - ClkHz) * 50 <= Div * Baud,
                    "traj_uart_rx: Baud is more than 2 percent away from ClkHz/Div")
  `TRAJ_PARAM_CHECK(g_bad_derived, Div == (ClkHz + Baud / 2) / Baud,
                    "traj_uart_rx: Div is derived; do not override it")

  logic                busy_q;   // a start bit was seen; sampling a character
  logic [3:0]          bit_q;    // 0 start, 1..8 data, 9 stop
  logic [CntWidth-1:0] cnt_q;    // clocks to the next sample point
  logic                rx_q;     // rx_i one cycle ago (start-edge detection)
  logic [7:0]          shift_q;  // data bits, LSB first from the top
  logic                valid_q, err_q;

  logic sample;
  assign sample = busy_q && (cnt_q == '0);

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      busy_q  <= 1'b0;
      bit_q   <= '0;
      cnt_q   <= '0;
      rx_q    <= 1'b0;  // a line low out of reset is not a start edge
      valid_q <= 1'b0;
      err_q   <= 1'b0;
    end else begin
      rx_q    <= rx_i;
      valid_q <= 1'b0;
      err_q   <= 1'b0;
      if (!busy_q) begin
        if (rx_q && !rx_i) begin
          busy_q <= 1'b1;
          bit_q  <= '0;
          cnt_q  <= CntWidth'(Half - 1);
        end
      end else if (!sample) begin
        cnt_q <= cnt_q - 1'b1;
      end else begin
        cnt_q <= CntWidth'(Div - 1);
        bit_q <= bit_q + 1'b1;
        if (bit_q == 4'd0 && rx_i) begin
          busy_q <= 1'b0;  // start bit gone by its middle: a glitch
        end else if (bit_q == 4'd9) begin
          busy_q  <= 1'b0;
          valid_q <= rx_i;
          err_q   <= !rx_i;
        end
      end
    end
  end

  // Data bits: datapath, not reset.
  always_ff @(posedge clk_i) begin
    if (sample && bit_q >= 4'd1 && bit_q <= 4'd8) shift_q <= {rx_i, shift_q[7:1]};
  end

  assign data_o  = shift_q;
  assign valid_o = valid_q;
  assign err_o   = err_q;

endmodule

`default_nettype wire
