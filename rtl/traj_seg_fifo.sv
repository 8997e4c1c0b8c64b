// trajcore: segment FIFO between the host link and the engine, mirrored by
// hls/traj_seg_fifo.hpp cycle for cycle.
//
// The memory holds Cap = Depth/SegWords slots of SegWords engine words (one
// segment each, in the engine's s_axis order: K, then the registers). It is one
// inferred single-port RAM (one address for reads and writes, synchronous
// read): Yosys maps it to SB_SPRAM256KA with `synth_ice40 -spram` (UP5K) and
// to SB_RAM40_4K otherwise (HX8K).
//
// Write side (the link), tentative until the frame's verdict:
//   * wr_i: one word of the open slot; taken while the open slot holds fewer
//     than SegWords words and a slot is free (stored < Cap), dropped otherwise.
//     Contract: wr_i at most every other cycle (a word waits one cycle in a
//     register when the reader holds the port); commit_i, rollback_i and
//     clear_i neither in that cycle nor the next, and no two of commit_i,
//     rollback_i and clear_i together (one frame verdict at a time).
//   * commit_i: the open slot becomes a stored segment if it holds exactly
//     SegWords words; otherwise (a partial or dropped write) it is rolled back.
//   * rollback_i: the open slot's words are forgotten (the write pointer
//     returns to the committed one). Nothing written since the last commit is
//     ever read.
//   * clear_i: stored segments not yet started are dropped, and none starts in
//     that cycle; honoured only while no segment is streaming (busy_o low),
//     ignored otherwise.
// Read side (the engine): a segment starts when release_i is high, none is
// streaming and one is stored; once started its SegWords words all leave on
// m_axis (valid/ready, tvalid a flop, data held until taken) whatever
// release_i does later. A write waiting for the port goes first.
// level_o: stored segments, counting a streaming one until its last word has
// been read from the RAM; credits_o = Cap - level_o.
`default_nettype none
`include "traj_check.svh"

