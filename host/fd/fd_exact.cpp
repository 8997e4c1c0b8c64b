// SPDX-License-Identifier: Apache-2.0
// The forward-difference compiler's exact integer path: exact dyadic sums on
// limb arrays sized per axis (mpz beyond them), for the segments the grid
// path cannot settle; see detail/fd_internal.hpp.
#include <algorithm>
#include <cmath>

#include "fd/detail/fd_internal.hpp"

namespace traj::fd::detail {
namespace {

constexpr int kMaxLimbs = 16;  // of the limb arrays; mpz beyond

}  // namespace

Scratch::Scratch() {
  for (int i = 0; i < 8; ++i) {
    mpz_init2(hp[i], 512);
    mpz_init2(u[i], 1024);
    mpz_init2(bin[i], 256);
  }
  for (mpz_ptr p : {x, c0, r0, e, t, half, q2, sb, sw}) mpz_init2(p, 1024);
}
Scratch::~Scratch() {
  for (int i = 0; i < 8; ++i) {
    mpz_clear(hp[i]);
    mpz_clear(u[i]);
    mpz_clear(bin[i]);
  }
  for (mpz_ptr p : {x, c0, r0, e, t, half, q2, sb, sw}) mpz_clear(p);
}
Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

Compiled compile_exact(const Format& f_, long double scale_ld, long double limit_ld, const PolySegment& seg,
                       const std::vector<mpz_class>* start, double start_tol_lsb, const std::string& where) {
  ++path_counts().exact;
  const int N = f_.degree;
  const int A = f_.axes;
  const uint64_t K = seg.ticks;
  const int G = f_.guard_bits;
  const int sigma = G + f_.frac_bits;  // scale = 2^sigma
  Scratch& S = scratch();

  // Shared by the axes: powers of m_h, C(K, i), 2 Q(K).
  const Dyadic hd = dyadic(seg.h);  // m_h > 0, odd, < 2^53
  mpz_set_ui(S.hp[0], 1);
  for (int j = 1; j <= N; ++j) mpz_mul_ui(S.hp[j], S.hp[j - 1], static_cast<unsigned long>(hd.m));
  // The same as zero-padded limb arrays (hpL = 0 if they do not fit).
  uint64_t hpl[8][kMaxLimbs] = {};
  int hpL = kMaxLimbs;
  if (mpz_size(S.hp[N]) <= static_cast<size_t>(kMaxLimbs)) {
    for (int j = 0; j <= N; ++j) {
      const mp_limb_t* p = mpz_limbs_read(S.hp[j]);
      for (size_t l = 0; l < mpz_size(S.hp[j]); ++l) hpl[j][l] = p[l];
    }
  } else {
    hpL = 0;
  }
  mpz_set_ui(S.bin[0], 1);
  mpz_set_ui(S.q2, 0);
  for (int i = 1; i <= N; ++i) {
    if (static_cast<uint64_t>(i) > K) {
      mpz_set_ui(S.bin[i], 0);
      continue;
    }
    mpz_mul_ui(S.bin[i], S.bin[i - 1], K - i + 1);
    mpz_divexact_ui(S.bin[i], S.bin[i], static_cast<unsigned long>(i));
    mpz_add(S.q2, S.q2, S.bin[i]);
  }
  const double q2_d = mpz_get_d(S.q2);               // = quant_bound_x2(N, K).get_d() (truncation)
  const double qbound_lsb = std::ldexp(q2_d, -(G + 1));  // = quant_bound_lsb(K): exact power-of-two scaling

  const Dyadic htol = dyadic(start_tol_lsb);  // output LSB = m 2^(e+G) register LSB
  const long double T_ld = static_cast<long double>(seg.h) * static_cast<long double>(K);

  Compiled out;
  out.ticks = static_cast<uint32_t>(K);
  out.regs.resize(A);
  for (auto& r : out.regs) r.resize(N + 1);
  out.end.resize(A);
  const mw::GmpAlloc alloc = mw::gmp_alloc_func();
  double carried = 0;
  for (int a = 0; a < A; ++a) {
    const std::vector<double>& cf = seg.coef[a];
    Dyadic d[8] = {};
    for (size_t j = 0; j < cf.size(); ++j) d[j] = dyadic(cf[j]);
    // Common exponent z <= -1 of all terms (and of the bias 2^(G-1), G >= 1).
    long z = -1;
    if (d[0].m) z = std::min<long>(z, d[0].e + sigma);
    long xe[8] = {};
    for (int j = 1; j <= N; ++j)
      if (d[j].m) {
        xe[j] = d[j].e + sigma + long(j) * hd.e;
        z = std::min(z, xe[j]);
      }
    const unsigned long sz = static_cast<unsigned long>(-z);
    mpz_set_ui(S.half, 0);
    mpz_setbit(S.half, sz - 1);  // 1/2 at scale 2^-z
    // c0 = x(0) 2^sigma + 2^(G-1), at scale 2^-z.
    mpz_set_ui(S.c0, 0);
    mpz_setbit(S.c0, static_cast<unsigned long>(G - 1 - z));
    if (d[0].m) {
      mpz_set_si(S.t, d[0].m);
      mpz_mul_2exp(S.t, S.t, static_cast<unsigned long>(d[0].e + sigma - z));
      mpz_add(S.c0, S.c0, S.t);
    }
    // Start state and carried error e0 = r0 - c0 (scale 2^-z).
    if (start) {
      mpz_set(S.r0, (*start)[a].get_mpz_t());
    } else {
      mpz_add(S.t, S.c0, S.half);
      mpz_fdiv_q_2exp(S.r0, S.t, sz);
    }
    mpz_mul_2exp(S.e, S.r0, sz);
    mpz_sub(S.e, S.e, S.c0);
    if (start) {
      // |e0| > tol/2 2^G  <=>  |E| 2^z > m 2^(e+G)
      const long s = htol.e + G - z;
      bool far;
      if (s >= 0) {
        mpz_set_si(S.t, htol.m);
        mpz_mul_2exp(S.t, S.t, static_cast<unsigned long>(s));
        far = mpz_cmpabs(S.e, S.t) > 0;
      } else {
        mpz_abs(S.t, S.e);
        mpz_mul_2exp(S.t, S.t, static_cast<unsigned long>(-s));
        far = mpz_cmp_si(S.t, htol.m) > 0;
      }
      if (far) return compile_reference(f_, seg, start, where, start_tol_lsb);  // words the refusal
    }
    // to_lsb(e0, G) = |e0 / 2^G| as a double, truncated (mpq_get_d).
    double e0_lsb = 0;
    if (mpz_sgn(S.e) != 0) {
      long ex;
      const double dm = mpz_get_d_2exp(&ex, S.e);  // truncated to 53 bits
      const long p = ex + z - G;
      if (p - 1 < -1021 || p > 1023) return compile_reference(f_, seg, start, where, start_tol_lsb);  // not a normal double
      e0_lsb = std::fabs(std::ldexp(dm, static_cast<int>(p)));
    }
    carried = std::max(carried, e0_lsb);

    // Range (see detail/fd_internal.hpp): the long double bound.
    {
      const long double r0_ld =
          mpz_size(S.r0) <= 2 ? static_cast<long double>(mpz_get_d(S.r0)) : mw::mpz_ldexp(S.r0, 0);
      if (!range_ok(N, cf, scale_ld, T_ld, r0_ld, mw::mpz_ldexp(S.e, z), q2_d, limit_ld))
        return compile_reference(f_, seg, start, where, start_tol_lsb);  // decides and words it
    }

    // Registers: exact differences at scale 2^-z, rounded to nearest.
    std::vector<mpz_class>& r = out.regs[a];
    // Size bound: |u_j| < 2^B, |X_i| < 2^(B+15) (sum of surj(j,i) <= 18720),
    // for r[1]: |K X_1| < 2^(B+3+32), |E|, K 2^(sz-1) < 2^(sz+32).
    long B = 0;
    for (int j = 1; j <= N; ++j)
      if (d[j].m)
        B = std::max<long>(B, mw::bitlen_u64(static_cast<uint64_t>(d[j].m < 0 ? -d[j].m : d[j].m)) +
                                  static_cast<long>(mpz_sizeinbase(S.hp[j], 2)) + (xe[j] - z));
    const long need = std::max({B + 35, static_cast<long>(mpz_sizeinbase(S.e, 2)), static_cast<long>(sz) + 33}) + 3;
    const int L = static_cast<int>(need / 64 + 1);
    if (L <= kMaxLimbs && L <= hpL) {
      uint64_t u[8][kMaxLimbs], x[kMaxLimbs], y[kMaxLimbs];
      for (int j = 1; j <= N; ++j)
        if (d[j].m) {
          mw::mul1(u[j], hpl[j], static_cast<uint64_t>(d[j].m < 0 ? -d[j].m : d[j].m), L);
          mw::shl(u[j], static_cast<unsigned long>(xe[j] - z), L);
          if (d[j].m < 0) mw::neg(u[j], L);
        }
      for (int i = 1; i <= N; ++i) {
        u128 c = 0;
        for (int l = 0; l < L; ++l) {
          u128 acc = c;
          for (int j = i; j <= N; ++j)
            if (d[j].m) acc += static_cast<u128>(u[j][l]) * kSurj.v[j][i];
          x[l] = static_cast<uint64_t>(acc);
          c = acc >> 64;
        }
        if (i == 1) {
          // floor((X - E/K) 2^z + 1/2) = floor(floor((K X - E + K half) / 2^-z) / K)
          mw::mul1(x, x, K, L);
          mw::from_mpz(y, S.e, true, L);
          mw::add(x, y, L);
          for (int l = 0; l < L; ++l) y[l] = 0;
          y[0] = K;
          mw::shl(y, sz - 1, L);
          mw::add(x, y, L);
          mw::sar(x, sz, L);
          mw::mpz_set_limbs(S.x, x, L, alloc);
          mpz_fdiv_q_ui(r[1].get_mpz_t(), S.x, K);
        } else {
          for (int l = 0; l < L; ++l) y[l] = 0;
          y[0] = 1;
          mw::shl(y, sz - 1, L);
          mw::add(x, y, L);
          mw::sar(x, sz, L);
          mw::mpz_set_limbs(r[i].get_mpz_t(), x, L, alloc);
        }
      }
    } else {
      for (int j = 1; j <= N; ++j)
        if (d[j].m) {
          mpz_mul_si(S.u[j], S.hp[j], static_cast<long>(d[j].m));
          mpz_mul_2exp(S.u[j], S.u[j], static_cast<unsigned long>(xe[j] - z));
        }
      for (int i = 1; i <= N; ++i) {
        mpz_set_ui(S.x, 0);
        for (int j = i; j <= N; ++j)
          if (d[j].m) mpz_addmul_ui(S.x, S.u[j], kSurj.v[j][i]);
        if (i == 1) {
          mpz_mul_ui(S.x, S.x, K);
          mpz_sub(S.x, S.x, S.e);
          mpz_addmul_ui(S.x, S.half, K);
          mpz_fdiv_q_2exp(S.x, S.x, sz);
          mpz_fdiv_q_ui(r[1].get_mpz_t(), S.x, K);
        } else {
          mpz_add(S.x, S.x, S.half);
          mpz_fdiv_q_2exp(r[i].get_mpz_t(), S.x, sz);
        }
      }
    }
    mpz_set(r[0].get_mpz_t(), S.r0);
    // End state r0(K) = sum_i r_i C(K, i).
    mpz_ptr end = out.end[a].get_mpz_t();
    mpz_set(end, S.r0);
    for (int i = 1; i <= N; ++i) mpz_addmul(end, r[i].get_mpz_t(), S.bin[i]);
  }
  out.carried_lsb = carried;
  out.bound_lsb = carried + qbound_lsb;
  set_needs(out.needs, N, k_data(N, K, f_.tol_lsb).needs);
  return out;
}

}  // namespace traj::fd::detail
