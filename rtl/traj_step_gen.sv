// trajcore: step/dir generator, all axes.
//
// Mirrors hls/traj_step_gen.hpp cycle for cycle. From the engine's samples
// (OutWidth bits, two's complement, one per tick) it makes step, direction
// and enable outputs for step-motor drivers:
//   * one step = 2^shift output LSB (shift per axis, 0..63, runtime);
//   * the commanded step count is floor(sample / 2^shift) at every tick,
//     exactly: no lost or extra step, ever (below);
//   * the steps of a tick are spread through the tick along quadratic
//     sub-chords, one tick behind the samples (below).
//
// Path. Per axis q = floor(sample * 2^F / 2^shift) (F = FracBits: the step
// position with F fraction bits; floor(q / 2^F) = floor(sample / 2^shift)).
// Between the samples of ticks k-1 and k the path is the parabola through
// the samples k-2, k-1, k, as M = 2^m straight sub-chords of P / M clocks
// (P: the tick period; m <= SubBits, the most for which 2^m divides P and
// P / 2^m >= 2 PrepClocks). With D1 = q_k - q_k-1 and D2 = D1 - D1 of the
// tick before, the parabola scaled by 2 M^2 is Y_i = 2 M^2 q_k-1 + 2 M i D1
// + i (i - M) D2 at sub-chord ends i = 0..M: integers; sub-chord i rises by
// dY_i = 2 M D1 + (2 i + 1 - M) D2.
//
// Exactness. A DDA per axis: a remainder r in [0, T), T = P * 2^(F+m+1);
// every clock r += dY_i, with one step up when r reaches T (r -= T) or one
// step down when r drops below 0 (r += T). With X = (steps) * T + r, the
// M sub-chords of a tick add (P / M) * (Y_M - Y_0) = P * 2M * D1 to X: the
// step count is floor(q_k / 2^F) after every tick, whatever D2 is, and r
// continues into the next tick (|dY| <= T: at most one step per clock).
// When P changes (or at the first interval after reset) the tick restarts
// from the step boundary: r = 0, q_k-1 with its fraction bits cleared,
// D2 = 0 (the same step count; only that tick's path starts at the
// boundary).
//
// Only q mod 2^RW is kept (RW = PeriodWidth + F + SubBits + 3 bits): all
// differences are exact modulo 2^RW because their magnitudes stay below
// 2^(RW-2).
//
// Preparation: one serial pass per sample (a tick pass) and one per later
// sub-chord (a sub pass), axis after axis, RW clocks per axis, one clock
// ahead of it to fetch the first bit, and one clock to finish:
// PrepClocks = Axes * RW + 3. The tick pass reads the bits of q, least
// significant first, from sample_i (bit shift - F + i, sign-extended; 0
// below bit 0) into a flop one clock before they are used (the read is a
// wide multiplexer; the flop keeps it off the subtraction's path) and forms
// D1 = q - q_prev, D2 = D1 - D1_prev and dY_0 = (D1 << m+1) - (D2 << m) + D2
// bit-serially (delay lines give the shifted bits); a sub pass forms
// dY += 2 D2. q_prev, D1_prev and D2 live bit by bit in block RAM (read at
// the fetch position, written back at the pass position); dY is a shift
// register per axis. dY -/+ T is formed when the sub-chord starts.
// sample_i must hold for PrepClocks after sample_valid (the FD engine holds
// its sample until its next tick). A sub-chord starts when the previous one
// ends (or at once when none runs): with ticks every P >= PrepClocks + 1
// clocks the intervals follow each other with no gap and a constant latency.
// The first sample after reset only sets the position (no steps).
//
// Pulses. A signed per-axis count `due` collects the DDA's steps (one clock
// after the DDA: a register between the remainder's carry chain and the
// count's); the pulse
// generator emits them one at a time: step high for pulse_i clocks, low for
// pulse_i clocks, then (unless the next step goes the same way at once) a
// hold of setup_i - pulse_i more clocks; a direction change (only after the
// hold) waits setup_i + 1 clocks before the next rising edge. The direction
// turns as soon as the DDA runs an interval the other way with nothing due.
// dir_o = 1: steps count up (positive direction).
//
// err_o (sticky until reset): a sample arrived while the previous one (or
// one of its sub-chords) was still being prepared or waiting; more than one
// step per clock (|dY| > T);
// |due| reached 2^(DueWidth-2) (the pulses cannot keep up with the samples:
// lower pulse_i or the speed).
//
// UseDsp = 1 computes the DDA's two sums of each axis (r + D, r + D -/+ T)
// in iCE40 SB_MAC16 blocks (traj_add): the same sums on every clock, with
// their low 32 bits off the logic cells; 2 Axes blocks (the UP5K has 8).
`default_nettype none
`include "traj_check.svh"