module traj_seg_fifo #(
  parameter int ChunkWidth = 16,    // word width
  parameter int SegWords   = 50,    // words per segment
  parameter int Depth      = 4096,  // RAM words (rounded down to whole slots)
  // derived, do not override
  parameter int Cap        = Depth / SegWords
) (
  input  logic                  clk_i,
  input  logic                  rst_ni,
  // write side
  input  logic                  wr_i,
  input  logic [ChunkWidth-1:0] wr_data_i,
  input  logic                  commit_i,
  input  logic                  rollback_i,
  input  logic                  clear_i,
  // read side
  input  logic                  release_i,
  output logic [ChunkWidth-1:0] m_axis_tdata,
  output logic                  m_axis_tvalid,
  input  logic                  m_axis_tready,
  // state
  output logic [15:0]           level_o,
  output logic [15:0]           credits_o,
  output logic                  busy_o
);

  localparam int Total    = Cap * SegWords;
  localparam int AddrW    = (Total > 1) ? $clog2(Total) : 1;
  localparam int CntW     = $clog2(SegWords + 1);

  `TRAJ_PARAM_CHECK(g_bad_chunk, ChunkWidth >= 8 && ChunkWidth <= 64,
                    "traj_seg_fifo: ChunkWidth must be 8..64")
  `TRAJ_PARAM_CHECK(g_bad_seg, SegWords >= 2,
                    "traj_seg_fifo: SegWords must be at least 2")
  `TRAJ_PARAM_CHECK(g_bad_depth, Cap >= 1 && Cap <= 65535,
                    "traj_seg_fifo: Depth must hold 1..65535 segments")
  `TRAJ_PARAM_CHECK(g_bad_cap, Cap == Depth / SegWords,
                    "traj_seg_fifo: Cap is derived; do not override it")

  logic [ChunkWidth-1:0] mem [Total];

  logic [AddrW-1:0]      wr_addr_q, wr_base_q, wr_pend_addr_q, rd_addr_q;
  logic [CntW-1:0]       wr_cnt_q, rd_cnt_q;
  logic                  wr_pend_q, rd_busy_q, out_valid_q;
  logic [ChunkWidth-1:0] wr_data_q, rdata_q;
  logic [15:0]           stored_q;

  function automatic logic [AddrW-1:0] next_addr(input logic [AddrW-1:0] a);
    next_addr = (a == AddrW'(Total - 1)) ? '0 : a + 1'b1;
  endfunction

  logic wr_take, commit_ok, rewind, start, issue, last_issue, seg_end, clear_ok;
  assign wr_take    = wr_i && (wr_cnt_q != CntW'(SegWords)) && (stored_q != 16'(Cap));
  assign commit_ok  = commit_i && (wr_cnt_q == CntW'(SegWords));
  assign rewind     = rollback_i || (commit_i && !commit_ok);
  assign start      = !rd_busy_q && (stored_q != '0) && release_i && !clear_i;
  assign issue      = (rd_busy_q || start) && (rd_cnt_q != CntW'(SegWords)) && !wr_pend_q
                    && (!out_valid_q || m_axis_tready);
  assign last_issue = issue && (rd_cnt_q == CntW'(SegWords - 1));
  assign seg_end    = out_valid_q && m_axis_tready && (rd_cnt_q == CntW'(SegWords));
  assign clear_ok   = clear_i && !rd_busy_q;

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      wr_addr_q   <= '0;
      wr_base_q   <= '0;
      wr_cnt_q    <= '0;
      wr_pend_q   <= 1'b0;
      rd_addr_q   <= '0;
      rd_cnt_q    <= '0;
      rd_busy_q   <= 1'b0;
      out_valid_q <= 1'b0;
      stored_q    <= '0;
    end else begin
      // write side
      wr_pend_q <= wr_take;
      if (commit_ok) begin
        wr_base_q <= wr_addr_q;
        wr_cnt_q  <= '0;
      end else if (rewind || clear_ok) begin
        wr_addr_q <= wr_base_q;
        wr_cnt_q  <= '0;
      end else if (wr_take) begin
        wr_addr_q <= next_addr(wr_addr_q);
        wr_cnt_q  <= wr_cnt_q + 1'b1;
      end
      // read side
      if (clear_ok) rd_addr_q <= wr_base_q;
      else if (issue) rd_addr_q <= next_addr(rd_addr_q);
      if (seg_end) begin
        rd_busy_q <= 1'b0;
        rd_cnt_q  <= '0;
      end else begin
        if (start) rd_busy_q <= 1'b1;
        if (issue) rd_cnt_q <= rd_cnt_q + 1'b1;
      end
      out_valid_q <= issue || (out_valid_q && !m_axis_tready);
      if (clear_ok) stored_q <= '0;
      else stored_q <= stored_q + 16'(commit_ok) - 16'(last_issue);
    end
  end

  // Datapath, not reset.
  always_ff @(posedge clk_i) begin
    if (wr_take) begin
      wr_data_q      <= wr_data_i;
      wr_pend_addr_q <= wr_addr_q;
    end
  end

  // The single-port RAM: one address, a write or a read per cycle.
  logic [AddrW-1:0] ram_addr;
  assign ram_addr = wr_pend_q ? wr_pend_addr_q : rd_addr_q;
  always_ff @(posedge clk_i) begin
    if (wr_pend_q) mem[ram_addr] <= wr_data_q;
    else if (issue) rdata_q <= mem[ram_addr];
  end

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Formal properties (scripts/formal.sh: bounded from reset and by
  // induction, rtl.formal.traj_seg_fifo.*). With the write-side contract
  // assumed, they prove: nothing tentative is read (the read pointer stays
  // within the committed words), a rollback restores the committed pointer,
  // and every committed segment leaves exactly once, in order, unless a
  // clear drops it before it starts (segments out + in flight + stored ==
  // committed - cleared; pointers advance by exactly SegWords per segment).
  // ---------------------------------------------------------------------
  logic       f_past_valid = 1'b0;
  logic [7:0] f_committed, f_cleared, f_ended, f_started;
  always_ff @(posedge clk_i) begin
    f_past_valid <= 1'b1;
    if (!rst_ni) begin
      f_committed <= '0;
      f_cleared   <= '0;
      f_ended     <= '0;
      f_started   <= '0;
    end else begin
      f_committed <= f_committed + 8'(commit_ok);
      f_cleared   <= f_cleared + (clear_ok ? 8'(stored_q) : 8'd0);
      f_ended     <= f_ended + 8'(seg_end);
      f_started   <= f_started + 8'(start);
    end
  end
  // the write-side contract
  always_comb begin
    if (!f_past_valid) assume (!rst_ni);
    if (wr_i || wr_pend_q) assume (!commit_i && !rollback_i && !clear_i);
    if (wr_pend_q) assume (!wr_i);
    assume (!(commit_i && rollback_i) && !(clear_i && (commit_i || rollback_i)));
  end

  logic [7:0] f_out, f_held;  // segments committed and neither out nor cleared; stored + in flight
  assign f_out  = f_committed - f_cleared - f_ended;
  assign f_held = 8'(stored_q) + 8'(rd_busy_q && rd_cnt_q == CntW'(SegWords));
  int f_unread;    // committed words not yet read from the RAM
  int f_in_open;   // words in the open slot
  assign f_unread  = 32'(stored_q) * SegWords - ((rd_cnt_q == CntW'(SegWords)) ? 0 : 32'(rd_cnt_q));
  assign f_in_open = 32'(wr_cnt_q);

  always_ff @(posedge clk_i) begin
    if (f_past_valid && rst_ni) begin
      // bounds
      assert (32'(stored_q) <= Cap);
      assert (32'(wr_cnt_q) <= SegWords && 32'(rd_cnt_q) <= SegWords);
      assert (32'(wr_addr_q) < Total && 32'(wr_base_q) < Total && 32'(rd_addr_q) < Total);
      // the open slot follows the committed words
      assert (32'(wr_addr_q) == (32'(wr_base_q) + f_in_open) % Total);
      if (wr_cnt_q != '0) assert (32'(stored_q) < Cap);
      // the read pointer never passes the committed write pointer
      assert (f_unread >= 0);
      assert ((32'(rd_addr_q) + f_unread) % Total == 32'(wr_base_q));
      if (rd_busy_q && rd_cnt_q != CntW'(SegWords)) assert (stored_q != '0);
      if (!rd_busy_q) assert (rd_cnt_q == '0 && !out_valid_q);
      if (rd_busy_q && rd_cnt_q == '0) assert (!out_valid_q);
      if (rd_busy_q && rd_cnt_q == CntW'(SegWords)) assert (out_valid_q);
      // a pending write lands in the open slot
      if (wr_pend_q) assert ((32'(wr_pend_addr_q) + 1) % Total == 32'(wr_addr_q) && wr_cnt_q != '0);
      // segment accounting: each committed segment leaves once, or is cleared unstarted
      assert (f_started - f_ended == 8'(rd_busy_q));
      assert (f_out == f_held);
      assert (level_o + credits_o == 16'(Cap));
    end
    if (f_past_valid && rst_ni && $past(rst_ni)) begin
      // a rollback (or a commit of a partial slot) restores the committed pointer
      if ($past(rewind)) assert (wr_addr_q == $past(wr_base_q) && wr_cnt_q == '0);
      // reads only from committed words
      if ($past(issue)) assert ($past(f_unread) > 0);
      // a word offered stays until taken
      if ($past(m_axis_tvalid && !m_axis_tready)) assert (m_axis_tvalid && m_axis_tdata == $past(m_axis_tdata));
    end
  end
`endif

  assign m_axis_tdata  = rdata_q;
  assign m_axis_tvalid = out_valid_q;
  assign level_o       = stored_q;
  assign credits_o     = 16'(Cap) - stored_q;
  assign busy_o        = rd_busy_q;

endmodule

`default_nettype wire
