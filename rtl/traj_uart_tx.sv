// trajcore: UART transmitter, 8N1, mirrored by hls/traj_uart_tx.hpp cycle for cycle.
//
// Contract: a byte is taken on s_tvalid && s_tready (s_tready is high exactly
// when no character is being sent, a flop, independent of s_tvalid); tx_o is a
// flop: start bit, 8 data bits LSB first, stop bit, each Div = round(ClkHz/Baud)
// clocks (at least 8, checked at elaboration). s_tready rises at the end of the
// stop bit (Div clocks; one more when the next byte follows at once).
`default_nettype none
`include "traj_check.svh"

module traj_uart_tx #(
  parameter int ClkHz = 48_000_000,  // clk_i frequency in Hz
  parameter int Baud  = 1_000_000,   // bit rate
  // derived, do not override
  parameter int Div   = (ClkHz + Baud / 2) / Baud  // clocks per bit
) (
  input  logic       clk_i,
  input  logic       rst_ni,
  input  logic [7:0] s_tdata,
  input  logic       s_tvalid,
  output logic       s_tready,
  output logic       tx_o       // serial output, idle high
);

  localparam int CntWidth = $clog2(Div);

  `TRAJ_PARAM_CHECK(g_bad_div, Div >= 8,
                    "traj_uart_tx: ClkHz/Baud must be at least 8 clocks per bit")
  `TRAJ_PARAM_CHECK(g_bad_rate, (ClkHz - Div * Baud) * 50 <= Div * Baud
                    && (Div * Baud - ClkHz) * 50 <= Div * Baud,
                    "traj_uart_tx: Baud is more than 2 percent away from ClkHz/Div")
  `TRAJ_PARAM_CHECK(g_bad_derived, Div == (ClkHz + Baud / 2) / Baud,
                    "traj_uart_tx: Div is derived; do not override it")

  logic                busy_q;
  logic [3:0]          left_q;   // bits still to send after the current one
  logic [CntWidth-1:0] cnt_q;    // clocks left in the current bit
  logic [8:0]          shift_q;  // {stop, data} still to send, LSB next
  logic                tx_q;

  logic accept;
  assign accept = s_tvalid && !busy_q;

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      busy_q <= 1'b0;
      left_q <= '0;
      cnt_q  <= '0;
      tx_q   <= 1'b1;
    end else if (accept) begin
      busy_q <= 1'b1;
      left_q <= 4'd9;
      cnt_q  <= CntWidth'(Div - 1);
      tx_q   <= 1'b0;
    end else if (busy_q) begin
      if (cnt_q != '0) begin
        cnt_q <= cnt_q - 1'b1;
      end else if (left_q == '0) begin
        busy_q <= 1'b0;
      end else begin
        cnt_q  <= CntWidth'(Div - 1);
        left_q <= left_q - 1'b1;
        tx_q   <= shift_q[0];
      end
    end
  end

  always_ff @(posedge clk_i) begin
    if (accept) begin
      shift_q <= {1'b1, s_tdata};
    end else if (busy_q && cnt_q == '0 && left_q != '0) begin
      shift_q <= {1'b1, shift_q[8:1]};
    end
  end

  assign s_tready = !busy_q;
  assign tx_o     = tx_q;

endmodule

`default_nettype wire
