// SPDX-License-Identifier: Apache-2.0
// The exact rational reference of the forward-difference compiler (mpq
// throughout), the exact budget functions, and the refusal messages with what
// would fit instead.
#include <algorithm>
#include <cmath>
#include <functional>

#include "fd/detail/fd_internal.hpp"
#include "fd/fd_compiler.hpp"
#include "util/tick_period.hpp"

namespace traj::fd {
namespace detail {

mpq_class exact(double v) {
  mpq_class q;
  mpq_set_d(q.get_mpq_t(), v);
  return q;
}

mpz_class round_nearest(const mpq_class& q) {
  // floor(q + 1/2)
  mpq_class t = q + mpq_class(1, 2);
  mpz_class r;
  mpz_fdiv_q(r.get_mpz_t(), t.get_num_mpz_t(), t.get_den_mpz_t());
  return r;
}

mpz_class pow2(int e) {
  mpz_class r = 1;
  r <<= e;
  return r;
}

double to_lsb(const mpq_class& reg_units, int guard_bits) {
  mpq_class q = reg_units / mpq_class(pow2(guard_bits));
  return std::fabs(q.get_d());
}

bool fits(int degree, uint64_t k, int guard_bits, double tol_lsb) {
  return mpq_class(Compiler::quant_bound_x2(degree, k)) <= exact(tol_lsb) * mpq_class(pow2(guard_bits));
}

}  // namespace detail

using namespace detail;

namespace {

// Upper bound of |p(t)| on [0, T] from the Bernstein coefficients of p(T u)
// (convex-hull property), in long double.
long double max_abs_on(const std::vector<mpq_class>& c, const mpq_class& T) {
  const int n = static_cast<int>(c.size()) - 1;
  std::vector<mpq_class> a(c.size());
  mpq_class Tj = 1;
  for (int j = 0; j <= n; ++j) {
    a[j] = c[j] * Tj;
    Tj *= T;
  }
  long double m = 0;
  for (int i = 0; i <= n; ++i) {
    mpq_class b = 0;
    for (int j = 0; j <= i; ++j) {
      mpz_class cij = binom(i, j), cnj = binom(n, j);
      b += a[j] * mpq_class(cij) / mpq_class(cnj);
    }
    m = std::max(m, std::fabs(static_cast<long double>(b.get_d())));
  }
  return m;
}

// 2^(G+F): register LSB per position unit, exactly.
mpq_class register_scale(const Format& f) {
  mpq_class scale = mpq_class(pow2(f.guard_bits));
  if (f.frac_bits >= 0) scale *= mpq_class(pow2(f.frac_bits));
  else scale /= mpq_class(pow2(-f.frac_bits));
  return scale;
}

double quant_bound_lsb_of(const Format& f, uint64_t k) {
  return to_lsb(mpq_class(Compiler::quant_bound_x2(f.degree, k), 2), f.guard_bits);
}

// "guard_bits >= g (width >= W: ...)" for the too-long refusal: the width is
// rounded up to a buildable one (a multiple of chunk_width, at most 128).
std::string guard_suggestion(const Format& f, int gneed) {
  const int ow = f.out_width();
  const int c = f.chunk_width;
  const int wbuild = (ow + gneed + c - 1) / c * c;
  const std::string g = "guard_bits >= " + std::to_string(gneed);
  if (wbuild <= 128)
    return g + " (width >= " + std::to_string(wbuild) + ": " + std::to_string(ow) + " output + " +
           std::to_string(gneed) + " guard bits, rounded up to a multiple of chunk_width=" + std::to_string(c) + ")";
  if (gneed <= 126)
    return g + " (at width=128 that leaves out_width <= " + std::to_string(128 - gneed) + ", fewer than " +
           std::to_string(ow) + ")";
  return g + " (no buildable width: width <= 128 holds at most 126 guard bits)";
}

// "r[3] binds: alone it needs 49 guard bits (r[1] 18, r[2] 34)".
std::string binding_note(const RegisterNeeds& nd) {
  std::string others;
  for (size_t i = 1; i < nd.alone.size(); ++i) {
    if (static_cast<int>(i) == nd.binding) continue;
    others += (others.empty() ? "" : ", ") + std::string("r[") + std::to_string(i) + "] " + std::to_string(nd.alone[i]);
  }
  return "r[" + std::to_string(nd.binding) + "] binds: alone it needs " + std::to_string(nd.alone[nd.binding]) +
         " guard bits" + (others.empty() ? "" : " (" + others + ")");
}

// Whether one axis polynomial stays in the output range of format g for any
// start within max(1/2 register LSB, tol/2) of it: a sufficient form of
// compile()'s range check (the blend e0 (1 - t/T) moves every Bernstein
// coefficient by at most |e0|, so max|b| + 2 e0max + sum C(K,i) + 2 < 2^(W-1)
// implies max|b'| + |e0| + sum C(K,i) + 2 < 2^(W-1)).
bool range_fits(const Format& g, const std::vector<double>& coef, const mpq_class& T, uint64_t K) {
  const int N = g.degree;
  const mpq_class scale = register_scale(g);
  std::vector<mpq_class> c(N + 1, 0);
  for (size_t j = 0; j < coef.size() && j <= static_cast<size_t>(N); ++j) c[j] = exact(coef[j]) * scale;
  c[0] += mpq_class(pow2(g.guard_bits), 2);
  const long double qmax = max_abs_on(c, T);
  const long double e0max = std::max(0.5L, std::ldexp(static_cast<long double>(g.tol_lsb) / 2, g.guard_bits));
  const long double need = qmax + 2 * e0max + static_cast<long double>(Compiler::quant_bound_x2(N, K).get_d()) + 2;
  return need * (1 + std::ldexp(1.0L, -40)) < std::ldexp(1.0L, g.width - 1);
}

// "; it fits with frac_bits <= F (|x| < X), or with width >= W (out_width=O)"
// for the range refusal: the largest frac_bits below the present one, and the
// smallest buildable width above the present one (same guard_bits), with which
// this axis would fit.
std::string range_suggestion(const Format& f, const std::vector<double>& coef, const mpq_class& T, uint64_t K) {
  std::string frac, wide;
  for (int fb = f.frac_bits - 1; fb >= -64; --fb) {
    Format g = f;
    g.frac_bits = fb;
    if (range_fits(g, coef, T, K)) {
      frac = "frac_bits <= " + std::to_string(fb) + " (|x| < " + fmt_double(std::ldexp(1.0, f.out_width() - 1 - fb)) +
             ")";
      break;
    }
  }
  for (int w = f.width + f.chunk_width; w <= 128; w += f.chunk_width) {
    Format g = f;
    g.width = w;
    if (range_fits(g, coef, T, K)) {
      wide = "width >= " + std::to_string(w) + " (out_width=" + std::to_string(g.out_width()) + " at guard_bits=" +
             std::to_string(f.guard_bits) + ")";
      break;
    }
  }
  if (frac.empty() && wide.empty())
    return "; no frac_bits >= -64 and no width <= 128 holds it: split the move or move the origin";
  return "; it fits with " + (frac.empty() ? wide : wide.empty() ? frac : frac + ", or with " + wide);
}

}  // namespace

mpz_class Compiler::position_to_state(double x) const {
  if (!std::isfinite(x)) throw CompileError("position " + fmt_double(x) + " is not finite");
  // (x 2^F + 1/2) 2^G
  mpq_class s = exact(x);
  if (f_.frac_bits >= 0) s *= mpq_class(pow2(f_.frac_bits));
  else s /= mpq_class(pow2(-f_.frac_bits));
  s = (s + mpq_class(1, 2)) * mpq_class(pow2(f_.guard_bits));
  return round_nearest(s);
}

mpz_class Compiler::quant_bound_x2(int degree, uint64_t k) {
  mpz_class s = 0;
  for (int i = 1; i <= degree; ++i) s += binom(k, i);
  return s;
}

double Compiler::quant_bound_lsb(uint64_t k) const { return quant_bound_lsb_of(f_, k); }

uint64_t Compiler::longest_segment(int degree, int guard_bits, double tol_lsb) {
  if (!fits(degree, 1, guard_bits, tol_lsb)) return 0;
  uint64_t lo = 1, hi = 2;
  while (hi < (uint64_t(1) << 62) && fits(degree, hi, guard_bits, tol_lsb)) {
    lo = hi;
    hi *= 2;
  }
  while (hi - lo > 1) {
    uint64_t mid = lo + (hi - lo) / 2;
    (fits(degree, mid, guard_bits, tol_lsb) ? lo : hi) = mid;
  }
  return lo;
}

int Compiler::guard_bits_needed(int degree, uint64_t k, double tol_lsb) {
  for (int g = 0; g < 400; ++g)
    if (fits(degree, k, g, tol_lsb)) return g;
  return 400;
}

namespace detail {

void check_segment(const Format& f_, const PolySegment& seg, const std::vector<mpz_class>* start,
                   const std::string& where) {
  const int N = f_.degree;
  const int A = f_.axes;
  auto fail = [&](const std::string& what) { throw CompileError(where + ": " + what); };
  if (static_cast<int>(seg.coef.size()) != A)
    fail("has " + std::to_string(seg.coef.size()) + " axes, the engine has " + std::to_string(A));
  if (const std::string m = util::tick_period_problem(seg.h); !m.empty()) fail(m);
  if (seg.ticks < 1) fail("tick count K=0: a segment needs at least one tick");
  if (seg.ticks > f_.max_ticks)
    fail("K=" + std::to_string(seg.ticks) + " ticks exceeds max_ticks=" + std::to_string(f_.max_ticks) +
         "; split the segment");
  for (int a = 0; a < A; ++a) {
    if (static_cast<int>(seg.coef[a].size()) > N + 1)
      fail("axis " + std::to_string(a) + " has degree " + std::to_string(seg.coef[a].size() - 1) +
           ", the engine is built for degree " + std::to_string(N));
    for (size_t j = 0; j < seg.coef[a].size(); ++j)
      if (!std::isfinite(seg.coef[a][j]))
        fail("axis " + std::to_string(a) + " coefficient c" + std::to_string(j) + " = " +
             fmt_double(seg.coef[a][j]) + " is not finite");
  }
  if (start && static_cast<int>(start->size()) != A) fail("start state has the wrong number of axes");
}

namespace {

// The exact core of both compile_reference() and Compiler::compile_target():
// per axis the target c (register units, r0's bias included) as a polynomial
// in t over [0, T = K h]. `range_hint(axis)` completes a range refusal.
Compiled compile_exact_target(const Format& f_, std::vector<std::vector<mpq_class>> c, const mpq_class& h, uint64_t K,
                              const std::vector<mpz_class>* start, const std::string& where,
                              const std::function<std::string(int)>& range_hint, double start_tol_lsb) {
  const int N = f_.degree;
  const int A = f_.axes;
  auto fail = [&](const std::string& what) { throw CompileError(where + ": " + what); };

  const int G = f_.guard_bits;
  // Quantisation budget: Q(K) <= tol/2.
  const RegisterNeeds needs = Compiler::register_needs(N, K, f_.tol_lsb);
  if (!fits(N, K, G, f_.tol_lsb)) {
    const uint64_t kmax = Compiler::longest_segment(N, G, f_.tol_lsb);
    const int gneed = Compiler::guard_bits_needed(N, K, f_.tol_lsb);
    fail("K=" + std::to_string(K) + " ticks at degree " + std::to_string(N) + " has quantisation bound " +
         fmt_double(quant_bound_lsb_of(f_, K)) + " LSB > tol/2 = " + fmt_double(f_.tol_lsb / 2) +
         " LSB with guard_bits=" + std::to_string(G) + "; split into segments of at most K=" +
         std::to_string(kmax) + " ticks, or use " + guard_suggestion(f_, gneed) + "; " + binding_note(needs));
  }

  const mpq_class T = h * mpq_class(mpz_class(std::to_string(K)));
  const mpq_class scale = register_scale(f_);
  const double start_tol = start_tol_lsb < 0 ? f_.tol_lsb / 2 : start_tol_lsb;
  const mpq_class half_tol_reg = exact(start_tol) * mpq_class(pow2(G));
  const mpq_class limit = mpq_class(pow2(f_.width - 1));  // |r0| must stay below 2^(W-1)

  Compiled out;
  out.ticks = static_cast<uint32_t>(K);
  out.regs.assign(A, std::vector<mpz_class>(N + 1));
  out.end.resize(A);
  double carried = 0;
  for (int a = 0; a < A; ++a) {
    std::vector<mpq_class>& ca = c[a];
    ca.resize(N + 1, 0);
    // Start state and carried error e0.
    mpz_class r0 = start ? (*start)[a] : round_nearest(ca[0]);
    mpq_class e0 = mpq_class(r0) - ca[0];
    if (abs(e0) > half_tol_reg && start)
      fail("axis " + std::to_string(a) + " starts " + fmt_double(to_lsb(e0, G)) +
           " LSB away from the previous segment's end (more than " +
           (start_tol == f_.tol_lsb / 2 ? "tol/2 = " : "") + fmt_double(start_tol) +
           " LSB): the path is not continuous here");
    carried = std::max(carried, to_lsb(e0, G));
    // Blend e0 out linearly: q += e0 (1 - t/T).
    ca[0] += e0;
    ca[1] -= e0 / T;
    // Range: |q(t)| + error < 2^(W-1) over [0, T].
    const long double qmax = max_abs_on(ca, T);
    const long double margin = std::fabs(static_cast<long double>(e0.get_d())) +
                               static_cast<long double>(Compiler::quant_bound_x2(N, K).get_d()) + 2;
    if (qmax + margin >= static_cast<long double>(limit.get_d()))
      fail("axis " + std::to_string(a) + " leaves the output range: |x| may reach " +
           fmt_double(static_cast<double>(qmax / static_cast<long double>(scale.get_d()))) +
           " units, the format holds |x| < " +
           fmt_double(std::ldexp(1.0, f_.out_width() - 1 - f_.frac_bits)) +
           " (out_width=" + std::to_string(f_.out_width()) + ", frac_bits=" + std::to_string(f_.frac_bits) + ")" +
           range_hint(a));
    // Exact samples q(m h), m = 0..N, then the forward-difference table.
    std::vector<mpq_class> y(N + 1);
    for (int m = 0; m <= N; ++m) {
      const mpq_class t = h * m;
      mpq_class v = 0;
      for (int j = N; j >= 0; --j) v = v * t + ca[j];
      y[m] = v;
    }
    out.regs[a][0] = r0;
    for (int i = 1; i <= N; ++i) {
      for (int m = 0; m + i <= N; ++m) y[m] = y[m + 1] - y[m];  // y[m] = Delta^i q(m h)
      out.regs[a][i] = round_nearest(y[0]);
    }
    out.end[a] = Compiler::state_at(out, a, K);
  }
  out.carried_lsb = carried;
  out.bound_lsb = carried + quant_bound_lsb_of(f_, K);
  out.needs = needs;
  return out;
}

}  // namespace

Compiled compile_reference(const Format& f_, const PolySegment& seg, const std::vector<mpz_class>* start,
                           const std::string& where, double start_tol_lsb) {
  ++path_counts().reference;
  check_segment(f_, seg, start, where);
  const mpq_class h = exact(seg.h);
  const mpq_class T = h * mpq_class(mpz_class(std::to_string(seg.ticks)));
  const mpq_class scale = register_scale(f_);
  // Target in register units: q(t) = x(t) * scale + bias, as exact coefficients.
  std::vector<std::vector<mpq_class>> c(f_.axes, std::vector<mpq_class>(f_.degree + 1, 0));
  for (int a = 0; a < f_.axes; ++a) {
    for (size_t j = 0; j < seg.coef[a].size(); ++j) c[a][j] = exact(seg.coef[a][j]) * scale;
    c[a][0] += mpq_class(pow2(f_.guard_bits), 2);
  }
  return compile_exact_target(f_, std::move(c), h, seg.ticks, start, where,
                              [&](int a) { return range_suggestion(f_, seg.coef[a], T, seg.ticks); }, start_tol_lsb);
}

}  // namespace detail

Compiled Compiler::compile_target(const ExactTarget& seg, const std::vector<mpz_class>* start,
                                  const std::string& where) const {
  ++path_counts().reference;
  auto fail = [&](const std::string& what) { throw CompileError(where + ": " + what); };
  if (static_cast<int>(seg.q.size()) != f_.axes)
    fail("has " + std::to_string(seg.q.size()) + " axes, the engine has " + std::to_string(f_.axes));
  if (seg.ticks < 1) fail("tick count K=0: a segment needs at least one tick");
  if (seg.ticks > f_.max_ticks)
    fail("K=" + std::to_string(seg.ticks) + " ticks exceeds max_ticks=" + std::to_string(f_.max_ticks) +
         "; split the segment");
  for (int a = 0; a < f_.axes; ++a)
    if (static_cast<int>(seg.q[a].size()) > f_.degree + 1)
      fail("axis " + std::to_string(a) + " has degree " + std::to_string(seg.q[a].size() - 1) +
           ", the engine is built for degree " + std::to_string(f_.degree));
  if (start && static_cast<int>(start->size()) != f_.axes) fail("start state has the wrong number of axes");
  Compiled out = compile_exact_target(f_, seg.q, mpq_class(1), seg.ticks, start, where, [](int) { return ""; }, -1);
  wrap_differences(out);
  return out;
}

}  // namespace traj::fd
