#include "fd/fd_compiler.hpp"

#include <algorithm>
#include <cfloat>
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
  if (guard_bits == 0)
    bad("guard_bits=0 is not supported by the compiler (the RTL builds it): with no bit below the output LSB "
        "every register rounding is a whole 1/2 output LSB, so the error bound admits no segment at tol < 1 "
        "and only K=1 at tol=1; use guard_bits >= 1 (Compiler::guard_bits_needed gives the count for K ticks)");
  if (guard_bits < 1 || guard_bits > width - 2)
    bad("guard_bits=" + std::to_string(guard_bits) + " out of range 1..width-2");
  if (frac_bits < -64 || frac_bits > 64)
    bad("frac_bits=" + std::to_string(frac_bits) + " out of range -64..64");
  if (!(tol_lsb > 0) || !std::isfinite(tol_lsb))
    bad("tol_lsb=" + fmt_double(tol_lsb) + " must be positive and finite");
  if (max_ticks < 1) bad("max_ticks must be at least 1");
}

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

namespace {

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
  mpq_class scale = mpq_class(pow2(g.guard_bits));
  if (g.frac_bits >= 0) scale *= mpq_class(pow2(g.frac_bits));
  else scale /= mpq_class(pow2(-g.frac_bits));
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

// The straightforward exact form (mpq throughout). The fast path of compile()
// falls back to it for every refusal and every case it cannot settle itself, so
// messages and borderline decisions are this function's by construction.
Compiled compile_reference(const Format& f_, const PolySegment& seg, const std::vector<mpz_class>* start,
                           const std::string& where) {
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
  const RegisterNeeds needs = Compiler::register_needs(N, K, f_.tol_lsb);
  if (!fits(N, K, G, f_.tol_lsb)) {
    const uint64_t kmax = Compiler::longest_segment(N, G, f_.tol_lsb);
    const int gneed = Compiler::guard_bits_needed(N, K, f_.tol_lsb);
    fail("K=" + std::to_string(K) + " ticks at degree " + std::to_string(N) + " has quantisation bound " +
         fmt_double(quant_bound_lsb_of(f_, K)) + " LSB > tol/2 = " + fmt_double(f_.tol_lsb / 2) +
         " LSB with guard_bits=" + std::to_string(G) + "; split into segments of at most K=" +
         std::to_string(kmax) + " ticks, or use " + guard_suggestion(f_, gneed) + "; " + binding_note(needs));
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
                               static_cast<long double>(Compiler::quant_bound_x2(N, K).get_d()) + 2;
    if (qmax + margin >= static_cast<long double>(limit.get_d()))
      fail("axis " + std::to_string(a) + " leaves the output range: |x| may reach " +
           fmt_double(static_cast<double>(qmax / static_cast<long double>(scale.get_d()))) +
           " units, the format holds |x| < " +
           fmt_double(std::ldexp(1.0, f_.out_width() - 1 - f_.frac_bits)) +
           " (out_width=" + std::to_string(f_.out_width()) + ", frac_bits=" + std::to_string(f_.frac_bits) + ")" +
           range_suggestion(f_, seg.coef[a], T, K));
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
    out.end[a] = Compiler::state_at(out, a, K);
  }
  out.carried_lsb = carried;
  out.bound_lsb = carried + quant_bound_lsb_of(f_, K);
  out.needs = needs;
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------
// Fast exact path.
//
// Every input is a double, so every quantity is a dyadic rational: h = m_h 2^e_h,
// c_j 2^(G+F) = m_j 2^(e_j+G+F), and the exact forward differences of the
// unblended target are
//     Delta^i q(0) = sum_{j>=i} c_j 2^(G+F) h^j surj(j,i),  surj(j,i) = i! S(j,i),
// integers over one common power of two 2^-z. The linear blend of the carried
// error e0 (c_1 -= e0/T, T = K h) adds -e0/K to Delta^1 only; it is folded in
// by one exact integer division by K. Rounding floor(x + 1/2) is then a shift
// (and, for r[1], a floor division by K): the registers equal the mpq
// reference's bit for bit, since they are the same rationals rounded the same
// way. The sums run on fixed-size two's complement limb arrays (at most 16
// limbs, size bounded in advance per axis; mpz otherwise), the rest on mpz
// scratch variables held per thread (no allocation once warm).
//
// The range check is first tried in long double: the Bernstein coefficients of
// the blended target are computed with an a-priori error bound (2^-48 times
// the sum of the magnitudes of their terms, against an actual worst case below
// 2^-51: every input is exact or carries one rounding of relative size 2^-52
// (double conversions of r0, e0) or 2^-64 (long double operations, at most ~30
// per coefficient)). The segment is accepted on this path only if
//     (max_i (|b_i| + 2^-48 sum_j |term_ij|) + |e0| + 2 Q(K) + 2) (1 + 2^-40)
//         < 2^(W-1) (1 - 2^-40),
// which implies that the reference's own long double computation accepts too
// (its roundings are relative 2^-52 at worst). Anything else (a refusal, or a
// path within that margin of the limit) goes to compile_reference(), which
// then decides and words the message exactly as before. The same holds for a
// discontinuous start and for a carried error too small for a normal double.
namespace {

// surj(j, i) = i! S(j, i) = Delta^i m^j at m = 0, j, i <= 7.
struct SurjTable {
  unsigned long v[8][8] = {};
  SurjTable() {
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i) {
        // sum_k (-1)^(i-k) C(i,k) k^j
        long long s = 0, cik = 1;
        for (int k = 0; k <= i; ++k) {
          long long kj = 1;
          for (int e = 0; e < j; ++e) kj *= k;
          s += ((i - k) % 2 ? -1 : 1) * cik * kj;
          cik = cik * (i - k) / (k + 1);
        }
        v[j][i] = static_cast<unsigned long>(s);
      }
  }
};
const SurjTable& surj_table() {
  static const SurjTable t;
  return t;
}

// w[n][i][j] = C(i,j) / C(n,j): Bernstein coefficient weights (degree n).
struct BernsteinWeights {
  long double w[8][8][8] = {};
  BernsteinWeights() {
    auto C = [](int n, int k) {
      long double r = 1;
      for (int t = 1; t <= k; ++t) r = r * (n - k + t) / t;  // exact small integers
      return r;
    };
    for (int n = 0; n < 8; ++n)
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= i; ++j) w[n][i][j] = C(i, j) / C(n, j);
  }
};
const BernsteinWeights& bernstein_weights() {
  static const BernsteinWeights t;
  return t;
}

// v = m 2^e with m odd (or m = 0, e = 0). Exact for every finite double.
struct Dyadic {
  int64_t m = 0;
  int e = 0;
};
Dyadic dyadic(double v) {
  Dyadic d;
  if (v == 0) return d;
  int e;
  const double f = std::frexp(v, &e);  // |f| in [0.5, 1)
  int64_t m = static_cast<int64_t>(std::ldexp(f, 53));
  e -= 53;
  const int tz = __builtin_ctzll(static_cast<uint64_t>(m));
  d.m = m / (int64_t(1) << tz);
  d.e = e + tz;
  return d;
}

// |v| 2^p as long double, v an integer (rounded to 53 bits; exact exponent).
long double mpz_ldexp_abs(const mpz_t v, long p) {
  if (mpz_sgn(v) == 0) return 0;
  long ex;
  const double d = mpz_get_d_2exp(&ex, v);
  return std::ldexp(std::fabs(static_cast<long double>(d)), static_cast<int>(ex + p));
}
long double mpz_ldexp(const mpz_t v, long p) {
  const long double a = mpz_ldexp_abs(v, p);
  return mpz_sgn(v) < 0 ? -a : a;
}

struct Scratch {
  mpz_t hp[8], u[8], bin[8], x, c0, r0, e, t, half, q2, sb, sw;
  Scratch() {
    for (int i = 0; i < 8; ++i) {
      mpz_init2(hp[i], 512);
      mpz_init2(u[i], 1024);
      mpz_init2(bin[i], 256);
    }
    for (mpz_ptr p : {x, c0, r0, e, t, half, q2, sb, sw}) mpz_init2(p, 1024);
  }
  ~Scratch() {
    for (int i = 0; i < 8; ++i) {
      mpz_clear(hp[i]);
      mpz_clear(u[i]);
      mpz_clear(bin[i]);
    }
    for (mpz_ptr p : {x, c0, r0, e, t, half, q2, sb, sw}) mpz_clear(p);
  }
};
Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

// Fixed-size two's complement integers (L 64-bit limbs, arithmetic modulo
// 2^(64 L)) for the register sums: the exact values are bounded in advance so
// that they fit in L limbs, and the ring operations (add, multiply by a
// non-negative constant, shift) then give them exactly.
static_assert(GMP_NUMB_BITS == 64 && sizeof(mp_limb_t) == 8, "64-bit GMP limbs expected");
constexpr int kMaxLimbs = 16;
using u128 = unsigned __int128;

void limbs_mul1(uint64_t* out, const uint64_t* x, uint64_t m, int L) {
  u128 c = 0;
  for (int l = 0; l < L; ++l) {
    c += static_cast<u128>(x[l]) * m;
    out[l] = static_cast<uint64_t>(c);
    c >>= 64;
  }
}
void limbs_shl(uint64_t* x, unsigned long s, int L) {  // in place, x <<= s
  const long q = static_cast<long>(s / 64);
  const unsigned r = static_cast<unsigned>(s % 64);
  for (long l = L - 1; l >= 0; --l) {
    const uint64_t hi = l - q >= 0 ? x[l - q] : 0;
    const uint64_t lo = l - q - 1 >= 0 ? x[l - q - 1] : 0;
    x[l] = r ? (hi << r) | (lo >> (64 - r)) : hi;
  }
}
void limbs_sar(uint64_t* x, unsigned long s, int L) {  // in place, x = floor(x / 2^s)
  const uint64_t fill = static_cast<int64_t>(x[L - 1]) < 0 ? ~uint64_t(0) : 0;
  const unsigned long q = s / 64;
  const unsigned r = static_cast<unsigned>(s % 64);
  for (unsigned long l = 0; l < static_cast<unsigned long>(L); ++l) {
    const uint64_t lo = l + q < static_cast<unsigned long>(L) ? x[l + q] : fill;
    const uint64_t hi = l + q + 1 < static_cast<unsigned long>(L) ? x[l + q + 1] : fill;
    x[l] = r ? (lo >> r) | (hi << (64 - r)) : lo;
  }
}
void limbs_neg(uint64_t* x, int L) {
  uint64_t carry = 1;
  for (int l = 0; l < L; ++l) {
    x[l] = ~x[l] + carry;
    carry = carry && x[l] == 0;
  }
}
void limbs_add(uint64_t* x, const uint64_t* y, int L) {
  u128 c = 0;
  for (int l = 0; l < L; ++l) {
    c += static_cast<u128>(x[l]) + y[l];
    x[l] = static_cast<uint64_t>(c);
    c >>= 64;
  }
}
// x = (negate ? -z : z), |z| < 2^(64 L - 1).
void limbs_from_mpz(uint64_t* x, mpz_srcptr z, bool negate, int L) {
  const int n = static_cast<int>(mpz_size(z));
  const mp_limb_t* p = mpz_limbs_read(z);
  for (int l = 0; l < L; ++l) x[l] = l < n ? p[l] : 0;
  if ((mpz_sgn(z) < 0) != negate && mpz_sgn(z) != 0) limbs_neg(x, L);
}
void limbs_to_mpz(mpz_ptr z, uint64_t* x, int L) {  // x is clobbered
  const bool neg = static_cast<int64_t>(x[L - 1]) < 0;
  if (neg) limbs_neg(x, L);
  int n = L;
  while (n > 0 && x[n - 1] == 0) --n;
  mp_limb_t* p = mpz_limbs_write(z, n > 0 ? n : 1);
  for (int l = 0; l < n; ++l) p[l] = x[l];
  mpz_limbs_finish(z, neg ? -n : n);
}
int bitlen_u64(uint64_t v) { return v ? 64 - __builtin_clzll(v) : 0; }

}  // namespace

