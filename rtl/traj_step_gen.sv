// trajcore: step/dir generator, all axes.
//
// Mirrors hls/traj_step_gen.hpp cycle for cycle. From the engine's samples
// (OutWidth bits, two's complement, one per tick) it makes step, direction
// and enable outputs for step-motor drivers:
//   * one step = 2^shift output LSB (shift per axis, 0..63, runtime);
//   * the commanded step count is floor(sample / 2^shift) at every tick,
//     exactly: no lost or extra step, ever (below);
//   * the steps of a tick are spread through the tick: a DDA along the chord
//     between consecutive samples over the tick period P (clocks), one tick
//     behind the samples.
//
// Exactness. Per axis q = floor(sample * 2^F / 2^shift) (F = FracBits; the
// step position with F fraction bits; floor(q / 2^F) = floor(sample /
// 2^shift)). An interval from q0 to q1 runs P clocks with D = q1 - q0 and a
// remainder r: it starts with r = frac(q0) * P (frac = the low F bits), and
// every clock r += D, with one step up when r reaches T = P * 2^F (r -= T)
// or one step down when r drops below 0 (r += T). After P clocks
// r = frac(q0) * P + P * D - T * steps, so steps = floor(q1 / 2^F) -
// floor(q0 / 2^F) exactly (r stays in [0, T); |D| <= T: at most one step per
// clock). Restarting r from frac(q0) * P at every interval (an F-cycle
// shift-and-add product) keeps it exact also when P changes between ticks.
//
// Per sample (the prep sequencer, all axes together): 64 clocks shift
// (sample * 2^F >>> shift, one bit per clock while the count is below the
// axis's shift), 1 clock difference, F clocks product, 1 clock for D -/+ T:
// kPrepClocks = 66 + F. The interval starts when the previous one ends (or at
// once when none runs): with ticks every P >= kPrepClocks + 1 clocks the
// intervals follow each other with no gap and a constant latency. The first
// sample after reset only sets the position (no steps).
//
// Pulses. A signed per-axis count `due` collects the DDA's steps; the pulse
// generator emits them one at a time: step high for pulse_i clocks, low for
// pulse_i clocks; a direction change waits setup_i clocks after the last
// step's falling edge (hold), changes dir, and waits setup_i + 1 clocks
// (setup) before the next rising edge. The direction turns as soon as the
// DDA runs an interval the other way with nothing due (so the setup time
// usually passes before the first step of the new direction is due).
// dir_o = 1: steps count up (positive direction).
//
// err_o (sticky until reset): a sample arrived while the previous one was
// still being prepared; a difference D wider than DeltaWidth; more than one
// step per clock (|D| > T); `due` overflow (the pulses cannot keep up with
// the samples: lower pulse_i or the speed).
`default_nettype none
`include "traj_check.svh"

