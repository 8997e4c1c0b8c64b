#include "fd/fd_compiler.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <sstream>
#include <type_traits>

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

PathCounts& path_counts() {
  thread_local PathCounts c;
  return c;
}

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

// The refusals before any arithmetic (shape, h, K, degree, finite
// coefficients, start state), shared by compile() and the reference.
void check_segment(const Format& f_, const PolySegment& seg, const std::vector<mpz_class>* start,
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
}

// The straightforward exact form (mpq throughout). The fast path of compile()
// falls back to it for every refusal and every case it cannot settle itself, so
// messages and borderline decisions are this function's by construction.
Compiled compile_reference(const Format& f_, const PolySegment& seg, const std::vector<mpz_class>* start,
                           const std::string& where) {
  ++path_counts().reference;
  const int N = f_.degree;
  const int A = f_.axes;
  auto fail = [&](const std::string& what) { throw CompileError(where + ": " + what); };

  check_segment(f_, seg, start, where);

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
// Fast exact paths: compile() first tries the fixed-point grid path
// (compile_grid, below), which settles nearly every segment without GMP, and
// hands what it cannot settle to the exact integer path (compile_exact), which
// hands refusals and borderline range decisions to compile_reference(). Both
// fast paths rest on the following.
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
// way. In compile_exact() the sums run on fixed-size two's complement limb
// arrays (at most 16 limbs, size bounded in advance per axis; mpz otherwise),
// the rest on mpz scratch variables held per thread (no allocation once warm).
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
// (its roundings are relative 2^-52 at worst). The grid path first tries the
// cruder bound sum_j |a_j| >= max_i |b_i| with the same margins. Anything else
// (a refusal, or a path within that margin of the limit) goes to
// compile_reference(), which then decides and words the message exactly as
// before. The same holds for a discontinuous start and for a carried error
// too small for a normal double.
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
struct Dyadic {  // trivial (arrays of it are not zeroed unless asked)
  int64_t m;
  int e;
};
Dyadic dyadic(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  const int ef = static_cast<int>((bits >> 52) & 0x7ff);
  uint64_t m = bits & ((uint64_t(1) << 52) - 1);
  Dyadic d{0, 0};
  if (ef == 0 && m == 0) return d;  // +-0
  int e = ef == 0 ? -1074 : ef - 1075;  // subnormal : normal
  if (ef != 0) m |= uint64_t(1) << 52;
  const int tz = __builtin_ctzll(m);
  d.m = static_cast<int64_t>(m >> tz);
  if (bits >> 63) d.m = -d.m;
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
using i128 = __int128;

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
  scale_ld_ = std::ldexp(1.0L, f_.guard_bits + f_.frac_bits);
  limit_ld_ = std::ldexp(1.0L, f_.width - 1) * (1 - std::ldexp(1.0L, -40));
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
// Unsigned multi-limb integers for the binomials C(K, i) (i <= 7, K < 2^64, so
// C < 2^448: at most 7 limbs) and the needs derived from them: exact, on the
// stack, no GMP.
struct Big {
  uint64_t v[8] = {};
  int n = 0;  // limbs in use; v[n-1] != 0 unless n == 0
};
void big_set(Big& x, uint64_t v) {
  x.v[0] = v;
  x.n = v ? 1 : 0;
}
void big_mul_small(Big& x, uint64_t m) {  // x *= m
  u128 c = 0;
  for (int l = 0; l < x.n; ++l) {
    c += static_cast<u128>(x.v[l]) * m;
    x.v[l] = static_cast<uint64_t>(c);
    c >>= 64;
  }
  if (c) x.v[x.n++] = static_cast<uint64_t>(c);
  if (m == 0) x.n = 0;
}
// x = floor(x / d), d < 2^32: two 64-by-32-bit steps per limb (the running
// remainder is below d, so every partial dividend fits in 64 bits).
uint64_t div_limbs_small(uint64_t* x, int n, uint64_t d) {
  uint64_t r = 0;
  for (int l = n - 1; l >= 0; --l) {
    const uint64_t hi = (r << 32) | (x[l] >> 32);
    const uint64_t qh = hi / d;
    r = hi - qh * d;
    const uint64_t lo = (r << 32) | (x[l] & 0xffffffffu);
    const uint64_t ql = lo / d;
    r = lo - ql * d;
    x[l] = (qh << 32) | ql;
  }
  return r;
}
void big_add(Big& x, const Big& y) {  // x += y
  const int n = std::max(x.n, y.n);
  u128 c = 0;
  for (int l = 0; l < n; ++l) {
    c += static_cast<u128>(l < x.n ? x.v[l] : 0) + (l < y.n ? y.v[l] : 0);
    x.v[l] = static_cast<uint64_t>(c);
    c >>= 64;
  }
  x.n = n;
  if (c) x.v[x.n++] = static_cast<uint64_t>(c);
}
int big_cmp(const Big& x, const Big& y) {
  if (x.n != y.n) return x.n < y.n ? -1 : 1;
  for (int l = x.n - 1; l >= 0; --l)
    if (x.v[l] != y.v[l]) return x.v[l] < y.v[l] ? -1 : 1;
  return 0;
}

// Bit length of an n-limb magnitude (leading zero limbs allowed).
int bitlen_limbs(const uint64_t* x, int n) {
  while (n > 0 && x[n - 1] == 0) --n;
  return n ? 64 * (n - 1) + bitlen_u64(x[n - 1]) : 0;
}
// Bits [pos, pos + 64) of an n-limb magnitude (pos >= 0).
uint64_t bits64_at(const uint64_t* x, int n, long pos) {
  const long q = pos >> 6;
  const unsigned r = static_cast<unsigned>(pos & 63);
  const uint64_t lo = q < n ? x[q] : 0;
  if (!r) return lo;
  const uint64_t hi = q + 1 < n ? x[q + 1] : 0;
  return (lo >> r) | (hi << (64 - r));
}
// Whether any of bits [0, pos) of x is set.
bool any_bits_below(const uint64_t* x, int n, long pos) {
  const long q = pos >> 6;
  for (long l = 0; l < q && l < n; ++l)
    if (x[l]) return true;
  const unsigned r = static_cast<unsigned>(pos & 63);
  return r && q < n && (x[q] & ((uint64_t(1) << r) - 1));
}
// Sign of x - m 2^s for an n-limb magnitude x and 1 <= m < 2^64, exactly.
int cmp_m2e(const uint64_t* x, int n, uint64_t m, long s) {
  const long bx = bitlen_limbs(x, n), bm = bitlen_u64(m);
  if (bx != bm + s) return bx > bm + s ? 1 : -1;
  if (s >= 0) {  // same bit length: compare the top bm bits, then the rest
    const uint64_t top = bits64_at(x, n, s) & (bm == 64 ? ~uint64_t(0) : (uint64_t(1) << bm) - 1);
    if (top != m) return top > m ? 1 : -1;
    return any_bits_below(x, n, s) ? 1 : 0;
  }
  const uint64_t xs = x[0] << (-s);  // bx = bm + s < 64 bits, shifted to bm bits
  return xs > m ? 1 : xs < m ? -1 : 0;
}
// Least integer p with x <= m 2^p (x >= 1, m >= 1): with p0 = bitlen(x) -
// bitlen(m), m 2^(p0-1) < 2^(bitlen(x)-1) <= x and x < 2^bitlen(x) <= m 2^(p0+1),
// so p is p0 or p0 + 1, decided by one exact comparison.
long least_pow2_exponent(const uint64_t* x, int n, uint64_t m) {
  const long p0 = static_cast<long>(bitlen_limbs(x, n)) - bitlen_u64(m);
  return cmp_m2e(x, n, m, p0) <= 0 ? p0 : p0 + 1;
}

// C(K, i), i = 0..N (zero for i > K), and their sum over i = 1..N, exactly.
struct Binomials {
  Big c[8];
  Big sum;
  void compute(int N, uint64_t K) {
    big_set(c[0], 1);
    big_set(sum, 0);
    for (int i = 1; i <= N; ++i) {
      c[i] = c[i - 1];
      if (static_cast<uint64_t>(i) > K) {
        big_set(c[i], 0);
        continue;
      }
      big_mul_small(c[i], K - static_cast<uint64_t>(i) + 1);  // C(K,i) = C(K,i-1) (K-i+1) / i, exact
      div_limbs_small(c[i].v, c[i].n, static_cast<uint64_t>(i));
      if (c[i].v[c[i].n - 1] == 0) --c[i].n;
      big_add(sum, c[i]);
    }
  }
};

// RegisterNeeds from C(K, i) (i = 1..N) and their sum, for tol = m 2^e:
// 1/2 X 2^-f <= tol/2 <=> X <= m 2^(e+f), so the least f is p - e with p from
// least_pow2_exponent (then at least 0).
struct NeedsArr {
  int alone[8] = {}, share[8] = {};
  int binding = 1, common = 0;
};
NeedsArr compute_needs(int N, const Binomials& b, const Dyadic& tol) {
  const uint64_t m = static_cast<uint64_t>(tol.m);
  auto need = [&](const Big& v) {
    return v.n == 0 ? 0 : static_cast<int>(std::max(0L, least_pow2_exponent(v.v, v.n, m) - tol.e));
  };
  NeedsArr nd;
  for (int i = 1; i <= N; ++i) {
    nd.alone[i] = need(b.c[i]);
    Big x = b.c[i];
    big_mul_small(x, static_cast<uint64_t>(N));
    nd.share[i] = need(x);
    if (big_cmp(b.c[i], b.c[nd.binding]) >= 0) nd.binding = i;  // the largest, highest i on ties
  }
  nd.common = need(b.sum);
  return nd;
}
void set_needs(RegisterNeeds& nd, int N, const NeedsArr& a) {
  nd.alone.assign(a.alone, a.alone + N + 1);
  nd.share.assign(a.share, a.share + N + 1);
  nd.binding = a.binding;
  nd.common = a.common;
}
}  // namespace

// ---------------------------------------------------------------------------
// Fixed-point grid path (the common case: no GMP, no heap until the result).
//
// The same dyadic sums as compile_exact(), but each term
//     u_j = c_j 2^sigma h^j = m_j m_h^j 2^(e_j + sigma + j e_h)
// is taken on a grid of 2^-64 register LSB (truncated towards zero: error
// below one grid unit, and none if the term lies on the grid), in L = 3 or 4
// limbs of two's complement (L chosen per segment from a bound on every
// quantity; larger segments go to compile_exact()). Since m_j and m_h are odd,
// a term is off the grid exactly when its exponent is below -64. Then
//     X_i = sum_j surj(j,i) u_j   differs from the exact Delta^i by less than
//     err_i = sum of surj(j,i) over the terms off the grid (< 2^15 grid units),
// and r_i = floor(X_i/2^64 + 1/2) is certain unless X_i + 2^63 lies within
// err_i of a multiple of 2^64 (probability ~2^-49 for arbitrary data; exact
// ties, e.g. dyadic h, have err_i = 0 and are decided exactly). r_1 also
// carries the blend -e0/K: with e0 (exact on the grid) = K qd + rd,
// 0 <= rd < K, the exact value is X_1 - qd - rd/K, i.e. within (-1, 0] of
// X_1 - qd. An undecided rounding sends the segment to compile_exact().
// The start error e0 = r0 - c0 is exact on the grid (c0 = x(0) 2^sigma +
// 2^(G-1) must lie on it, else compile_exact()), so the continuity check,
// carried_lsb (truncated to a double as mpq_get_d does) and the range check's
// inputs are those of compile_exact(). The end state r0 + sum r_i C(K,i) is
// taken modulo 2^128: the range check bounds the exact value below
// 2^(W-1) <= 2^127 in magnitude (|r0(K) - q(T)| <= Q(K), README), so the
// residue read as a signed 128-bit integer is the exact value.
namespace {

// Bits [pos, pos + 64) of an n-limb magnitude, pos of any sign (bits below 0
// are zero).
inline uint64_t get64(const uint64_t* x, int n, long pos) {
  if (pos >= 0) return bits64_at(x, n, pos);
  if (pos <= -64) return 0;
  return x[0] << (-pos);
}

// m_h^j, j = 0..7, of the tick period's odd mantissa m_h < 2^53 (at most 371
// bits: 6 limbs), cached per thread for the last h.
struct HPowers {
  uint64_t key = 0;  // bit pattern of h (h > 0, so 0 means empty)
  Dyadic hd{0, 0};
  uint64_t p[8][6] = {};
  int n[8] = {};     // limbs in use
  int bits[8] = {};  // bit length
  u128 top[8] = {};  // m_h^j ~ top 2^tshift, top normalised to 128 bits (exact if bits <= 128)
  int tshift[8] = {};
};
const HPowers& h_powers(double h) {
  thread_local HPowers c;
  uint64_t key;
  std::memcpy(&key, &h, sizeof key);
  if (c.key != key) {
    c.key = key;
    c.hd = dyadic(h);
    const uint64_t m = static_cast<uint64_t>(c.hd.m);
    c.p[0][0] = 1;
    c.n[0] = 1;
    for (int j = 1; j < 8; ++j) {
      u128 carry = 0;
      for (int l = 0; l < c.n[j - 1]; ++l) {
        carry += static_cast<u128>(c.p[j - 1][l]) * m;
        c.p[j][l] = static_cast<uint64_t>(carry);
        carry >>= 64;
      }
      c.n[j] = c.n[j - 1];
      if (carry) c.p[j][c.n[j]++] = static_cast<uint64_t>(carry);
    }
    for (int j = 0; j < 8; ++j) {
      c.bits[j] = bitlen_limbs(c.p[j], c.n[j]);
      c.tshift[j] = c.bits[j] - 128;
      const uint64_t lo = get64(c.p[j], c.n[j], c.tshift[j]), hi = get64(c.p[j], c.n[j], c.tshift[j] + 64);
      c.top[j] = (static_cast<u128>(hi) << 64) | lo;
    }
  }
  return c;
}

template <int L>
inline void neg_l(uint64_t* x) {
  uint64_t c = 1;
  for (int l = 0; l < L; ++l) {
    x[l] = ~x[l] + c;
    c = c && x[l] == 0;
  }
}
template <int L>
inline bool is_neg(const uint64_t* x) {
  return static_cast<int64_t>(x[L - 1]) < 0;
}
template <int L>
inline void abs_l(const uint64_t* x, uint64_t* m) {
  for (int l = 0; l < L; ++l) m[l] = x[l];
  if (is_neg<L>(x)) neg_l<L>(m);
}
template <int L>
inline void sub_l(uint64_t* x, const uint64_t* y) {  // x -= y (modulo 2^(64 L))
  uint64_t borrow = 0;
  for (int l = 0; l < L; ++l) {
    const uint64_t t = x[l] - y[l];
    const uint64_t b1 = x[l] < y[l];
    x[l] = t - borrow;
    borrow = b1 | (t < borrow);
  }
}
template <int L>
inline void add_u64_at(uint64_t* x, uint64_t v, int at) {  // x += v 2^(64 at) (modulo 2^(64 L))
  uint64_t c = v;
  for (int l = at; l < L; ++l) {
    x[l] += c;
    c = x[l] < c;
  }
}
template <int L>
inline void sub_u64(uint64_t* x, uint64_t v) {  // x -= v (modulo 2^(64 L))
  uint64_t b = v;
  for (int l = 0; l < L; ++l) {
    const uint64_t t = x[l];
    x[l] = t - b;
    b = t < b;
  }
}
template <int L>
inline bool is_zero(const uint64_t* x) {
  uint64_t o = 0;
  for (int l = 0; l < L; ++l) o |= x[l];
  return o == 0;
}
// Signed L-limb value as long double (relative error below 2^-61).
template <int L>
long double ld_of(const uint64_t* x) {
  uint64_t m[L];
  abs_l<L>(x, m);
  long double v = 0;
  for (int l = L - 1; l >= 0; --l) v = v * 0x1p64L + static_cast<long double>(m[l]);
  return is_neg<L>(x) ? -v : v;
}
// |x| 2^p of an n-limb magnitude as a double, truncated to 53 bits like
// mpz_get_d / mpq_get_d; false if the result would not be a normal double.
bool trunc_double(const uint64_t* x, int n, long p, double& out) {
  const int bx = bitlen_limbs(x, n);
  if (bx == 0) {
    out = 0;
    return true;
  }
  uint64_t mant = bx <= 64 ? x[0] : bits64_at(x, n, bx - 64);
  const int bm = bx <= 64 ? bx : 64;
  p += bx - bm;
  if (bm > 53) {
    mant >>= bm - 53;
    p += bm - 53;
  }
  const long binade = p + std::min(bm, 53) - 1;
  if (binade < -1022 || binade > 1023) return false;
  const uint64_t bits = (static_cast<uint64_t>(binade + 1023) << 52) |
                        ((mant << (53 - std::min(bm, 53))) & ((uint64_t(1) << 52) - 1));
  std::memcpy(&out, &bits, sizeof out);
  return true;
}
// The result's registers are written straight into their mpz: in place if
// there is room (a reused result); a fresh mpz (GMP >= 6.2: mpz_init
// allocates nothing, _mp_alloc = 0) gets exactly the limbs it needs from
// GMP's own allocation function (fetched once per compile(), so a program
// that sets its own keeps it), which is what mpz_limbs_write would do through
// _mpz_realloc, minus the round trip; GMP frees them with mpz_clear.
using GmpAlloc = void* (*)(size_t);
GmpAlloc gmp_alloc_func() {
  void* (*fa)(size_t);
  mp_get_memory_functions(&fa, nullptr, nullptr);
  return fa;
}
inline mp_limb_t* mpz_room(mpz_ptr z, int k, GmpAlloc alloc) {  // k >= 1
  if (z->_mp_alloc >= k) return z->_mp_d;
  if (z->_mp_alloc == 0) {
    mp_limb_t* p = static_cast<mp_limb_t*>(alloc(static_cast<size_t>(k) * sizeof(mp_limb_t)));
    z->_mp_d = p;
    z->_mp_alloc = k;
    return p;
  }
  return mpz_limbs_write(z, k);
}
// z = sign * the k-limb magnitude m (m[k-1] != 0 or k = 0).
inline void mpz_set_mag(mpz_ptr z, const uint64_t* m, int k, bool neg, GmpAlloc alloc) {
  if (k > 0) {
    mp_limb_t* p = mpz_room(z, k, alloc);
    for (int l = 0; l < k; ++l) p[l] = m[l];
  }
  z->_mp_size = neg ? -k : k;
}
// z = the signed n-limb two's complement value x (n <= 4).
inline void mpz_set_limbs(mpz_ptr z, const uint64_t* x, int n, GmpAlloc alloc) {
  uint64_t m[4];
  const bool neg = static_cast<int64_t>(x[n - 1]) < 0;
  const uint64_t flip = neg ? ~uint64_t(0) : 0;
  uint64_t c = neg ? 1 : 0;
  for (int l = 0; l < n; ++l) {  // m = neg ? ~x + 1 : x
    m[l] = (x[l] ^ flip) + c;
    c = c & (m[l] == 0);
  }
  int k = n;
  while (k > 0 && m[k - 1] == 0) --k;
  mpz_set_mag(z, m, k, neg, alloc);
}
// z = v, a signed 128-bit value.
inline void mpz_set_s128(mpz_ptr z, u128 v, GmpAlloc alloc) {
  const bool neg = static_cast<i128>(v) < 0;
  const u128 m = neg ? -v : v;
  const uint64_t lo = static_cast<uint64_t>(m), hi = static_cast<uint64_t>(m >> 64);
  const int k = hi ? 2 : lo ? 1 : 0;
  if (k > 0) {
    mp_limb_t* p = mpz_room(z, k, alloc);
    p[0] = lo;
    if (k == 2) p[1] = hi;
  }
  z->_mp_size = neg ? -k : k;
}
// Low 128 bits of an mpz in two's complement.
u128 low128(mpz_srcptr z) {
  const int n = std::abs(z->_mp_size);
  u128 v = n > 0 ? z->_mp_d[0] : 0;
  if (n > 1) v |= static_cast<u128>(z->_mp_d[1]) << 64;
  return z->_mp_size < 0 ? -v : v;
}

// Per (degree, K, tol): C(K, i) modulo 2^128, 2 Q(K) = sum C(K, i) as a
// double truncated like mpz_get_d, and the register needs. A planner's
// segments repeat a few hundred lengths, so this is cached per thread
// (direct-mapped; a miss costs one exact computation on limbs).
struct KData {
  uint64_t K = 0, tol = 0;
  int N = 0;  // 0: empty
  double q2_d = 0;
  u128 binlo[8] = {};
  NeedsArr needs;
};
constexpr int kKCacheBits = 10;
struct KCacheOwner {
  KData* p = nullptr;
  ~KCacheOwner() { delete[] p; }
};
const KData& k_data(int N, uint64_t K, double tol_lsb) {
  thread_local KData* cache = nullptr;
  if (!cache) {
    thread_local KCacheOwner owner;
    cache = owner.p = new KData[size_t(1) << kKCacheBits];
  }
  uint64_t tb;
  std::memcpy(&tb, &tol_lsb, sizeof tb);
  const uint64_t h = (K * 0x9E3779B97F4A7C15ull) ^ (tb * 0xC2B2AE3D27D4EB4Full) ^ static_cast<uint64_t>(N);
  KData& e = cache[h >> (64 - kKCacheBits)];
  if (e.N == N && e.K == K && e.tol == tb) return e;
  Binomials b;
  b.compute(N, K);
  e.K = K;
  e.tol = tb;
  e.N = N;
  trunc_double(b.sum.v, b.sum.n, 0, e.q2_d);  // >= 1 and < 2^448: always a normal double
  for (int i = 0; i < 8; ++i)
    e.binlo[i] = i > N || b.c[i].n == 0 ? 0 : (static_cast<u128>(b.c[i].n > 1 ? b.c[i].v[1] : 0) << 64) | b.c[i].v[0];
  e.needs = compute_needs(N, b, dyadic(tol_lsb));
  return e;
}

// The power-basis terms of the blended target over the segment, register
// units: av[0] = r0, av[1] = (c1 - e0 / T) T, av[j] = c_j T^j; mag[j] bounds
// |av[j]| (mag[1] with the two parts of av[1] added in magnitude).
void power_terms(int N, const std::vector<double>& cf, long double scale_ld, long double T_ld, long double r0_ld,
                 long double e0_ld, long double* av, long double* mag) {
  const long double e0_abs = std::fabs(e0_ld);
  av[0] = r0_ld;
  mag[0] = std::fabs(r0_ld);
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
}

// The range check of the grid paths (see "Fast exact paths" above) for the
// blended target with r0 = r0_ld, e0 = e0_ld (register units): true if it
// accepts; false leaves the decision (and a refusal's words) to
// compile_exact() and the reference.
bool range_ok(int N, const std::vector<double>& cf, long double scale_ld, long double T_ld, long double r0_ld,
              long double e0_ld, double q2_d, long double limit_ld) {
  const long double err_rel = 0x1p-48L;
  const long double grow = 1 + 0x1p-40L;
  const long double e0_abs = std::fabs(e0_ld);
  long double av[8], mag[8];
  power_terms(N, cf, scale_ld, T_ld, r0_ld, e0_ld, av, mag);
  // First the power-basis bound sum_j |a_j| >= sum_j w_ij |a_j| >= |b_i|
  // (0 < w_ij <= 1), with the same relative margin; far from the limit
  // (nearly always) it settles the check without the Bernstein sums.
  long double sum_mag = 0;
  for (int j = 0; j <= N; ++j) sum_mag += mag[j];
  const long double rest = e0_abs + static_cast<long double>(q2_d) + 2;
  if ((sum_mag * (1 + err_rel) + rest) * grow < limit_ld) return true;
  const long double(*w)[8] = bernstein_weights().w[N];
  long double mhi = 0;
  for (int i = 0; i <= N; ++i) {
    long double bb = 0, sm = 0;
    for (int j = 0; j <= i; ++j) {
      bb += av[j] * w[i][j];
      sm += mag[j] * w[i][j];
    }
    mhi = std::max(mhi, std::fabs(bb) + sm * err_rel);
  }
  return (mhi + rest) * grow < limit_ld;
}

struct GridOut {
  uint64_t reg[8][8][3];  // [axis][i] r[i] as L-1 limbs (i = 0 only if no start)
  u128 end[8];
};

// The axes of one segment on the L-limb grid; false if a rounding is not
// certain or anything else is left to compile_exact().
template <int L>
bool grid_axes(const Format& f, const PolySegment& seg, const std::vector<mpz_class>* start, const HPowers& hp,
               const Dyadic (*d)[8], const u128* binlo, double q2_d, const Dyadic& htol, long double scale_ld,
               long double limit_ld, double& carried, GridOut& o) {
  const int N = f.degree;
  const int G = f.guard_bits;
  const long sigma = G + f.frac_bits;
  const uint64_t K = seg.ticks;
  const long double T_ld = static_cast<long double>(seg.h) * static_cast<long double>(K);
  const SurjTable& surj = surj_table();

  for (int a = 0; a < f.axes; ++a) {
    const std::vector<double>& cf = seg.coef[a];
    const Dyadic* da = d[a];
    // c0 = x(0) 2^sigma + 2^(G-1) on the grid.
    uint64_t c0[L] = {};
    if (da[0].m) {
      const uint64_t am = static_cast<uint64_t>(da[0].m < 0 ? -da[0].m : da[0].m);
      const long s0 = da[0].e + sigma + 64;
      for (int l = 0; l < L; ++l) c0[l] = get64(&am, 1, 64 * l - s0);
      if (da[0].m < 0) neg_l<L>(c0);
    }
    add_u64_at<L>(c0, uint64_t(1) << ((G + 63) % 64), (G + 63) / 64);
    // r0 and e0 = r0 - c0 (grid units).
    uint64_t e0[L];
    u128 r0lo;
    if (start) {
      mpz_srcptr z = (*start)[a].get_mpz_t();
      const int n = std::abs(z->_mp_size);
      uint64_t r0g[L] = {};
      for (int l = 0; l < n; ++l) r0g[l + 1] = z->_mp_d[l];
      if (z->_mp_size < 0) neg_l<L>(r0g);
      for (int l = 0; l < L; ++l) e0[l] = r0g[l];
      sub_l<L>(e0, c0);
      r0lo = low128(z);
    } else {
      uint64_t zz[L];
      for (int l = 0; l < L; ++l) zz[l] = c0[l];
      add_u64_at<L>(zz, uint64_t(1) << 63, 0);
      for (int l = 1; l < L; ++l) o.reg[a][0][l - 1] = zz[l];
      r0lo = (static_cast<u128>(zz[2]) << 64) | zz[1];
      // e0 = 2^63 - (low limb of c0 + 2^63), in (-2^63, 2^63]
      const uint64_t low = zz[0];
      const uint64_t v = (uint64_t(1) << 63) - low;  // modulo 2^64
      const bool negv = low > (uint64_t(1) << 63);
      e0[0] = v;
      for (int l = 1; l < L; ++l) e0[l] = negv ? ~uint64_t(0) : 0;
    }
    uint64_t e0m[L];
    abs_l<L>(e0, e0m);
    const bool e0zero = is_zero<L>(e0);
    // Continuity (refused by the reference: compile_exact() words it).
    if (start && !e0zero && cmp_m2e(e0m, L, static_cast<uint64_t>(htol.m), htol.e + G + 64) > 0) return false;
    double e0_lsb;
    if (!trunc_double(e0m, L, -(64L + G), e0_lsb)) return false;
    carried = std::max(carried, e0_lsb);

    // Range: the same long double Bernstein bound as compile_exact().
    {
      uint64_t r0l[L];  // r0 (register units), L limbs
      if (start) {
        mpz_srcptr z = (*start)[a].get_mpz_t();
        const int n = std::abs(z->_mp_size);
        for (int l = 0; l < L; ++l) r0l[l] = l < n ? z->_mp_d[l] : 0;
        if (z->_mp_size < 0) neg_l<L>(r0l);
      } else {
        for (int l = 0; l < L - 1; ++l) r0l[l] = o.reg[a][0][l];
        r0l[L - 1] = static_cast<int64_t>(r0l[L - 2]) < 0 ? ~uint64_t(0) : 0;
      }
      if (!range_ok(N, cf, scale_ld, T_ld, ld_of<L>(r0l), ld_of<L>(e0) * 0x1p-64L, q2_d, limit_ld)) return false;
    }

    // Terms on the grid.
    uint64_t u[8][L];
    uint64_t off[8];  // all ones if term j is off the grid (then its error is below one grid unit)
    for (int j = 1; j <= N; ++j) {
      off[j] = 0;
      if (!da[j].m) {
        for (int l = 0; l < L; ++l) u[j][l] = 0;
        continue;
      }
      const uint64_t am = static_cast<uint64_t>(da[j].m < 0 ? -da[j].m : da[j].m);
      // prod = |m_j| m_h^j (at most 7 limbs) at buf[4..], zeros around it.
      uint64_t buf[16];
      buf[0] = buf[1] = buf[2] = buf[3] = 0;
      u128 carry = 0;
      const int pn = hp.n[j];
      for (int l = 0; l < pn; ++l) {
        carry += static_cast<u128>(hp.p[j][l]) * am;
        buf[4 + l] = static_cast<uint64_t>(carry);
        carry >>= 64;
      }
      buf[4 + pn] = static_cast<uint64_t>(carry);
      for (int l = 0; l < L; ++l) buf[5 + pn + l] = 0;  // read up to buf[4 + q + L], q <= pn
      // u_j = prod 2^s truncated: limb l holds bits [64 l - s, 64 l - s + 64)
      // of prod, i.e. words q + l, q + l + 1 of buf + 4 with q = floor(-s/64).
      // The size bound of compile_grid (bitlen(prod) + s - 64 + 3 + 67 <= 255)
      // gives s <= 248, so q >= -4.
      const long s = da[j].e + sigma + static_cast<long>(j) * hp.hd.e + 64;
      const long q = (-s) >> 6;  // floor
      const unsigned r = static_cast<unsigned>((-s) & 63);
      if (q > pn) {
        for (int l = 0; l < L; ++l) u[j][l] = 0;
      } else {
        const uint64_t* w0 = buf + 4 + q;
        for (int l = 0; l < L; ++l) u[j][l] = (w0[l] >> r) | ((w0[l + 1] << 1) << (63 - r));
      }
      off[j] = s < 0 ? ~uint64_t(0) : 0;
      if (da[j].m < 0) neg_l<L>(u[j]);
    }
    // e0 = K qd + rd, 0 <= rd < K (floor division).
    uint64_t qd[L] = {};
    uint64_t rd = 0;
    if (!e0zero) {
      for (int l = 0; l < L; ++l) qd[l] = e0m[l];
      const uint64_t r = div_limbs_small(qd, L, K);
      if (is_neg<L>(e0)) {
        if (r) add_u64_at<L>(qd, 1, 0);
        neg_l<L>(qd);
        rd = r ? K - r : 0;
      } else {
        rd = r;
      }
    }
    u128 end = r0lo;
    for (int i = 1; i <= N; ++i) {
      // X_i = sum_{j >= i} surj(j,i) u_j (modulo 2^(64 L); each limb column
      // below 7 2^79, so one u128 per column), err_i as above.
      u128 acc[L] = {};
      uint64_t err = 0;
      for (int j = i; j <= N; ++j) {
        const uint64_t sj = surj.v[j][i];
        for (int l = 0; l < L; ++l) acc[l] += static_cast<u128>(u[j][l]) * sj;
        err += off[j] & sj;
      }
      uint64_t x[L];
      u128 c = 0;
      for (int l = 0; l < L; ++l) {
        c += acc[l];
        x[l] = static_cast<uint64_t>(c);
        c >>= 64;
      }
      add_u64_at<L>(x, uint64_t(1) << 63, 0);
      uint64_t below = 0;  // 1 if the exact value lies below x by a fraction of a grid unit
      if (i == 1) {
        sub_l<L>(x, qd);
        below = rd != 0;
      }
      if (err == 0) {
        sub_u64<L>(x, below);
      } else if (x[0] < err + below || x[0] > uint64_t(0) - err) {
        return false;  // within the truncation error of a rounding boundary
      }
      for (int l = 1; l < L; ++l) o.reg[a][i][l - 1] = x[l];
      end += ((static_cast<u128>(x[2]) << 64) | x[1]) * binlo[i];
    }
    // |end| < 2^(W-1) by the range check; anything else would be a bug, and
    // compile_exact() would then compute it exactly.
    const u128 lim = static_cast<u128>(1) << (f.width - 1);  // W <= 128: 2^127 at most
    if (end + lim - 1 > 2 * (lim - 1)) return false;
    o.end[a] = end;
  }
  return true;
}

// surj(j, i) as compile-time constants (the same values as SurjTable).
struct SurjConst {
  uint64_t v[8][8];
};
constexpr SurjConst make_surj() {
  SurjConst t{};
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i <= j; ++i) {
      int64_t sum = 0, cik = 1;  // sum_k (-1)^(i-k) C(i,k) k^j
      for (int k = 0; k <= i; ++k) {
        int64_t kj = 1;
        for (int e = 0; e < j; ++e) kj *= k;
        sum += ((i - k) % 2 ? -1 : 1) * cik * kj;
        cik = cik * (i - k) / (k + 1);
      }
      t.v[j][i] = static_cast<uint64_t>(sum);
    }
  return t;
}
constexpr SurjConst kSurj = make_surj();
static_assert(kSurj.v[5][5] == 120 && kSurj.v[7][4] == 8400 && kSurj.v[3][2] == 6, "surj(j,i) = i! S(j,i)");

// The axes on the 2-limb grid of 2^-g register LSB (32 <= g <= 64; the
// caller's bound keeps every quantity below 2^127 grid units, every term below
// 2^124): as grid_axes, on native 128-bit integers (modular, the exact values
// fitting), with m_h^j taken to its top 128 bits, for degree N (a template
// argument: the sums unroll on constant surj(j,i)). For a term below 2^125
// grid units that truncation errs by less than m_j 2^(t+s) < 2^125 / top <=
// 1/4 grid unit, so a term off the grid errs by less than 2 units (1 if m_h^j
// has at most 128 bits).
template <int N>
bool grid2_axes(const Format& f, const PolySegment& seg, const std::vector<mpz_class>* start, const HPowers& hp,
                const Dyadic (*d)[8], const long (*tb)[8], const u128* binlo, double q2_d, const Dyadic& htol, long double scale_ld,
                long double limit_ld, int g, double& carried, GridOut& o) {
  const int G = f.guard_bits;
  const long sigma = G + f.frac_bits;
  const uint64_t K = seg.ticks;
  const long double T_ld = static_cast<long double>(seg.h) * static_cast<long double>(K);
  const long double grid_ld = g == 64 ? 0x1p-64L : 1.0L / static_cast<long double>(uint64_t(1) << g);  // 2^-g
  const u128 half = static_cast<u128>(1) << (g - 1);
  const uint64_t mask = g == 64 ? ~uint64_t(0) : (uint64_t(1) << g) - 1;  // 2^g - 1
  uint64_t wt[8];  // error weight of term j when off the grid
  for (int j = 1; j <= N; ++j) wt[j] = hp.bits[j] <= 128 ? 1 : 2;
  long sj[8];   // the exponent s of term j less e_j
  long rsb[8];  // the right shift rs of term j plus e_j
  for (int j = 1; j <= N; ++j) {
    sj[j] = sigma + static_cast<long>(j) * hp.hd.e + g;
    rsb[j] = -(sj[j] + hp.tshift[j]);
  }
  // The continuity bound tol/2 2^G in grid units, m 2^(e+G+g), as one 128-bit
  // threshold when it is an integer below 2^127 (else cmp_m2e decides).
  const long tol_sh = htol.e + G + g;
  const bool tol_fast = tol_sh >= 0 && bitlen_u64(static_cast<uint64_t>(htol.m)) + tol_sh <= 127;
  const u128 tol_thr = tol_fast ? static_cast<u128>(static_cast<uint64_t>(htol.m)) << tol_sh : 0;
  const long k_bits = bitlen_u64(K);
  long q2_bits;  // 2 Q(K) < 2^q2_bits (q2_d is it truncated: same binary exponent)
  {
    uint64_t qb;
    std::memcpy(&qb, &q2_d, sizeof qb);
    q2_bits = static_cast<long>((qb >> 52) & 0x7ff) - 1022;  // normal, >= 1
  }

  for (int a = 0; a < f.axes; ++a) {
    const Dyadic* da = d[a];
    // c0 = x(0) 2^sigma + 2^(G-1) on the grid (the caller checked e_0 + sigma + g >= 0).
    u128 c0 = static_cast<u128>(1) << (G - 1 + g);
    if (da[0].m) {
      const u128 t = static_cast<u128>(da[0].m < 0 ? -da[0].m : da[0].m) << (da[0].e + sigma + g);
      c0 = da[0].m < 0 ? c0 - t : c0 + t;
    }
    u128 e0, r0;
    if (start) {
      r0 = low128((*start)[a].get_mpz_t());  // |r0| < 2^(125-g) (the caller's bound)
      e0 = (r0 << g) - c0;
    } else {
      const u128 z = c0 + half;
      r0 = static_cast<u128>(static_cast<i128>(z) >> g);
      e0 = half - (static_cast<uint64_t>(z) & mask);
      o.reg[a][0][0] = static_cast<uint64_t>(r0);
      o.reg[a][0][1] = static_cast<uint64_t>(r0 >> 64);
    }
    const bool eneg = static_cast<i128>(e0) < 0;
    const u128 em = eneg ? -e0 : e0;
    const uint64_t eml[2] = {static_cast<uint64_t>(em), static_cast<uint64_t>(em >> 64)};
    if (start && em && (tol_fast ? em > tol_thr : cmp_m2e(eml, 2, static_cast<uint64_t>(htol.m), tol_sh) > 0))
      return false;
    double e0_lsb;
    // = trunc_double(eml, 2, -(g + G)): |e0| 2^-(g+G) truncated to 53 bits, a
    // normal double for every e0 != 0 (binary exponent bitlen - 1 - (g + G)
    // in [-190, 127]).
    if (em == 0) {
      e0_lsb = 0;
    } else {
      const int bx = eml[1] ? 128 - __builtin_clzll(eml[1]) : 64 - __builtin_clzll(eml[0]);
      const uint64_t mant = static_cast<uint64_t>(bx > 53 ? em >> (bx - 53) : em << (53 - bx));
      const uint64_t eb = (static_cast<uint64_t>(bx - 1 - (g + G) + 1023) << 52) | (mant & ((uint64_t(1) << 52) - 1));
      std::memcpy(&e0_lsb, &eb, sizeof e0_lsb);
    }
    carried = std::max(carried, e0_lsb);
    // Range, first by bit lengths: the blended target's power coefficients
    // are a_0 = r0, a_1 = u_1 K - e0, a_j = u_j K^j with |u_j| < 2^(bitlen m_j +
    // bitlen m_h^j + e_j + sigma + j e_h) and K^j < 2^(j bitlen K). If those
    // bounds, 2 |e0| and 2 Q(K) stay below 2^(W-5), then sum |a_j| + |e0| +
    // 2 Q(K) + 2 (at most 11 such terms, N <= 7) is below 11/16 of the limit
    // 2^(W-1), and sum |a_j| >= max |b_i|: the reference (exact, then a few
    // roundings of relative size 2^-52 at most) accepts. Otherwise the long
    // double bound decides.
    {
      const u128 r0m = static_cast<i128>(r0) < 0 ? -r0 : r0;
      const uint64_t r0l[2] = {static_cast<uint64_t>(r0m), static_cast<uint64_t>(r0m >> 64)};
      long mb = std::max<long>({bitlen_limbs(r0l, 2), static_cast<long>(bitlen_limbs(eml, 2)) - g + 1, q2_bits});
      for (int j = 1; j <= N; ++j) mb = std::max<long>(mb, tb[a][j] + j * k_bits);  // tb: bits of |u_j|
      if (mb > f.width - 5) {
        const long double e0_ld = static_cast<long double>(eml[1]) * 0x1p64L + static_cast<long double>(eml[0]);
        const long double r0_ld = static_cast<long double>(r0l[1]) * 0x1p64L + static_cast<long double>(r0l[0]);
        if (!range_ok(N, seg.coef[a], scale_ld, T_ld, static_cast<i128>(r0) < 0 ? -r0_ld : r0_ld,
                      (eneg ? -e0_ld : e0_ld) * grid_ld, q2_d, limit_ld))
          return false;
      }
    }
    // Terms: u_j = m_j top_j 2^(tshift_j + s), s = e_j + sigma + j e_h + g,
    // truncated; m_j top_j >= 2^127 > 2^124 > u_j, so tshift_j + s < -3 (a
    // right shift).
    u128 u[N + 1];
    uint64_t off[N + 1];
    for (int j = 1; j <= N; ++j) {
      u[j] = 0;
      off[j] = 0;
      if (!da[j].m) continue;
      // m top = A + B 2^64 (A, B the products with top's halves), taken down
      // by rs bits: floor((A + B 2^64) / 2^rs), below 2^124.
      const uint64_t am = static_cast<uint64_t>(da[j].m < 0 ? -da[j].m : da[j].m);
      const u128 A = static_cast<u128>(static_cast<uint64_t>(hp.top[j])) * am;
      const u128 B = static_cast<u128>(static_cast<uint64_t>(hp.top[j] >> 64)) * am;
      const long s = da[j].e + sj[j];
      const long rs = rsb[j] - da[j].e;
      u128 v = 0;
      if (rs < 64) v = (B << (64 - rs)) + (A >> rs);  // exact below 2^128 (rs >= 4)
      else if (rs < 192) v = (B + (A >> 64)) >> (rs - 64);
      u[j] = da[j].m < 0 ? -v : v;
      off[j] = s < 0 ? wt[j] : 0;
    }
    // e0 = K qd + rd, 0 <= rd < K.
    u128 qd = 0;
    uint64_t rd = 0;
    if (em) {
      uint64_t ql[2] = {eml[0], eml[1]};
      const uint64_t r = div_limbs_small(ql, 2, K);
      const u128 q = (static_cast<u128>(ql[1]) << 64) | ql[0];
      qd = eneg ? -(q + (r != 0)) : q;
      rd = eneg ? (r ? K - r : 0) : r;
    }
    // X_i = sum_j surj(j,i) u_j = i! c_i with c the coefficients of
    // sum_j u_j m^j in the falling factorials m(m-1)...(m-i+1) (surj(j,i) =
    // i! S(j,i)): c by synthetic division at the nodes 1..N-1 (ring
    // operations modulo 2^128 on the exact integers, so exact), with multiples
    // k <= 6 instead of the N(N+1)/2 products by surj(j,i). err_i the same way
    // on the error weights.
    for (int k = 1; k < N; ++k)
      for (int j = N - 1; j >= k; --j) {
        u[j] += u[j + 1] * static_cast<uint64_t>(k);
        off[j] += off[j + 1] * static_cast<uint64_t>(k);
      }
    u128 end = r0;
    for (int i = 1; i <= N; ++i) {
      u128 x = half + u[i] * kSurj.v[i][i];  // i! c_i
      const uint64_t err = off[i] * kSurj.v[i][i];
      uint64_t below = 0;
      if (i == 1) {
        x -= qd;
        below = rd != 0;
      }
      if (err == 0) {
        x -= below;
      } else {
        const uint64_t low = static_cast<uint64_t>(x) & mask;
        if (low < err + below || low > mask - (err - 1)) return false;  // within the error of a rounding boundary
      }
      const u128 ri = static_cast<u128>(static_cast<i128>(x) >> g);
      o.reg[a][i][0] = static_cast<uint64_t>(ri);
      o.reg[a][i][1] = static_cast<uint64_t>(ri >> 64);
      end += ri * binlo[i];
    }
    const u128 lim = static_cast<u128>(1) << (f.width - 1);
    if (end + lim - 1 > 2 * (lim - 1)) return false;
    o.end[a] = end;
  }
  return true;
}

// The grid path of compile() for a segment that passed the checks before any
// arithmetic and the budget check: true with `out` filled, or false (nothing
// decided) for compile_exact().
bool compile_grid(const Format& f, long double scale_ld, long double limit_ld, const PolySegment& seg,
                  const std::vector<mpz_class>* start, Compiled& out) {
  const int N = f.degree;
  const int A = f.axes;
  const int G = f.guard_bits;
  const long sigma = G + f.frac_bits;
  const HPowers& hp = h_powers(seg.h);
  // Decompose the coefficients and bound every quantity in bits of register
  // units: c0 (and its bias 2^(G-1)), r0, and each term u_j times the largest
  // surj(j,i) (bitlen 1, 2, 3, 6, 8, 11, 15 for j = 1..7), plus 3 for a sum of
  // at most 7. Then |X_i|, |c0|, |r0| < 2^bits, |e0|, |qd| < 2^(bits+2), and
  // X_i + 2^(g-1) - qd stays below 2^(bits+3) in magnitude: the 2-limb grid
  // takes g = min(64, 124 - bits) >= 32 fraction bits, the 3- and 4-limb grids
  // 64 (bits + 67 <= 191, 255). c0 must lie on the grid: g >= gmin.
  static constexpr int kSurjBits[8] = {0, 1, 2, 3, 6, 8, 11, 15};
  Dyadic d[8][8];
  long tb[8][8];  // bits of |u_j| (register units), a large negative number if u_j = 0
  long bits = G, gmin = 1;
  for (int a = 0; a < A; ++a) {
    const std::vector<double>& cf = seg.coef[a];
    for (int j = 0; j <= N; ++j) d[a][j] = j < static_cast<int>(cf.size()) ? dyadic(cf[j]) : Dyadic{0, 0};
    if (d[a][0].m) {
      gmin = std::max<long>(gmin, -(d[a][0].e + sigma));
      bits = std::max<long>(bits, bitlen_u64(static_cast<uint64_t>(std::abs(d[a][0].m))) + d[a][0].e + sigma);
    }
    for (int j = 1; j <= N; ++j) {
      tb[a][j] = d[a][j].m ? bitlen_u64(static_cast<uint64_t>(std::abs(d[a][j].m))) + hp.bits[j] + d[a][j].e + sigma +
                                 static_cast<long>(j) * hp.hd.e
                           : -(1L << 30);
      bits = std::max<long>(bits, tb[a][j] + kSurjBits[j] + 3);
    }
    if (start) {
      mpz_srcptr z = (*start)[a].get_mpz_t();
      const int n = std::abs(z->_mp_size);
      bits = std::max<long>(bits, n ? 64L * (n - 1) + bitlen_u64(z->_mp_d[n - 1]) : 0);
    }
  }
  const KData& kd = k_data(N, seg.ticks, f.tol_lsb);
  const double q2_d = kd.q2_d;
  const Dyadic htol = dyadic(f.tol_lsb / 2);
  GridOut o;
  double carried = 0;
  int L1 = 0;  // limbs of a register, 0: not settled
  const long g2 = std::min<long>(64, 124 - bits);
  auto grid2 = [&](auto deg) {
    return grid2_axes<decltype(deg)::value>(f, seg, start, hp, d, tb, kd.binlo, q2_d, htol, scale_ld, limit_ld,
                                            static_cast<int>(g2), carried, o);
  };
  bool ok2 = false;
  if (g2 >= 32 && g2 >= gmin) {
    switch (N) {
      case 1: ok2 = grid2(std::integral_constant<int, 1>()); break;
      case 2: ok2 = grid2(std::integral_constant<int, 2>()); break;
      case 3: ok2 = grid2(std::integral_constant<int, 3>()); break;
      case 4: ok2 = grid2(std::integral_constant<int, 4>()); break;
      case 5: ok2 = grid2(std::integral_constant<int, 5>()); break;
      case 6: ok2 = grid2(std::integral_constant<int, 6>()); break;
      default: ok2 = grid2(std::integral_constant<int, 7>()); break;
    }
  }
  if (ok2) {
    ++path_counts().grid2;
    L1 = 2;
  } else if (gmin <= 64) {
    const long need = bits + 64 + 3;
    carried = 0;
    if (need <= 191 && grid_axes<3>(f, seg, start, hp, d, kd.binlo, q2_d, htol, scale_ld, limit_ld, carried, o)) {
      ++path_counts().grid3;
      L1 = 2;
    } else if (need > 191 && need <= 255 &&
               grid_axes<4>(f, seg, start, hp, d, kd.binlo, q2_d, htol, scale_ld, limit_ld, carried, o)) {
      ++path_counts().grid4;
      L1 = 3;
    }
  }
  if (!L1) return false;

  out.ticks = static_cast<uint32_t>(seg.ticks);
  out.regs.resize(A);
  out.end.resize(A);
  const GmpAlloc alloc = gmp_alloc_func();
  for (int a = 0; a < A; ++a) {
    std::vector<mpz_class>& r = out.regs[a];
    r.resize(N + 1);
    if (start) {
      mpz_srcptr z = (*start)[a].get_mpz_t();
      mpz_set_mag(r[0].get_mpz_t(), z->_mp_d, std::abs(z->_mp_size), z->_mp_size < 0, alloc);
    } else if (L1 == 2) {
      mpz_set_s128(r[0].get_mpz_t(), (static_cast<u128>(o.reg[a][0][1]) << 64) | o.reg[a][0][0], alloc);
    } else {
      mpz_set_limbs(r[0].get_mpz_t(), o.reg[a][0], L1, alloc);
    }
    for (int i = 1; i <= N; ++i) {
      if (L1 == 2) mpz_set_s128(r[i].get_mpz_t(), (static_cast<u128>(o.reg[a][i][1]) << 64) | o.reg[a][i][0], alloc);
      else mpz_set_limbs(r[i].get_mpz_t(), o.reg[a][i], L1, alloc);
    }
    mpz_set_s128(out.end[a].get_mpz_t(), o.end[a], alloc);
  }
  out.carried_lsb = carried;
  // = quant_bound_lsb(K): q2_d 2^-(G+1), exact (q2_d >= 1, G + 1 <= 127: normal)
  double scale;
  const uint64_t sbits = static_cast<uint64_t>(1023 - (G + 1)) << 52;
  std::memcpy(&scale, &sbits, sizeof scale);
  out.bound_lsb = carried + q2_d * scale;
  set_needs(out.needs, N, kd.needs);
  return true;
}

}  // namespace

