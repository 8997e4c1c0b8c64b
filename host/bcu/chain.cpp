// SPDX-License-Identifier: Apache-2.0
#include "bcu/chain.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace traj::bcu {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("traj::bcu: " + what); }

mpz_class pow2(int e) {
  mpz_class r = 1;
  r <<= e;
  return r;
}

// floor(v 2^e) for any sign of e (exact).
mpz_class shift_floor(const mpz_class& v, int e) {
  mpz_class r;
  if (e >= 0) {
    mpz_mul_2exp(r.get_mpz_t(), v.get_mpz_t(), e);
  } else {
    mpz_fdiv_q_2exp(r.get_mpz_t(), v.get_mpz_t(), -e);
  }
  return r;
}

// 2^(G-1) for G > 0, else 0: the generator's rounding half at t = 0 and 1.
mpz_class half_of(int g) { return g > 0 ? pow2(g - 1) : mpz_class(0); }

void check_compatible(const EndState& prev, int axes, int frac_bits, const char* to) {
  if (prev.v.empty()) fail(std::string("no previous segment to chain the ") + to + " segment onto");
  if (static_cast<int>(prev.v.size()) != axes) {
    std::ostringstream m;
    m << "previous segment has " << prev.v.size() << " axes, the " << to << " format " << axes;
    fail(m.str());
  }
  if (prev.frac_bits != frac_bits) {
    std::ostringstream m;
    m << "previous segment's output LSB is 2^-" << prev.frac_bits << ", the " << to << " format's 2^-"
      << frac_bits << ": chaining needs one output LSB";
    fail(m.str());
  }
}

}  // namespace

int64_t EndState::sample(int a) const {
  mpz_class s = v[a];
  if (kind == Kind::kBcu) s += half_of(guard_bits);
  mpz_fdiv_q_2exp(s.get_mpz_t(), s.get_mpz_t(), guard_bits);
  if (!s.fits_slong_p()) fail("end sample does not fit 64 bits");
  return s.get_si();
}

EndState end_of(const fd::Compiled& c, const fd::Format& f) {
  EndState e;
  e.kind = Kind::kFd;
  e.guard_bits = f.guard_bits;
  e.frac_bits = f.frac_bits;
  e.v = c.end;
  // Q(K) in output LSB: the register error at k = K (the carried start error is 0 there)
  const mpq_class q(fd::Compiler::quant_bound_x2(f.degree, c.ticks), pow2(f.guard_bits + 1));
  e.err_lsb = q.get_d();
  return e;
}

EndState end_of(const Segment& s) {
  EndState e;
  e.kind = Kind::kBcu;
  e.guard_bits = s.guard_bits;
  e.frac_bits = s.frac_bits;
  for (const auto& row : s.ctrl) e.v.push_back(row[3]);
  for (const auto& o : s.end_offset) e.err_lsb = std::max(e.err_lsb, std::fabs(o.get_d()));
  return e;
}

std::vector<mpz_class> bcu_start(const EndState& prev, const Format& f) {
  check_compatible(prev, f.axes, f.frac_bits, "BCU");
  std::vector<mpz_class> c(prev.v.size());
  for (size_t a = 0; a < c.size(); ++a) {
    if (prev.kind == Kind::kFd) {
      // c_A = floor(E 2^Gb / 2^Gf) - h: floor((c_A + h) / 2^Gb) = floor(E / 2^Gf)
      c[a] = shift_floor(prev.v[a], f.guard_bits - prev.guard_bits) - half_of(f.guard_bits);
    } else {
      // c_A = floor((c_D + h_prev) 2^Gb / 2^Gprev) - h; = c_D for one BCU format
      c[a] = shift_floor(prev.v[a] + half_of(prev.guard_bits), f.guard_bits - prev.guard_bits) -
             half_of(f.guard_bits);
    }
  }
  return c;
}