module traj_step_gen #(
  parameter int Axes        = 3,   // 1..8
  parameter int OutWidth    = 48,  // sample width, 8..64
  parameter int FracBits    = 14,  // step fraction bits of the chord, 1..16
  parameter int PeriodWidth = 18,  // tick period width (clocks), 8..32
  parameter int DueWidth    = 8,   // steps waiting for their pulse, 4..32
  parameter int TimeWidth   = 16,  // pulse width and setup counters, 2..16
  parameter int SubBits     = 3,   // up to 2^SubBits quadratic sub-chords per tick, 0..4
  parameter int UseDsp      = 0    // 1: the DDA's two sums of each axis in SB_MAC16 blocks (iCE40 UP5K: 2 Axes of its 8)
) (
  input  logic                     clk_i,
  input  logic                     rst_ni,
  // configuration (constant while samples come)
  input  logic [Axes*6-1:0]        shift_i,    // axis a: one step = 2^shift LSB
  input  logic [PeriodWidth-1:0]   period_i,   // tick period in clocks (>= 1, latched per sample; held
                                               // in the clock before sample_valid_i too: pm_q)
  input  logic [TimeWidth-1:0]     pulse_i,    // step high and low time, clocks, >= 1
  input  logic [TimeWidth-1:0]     setup_i,    // direction setup and hold, clocks
  input  logic                     enable_i,
  // samples
  input  logic                     sample_valid_i,
  input  logic [Axes*OutWidth-1:0] sample_i,
  // driver outputs (registered)
  output logic [Axes-1:0]          step_o,
  output logic [Axes-1:0]          dir_o,
  output logic                     enable_o,
  output logic                     err_o
);

  localparam int F  = FracBits;
  localparam int RW = PeriodWidth + F + SubBits + 3;  // q window, D1, D2, D, r, D -/+ T: signed
  localparam int NW = PeriodWidth + SubBits + 3;      // T / 2^F, signed
  localparam int DW2 = (SubBits > 0) ? SubBits : 1;   // D2 delay line
  localparam int MW = 3;                              // m, 0..4
  localparam int PrepClocks = Axes * RW + 3;          // take (or load) -> next interval ready
  localparam int BW = $clog2(RW);            // bit counter
  localparam int AW = (Axes > 1) ? $clog2(Axes) : 1;
  localparam int JW = 8;                     // sample bit index, signed: -F .. 63+RW

  `TRAJ_PARAM_CHECK(g_bad_axes, Axes >= 1 && Axes <= 8, "traj_step_gen: Axes must be 1..8")
  `TRAJ_PARAM_CHECK(g_bad_out, OutWidth >= 8 && OutWidth <= 64, "traj_step_gen: OutWidth must be 8..64")
  `TRAJ_PARAM_CHECK(g_bad_frac, FracBits >= 1 && FracBits <= 16, "traj_step_gen: FracBits must be 1..16")
  `TRAJ_PARAM_CHECK(g_bad_period, PeriodWidth >= 8 && PeriodWidth <= 32,
                    "traj_step_gen: PeriodWidth must be 8..32")
  `TRAJ_PARAM_CHECK(g_bad_due, DueWidth >= 4 && DueWidth <= 32, "traj_step_gen: DueWidth must be 4..32")
  `TRAJ_PARAM_CHECK(g_bad_time, TimeWidth >= 2 && TimeWidth <= 16, "traj_step_gen: TimeWidth must be 2..16")
  `TRAJ_PARAM_CHECK(g_bad_sub, SubBits >= 0 && SubBits <= 4, "traj_step_gen: SubBits must be 0..4")
  `TRAJ_PARAM_CHECK(g_bad_dsp, UseDsp == 0 || UseDsp == 1, "traj_step_gen: UseDsp must be 0 or 1")

  // ---------------------------------------------------------------------
  // Serial preparation (shared by all axes).
  // ---------------------------------------------------------------------
  logic                   fetch_q;    // the pass's sample bits are being read
  logic [AW-1:0]          fax_q;      // axis of the bit being read
  logic [BW-1:0]          fbit_q;     // its bit of q
  logic [JW-1:0]          j_q;        // sample bit read for it (signed)
  logic                   sbit_q;     // the bit read: the bit of q in use
  logic                   prep_q;     // the pass is running: fetch_q one clock later
  logic [AW-1:0]          ax_q;       // its axis (fax_q one clock later)
  logic [BW-1:0]          bit_q;      // its bit of q (fbit_q one clock later)
  logic                   borrow_q, borrow2_q, c1_q, b2_q;  // the pass's serial carries
  logic [SubBits:0]       dl1_q;      // the axis's last D1 bits in the pass, newest in bit 0
  logic [DW2-1:0]         dl2_q;      // its last D2 bits
  logic                   first_q;    // no sample since reset: the next one sets the position
  logic                   reinit_q;   // this tick restarts from the step boundary
  logic                   tickp_q;    // the pass (or the last one) is a tick pass, else a sub pass
  logic [MW-1:0]          nm_q;       // m of the tick: 2^m sub-chords
  logic [MW-1:0]          pm_q;       // m of period_i in the clock before (the count's compares off the take's path)
  logic [SubBits:0]       subs_q;     // sub-chords of the tick still to prepare
  logic                   alt_q_st;   // the pass has ended: one clock to nready_q
  logic                   nready_q;   // the next interval's D is ready
  logic [PeriodWidth-1:0] nper_q;     // its period; at a take, that of the last interval loaded (0: none
                                      // yet; a take finds every interval prepared before it loaded)
  // DDA (shared interval counter)
  logic                   active_q, last_q;  // last_q == (cnt_q == 1)
  logic [PeriodWidth-1:0] cnt_q;
  logic [NW-1:0]          ntq_q;      // T / 2^F of the next interval (nper_q and nm_q hold
                                      // from take to the loads)
  logic [PeriodWidth-1:0] nlen_q;     // its length, clocks: P / 2^m
  logic                   loaded_q;   // an interval started in the last clock (its step-rate check)
  logic [TimeWidth-1:0]   hold_q;     // setup_i - pulse_i, at least 0
  logic                   en_q, err_q;
  logic                   pulse_one, setup_zero, hold_zero;  // the timer's loads that are 0

  logic take, load, subgo, last_bit, last_axis, f_last_bit, f_last_axis, sbit;
  logic pbit, dbit, borrow_d, ppbit, ddbit_t, borrow2_d, ddbit, add_a, add_c, sub_b, s1, c1_d, ndbit, b2_d;
  logic [Axes-1:0] err_axis;
  logic [AW-1:0]   fax_inc;           // the axis the read goes to after fax_q
  logic [Axes*JW-1:0] jst_q;          // axis a: its first sample bit, shift - F (a flop of shift_i)

  assign take        = sample_valid_i && !fetch_q && !prep_q && !alt_q_st && !nready_q && (subs_q == '0);
  assign load        = nready_q && (!active_q || last_q);
  assign subgo       = load && (subs_q != '0);  // the next sub-chord's pass
  assign last_bit    = (bit_q == BW'(RW - 1));
  assign last_axis   = (ax_q == AW'(Axes - 1));
  assign f_last_bit  = (fbit_q == BW'(RW - 1));
  assign f_last_axis = (fax_q == AW'(Axes - 1));
  assign fax_inc     = f_last_axis ? '0 : fax_q + 1'b1;
  assign pulse_one   = (pulse_i == TimeWidth'(1));
  assign setup_zero  = (setup_i == '0);
  assign hold_zero   = (hold_q == '0);
  // setup_i - pulse_i, its sign in the top bit: the subtraction's borrow
  // decides the clamp to 0 (no comparator beside it)
  logic [TimeWidth:0] hold_d;
  assign hold_d      = {1'b0, setup_i} - {1'b0, pulse_i};

  // the sample bit of q's bit fbit_q of axis fax_q: sign-extended above, 0
  // below; one OutWidth:1 multiplexer per axis, then the axis (a variable
  // part-select over all axes would be a barrel shifter)
  logic                      j_neg, j_above;
  logic [Axes-1:0]           sbit_axis;
  logic [$clog2(OutWidth)-1:0] j_idx;
  assign j_neg   = j_q[JW-1];
  assign j_above = (32'(j_q) >= 32'(OutWidth));
  assign j_idx   = j_q[$clog2(OutWidth)-1:0];
  for (genvar a = 0; a < Axes; a++) begin : g_sbit
    logic [OutWidth-1:0] smp;
    assign smp          = sample_i[a*OutWidth +: OutWidth];
    assign sbit_axis[a] = j_neg ? 1'b0 : (j_above ? smp[OutWidth-1] : smp[j_idx]);
  end
  assign sbit = sbit_axis[fax_q];

  // sub-chords per tick = 2^m: the most (m <= SubBits) that divide the period
  // into intervals of at least 2 PrepClocks clocks (P / 2^k >= 2 PrepClocks
  // <=> P >= 2 PrepClocks 2^k: a comparison with a constant, as logic)
  `include "traj_ge_const.svh"
  function automatic logic [MW-1:0] sub_bits(input logic [PeriodWidth-1:0] p);
    logic ok;
    sub_bits = '0;
    ok = 1'b1;
    for (int k = 1; k <= SubBits; k++) begin
      ok = ok && (p[k-1] == 1'b0) && traj_ge_const(32'(p), 32'((2 * PrepClocks) << k));
      if (ok) sub_bits = MW'(k);
    end
  endfunction

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      fetch_q   <= 1'b0;
      fax_q     <= '0;
      fbit_q    <= '0;
      prep_q    <= 1'b0;
      ax_q      <= '0;
      bit_q     <= '0;
      first_q   <= 1'b1;
      reinit_q  <= 1'b0;
      tickp_q   <= 1'b0;
      subs_q    <= '0;
      alt_q_st  <= 1'b0;
      nready_q  <= 1'b0;
      active_q  <= 1'b0;
      loaded_q  <= 1'b0;
      last_q    <= 1'b0;
      cnt_q     <= '0;
      nper_q    <= '0;
      en_q      <= 1'b0;
      err_q     <= 1'b0;
    end else begin
      en_q  <= enable_i;
      err_q <= err_q || (sample_valid_i && !take) || (|err_axis);
      if (take) begin
        fetch_q  <= 1'b1;
        fax_q    <= '0;
        fbit_q   <= '0;
        // restart from the step boundary when the period differs from the
        // last interval's (0 after reset: the first interval)
        reinit_q <= (period_i != nper_q);
        // (the first sample's pass loads no interval: 0 stays the last period)
        if (!first_q) nper_q <= period_i;
        tickp_q  <= 1'b1;
        subs_q   <= first_q ? '0 : (SubBits+1)'((1 << pm_q) - 1);
      end else if (subgo) begin
        fetch_q  <= 1'b1;
        fax_q    <= '0;
        fbit_q   <= '0;
        tickp_q  <= 1'b0;
        subs_q   <= subs_q - 1'b1;
      end else if (fetch_q) begin
        if (!f_last_bit) begin
          fbit_q <= fbit_q + 1'b1;
        end else begin
          fbit_q <= '0;
          fax_q  <= fax_inc;
          if (f_last_axis) fetch_q <= 1'b0;
        end
      end
      prep_q <= fetch_q;
      ax_q   <= fax_q;
      bit_q  <= fbit_q;
      if (prep_q && last_bit && last_axis) begin
        first_q  <= 1'b0;
        alt_q_st <= !first_q;
      end
      if (alt_q_st) begin
        alt_q_st <= 1'b0;
        nready_q <= 1'b1;
      end
      loaded_q <= load;
      if (load) begin
        nready_q  <= 1'b0;
        active_q  <= 1'b1;
        cnt_q     <= nlen_q;
        last_q    <= (nlen_q == PeriodWidth'(1));
      end else if (active_q) begin
        cnt_q  <= cnt_q - 1'b1;
        last_q <= (cnt_q == PeriodWidth'(2));
        if (last_q) active_q <= 1'b0;
      end
    end
  end

  // datapath of the pass (not reset)
  always_ff @(posedge clk_i) begin
    hold_q <= hold_d[TimeWidth] ? '0 : hold_d[TimeWidth-1:0];
    pm_q   <= sub_bits(period_i);
    ntq_q  <= NW'({nper_q, 1'b0}) << nm_q;
    nlen_q <= nper_q >> nm_q;
    sbit_q <= sbit;
    if (take) begin
      nm_q   <= pm_q;
      j_q    <= jst_q[0 +: JW];
    end else if (fetch_q) begin
      j_q    <= f_last_bit ? jst_q[32'(fax_inc)*JW +: JW] : j_q + 1'b1;
    end
    for (int a = 0; a < Axes; a++) jst_q[a*JW +: JW] <= JW'(shift_i[a*6 +: 6]) - JW'(F);
    // carries and delay lines: cleared at each axis's bit 0
    if (take || subgo || (prep_q && last_bit)) begin
      borrow_q  <= 1'b0;
      borrow2_q <= 1'b0;
      c1_q      <= 1'b0;
      b2_q      <= 1'b0;
      dl1_q     <= '0;
      dl2_q     <= '0;
    end else if (prep_q) begin
      borrow_q  <= borrow_d;
      borrow2_q <= borrow2_d;
      c1_q      <= c1_d;
      b2_q      <= b2_d;
      dl1_q     <= (SubBits+1)'({dl1_q, dbit});
      dl2_q     <= DW2'({dl2_q, ddbit});
    end
  end

  // The pass, least significant bit first, on the bit read one clock earlier:
  //   tick pass: D1 = q - q_prev, D2 = D1 - D1_prev (0 on a restart),
  //              D = 2M D1 - (M - 1) D2 (M = 2^m; shifted bits from the delay lines);
  //   sub pass:  D = D + 2 D2.
  logic [Axes-1:0] nd_lsb;

  // q_prev (the previous sample's q), D1_prev (the last tick's D1) and D2 (the
  // tick's) of every axis, bit by bit in block RAM (they are only ever used
  // bit-serially): word {axis, bit} = {D2, D1_prev, q_prev}. Read at the
  // fetch position (fax_q, fbit_q), so the word of the pass position (ax_q,
  // bit_q) is in prd_q; written back at the pass position (a tick pass
  // writes q and D1 there, a sub pass keeps them).
  localparam int RA = AW + BW;
  logic [2:0] pram [0:(1<<RA)-1];
  logic [2:0] prd_q;
  always_ff @(posedge clk_i) begin
    prd_q <= pram[{fax_q, fbit_q}];
    if (prep_q) pram[{ax_q, bit_q}] <= {ddbit, tickp_q ? dbit : prd_q[1], tickp_q ? sbit_q : prd_q[0]};
  end

  assign pbit      = prd_q[0] && !(reinit_q && !traj_ge_const(32'(bit_q), 32'(F)));
  assign dbit      = sbit_q ^ pbit ^ borrow_q;
  assign borrow_d  = (!sbit_q && pbit) || (!sbit_q && borrow_q) || (pbit && borrow_q);
  assign ppbit     = prd_q[1];
  assign ddbit_t   = !reinit_q && (dbit ^ ppbit ^ borrow2_q);
  assign borrow2_d = !reinit_q && ((!dbit && ppbit) || (!dbit && borrow2_q) || (ppbit && borrow2_q));
  assign ddbit     = tickp_q ? ddbit_t : prd_q[2];
  // D1 at bit j-m-1 and D2 at bit j-m (nm_q <= SubBits)
  logic [7:0] d1_line, d2_line;
  logic       d1_shifted, d2_shifted;
  assign d1_line    = 8'(dl1_q);             // bit k: D1 at bit j-1-k
  assign d2_line    = 8'({dl2_q, ddbit_t});  // bit k: D2 at bit j-k
  assign d1_shifted = d1_line[nm_q];
  assign d2_shifted = d2_line[nm_q];
  assign add_a     = tickp_q ? d1_shifted : nd_lsb[ax_q];
  assign add_c     = tickp_q ? ddbit_t : dl2_q[0];
  assign sub_b     = tickp_q && d2_shifted;
  assign s1        = add_a ^ add_c ^ c1_q;
  assign c1_d      = (add_a && add_c) || (add_a && c1_q) || (add_c && c1_q);
  assign ndbit     = s1 ^ sub_b ^ b2_q;
  assign b2_d      = (!s1 && sub_b) || (!s1 && b2_q) || (sub_b && b2_q);

  // ---------------------------------------------------------------------
  // Per axis: q_prev and D shift registers, DDA, pulses.
  // ---------------------------------------------------------------------
  typedef enum logic [2:0] {PgIdle, PgSetup, PgHigh, PgLow, PgHold} pg_e;

  for (genvar a = 0; a < Axes; a++) begin : g_axis
    logic [RW-1:0]        nd_q;      // next interval's D (rotates during the pass)
    logic [RW-1:0]        r_q;       // running interval's remainder (its D and D -/+ T are
                                     // the adders' registers, below)
    logic                 fast_q;    // its |D| > T (more than one step per clock)
    logic                 dpos_q;    // running interval's D >= 0
    logic                 dnz_q;     // running interval's D != 0
    logic                 nnz_q;     // nd_q != 0, formed with it in the pass (no wide OR)
    logic                 up_q, down_q;  // the DDA's steps, one clock later (timing)
    logic [DueWidth-1:0]  due_q;
    pg_e                  pg_q;
    logic [TimeWidth-1:0] timer_q;
    logic                 tz_q;      // timer_q == 0 (a flop: off the pulse decision's path)
    logic                 step_q, dir_q;
    logic                 mine;

    assign mine         = prep_q && (ax_q == AW'(a));
    assign nd_lsb[a]     = nd_q[0];

    always_ff @(posedge clk_i) begin
      if (mine) begin
        nd_q  <= {ndbit, nd_q[RW-1:1]};
        nnz_q <= ndbit || (nnz_q && bit_q != '0);
      end
    end

    // DDA: at most one step per clock
    // (r_q's update is written as enable / clear / a 2:1 multiplexer so the
    // flop's enable and reset take the control, not the remainder's path)
    logic [RW-1:0] sum_d, sum_alt, r_step;
    /* verilator lint_off UNUSEDSIGNAL */
    logic [NW:0]   alt_c;  // bit 0: the carry-in's place ({x, 1} + {y, c}: bit 0 carries c)
    /* verilator lint_on UNUSEDSIGNAL */
    logic [RW-1:F] alt_d;
    logic          up, down, steps_now;
    // each sum one whole carry chain (split at bit F, the low half's carry-out
    // into the upper halves, Yosys mapped those upper halves' carries as a LUT
    // per bit: 25 MHz on the HX8K); in DSP blocks (UseDsp) their low 32 bits
    // take no logic cells (traj_add). The running interval's D and D -/+ T
    // (above bit F; T's low F bits are 0: below, D's) are the adders' own
    // registers, loaded with the interval (RegB: in a DSP block, the block's
    // input registers, no logic cells)
    traj_add #(.Width(RW), .UseDsp(UseDsp), .RegB(1)) u_sum_d (
      .clk_i, .be_i(load), .a_i(r_q), .b_i(nd_q), .ci_i(1'b0), .sum_o(sum_d)
    );
    traj_add #(.Width(RW), .UseDsp(UseDsp), .RegB(1)) u_sum_alt (
      .clk_i, .be_i(load), .a_i(r_q), .b_i({alt_d, nd_q[F-1:0]}), .ci_i(1'b0), .sum_o(sum_alt)
    );
    assign steps_now = active_q && (dpos_q ? !sum_alt[RW-1] : sum_d[RW-1]);  // a step this clock
    assign up      = steps_now && dpos_q;
    assign down    = steps_now && !dpos_q;
    assign r_step  = steps_now ? sum_alt : sum_d;
    // the next interval's D + T for D < 0, D - T otherwise, above bit F (T's
    // low bits are 0); -T = ~T + 1: the sign picks T or its complement and the
    // carry-in
    assign alt_c   = {nd_q[RW-1:F], 1'b1} + {ntq_q ^ {NW{!nd_q[RW-1]}}, !nd_q[RW-1]};
    assign alt_d   = alt_c[NW:1];

    always_ff @(posedge clk_i) begin
      if (load) begin
        fast_q <= nd_q[RW-1] ? alt_d[RW-1] : (!alt_d[RW-1] && {alt_d, nd_q[F-1:0]} != '0);
        dpos_q <= !nd_q[RW-1];
        dnz_q  <= nnz_q;
      end
      if (load && reinit_q && tickp_q) r_q <= '0;  // a tick's first sub-chord after a period change
      else if (active_q)    r_q <= r_step;
    end

    // pulses
    logic want_dir, can_emit, turn, t_one;
    assign t_one    = (timer_q == TimeWidth'(1));
    logic [DueWidth-1:0] due_d;
    assign want_dir = (due_q != '0) ? !due_q[DueWidth-1]
                    : ((active_q && dnz_q) ? dpos_q : dir_q);
    assign can_emit = (due_q != '0) && (want_dir == dir_q)
                    && (pg_q == PgIdle || pg_q == PgHold || (pg_q == PgLow && tz_q));
    assign turn     = (pg_q == PgIdle) && (want_dir != dir_q);
    assign due_d    = due_q + DueWidth'(up_q) - DueWidth'(down_q)
                    - (can_emit ? (dir_q ? DueWidth'(1) : '1) : '0);

    always_ff @(posedge clk_i) begin
      if (!rst_ni) begin
        up_q    <= 1'b0;
        down_q  <= 1'b0;
        due_q   <= '0;
        pg_q    <= PgIdle;
        timer_q <= '0;
        tz_q    <= 1'b1;
        step_q  <= 1'b0;
        dir_q   <= 1'b1;
      end else begin
        up_q   <= up;
        down_q <= down;
        due_q  <= due_d;
        if (can_emit) begin
          step_q  <= 1'b1;
          timer_q <= pulse_i - 1'b1;
          tz_q    <= pulse_one;
          pg_q    <= PgHigh;
        end else begin
          case (pg_q)
            PgIdle:  if (turn) begin
                       dir_q   <= want_dir;
                       timer_q <= setup_i;
                       tz_q    <= setup_zero;
                       pg_q    <= PgSetup;
                     end
            PgSetup: if (tz_q) begin
                       pg_q    <= PgIdle;
                     end else begin
                       timer_q <= timer_q - 1'b1;
                       tz_q    <= t_one;
                     end
            PgHigh:  if (tz_q) begin
                       step_q  <= 1'b0;
                       timer_q <= pulse_i - 1'b1;
                       tz_q    <= pulse_one;
                       pg_q    <= PgLow;
                     end else begin
                       timer_q <= timer_q - 1'b1;
                       tz_q    <= t_one;
                     end
            PgLow:   if (tz_q) begin
                       timer_q <= hold_q;
                       tz_q    <= hold_zero;
                       pg_q    <= PgHold;
                     end else begin
                       timer_q <= timer_q - 1'b1;
                       tz_q    <= t_one;
                     end
            PgHold:  if (tz_q) begin
                       pg_q    <= PgIdle;
                     end else begin
                       timer_q <= timer_q - 1'b1;
                       tz_q    <= t_one;
                     end
            default: pg_q <= PgIdle;
          endcase
        end
      end
    end

    // errors: more than one step per clock (checked the clock after the
    // interval starts), due overflow (flagged at
    // |due| >= 2^(DueWidth-2), before it can wrap: it moves by <= 2 per clock)
    logic too_fast;
    assign too_fast    = loaded_q && fast_q;
    assign err_axis[a] = too_fast || (due_q[DueWidth-1] != due_q[DueWidth-2]);

    assign step_o[a] = step_q;
    assign dir_o[a]  = dir_q;
  end

  assign enable_o = en_q;
  assign err_o    = err_q;

endmodule

`default_nettype wire