namespace {
// The exact integer path (compile()'s fast path before the fixed-point grid
// path above): exact dyadic sums on limb arrays sized per axis, mpz
// otherwise. compile() takes it when the grid path cannot settle a segment.
Compiled compile_exact(const Format& f_, const PolySegment& seg, const std::vector<mpz_class>* start,
                       const std::string& where) {
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
      power_terms(N, cf, scale_ld, T_ld,
                  mpz_size(S.r0) <= 2 ? static_cast<long double>(mpz_get_d(S.r0)) : mpz_ldexp(S.r0, 0), e0_ld, av,
                  mag);
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
    set_needs(out.needs, N, k_data(N, K, f_.tol_lsb).needs);
  }
  return out;
}
}  // namespace

RegisterNeeds Compiler::register_needs(int degree, uint64_t k, double tol_lsb) {
  if (!(tol_lsb > 0) || !std::isfinite(tol_lsb))
    throw CompileError("register_needs: tol_lsb=" + fmt_double(tol_lsb) + " must be positive and finite");
  if (degree < 1 || degree > 7) throw CompileError("register_needs: degree out of range 1..7");
  RegisterNeeds nd;
  set_needs(nd, degree, k_data(degree, k, tol_lsb).needs);
  return nd;
}

void Compiler::compile(const PolySegment& seg, const std::vector<mpz_class>* start, const std::string& where,
                       Compiled& out) const {
  // The refusals before any arithmetic, in the reference's order and words.
  check_segment(f_, seg, start, where);
  if (seg.ticks > kfit_) {
    out = compile_reference(f_, seg, start, where);  // words the refusal
    return;
  }
  // compile_grid() reads `start` before it writes `out` (r[0] of an axis
  // before its end), so start may be &out.end.
  if (!compile_grid(f_, scale_ld_, limit_ld_, seg, start, out)) out = compile_exact(f_, seg, start, where);
}

Compiled Compiler::compile(const PolySegment& seg, const std::vector<mpz_class>* start,
                           const std::string& where) const {
  Compiled out;
  compile(seg, start, where, out);
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