std::vector<mpz_class> fd_start(const EndState& prev, const fd::Format& f) {
  check_compatible(prev, f.axes, f.frac_bits, "FD");
  std::vector<mpz_class> r(prev.v.size());
  for (size_t a = 0; a < r.size(); ++a) {
    if (prev.kind == Kind::kFd) {
      if (prev.guard_bits != f.guard_bits) {
        std::ostringstream m;
        m << "FD -> FD across formats (guard bits " << prev.guard_bits << " -> " << f.guard_bits
          << ") is not supported";
        fail(m.str());
      }
      r[a] = prev.v[a];
    } else {
      // r0 = floor(c_D 2^Gf / 2^Gb) + 2^(Gf-1): floor(r0 / 2^Gf) = floor(c_D / 2^Gb + 1/2)
      r[a] = shift_floor(prev.v[a], f.guard_bits - prev.guard_bits) + pow2(f.guard_bits - 1);
    }
  }
  return r;
}

Segment compile_segment_after(const EndState& prev, const Controls& b, int depth, const Format& f,
                              const std::string& where, double jump_tol_lsb) {
  f.validate();
  std::vector<mpz_class> start;
  Segment s;
  try {
    start = bcu_start(prev, f);
    s = compile_segment(b, depth, f, start);
  } catch (const std::invalid_argument& e) {
    std::string w = e.what();
    const std::string pre = "traj::bcu: ";
    if (w.compare(0, pre.size(), pre) == 0) w = w.substr(pre.size());
    fail(where + ": " + w);
  }
  const double allowed = prev.err_lsb + std::ldexp(1.0, -f.guard_bits) + jump_tol_lsb;
  for (int a = 0; a < f.axes; ++a) {
    const double off = std::fabs(s.offset[a].get_d());
    if (!(off <= allowed)) {
      std::ostringstream m;
      m.precision(6);
      m << where << ": axis " << a << " starts " << off << " LSB away from its control point b0 = " << b(a, 0)
        << " (more than the previous end's error " << prev.err_lsb << " + grid 2^-" << f.guard_bits
        << " + jump tolerance " << jump_tol_lsb << " LSB): the path is not continuous here";
      fail(m.str());
    }
  }
  return s;
}

fd::PolySegment fd_poly_of_bezier(const Controls& b, uint64_t K, double h, uint64_t k0, uint64_t k1) {
  if (k1 == 0) k1 = K;
  fd::PolySegment seg;
  seg.h = h;
  seg.ticks = k1 - k0;
  const double u0 = static_cast<double>(k0) / static_cast<double>(K);
  const double sc = 1.0 / (static_cast<double>(K) * h);  // du/dt
  for (int a = 0; a < b.rows(); ++a) {
    const double p[4] = {b(a, 0), 3 * (b(a, 1) - b(a, 0)), 3 * (b(a, 0) - 2 * b(a, 1) + b(a, 2)),
                         b(a, 3) - 3 * b(a, 2) + 3 * b(a, 1) - b(a, 0)};
    // sum_j p_j (u0 + sc t)^j = sum_m t^m sc^m sum_{j>=m} p_j C(j,m) u0^(j-m)
    std::vector<double> c(4, 0.0);
    static const double C[4][4] = {{1, 0, 0, 0}, {1, 1, 0, 0}, {1, 2, 1, 0}, {1, 3, 3, 1}};
    for (int m = 0; m < 4; ++m) {
      double v = 0, up = 1;
      for (int j = m; j < 4; ++j) {
        v += p[j] * C[j][m] * up;
        up *= u0;
      }
      c[m] = v * std::pow(sc, m);
    }
    seg.coef.push_back(c);
  }
  return seg;
}

double MixedChain::Piece::bound_lsb(int a, uint64_t k) const {
  if (kind == Kind::kFd) return 0.5 + fd.bound_lsb;
  return bcu.exact_bound_lsb(a, static_cast<int>(k));
}