module traj_step_gen #(
  parameter int Axes        = 3,   // 1..8
  parameter int OutWidth    = 48,  // sample width, 8..64
  parameter int FracBits    = 8,   // step fraction bits of the chord, 1..16
  parameter int PeriodWidth = 24,  // tick period width (clocks), 8..32
  parameter int DeltaWidth  = 32,  // per-tick difference, step units * 2^F, 8..PeriodWidth+FracBits+1
  parameter int DueWidth    = 16,  // steps waiting for their pulse, 4..32
  parameter int TimeWidth   = 16   // pulse width and setup counters, 2..16
) (
  input  logic                     clk_i,
  input  logic                     rst_ni,
  // configuration (constant while samples come)
  input  logic [Axes*6-1:0]        shift_i,    // axis a: one step = 2^shift LSB
  input  logic [PeriodWidth-1:0]   period_i,   // tick period in clocks (latched per sample)
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
  localparam int QW = OutWidth + F;           // q before and after the shift
  localparam int RW = PeriodWidth + F + 2;    // remainder, D and D -/+ T, signed
  localparam int FW = (F > 1) ? $clog2(F) : 1;

  `TRAJ_PARAM_CHECK(g_bad_axes, Axes >= 1 && Axes <= 8, "traj_step_gen: Axes must be 1..8")
  `TRAJ_PARAM_CHECK(g_bad_out, OutWidth >= 8 && OutWidth <= 64, "traj_step_gen: OutWidth must be 8..64")
  `TRAJ_PARAM_CHECK(g_bad_frac, FracBits >= 1 && FracBits <= 16, "traj_step_gen: FracBits must be 1..16")
  `TRAJ_PARAM_CHECK(g_bad_period, PeriodWidth >= 8 && PeriodWidth <= 32,
                    "traj_step_gen: PeriodWidth must be 8..32")
  `TRAJ_PARAM_CHECK(g_bad_delta, DeltaWidth >= 8 && DeltaWidth <= PeriodWidth + FracBits + 1 && DeltaWidth <= QW,
                    "traj_step_gen: DeltaWidth must be 8..PeriodWidth+FracBits+1 (and <= OutWidth+FracBits)")
  `TRAJ_PARAM_CHECK(g_bad_due, DueWidth >= 4 && DueWidth <= 32, "traj_step_gen: DueWidth must be 4..32")
  `TRAJ_PARAM_CHECK(g_bad_time, TimeWidth >= 2 && TimeWidth <= 16, "traj_step_gen: TimeWidth must be 2..16")

  // ---------------------------------------------------------------------
  // Prep sequencer (shared by all axes).
  // ---------------------------------------------------------------------
  typedef enum logic [2:0] {SqIdle, SqShift, SqDiff, SqMul, SqAlt} sq_e;
  sq_e                  sq_q;
  logic [5:0]           scnt_q;     // shift clock 0..63
  logic [FW-1:0]        mcnt_q;     // product clock 0..F-1
  logic                 first_q;    // no sample since reset: the next one sets the position
  logic                 nready_q;   // the next interval's operands are ready
  logic [PeriodWidth-1:0] nper_q;   // its period
  logic [RW-1:0]        nt_q;       // its T = P * 2^F
  // DDA (shared interval counter)
  logic                 active_q, last_q;  // last_q == (cnt_q == 1)
  logic [PeriodWidth-1:0] cnt_q;
  logic                 en_q, err_q;

  logic take, load, err_in;
  assign take = sample_valid_i && (sq_q == SqIdle) && !nready_q;
  assign load = nready_q && (!active_q || last_q);

  logic [Axes-1:0] err_axis;
  assign err_in = (sample_valid_i && !take) || (|err_axis);

  always_ff @(posedge clk_i) begin
    if (!rst_ni) begin
      sq_q     <= SqIdle;
      scnt_q   <= '0;
      mcnt_q   <= '0;
      first_q  <= 1'b1;
      nready_q <= 1'b0;
      active_q <= 1'b0;
      last_q   <= 1'b0;
      cnt_q    <= '0;
      en_q     <= 1'b0;
      err_q    <= 1'b0;
    end else begin
      en_q  <= enable_i;
      err_q <= err_q || err_in;
      case (sq_q)
        SqIdle:  if (take) begin sq_q <= SqShift; scnt_q <= '0; end
        SqShift: if (scnt_q == 6'd63) sq_q <= SqDiff; else scnt_q <= scnt_q + 1'b1;
        SqDiff:  begin
                   first_q <= 1'b0;
                   sq_q    <= first_q ? SqIdle : SqMul;
                   mcnt_q  <= '0;
                 end
        SqMul:   if (mcnt_q == FW'(F - 1)) sq_q <= SqAlt; else mcnt_q <= mcnt_q + 1'b1;
        SqAlt:   begin sq_q <= SqIdle; nready_q <= 1'b1; end
        default: sq_q <= SqIdle;
      endcase
      if (load) begin
        nready_q <= 1'b0;
        active_q <= 1'b1;
        cnt_q    <= nper_q;
        last_q   <= (nper_q == PeriodWidth'(1));
      end else if (active_q) begin
        cnt_q    <= cnt_q - 1'b1;
        last_q   <= (cnt_q == PeriodWidth'(2));
        if (last_q) active_q <= 1'b0;
      end
    end
  end

  // the next interval's period and T, latched with the difference
  always_ff @(posedge clk_i) begin
    if (sq_q == SqDiff) begin
      nper_q <= period_i;
      nt_q   <= {{(RW-PeriodWidth-F){1'b0}}, period_i, {F{1'b0}}};
    end
  end

  // ---------------------------------------------------------------------
  // Per axis: shift, difference, product, DDA, pulses.
  // ---------------------------------------------------------------------
  typedef enum logic [1:0] {PgIdle, PgSetup, PgHigh, PgLow} pg_e;

  for (genvar a = 0; a < Axes; a++) begin : g_axis
    logic [5:0]           shift;
    logic [QW-1:0]        sh_q;      // sample * 2^F, then shifted: q
    logic [QW-1:0]        qprev_q;   // q of the previous sample
    logic [F-1:0]         frac_q;    // frac(q_prev), consumed by the product from the top
    logic [RW-1:0]        nd_q, nr_q, nalt_q;  // next interval: D, r start, D -/+ T
    logic [RW-1:0]        d_q, alt_q, r_q;     // running interval
    logic                 dpos_q;    // running interval's D >= 0
    logic [DueWidth-1:0]  due_q;
    pg_e                  pg_q;
    logic [TimeWidth-1:0] timer_q;
    logic [TimeWidth-1:0] since_q;   // clocks since the last falling step edge (saturating)
    logic                 step_q, dir_q;
    logic                 err_d;

    assign shift = shift_i[a*6 +: 6];

    // difference (QW bits) and its fit in DeltaWidth
    logic [QW-1:0] diff;
    logic          fits;
    assign diff = sh_q - qprev_q;
    if (QW > DeltaWidth) begin : g_fit
      assign fits = (diff[QW-1:DeltaWidth-1] == '0) || (diff[QW-1:DeltaWidth-1] == '1);
    end else begin : g_fit_all
      assign fits = 1'b1;
    end

    always_ff @(posedge clk_i) begin
      if (take) begin
        sh_q <= {sample_i[a*OutWidth +: OutWidth], {F{1'b0}}};
      end else if (sq_q == SqShift && scnt_q < shift) begin
        sh_q <= {sh_q[QW-1], sh_q[QW-1:1]};
      end
      if (sq_q == SqDiff) begin
        qprev_q <= sh_q;
        frac_q  <= qprev_q[F-1:0];
        nd_q    <= {{(RW-DeltaWidth){diff[DeltaWidth-1]}}, diff[DeltaWidth-1:0]};
        nr_q    <= '0;
      end else if (sq_q == SqMul) begin
        nr_q   <= {nr_q[RW-2:0], 1'b0} + (frac_q[F-1] ? RW'(nper_q) : '0);
        frac_q <= {frac_q[F-2:0], 1'b0};
      end else if (sq_q == SqAlt) begin
        nalt_q <= nd_q[RW-1] ? nd_q + nt_q : nd_q - nt_q;
      end
    end

    // DDA: one step at most per clock
    logic [RW-1:0] sum_d, sum_alt;
    logic          up, down;
    assign sum_d   = r_q + d_q;
    assign sum_alt = r_q + alt_q;
    assign up      = active_q && dpos_q && !sum_alt[RW-1];
    assign down    = active_q && !dpos_q && sum_d[RW-1];

    always_ff @(posedge clk_i) begin
      if (load) begin
        d_q    <= nd_q;
        alt_q  <= nalt_q;
        r_q    <= nr_q;
        dpos_q <= !nd_q[RW-1];
      end else if (active_q) begin
        r_q <= (up || down) ? sum_alt : sum_d;
      end
    end

    // pulses
    logic want_dir, turn, emit;
    logic [DueWidth-1:0] due_d;
    assign want_dir = (due_q != '0) ? !due_q[DueWidth-1]
                    : ((active_q && d_q != '0) ? dpos_q : dir_q);
    assign turn = (pg_q == PgIdle) && (want_dir != dir_q) && (since_q >= setup_i);
    assign emit = (pg_q == PgIdle) && (due_q != '0) && (want_dir == dir_q);
    assign due_d = due_q + DueWidth'(up) - DueWidth'(down)
                 - (emit ? (dir_q ? DueWidth'(1) : '1) : '0);

    always_ff @(posedge clk_i) begin
      if (!rst_ni) begin
        due_q   <= '0;
        pg_q    <= PgIdle;
        timer_q <= '0;
        since_q <= '1;
        step_q  <= 1'b0;
        dir_q   <= 1'b1;
      end else begin
        due_q <= due_d;
        if (since_q != '1) since_q <= since_q + 1'b1;
        case (pg_q)
          PgIdle:  if (turn) begin
                     dir_q   <= want_dir;
                     timer_q <= setup_i;
                     pg_q    <= PgSetup;
                   end else if (emit) begin
                     step_q  <= 1'b1;
                     timer_q <= pulse_i - 1'b1;
                     pg_q    <= PgHigh;
                   end
          PgSetup: if (timer_q == '0) pg_q <= PgIdle; else timer_q <= timer_q - 1'b1;
          PgHigh:  if (timer_q == '0) begin
                     step_q  <= 1'b0;
                     since_q <= '0;
                     timer_q <= pulse_i - 1'b1;
                     pg_q    <= PgLow;
                   end else begin
                     timer_q <= timer_q - 1'b1;
                   end
          PgLow:   if (timer_q == '0) pg_q <= PgIdle; else timer_q <= timer_q - 1'b1;
          default: pg_q <= PgIdle;
        endcase
      end
    end

    // errors: D too wide, more than one step per clock, due overflow
    logic too_fast, due_ovf;
    assign too_fast = load && (nd_q[RW-1] ? nalt_q[RW-1] : !nalt_q[RW-1] && nalt_q != '0);
    // |due| >= 2^(DueWidth-2): flagged before it can wrap (it moves by <= 2 per clock)
    assign due_ovf  = (due_d[DueWidth-1] != due_d[DueWidth-2]);
    assign err_d = (sq_q == SqDiff && !first_q && !fits) || too_fast || due_ovf;
    assign err_axis[a] = err_d;

    assign step_o[a] = step_q;
    assign dir_o[a]  = dir_q;
  end

  assign enable_o = en_q;
  assign err_o    = err_q;

endmodule

`default_nettype wire
