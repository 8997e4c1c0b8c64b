// SPDX-License-Identifier: Apache-2.0
#include "bcu/bcu_compiler.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace traj::bcu {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("traj::bcu: " + what);
}

mpz_class pow2(int e) {
  mpz_class r = 1;
  r <<= e;
  return r;
}

}  // namespace

double de_casteljau(const double b[4], double t) {
  const double u = 1.0 - t;
  double p0 = u * b[0] + t * b[1], p1 = u * b[1] + t * b[2], p2 = u * b[2] + t * b[3];
  p0 = u * p0 + t * p1;
  p1 = u * p1 + t * p2;
  return u * p0 + t * p1;
}

double error_bound(const Format& f, double max_abs) {
  const double eps = std::numeric_limits<double>::epsilon() / 2;  // unit roundoff 2^-53
  return std::ldexp(1.0, -(f.frac_bits + 1)) + std::ldexp(1.0, -(f.frac_bits + f.guard_bits + 1)) +
         8 * eps * max_abs;
}

int64_t predict_sample(const std::vector<mpz_class>& c, int depth, int j, int guard_bits) {
  const mpz_class K = pow2(depth);
  const mpz_class jj = j, kj = K - jj;
  mpz_class n = kj * kj * kj * c[0] + 3 * kj * kj * jj * c[1] + 3 * kj * jj * jj * c[2] +
                jj * jj * jj * c[3];
  const int s = 3 * depth + guard_bits;
  if (s > 0) {
    n += pow2(s - 1);
    mpz_fdiv_q_2exp(n.get_mpz_t(), n.get_mpz_t(), s);  // floor
  }
  if (!n.fits_slong_p()) fail("predicted sample does not fit 64 bits");
  return n.get_si();
}

std::vector<uint64_t> stream_words(const std::vector<std::vector<mpz_class>>& c, int depth,
                                   const Format& f) {
  // Every value is sent pre-scaled by 8^(max_depth - d) (the generator then
  // needs no pre-scaling pass), in nw*chunk_width bits two's complement, and
  // the words are interleaved digit by digit: for each axis, for each digit k
  // (least significant first): digit k of A, B, C, D.
  const int nw = f.words_per_value();
  const int wp = nw * f.chunk_width;
  const mpz_class wmask = pow2(f.chunk_width) - 1;
  std::vector<uint64_t> w;
  w.push_back(static_cast<uint64_t>(depth));
  for (const auto& axis : c) {
    mpz_class v[4];
    for (int i = 0; i < 4; ++i) {
      v[i] = axis[i] * pow2(3 * (f.max_depth - depth));
      if (v[i] < 0) v[i] += pow2(wp);
    }
    for (int k = 0; k < nw; ++k) {
      for (int i = 0; i < 4; ++i) {
        mpz_class word = v[i] & wmask;
        v[i] >>= f.chunk_width;
        uint64_t u = 0;
        mpz_export(&u, nullptr, -1, sizeof(u), 0, 0, word.get_mpz_t());
        w.push_back(u);
      }
    }
  }
  return w;
}