MixedChain::MixedChain(const fd::Format& ff, const Format& bf) : fdc_(ff), bf_(bf) {
  bf_.validate();
  std::ostringstream m;
  if (ff.axes != bf.axes) m << "FD format has " << ff.axes << " axes, BCU format " << bf.axes;
  else if (ff.frac_bits != bf.frac_bits)
    m << "output LSBs differ: FD frac_bits " << ff.frac_bits << ", BCU frac_bits " << bf.frac_bits;
  else if (ff.out_width() != bf.out_width)
    m << "sample widths differ: FD width - guard_bits = " << ff.out_width() << ", BCU out_width " << bf.out_width
      << " (traj_core has one sample port)";
  else if (ff.chunk_width != bf.chunk_width)
    m << "word widths differ: FD chunk_width " << ff.chunk_width << ", BCU chunk_width " << bf.chunk_width
      << " (traj_core has one word stream)";
  else
    return;
  fail("MixedChain: " + m.str());
}

const MixedChain::Piece& MixedChain::add_fd(const fd::PolySegment& s, const std::string& where) {
  Piece p;
  p.kind = Kind::kFd;
  std::vector<mpz_class> st;
  if (!pieces_.empty()) st = fd_start(end_, fdc_.format());
  p.fd = fdc_.compile(s, pieces_.empty() ? nullptr : &st, where);
  p.ticks = p.fd.ticks;
  p.words = fdc_.words(p.fd);
  // exact samples k = 0..K by the engine's own recurrence on exact integers,
  // r0 reduced to Width bits as the engine holds it (r[1..N] may have wrapped)
  const int A = fdc_.format().axes, N = fdc_.format().degree, G = fdc_.format().guard_bits;
  p.samples.assign(p.ticks + 1, std::vector<int64_t>(A));
  for (int a = 0; a < A; ++a) {
    std::vector<mpz_class> r = p.fd.regs[a];
    mpz_class s0;
    for (uint64_t k = 0; k <= p.ticks; ++k) {
      s0 = r[0];
      fd::wrap_to_width(s0, fdc_.format().width);
      mpz_fdiv_q_2exp(s0.get_mpz_t(), s0.get_mpz_t(), G);
      p.samples[k][a] = s0.get_si();
      for (int i = 0; i < N; ++i) r[i] += r[i + 1];
    }
  }
  end_ = end_of(p.fd, fdc_.format());
  pieces_.push_back(std::move(p));
  return pieces_.back();
}

int MixedChain::add_fd_bezier(const Controls& b, uint64_t K, double h, const std::string& where, int min_pieces) {
  const fd::Format& f = fdc_.format();
  uint64_t kmax = fd::Compiler::longest_segment(f.degree, f.guard_bits, f.tol_lsb);
  kmax = std::min<uint64_t>(kmax, f.max_ticks);
  if (kmax == 0) throw fd::CompileError(where + ": the FD format admits no segment at all");
  uint64_t n = std::max<uint64_t>(static_cast<uint64_t>(std::max(min_pieces, 1)), (K + kmax - 1) / kmax);
  if (n > K) n = K;
  for (uint64_t p = 0; p < n; ++p) {
    const uint64_t k0 = K * p / n, k1 = K * (p + 1) / n;
    add_fd(fd_poly_of_bezier(b, K, h, k0, k1), n > 1 ? where + " piece " + std::to_string(p) : where);
  }
  return static_cast<int>(n);
}

const MixedChain::Piece& MixedChain::add_bcu(const Controls& b, int depth, const std::string& where) {
  Piece p;
  p.kind = Kind::kBcu;
  if (pieces_.empty()) {
    try {
      p.bcu = compile_segment(b, depth, bf_);
    } catch (const std::invalid_argument& e) {
      std::string w = e.what();
      const std::string pre = "traj::bcu: ";
      if (w.compare(0, pre.size(), pre) == 0) w = w.substr(pre.size());
      fail(where + ": " + w);
    }
  } else {
    p.bcu = compile_segment_after(end_, b, depth, bf_, where);
  }
  p.ticks = 1u << depth;
  p.words = p.bcu.words;
  p.samples = p.bcu.samples;
  end_ = end_of(p.bcu);
  pieces_.push_back(std::move(p));
  return pieces_.back();
}

}  // namespace traj::bcu