Compiler::Compiler(Format f) : f_(f) {
  f_.validate();
  // Q(K) is increasing in K, so the budget check is K <= kfit_ for every
  // K <= max_ticks; found with the exact fits() test.
  if (fits(f_.degree, f_.max_ticks, f_.guard_bits, f_.tol_lsb)) {
    kfit_ = f_.max_ticks;
  } else if (fits(f_.degree, 1, f_.guard_bits, f_.tol_lsb)) {
    uint64_t lo = 1, hi = f_.max_ticks;  // fits(lo), !fits(hi)
    while (hi - lo > 1) {
      const uint64_t mid = lo + (hi - lo) / 2;
      (fits(f_.degree, mid, f_.guard_bits, f_.tol_lsb) ? lo : hi) = mid;
    }
    kfit_ = lo;
  } else {
    kfit_ = 0;
  }
}

namespace {
// Least integer p with x <= m 2^p (x >= 1, 1 <= m < 2^63); t is scratch.
//   x <= m:  p = -s, s the largest with x 2^s <= m, i.e. 2^s <= floor(m/x)
//   x >  m:  p = ceil(log2 ceil(x/m)) = bitlen(ceil(x/m) - 1)
long least_pow2_exponent(mpz_srcptr x, uint64_t m, mpz_ptr t) {
  if (mpz_cmp_ui(x, m) <= 0) return -(bitlen_u64(m / mpz_get_ui(x)) - 1);
  mpz_cdiv_q_ui(t, x, m);
  mpz_sub_ui(t, t, 1);
  return static_cast<long>(mpz_sizeinbase(t, 2));
}

// RegisterNeeds from bin[i] = C(K, i) (i = 1..N, zero for i > K) and their
// sum, for tol = m 2^e: 1/2 X 2^-f <= tol/2 <=> X <= m 2^(e+f), so the least
// f is p - e with p from least_pow2_exponent (then at least 0). t, x: scratch.
void fill_needs(RegisterNeeds& nd, int N, const mpz_srcptr* bin, mpz_srcptr sum, const Dyadic& tol, mpz_ptr t,
                mpz_ptr x) {
  const uint64_t m = static_cast<uint64_t>(tol.m);
  auto need = [&](mpz_srcptr v) {
    return mpz_sgn(v) == 0 ? 0 : static_cast<int>(std::max(0L, least_pow2_exponent(v, m, t) - tol.e));
  };
  nd.alone.assign(N + 1, 0);
  nd.share.assign(N + 1, 0);
  nd.binding = 1;
  for (int i = 1; i <= N; ++i) {
    nd.alone[i] = need(bin[i]);
    mpz_mul_ui(x, bin[i], static_cast<unsigned long>(N));
    nd.share[i] = need(x);
    if (mpz_cmp(bin[i], bin[nd.binding]) >= 0) nd.binding = i;  // the largest, highest i on ties
  }
  nd.common = need(sum);
}
}  // namespace

