// SPDX-License-Identifier: Apache-2.0
// traj::bcu chaining across segment kinds: forward-difference segments
// (traj::fd::Compiler, traj_fd_engine) and BCU segments (traj::bcu, traj_bcu_gen)
// played one after the other by traj_core (one stream, tuser = kind).
//
// Guarantee: at every hand-off the first sample of the new segment equals,
// bit for bit, the end sample of the previous one (the sample it would emit at
// k = K, t = 1). Both hand-offs are integer maps of the previous segment's
// exact end state; no double is involved. Grids (one output LSB = 2^-F units
// for both kinds; checked):
//   FD register r0 : 1 LSB = 2^-Gf output LSB, r0 holds (x 2^F + 1/2) 2^Gf,
//                    the engine emits floor(r0 / 2^Gf);
//   BCU control c  : 1 LSB = 2^-Gb output LSB, c holds x 2^F 2^Gb,
//                    the generator emits floor(c / 2^Gb + 1/2) at t = 0 and 1.
//
// FD -> BCU. E = the FD segment's exact end state (fd::Compiled::end). The BCU
// segment's A control value is
//     c_A = floor(E 2^Gb / 2^Gf) - h,   h = 2^(Gb-1) (Gb > 0), 0 (Gb = 0),
// so floor((c_A + h) / 2^Gb) = floor(floor(E 2^(Gb-Gf)) / 2^Gb) = floor(E / 2^Gf):
// the BCU's first sample IS the FD end sample (exact for any Gf, Gb).
// What enters the BCU bound is the start offset (Segment::offset, exact)
//     delta = c_A / 2^Gb - b0 2^F                           (output LSB)
// with the weight B0(t) = (1-t)^3 (Segment::exact_bound_lsb):
//     |s_j - x(t_j) 2^F| <= 1/2 + B0 |delta| + (1 - B0) 2^-(Gb+1).
// Where delta comes from: E = q(T) + eps_E with the FD target at the end
// q(T) = x_fd(T) 2^(F+Gf) + 2^(Gf-1) (the carried start error is blended out
// to 0 at t = T) and |eps_E| <= Q(K) 2^Gf (fd_compiler.hpp, Q in output LSB);
// floor(E 2^(Gb-Gf)) / 2^Gb = E / 2^Gf - phi with 0 <= phi <= 2^-Gb - 2^-Gf
// (phi = 0 when Gb >= Gf). Hence, for Gb > 0,
//     delta = Delta + eps_E / 2^Gf - phi,   Delta = (x_fd(T) - b0) 2^F,
//     Delta - Q(K) - (2^-Gb - 2^-Gf) <= delta <= Delta + Q(K),
// so |delta| <= Q(K) + 2^-Gb + |Delta|, where Delta is only the difference of
// the two pieces' own double descriptions at the joint (0 for a path that is
// G0 in exact arithmetic; ~1e-8 LSB after a power-basis conversion in
// double). At the default FD tol = 0.5 LSB, Q(K) <= 0.25 and Gb = 9:
// |delta| <= 0.252 LSB + |Delta|; the first BCU sample is exact (the FD end
// sample), the offset fades out as (1-t)^3, and the BCU's own end c_D is
// round(b3 2^(F+Gb)) again: nothing is carried further (no drift).
// (tb/core/mixed_chain_test.cpp checks every step of this in exact rationals.)
//
// BCU -> FD. c_D = the BCU segment's exact end control value. The FD start is
//     r0 = floor(c_D 2^Gf / 2^Gb) + 2^(Gf-1)
// so floor(r0 / 2^Gf) = floor((c_D 2^-Gb + 1/2)) (nested floors of integers):
// the FD's first sample IS the BCU end value round(D), exact for any Gf >= 1,
// Gb. fd::Compiler::compile takes r0 as its start: its carried error
// e0 = r0 - q(0) is, in output LSB, within (c_D 2^-Gb - b3 2^F) + (b3 - x_fd(0)) 2^F
// (+ 2^-Gf when Gb > Gf), i.e. <= 2^-(Gb+1) + |Delta| (<= 2^-10 at Gb = 9),
// well inside the compiler's tol/2, and blended out over the FD segment as
// for any FD start (fd_compiler.hpp). With Gb = 0 the BCU end may be 1/2 LSB
// from the curve, more than the FD compiler's default tol/2 = 0.25 accepts:
// BCU -> FD then needs Gb >= 1 (or a larger FD tol).
//
// Same kind: FD -> FD r0 = E (as fd::Compiler always did); BCU -> BCU c_A = c_D.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "bcu/bcu_compiler.hpp"
#include "fd/fd_compiler.hpp"