namespace {

// Exact rational of a finite double.
mpq_class exact(double x) {
  mpq_class q;
  mpq_set_d(q.get_mpq_t(), x);
  return q;
}

// 2^e as a rational, any sign of e.
mpq_class pow2q(int e) { return e >= 0 ? mpq_class(pow2(e)) : mpq_class(mpz_class(1), pow2(-e)); }

void check_depth_axes(const Controls& b, int depth, const Format& f) {
  if (depth < 0 || depth > f.max_depth) {
    std::ostringstream m;
    m << "segment depth d = " << depth << " out of range 0.." << f.max_depth
      << " (K = 2^d ticks)";
    fail(m.str());
  }
  if (b.rows() != f.axes) {
    std::ostringstream m;
    m << "segment has " << b.rows() << " axes, format expects " << f.axes;
    fail(m.str());
  }
}

// Integer control values round(b 2^(F+G)) (ties away from zero), range-checked.
std::vector<std::vector<mpz_class>> round_controls(const Controls& b, const Format& f, double& max_abs) {
  const mpz_class lim = pow2(f.ctrl_width - 1);
  max_abs = 0;
  std::vector<std::vector<mpz_class>> ctrl;
  for (int a = 0; a < f.axes; ++a) {
    std::vector<mpz_class> row(4);
    for (int i = 0; i < 4; ++i) {
      const double x = b(a, i);
      std::ostringstream where;
      where << "axis " << a << " control value b" << i;
      if (std::isnan(x)) fail(where.str() + " is NaN");
      if (std::isinf(x)) fail(where.str() + " is infinite");
      max_abs = std::max(max_abs, std::fabs(x));
      // exact: x * 2^(F+G) as a rational, rounded to nearest, ties away from 0
      mpq_class q(x);
      const int e = f.frac_bits + f.guard_bits;
      if (e >= 0) q *= mpq_class(pow2(e));
      else q /= mpq_class(pow2(-e));
      mpz_class r;
      mpq_class aq = abs(q) + mpq_class(1, 2);
      mpz_fdiv_q(r.get_mpz_t(), aq.get_num_mpz_t(), aq.get_den_mpz_t());
      if (q < 0) r = -r;
      if (r >= lim || r < -lim) {
        std::ostringstream m;
        m << where.str() << " = " << x << " out of range: needs |x| < 2^"
          << (f.ctrl_width - 1 - e) << " for ctrl_width " << f.ctrl_width << ", F+G = " << e;
        fail(m.str());
      }
      row[i] = r;
    }
    ctrl.push_back(row);
  }
  return ctrl;
}

// Words, predicted samples, offsets and bounds of integer control values.
Segment finish(std::vector<std::vector<mpz_class>> ctrl, const Controls& b, int depth, const Format& f,
               double max_abs) {
  Segment s;
  s.depth = depth;
  s.ctrl = std::move(ctrl);
  s.guard_bits = f.guard_bits;
  s.frac_bits = f.frac_bits;
  s.words = stream_words(s.ctrl, depth, f);
  const int K = 1 << depth;
  s.samples.assign(K + 1, std::vector<int64_t>(f.axes));
  for (int j = 0; j <= K; ++j)
    for (int a = 0; a < f.axes; ++a) s.samples[j][a] = predict_sample(s.ctrl[a], depth, j, f.guard_bits);
  // offset = c0 2^-G - b0 2^F, exact
  double worst_extra = 0;  // max(0, |offset| - 2^-(G+1)) over the axes
  const double half_grid = std::ldexp(1.0, -(f.guard_bits + 1));
  for (int a = 0; a < f.axes; ++a) {
    mpq_class o = mpq_class(s.ctrl[a][0]) * pow2q(-f.guard_bits) - exact(b(a, 0)) * pow2q(f.frac_bits);
    o.canonicalize();
    s.offset.push_back(o);
    mpq_class e = mpq_class(s.ctrl[a][3]) * pow2q(-f.guard_bits) - exact(b(a, 3)) * pow2q(f.frac_bits);
    e.canonicalize();
    s.end_offset.push_back(e);
    worst_extra = std::max(worst_extra, std::fabs(o.get_d()) - half_grid);
  }
  s.ref_lsb = std::ldexp(8 * (std::numeric_limits<double>::epsilon() / 2) * max_abs, f.frac_bits);
  // uniform bound: 1/2 + 2^-(G+1) + max(0, |offset| - 2^-(G+1)) + ref (LSB), in units
  s.bound = error_bound(f, max_abs) + std::ldexp(worst_extra, -f.frac_bits);
  return s;
}

}  // namespace

double Segment::exact_bound_lsb(int a, int j) const {
  const double t = std::ldexp(static_cast<double>(j), -depth);  // exact
  const double u = 1.0 - t;                                     // exact
  const double b0 = u * u * u;  // exact for d <= 17 (3d significant bits)
  return 0.5 + b0 * std::fabs(offset[a].get_d()) + (1.0 - b0) * std::ldexp(1.0, -(guard_bits + 1));
}

Segment compile_segment(const Controls& b, int depth, const Format& f) {
  f.validate();
  check_depth_axes(b, depth, f);
  double max_abs = 0;
  auto ctrl = round_controls(b, f, max_abs);
  return finish(std::move(ctrl), b, depth, f, max_abs);
}

Segment compile_segment(const Controls& b, int depth, const Format& f, const std::vector<mpz_class>& start) {
  f.validate();
  check_depth_axes(b, depth, f);
  if (static_cast<int>(start.size()) != f.axes) {
    std::ostringstream m;
    m << "start state has " << start.size() << " axes, format expects " << f.axes;
    fail(m.str());
  }
  double max_abs = 0;
  auto ctrl = round_controls(b, f, max_abs);
  const mpz_class lim = pow2(f.ctrl_width - 1);
  for (int a = 0; a < f.axes; ++a) {
    if (start[a] >= lim || start[a] < -lim) {
      std::ostringstream m;
      m << "axis " << a << " start value A = " << start[a].get_str() << " does not fit ctrl_width "
        << f.ctrl_width;
      fail(m.str());
    }
    ctrl[a][0] = start[a];
  }
  return finish(std::move(ctrl), b, depth, f, max_abs);
}

}  // namespace traj::bcu
