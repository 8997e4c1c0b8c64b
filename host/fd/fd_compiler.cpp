#include "fd/fd_compiler.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace traj::fd {
namespace {

std::string fmt_double(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

// Exact rational of a finite double.
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

}  // namespace

mpz_class binom(uint64_t k, int i) {
  mpz_class r;
  mpz_bin_uiui(r.get_mpz_t(), k, static_cast<unsigned long>(i));
  return r;
}

void Format::validate() const {
  auto bad = [](const std::string& what) { throw CompileError("format: " + what); };
  if (axes < 1 || axes > 8) bad("axes=" + std::to_string(axes) + " out of range 1..8");
  if (degree < 1 || degree > 7) bad("degree=" + std::to_string(degree) + " out of range 1..7");
  if (chunk_width != 16 && chunk_width != 32 && chunk_width != 64)
    bad("chunk_width=" + std::to_string(chunk_width) + " must be 16, 32 or 64");
  if (width < chunk_width || width > 128 || width % chunk_width != 0)
    bad("width=" + std::to_string(width) + " must be a multiple of chunk_width=" +
        std::to_string(chunk_width) + ", at most 128");
  if (guard_bits < 1 || guard_bits > width - 2)
    bad("guard_bits=" + std::to_string(guard_bits) + " out of range 1..width-2");
  if (frac_bits < -64 || frac_bits > 64)
    bad("frac_bits=" + std::to_string(frac_bits) + " out of range -64..64");
  if (!(tol_lsb > 0) || !std::isfinite(tol_lsb))
    bad("tol_lsb=" + fmt_double(tol_lsb) + " must be positive and finite");
  if (max_ticks < 1) bad("max_ticks must be at least 1");
}

Compiler::Compiler(Format f) : f_(f) { f_.validate(); }

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

double Compiler::quant_bound_lsb(uint64_t k) const {
  return to_lsb(mpq_class(quant_bound_x2(f_.degree, k), 2), f_.guard_bits);
}

// Q(K) <= tol/2 * 2^G  <=>  sum C(K,i) <= tol * 2^G
static bool fits(int degree, uint64_t k, int guard_bits, double tol_lsb) {
  return mpq_class(Compiler::quant_bound_x2(degree, k)) <= exact(tol_lsb) * mpq_class(pow2(guard_bits));
}

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

Compiled Compiler::compile(const PolySegment& seg, const std::vector<mpz_class>* start,
                           const std::string& where) const {
  const int N = f_.degree;
  const int A = f_.axes;
  auto fail = [&](const std::string& what) { throw CompileError(where + ": " + what); };

  if (static_cast<int>(seg.coef.size()) != A)
    fail("has " + std::to_string(seg.coef.size()) + " axes, the engine has " + std::to_string(A));
  if (!(seg.h > 0) || !std::isfinite(seg.h)) fail("tick period h=" + fmt_double(seg.h) + " must be positive and finite");
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

  const uint64_t K = seg.ticks;
  const int G = f_.guard_bits;
  // Quantisation budget: Q(K) <= tol/2.
  if (!fits(N, K, G, f_.tol_lsb)) {
    const uint64_t kmax = longest_segment(N, G, f_.tol_lsb);
    const int gneed = guard_bits_needed(N, K, f_.tol_lsb);
    fail("K=" + std::to_string(K) + " ticks at degree " + std::to_string(N) + " has quantisation bound " +
         fmt_double(quant_bound_lsb(K)) + " LSB > tol/2 = " + fmt_double(f_.tol_lsb / 2) +
         " LSB with guard_bits=" + std::to_string(G) + "; split into segments of at most K=" +
         std::to_string(kmax) + " ticks, or use guard_bits >= " + std::to_string(gneed) +
         " (width >= " + std::to_string(f_.out_width() + gneed) + ")");
  }

  const mpq_class h = exact(seg.h);
  const mpq_class T = h * mpq_class(mpz_class(std::to_string(K)));
  mpq_class scale = mpq_class(pow2(G));
  if (f_.frac_bits >= 0) scale *= mpq_class(pow2(f_.frac_bits));
  else scale /= mpq_class(pow2(-f_.frac_bits));
  const mpq_class bias(pow2(G), 2);
  const mpq_class half_tol_reg = exact(f_.tol_lsb / 2) * mpq_class(pow2(G));
  const mpq_class limit = mpq_class(pow2(f_.width - 1));  // |r0| must stay below 2^(W-1)

  Compiled out;
  out.ticks = static_cast<uint32_t>(K);
  out.regs.assign(A, std::vector<mpz_class>(N + 1));
  out.end.resize(A);
  double carried = 0;
  for (int a = 0; a < A; ++a) {
    // Target in register units: q(t) = x(t) * scale + bias, as exact coefficients.
    std::vector<mpq_class> c(N + 1, 0);
    for (size_t j = 0; j < seg.coef[a].size(); ++j) c[j] = exact(seg.coef[a][j]) * scale;
    c[0] += bias;
    // Start state and carried error e0.
    mpz_class r0 = start ? (*start)[a] : round_nearest(c[0]);
    mpq_class e0 = mpq_class(r0) - c[0];
    if (abs(e0) > half_tol_reg && start)
      fail("axis " + std::to_string(a) + " starts " + fmt_double(to_lsb(e0, G)) +
           " LSB away from the previous segment's end (more than tol/2 = " + fmt_double(f_.tol_lsb / 2) +
           " LSB): the path is not continuous here");
    carried = std::max(carried, to_lsb(e0, G));
    // Blend e0 out linearly: q += e0 (1 - t/T).
    c[0] += e0;
    c[1] -= e0 / T;
    // Range: |q(t)| + error < 2^(W-1) over [0, T].
    const long double qmax = max_abs_on(c, T);
    const long double margin = std::fabs(static_cast<long double>(e0.get_d())) +
                               static_cast<long double>(quant_bound_x2(N, K).get_d()) + 2;
    if (qmax + margin >= static_cast<long double>(limit.get_d()))
      fail("axis " + std::to_string(a) + " leaves the output range: |x| may reach " +
           fmt_double(static_cast<double>(qmax / static_cast<long double>(scale.get_d()))) +
           " units, the format holds |x| < " +
           fmt_double(std::ldexp(1.0, f_.out_width() - 1 - f_.frac_bits)) +
           " (out_width=" + std::to_string(f_.out_width()) + ", frac_bits=" + std::to_string(f_.frac_bits) + ")");
    // Exact samples q(m h), m = 0..N, then the forward-difference table.
    std::vector<mpq_class> y(N + 1);
    for (int m = 0; m <= N; ++m) {
      const mpq_class t = h * m;
      mpq_class v = 0;
      for (int j = N; j >= 0; --j) v = v * t + c[j];
      y[m] = v;
    }
    out.regs[a][0] = r0;
    for (int i = 1; i <= N; ++i) {
      for (int m = 0; m + i <= N; ++m) y[m] = y[m + 1] - y[m];  // y[m] = Delta^i q(m h)
      out.regs[a][i] = round_nearest(y[0]);
    }
    out.end[a] = state_at(out, a, K);
  }
  out.carried_lsb = carried;
  out.bound_lsb = carried + quant_bound_lsb(K);
  return out;
}

mpz_class Compiler::state_at(const Compiled& c, int axis, uint64_t k) {
  const auto& r = c.regs[axis];
  mpz_class s = 0;
  for (size_t i = 0; i < r.size(); ++i) s += r[i] * binom(k, static_cast<int>(i));
  return s;
}

mpz_class Compiler::sample_at(const Compiled& c, int axis, uint64_t k) const {
  mpz_class s = state_at(c, axis, k), q;
  mpz_fdiv_q_2exp(q.get_mpz_t(), s.get_mpz_t(), f_.guard_bits);
  return q;
}

std::vector<uint64_t> Compiler::words(const Compiled& c) const {
  const int C = f_.chunk_width;
  std::vector<uint64_t> w;
  const uint64_t cmask = C == 64 ? ~uint64_t(0) : ((uint64_t(1) << C) - 1);
  if (C < 32) {
    for (int s = 0; s < 32; s += C) w.push_back((uint64_t(c.ticks) >> s) & cmask);
  } else {
    w.push_back(c.ticks);
  }
  const mpz_class mod = pow2(f_.width);
  for (const auto& axis : c.regs) {
    for (const auto& r : axis) {
      mpz_class v = r % mod;  // two's complement, W bits
      if (v < 0) v += mod;
      for (int s = 0; s < f_.width; s += C) {
        const mpz_class chunk = (v >> s) & (pow2(C) - 1);  // fits 64 bits
        uint64_t lo = mpz_class(chunk & mpz_class(0xffffffffUL)).get_ui();
        uint64_t hi = mpz_class(chunk >> 32).get_ui();
        w.push_back(lo | (hi << 32));
      }
    }
  }
  return w;
}

}  // namespace traj::fd