namespace traj::bcu {

enum class Kind : uint8_t { kFd = 0, kBcu = 1 };  // == traj_core's tuser

// The exact end of a compiled segment, on its engine's grid.
struct EndState {
  Kind kind = Kind::kFd;
  int guard_bits = 0;          // grid: 1 LSB = 2^-guard_bits output LSB (Gf or Gb)
  int frac_bits = 0;           // F: output LSB = 2^-F units
  std::vector<mpz_class> v;    // per axis: FD r0 after K ticks; BCU c_D
  double err_lsb = 0;          // bound on |state - its own target| in output LSB
                               // (FD: Q(K); BCU: |c_D 2^-Gb - b3 2^F|, exact)
  // The end sample of axis a: what the engine would emit at k = K (t = 1).
  int64_t sample(int a) const;
};

EndState end_of(const fd::Compiled& c, const fd::Format& f);
EndState end_of(const Segment& s);  // (Segment carries its G and F)

// The hand-off maps (header comment). Throw std::invalid_argument if the
// output LSBs differ (frac_bits) or the axis counts differ.
std::vector<mpz_class> bcu_start(const EndState& prev, const Format& f);     // c_A per axis
std::vector<mpz_class> fd_start(const EndState& prev, const fd::Format& f);  // r0 per axis

// A BCU segment starting exactly at `prev`'s end. Refuses (std::invalid_argument
// naming `where` and the axis) a start farther from b0 than
// prev.err_lsb + 2^-Gb + jump_tol_lsb output LSB: the pieces do not meet there
// (a jump in the path, not a rounding).
Segment compile_segment_after(const EndState& prev, const Controls& b, int depth, const Format& f,
                              const std::string& where = "segment", double jump_tol_lsb = 1.0 / 64);

// The FD time polynomial of a cubic Bezier traversed with u linear in time
// over K ticks of h seconds, restricted to ticks k0..k1 (k1 = 0: K):
// coefficients of t^0..t^3 per axis, t in seconds from tick k0, of
// x(k0/K + t/(K h)) (power basis and composition computed in double).
fd::PolySegment fd_poly_of_bezier(const Controls& b, uint64_t K, double h, uint64_t k0 = 0, uint64_t k1 = 0);

// A chain of mixed segments compiled back to back, each starting exactly at
// the previous one's end. Checks at construction that the two formats can be
// chained: same axes and frac_bits (one output LSB), same output width and
// chunk width (one sample port, one word stream: traj_core).
class MixedChain {
 public:
  struct Piece {
    Kind kind = Kind::kFd;
    uint32_t ticks = 0;                          // K
    fd::Compiled fd;                             // kind FD
    Segment bcu;                                 // kind BCU
    std::vector<uint64_t> words;                 // the engine's stream words (tuser = kind)
    std::vector<std::vector<int64_t>> samples;   // [k][axis], k = 0..K (k = K: end sample)
    // Error bound of sample k against the exact polynomial of this piece's
    // input (FD: its power-basis coefficients; BCU: its Bezier controls), in
    // output LSB: FD 1/2 + fd.bound_lsb (fd_compiler.hpp), BCU
    // bcu.exact_bound_lsb(a, k).
    double bound_lsb(int a, uint64_t k) const;
  };

  MixedChain(const fd::Format& ff, const Format& bf);
  const fd::Compiler& fd_compiler() const { return fdc_; }
  const Format& bcu_format() const { return bf_; }

  // Append a segment (the first starts from its own value). Throws
  // fd::CompileError / std::invalid_argument naming `where`.
  const Piece& add_fd(const fd::PolySegment& s, const std::string& where = "segment");
  const Piece& add_bcu(const Controls& b, int depth, const std::string& where = "segment");
  // A cubic Bezier on K ticks of h seconds as FD segments: split into at least
  // `min_pieces` pieces, and into as many more as the FD format needs (each at
  // most fd::Compiler::longest_segment and max_ticks ticks). Returns the number
  // of pieces appended; piece p covers ticks [K p/n, K (p+1)/n) of the curve.
  int add_fd_bezier(const Controls& b, uint64_t K, double h, const std::string& where = "segment",
                    int min_pieces = 1);

  const std::vector<Piece>& pieces() const { return pieces_; }
  bool empty() const { return pieces_.empty(); }
  const EndState& end() const { return end_; }  // valid if !empty()

 private:
  fd::Compiler fdc_;
  Format bf_;
  std::vector<Piece> pieces_;
  EndState end_;
};

}  // namespace traj::bcu