RegisterNeeds Compiler::register_needs(int degree, uint64_t k, double tol_lsb) {
  if (!(tol_lsb > 0) || !std::isfinite(tol_lsb))
    throw CompileError("register_needs: tol_lsb=" + fmt_double(tol_lsb) + " must be positive and finite");
  if (degree < 1 || degree > 7) throw CompileError("register_needs: degree out of range 1..7");
  mpz_class c[8], sum = 0, t, x;
  mpz_srcptr bin[8];
  c[0] = 1;
  for (int i = 1; i <= degree; ++i) {
    if (static_cast<uint64_t>(i) <= k) {
      c[i] = c[i - 1] * static_cast<unsigned long>(k - i + 1);
      mpz_divexact_ui(c[i].get_mpz_t(), c[i].get_mpz_t(), static_cast<unsigned long>(i));
    }  // else C(k, i) = 0 (default)
    sum += c[i];
  }
  for (int i = 0; i <= degree; ++i) bin[i] = c[i].get_mpz_t();
  RegisterNeeds nd;
  fill_needs(nd, degree, bin, sum.get_mpz_t(), dyadic(tol_lsb), t.get_mpz_t(), x.get_mpz_t());
  return nd;
}

Compiled Compiler::compile(const PolySegment& seg, const std::vector<mpz_class>* start,
                           const std::string& where) const {
  const int N = f_.degree;
  const int A = f_.axes;
  auto fail = [&](const std::string& what) { throw CompileError(where + ": " + what); };

  // The refusals before any arithmetic, in the reference's order and words.
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
  if (seg.ticks > kfit_) return compile_reference(f_, seg, start, where);  // words the refusal

  const uint64_t K = seg.ticks;
  const int G = f_.guard_bits;
  const int sigma = G + f_.frac_bits;  // scale = 2^sigma
  Scratch& S = scratch();

  // Shared by the axes: powers of m_h, C(K, i), 2 Q(K).
  const Dyadic hd = dyadic(seg.h);  // m_h > 0, odd, < 2^53
  mpz_set_ui(S.hp[0], 1);
  for (int j = 1; j <= N; ++j) mpz_mul_ui(S.hp[j], S.hp[j - 1], static_cast<unsigned long>(hd.m));
  // The same as zero-padded limb arrays (hpL = kMaxLimbs + 1 if they do not fit).
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

  const Dyadic htol = dyadic(f_.tol_lsb / 2);  // tol/2 output LSB = m 2^(e+G) register LSB
  const long double T_ld = static_cast<long double>(seg.h) * static_cast<long double>(K);
  const long double limit_ld = std::ldexp(1.0L, f_.width - 1) * (1 - std::ldexp(1.0L, -40));
  const long double err_rel = std::ldexp(1.0L, -48);
  const long double grow = 1 + std::ldexp(1.0L, -40);
  const long double(*w)[8] = bernstein_weights().w[N];
  const SurjTable& surj = surj_table();

  Compiled out;
  out.ticks = static_cast<uint32_t>(K);
  out.regs.resize(A);
  for (auto& r : out.regs) r.resize(N + 1);
  out.end.resize(A);
  const long double scale_ld = std::ldexp(1.0L, sigma);  // exact power of two
  double carried = 0;
  for (int a = 0; a < A; ++a) {
    const std::vector<double>& cf = seg.coef[a];
    Dyadic d[8];
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
      if (far) return compile_reference(f_, seg, start, where);  // words the refusal
    }
    // to_lsb(e0, G) = |e0 / 2^G| as a double, truncated (mpq_get_d).
    double e0_lsb = 0;
    if (mpz_sgn(S.e) != 0) {
      long ex;
      const double dm = mpz_get_d_2exp(&ex, S.e);  // truncated to 53 bits
      const long p = ex + z - G;
      if (p - 1 < -1021 || p > 1023) return compile_reference(f_, seg, start, where);  // not a normal double
      e0_lsb = std::fabs(std::ldexp(dm, static_cast<int>(p)));
    }
    carried = std::max(carried, e0_lsb);

    // Range (see above): Bernstein bound of the blended target in long double.
    {
      const long double e0_ld = mpz_ldexp(S.e, z);
      const long double e0_abs = std::fabs(e0_ld);
      long double av[8], mag[8];
      av[0] = mpz_size(S.r0) <= 2 ? static_cast<long double>(mpz_get_d(S.r0)) : mpz_ldexp(S.r0, 0);
      mag[0] = std::fabs(av[0]);
      long double Tj = 1;
      for (int j = 1; j <= N; ++j) {
        Tj *= T_ld;
        const long double cj = j < static_cast<int>(cf.size()) ? static_cast<long double>(cf[j]) * scale_ld : 0;
        if (j == 1) {
          av[1] = (cj - e0_ld / T_ld) * T_ld;
          mag[1] = (std::fabs(cj) + e0_abs / T_ld) * T_ld;
        } else {
          av[j] = cj * Tj;
          mag[j] = std::fabs(av[j]);
        }
      }
      long double mhi = 0;
      for (int i = 0; i <= N; ++i) {
        long double b = 0, sm = 0;
        for (int j = 0; j <= i; ++j) {
          b += av[j] * w[i][j];
          sm += mag[j] * w[i][j];
        }
        mhi = std::max(mhi, std::fabs(b) + sm * err_rel);
      }
      const long double total = (mhi + e0_abs + static_cast<long double>(q2_d) + 2) * grow;
      if (!(total < limit_ld)) return compile_reference(f_, seg, start, where);  // decides and words it
    }

    // Registers: exact differences at scale 2^-z, rounded to nearest.
    std::vector<mpz_class>& r = out.regs[a];
    // Size bound: |u_j| < 2^B, |X_i| < 2^(B+15) (sum of surj(j,i) <= 18720),
    // for r[1]: |K X_1| < 2^(B+3+32), |E|, K 2^(sz-1) < 2^(sz+32).
    long B = 0;
    for (int j = 1; j <= N; ++j)
      if (d[j].m)
        B = std::max<long>(B, bitlen_u64(static_cast<uint64_t>(d[j].m < 0 ? -d[j].m : d[j].m)) +
                                  static_cast<long>(mpz_sizeinbase(S.hp[j], 2)) + (xe[j] - z));
    const long need = std::max({B + 35, static_cast<long>(mpz_sizeinbase(S.e, 2)), static_cast<long>(sz) + 33}) + 3;
    const int L = static_cast<int>(need / 64 + 1);
    if (L <= kMaxLimbs && L <= hpL) {
      uint64_t u[8][kMaxLimbs], x[kMaxLimbs], y[kMaxLimbs];
      for (int j = 1; j <= N; ++j)
        if (d[j].m) {
          limbs_mul1(u[j], hpl[j], static_cast<uint64_t>(d[j].m < 0 ? -d[j].m : d[j].m), L);
          limbs_shl(u[j], static_cast<unsigned long>(xe[j] - z), L);
          if (d[j].m < 0) limbs_neg(u[j], L);
        }
      for (int i = 1; i <= N; ++i) {
        u128 c = 0;
        for (int l = 0; l < L; ++l) {
          u128 acc = c;
          for (int j = i; j <= N; ++j)
            if (d[j].m) acc += static_cast<u128>(u[j][l]) * surj.v[j][i];
          x[l] = static_cast<uint64_t>(acc);
          c = acc >> 64;
        }
        if (i == 1) {
          // floor((X - E/K) 2^z + 1/2) = floor(floor((K X - E + K half) / 2^-z) / K)
          limbs_mul1(x, x, K, L);
          limbs_from_mpz(y, S.e, true, L);
          limbs_add(x, y, L);
          for (int l = 0; l < L; ++l) y[l] = 0;
          y[0] = K;
          limbs_shl(y, sz - 1, L);
          limbs_add(x, y, L);
          limbs_sar(x, sz, L);
          limbs_to_mpz(S.x, x, L);
          mpz_fdiv_q_ui(r[1].get_mpz_t(), S.x, K);
        } else {
          for (int l = 0; l < L; ++l) y[l] = 0;
          y[0] = 1;
          limbs_shl(y, sz - 1, L);
          limbs_add(x, y, L);
          limbs_sar(x, sz, L);
          limbs_to_mpz(r[i].get_mpz_t(), x, L);
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
          if (d[j].m) mpz_addmul_ui(S.x, S.u[j], surj.v[j][i]);
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
  {
    mpz_srcptr bin[8];
    for (int i = 0; i <= N; ++i) bin[i] = S.bin[i];
    fill_needs(out.needs, N, bin, S.q2, dyadic(f_.tol_lsb), S.t, S.x);
  }
  return out;
}

mpz_class Compiler::state_at(const Compiled& c, int axis, uint64_t k) {
  const auto& r = c.regs[axis];
  mpz_class s = 0;
  if (r.empty()) return s;
  mpz_ptr sp = s.get_mpz_t();
  mpz_set(sp, r[0].get_mpz_t());
  mpz_ptr b = scratch().sb;  // C(k, i), built incrementally
  mpz_set_ui(b, 1);
  for (size_t i = 1; i < r.size() && i <= k; ++i) {
    mpz_mul_ui(b, b, k - i + 1);
    mpz_divexact_ui(b, b, static_cast<unsigned long>(i));
    mpz_addmul(sp, r[i].get_mpz_t(), b);
  }
  return s;
}

mpz_class Compiler::sample_at(const Compiled& c, int axis, uint64_t k) const {
  mpz_class s = state_at(c, axis, k);
  mpz_fdiv_q_2exp(s.get_mpz_t(), s.get_mpz_t(), f_.guard_bits);
  return s;
}

std::vector<uint64_t> Compiler::words(const Compiled& c) const {
  static_assert(GMP_NUMB_BITS == 64, "words() reads 64-bit GMP limbs");
  const int C = f_.chunk_width;
  std::vector<uint64_t> w;
  size_t nregs = 0;
  for (const auto& axis : c.regs) nregs += axis.size();
  w.reserve(2 + nregs * static_cast<size_t>(f_.width / C));
  const uint64_t cmask = C == 64 ? ~uint64_t(0) : ((uint64_t(1) << C) - 1);
  if (C < 32) {
    for (int s = 0; s < 32; s += C) w.push_back((uint64_t(c.ticks) >> s) & cmask);
  } else {
    w.push_back(c.ticks);
  }
  mpz_ptr v = scratch().sw;
  for (const auto& axis : c.regs) {
    for (const auto& r : axis) {
      mpz_fdiv_r_2exp(v, r.get_mpz_t(), static_cast<mp_bitcnt_t>(f_.width));  // two's complement, W bits
      // C divides 64, so a chunk never straddles two limbs.
      for (int s = 0; s < f_.width; s += C)
        w.push_back((static_cast<uint64_t>(mpz_getlimbn(v, s / 64)) >> (s % 64)) & cmask);
    }
  }
  return w;
}

}  // namespace traj::fd
