// trajcore: board reset. Power-on reset (iCE40 flops start at 0 after
// configuration), held until the PLL has locked and the reset button is
// released, for 2^CountWidth - 1 clocks after both; lock and button pass a
// 2-flop synchroniser each. rst_no is a flop, released synchronously.
`default_nettype none

module traj_reset_sync #(
  parameter int CountWidth = 4
) (
  input  logic clk_i,
  input  logic lock_i,   // PLL lock, asynchronous
  input  logic btn_ni,   // reset button, low = pressed, asynchronous
  output logic rst_no
);

  logic [1:0]            lock_q, btn_q;  // synchronisers
  logic [CountWidth-1:0] cnt_q;
  logic                  rst_nq;

  always_ff @(posedge clk_i) begin
    lock_q <= {lock_q[0], lock_i};
    btn_q  <= {btn_q[0], btn_ni};
    if (!lock_q[1] || !btn_q[1]) cnt_q <= '0;
    else if (cnt_q != '1)        cnt_q <= cnt_q + 1'b1;
    rst_nq <= (cnt_q == '1);
  end

  // power-on values (the iCE40 configuration clears every flop)
  initial begin
    lock_q = '0;
    btn_q  = '0;
    cnt_q  = '0;
    rst_nq = 1'b0;
  end

  assign rst_no = rst_nq;

endmodule

`default_nettype wire
