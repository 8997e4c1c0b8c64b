// SPDX-License-Identifier: Apache-2.0
// A segment stream re-compiled at a finer engine tick: every tick of the
// stream becomes n engine ticks.
//
// Why: the board's step generator (rtl/traj_step_gen.sv) places each step
// edge on a quadratic through the engine's last three samples; its error
// against the polynomial grows as h^3 (tb/board/bench_step_timing: 4.4 us at
// h = 1 ms, 25 us at 2 ms). A stream planned at a longer tick is therefore
// played with its tick split into n = ceil(h / 1 ms) engine ticks, so that
// the edges keep within 10 us whatever the stream's tick period
// (`trajcore upload`, and `trajcore board --expect` for its prediction).
//
// How, exactly. A coarse FD record is the engine's exact polynomial
//     P(k) = sum_i d_i C(k, i)    (register units, k in coarse ticks, real),
// with d_i its forward differences, recovered from the engine states at
// k = 0..N when K >= N (so a register the compiler wrapped to Width bits does
// not matter). A segment shorter than the degree has fewer states than
// differences: its registers r[K+1..N] are taken as read, and refused
// (StreamError) if any is at least 2^(W-3) in magnitude, since a register the
// compiler wrapped (true value beyond 2^(W-1)) then cannot be told from one
// it did not: its path between ticks is not known. That takes ticks far
// beyond the board's use: r[5] = 120 c5 h^5 2^(G+F) reaches 2^93 at the main
// job's format only for a fifth-order term of 68 mm within one tick (the
// butterfly at 1 s ticks does it; at 10 ms every term is below 2 mm). A
// wrapped register whose true value lies within 2^(W-3) of a nonzero multiple
// of 2^W would pass unnoticed; the same argument keeps it out of reach. Its nK fine ticks become one
// or more fine segments (at most fd::Compiler::longest_segment ticks each,
// split as evenly as possible), each compiled by fd::Compiler::compile_target
// from the exact target q(m) = P(k0 + m/n): no double anywhere. The first
// fine segment starts at the coarse stream's first state; every later one
// starts at the exact end of the previous fine segment (no drift), its
// carried error blended out as the compiler does for every segment.
//
// Bound. Every fine register state is within |e0| + Q(L) <= tol (the
// format's budget, 1/2 output LSB) of P at that instant. At the coarse ticks
// (fine tick n k) P is the coarse engine's exact state, so the fine engine's
// output sample there differs from the coarse stream's by at most 1 LSB; in
// between it follows the coarse polynomial itself, which is within the
// coarse compile's bound of the planned path (|C(k,i)| <= max(1, C(K,i)) for
// real k in [0, K]). tb/host/retick_test.cpp checks both exactly.
#pragma once
#include <cstdint>
#include <vector>

#include "fd/fd_compiler.hpp"
#include "stream/segment_stream.hpp"

namespace traj::stream {

// The longest engine tick the board's step timing is measured for (10 us).
constexpr double kMaxStepEngineTick = 1e-3;

// ceil(period / max_engine_tick) (1 when the stream's tick is short enough);
// max_engine_tick <= 0: 1 (play at the stream's tick).
uint32_t engine_ticks_per_tick(double period, double max_engine_tick = kMaxStepEngineTick);

class Reticker {
 public:
  // `coarse`: the stream's header (FD only: a BCU format is refused); n >= 1.
  Reticker(const Header& coarse, uint32_t n);
  // The fine stream's header: the same format at period / n.
  const Header& header() const { return fine_; }
  uint32_t n() const { return n_; }
  // Appends the fine records of `r`, the next FD record of the coarse stream
  // (as a StreamReader accepts it: in order and continuous), numbered on
  // from the last. Throws StreamError naming the coarse segment if a fine
  // segment cannot be compiled (the message says which and why).
  void add(const Record& r, std::vector<Record>& out);
  // Largest register error bound of the fine segments so far, output LSB.
  double bound_lsb() const { return bound_lsb_; }

 private:
  std::vector<mpq_class> coarse_polynomial(const Record& r, int axis) const;
  Header fine_;
  uint32_t n_;
  fd::Compiler compiler_;
  uint64_t longest_ = 0;  // longest fine segment the format's budget allows
  std::vector<mpz_class> end_;  // exact state where the last fine segment ends
  uint32_t seq_ = 0;
  double bound_lsb_ = 0;
};

// A whole stream re-ticked (the board check's prediction). `coarse` must be
// complete.
ReadResult retick(const ReadResult& coarse, uint32_t n);

}  // namespace traj::stream
