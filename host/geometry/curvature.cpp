// SPDX-License-Identifier: Apache-2.0
#include "geometry/curvature.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/error.hpp"

namespace traj::geo {

namespace {

struct Local {
  double d1d1, d1d2, d2d2, d1d3, d2d3;
};

// Dot products of r', r'', r''' from an eval_span buffer b[k*dim + axis].
Local products_of(const double* b, int dim) {
  Local l{0, 0, 0, 0, 0};
  for (int d = 0; d < dim; ++d) {
    const double a1 = b[dim + d], a2 = b[2 * dim + d], a3 = b[3 * dim + d];
    l.d1d1 += a1 * a1;
    l.d1d2 += a1 * a2;
    l.d2d2 += a2 * a2;
    l.d1d3 += a1 * a3;
    l.d2d3 += a2 * a3;
  }
  return l;
}

// Evaluation buffer: on the stack up to 16 axes.
struct EvalBuf {
  double stack[4 * 16];
  std::vector<double> heap;
  double* p;
  explicit EvalBuf(int dim) : p(stack) {
    if (dim > 16) {
      heap.resize(4 * static_cast<size_t>(dim));
      p = heap.data();
    }
  }
};

Local products(const Curve& c, int span, double u) {
  const int dim = c.dim();
  EvalBuf b(dim);
  c.eval_span(span, u, 3, b.p);
  return products_of(b.p, dim);
}

double kappa_of(const Local& l) {
  const double G = std::max(0.0, l.d1d1 * l.d2d2 - l.d1d2 * l.d1d2);
  return std::sqrt(G) / std::pow(l.d1d1, 1.5);
}

// d(kappa^2)/du.
double dk2(const Local& l) {
  const double G = std::max(0.0, l.d1d1 * l.d2d2 - l.d1d2 * l.d1d2);
  const double Gp = 2 * l.d1d1 * l.d2d3 - 2 * l.d1d2 * l.d1d3;
  const double v2 = l.d1d1;
  return Gp / (v2 * v2 * v2) - 6 * G * l.d1d2 / (v2 * v2 * v2 * v2);
}

// ---- rounding-error bound of d(kappa^2)/du (the noise-aware scan) ----
//
// Errors are bounded per derivative vector, in the Euclidean norm (e_k >= |computed C^(k) - exact|).
// 1. Tables. A value of derivative table k (column c: an axis, or the weight of a NURBS) carries two
//    errors. (a) Horner at tau in [-h/2, h/2] on coefficients rounded once after the Bezier -> power
//    conversion: <= gamma_q S_kc, S_kc = sum_j |a_kjc| (h/2)^j (a per-span constant: the error of a
//    value near zero is that of its terms, not of the value), gamma_q = (4q + 2^(q+2)) eps, q = p - k
//    (2q roundings of Horner plus the conversion's ~2^q growth, each with a factor 2 to spare).
//    (b) The rounding of the (homogeneous) control points, eps |Q|, carried into derivative k by k
//    differences over the span width h: <= 2 eps H_c 2^k p!/(p-k)! / h^k, H_c = max |Bezier point|
//    of the span in column c. (b) is the backward error: a curve whose control points moved by a few
//    ulps (an exact circle's are irrational) has d(kappa^2)/du of that size, and it dominates where the
//    coordinates are large against the curve's size (a small arc far from the origin).
//    Per span: EA_k = |(a) + (b)| over the axis columns (norm), EW_k = (a) + (b) of the weight column.
// 2. Quotient rule (NURBS): C^(k) = (A^(k) - sum_i C(k,i) w^(i) C^(k-i)) / w, errors propagated
//    term by term with |w| >= w - EW_0, plus (k+2) eps of the magnitude of the sum for its roundings.
// 3. Dot products x.y: |x| e_y + |y| e_x + e_x e_y + dim eps |x| |y|.
// 4. G = |r'|^2|r''|^2 - (r'.r'')^2 and G' = 2|r'|^2 (r''.r''') - 2 (r'.r'')(r'.r''') from those, and
//    d(kappa^2)/du = G'/v^3 - 6 G (r'.r'')/v^4 (v = |r'|^2, relative error rho = e(v)/v) bounded by
//    ((|G'| + e(G')) (1-rho)^-3 - |G'|)/v^3 + 6 ((G + e(G)) (|r'.r''| + e(r'.r'')) (1-rho)^-4 -
//    G |r'.r''|)/v^4 + 8 eps (|T1| + |T2|); rho >= 1/2 gives +inf (the speed is rounding noise).
// On a circle d(kappa^2)/du is zero and the computed value is rounding noise inside this bound
// (test GeometryCurvatureNoise.*: at most 0.07 of it over radii 1e-3..1e4, centres up to 1e5 away,
// 2-D and 3-D; the scan's threshold is 4x the bound).
struct SpanScales {
  double EA[kMaxDeriv + 1] = {0, 0, 0, 0};  // error bound (norm) of the axis columns of table k
  double EW[kMaxDeriv + 1] = {0, 0, 0, 0};  // error bound of the weight column of table k (NURBS)
};

void span_scales(const Curve& curve, int span, SpanScales& out) {
  constexpr double eps = std::numeric_limits<double>::epsilon();
  const PowerSpan& s = curve.spans()[span];
  const Eigen::MatrixXd& hom = curve.bezier()[span].hom;
  const int p = s.degree, cols = s.cols, dim = curve.dim();
  out = SpanScales{};
  const double h = s.u1 - s.u0, hh = 0.5 * h;
  double dfac = 2 * eps;  // (b): 2 eps 2^k p!/(p-k)! / h^k
  for (int k = 0; k <= std::min(kMaxDeriv, p); ++k) {
    if (k > 0) dfac *= 2.0 * (p - k + 1) / h;
    const int q = p - k;
    const double gamma = (4.0 * q + std::ldexp(1.0, q + 2)) * eps;
    const double* a = s.coef.data() + s.offset(k);
    double ea2 = 0;
    for (int c = 0; c < cols; ++c) {
      double acc = 0, hj = 1;
      for (int j = 0; j <= q; ++j, hj *= hh) acc += std::abs(a[j * cols + c]) * hj;
      // column c of hom: the axes (w x), then the weight; a non-rational curve stores no weight column
      const double e = gamma * acc + dfac * hom.col(c).cwiseAbs().maxCoeff();
      if (c < dim) ea2 += e * e;
      else out.EW[k] = e;
    }
    out.EA[k] = std::sqrt(ea2);
  }
}

// Bound on the rounding error of dk2(l), l = products_of(b, dim), b = eval_span(span, u, 3) (see above).
double dk2_error_bound(const Curve& c, int span, double u, const double* b, const Local& l, const SpanScales& sc) {
  constexpr double eps = std::numeric_limits<double>::epsilon();
  constexpr double inf = std::numeric_limits<double>::infinity();
  const int dim = c.dim();
  double n3s = 0;
  for (int d = 0; d < dim; ++d) n3s += b[3 * dim + d] * b[3 * dim + d];
  const double n1 = std::sqrt(l.d1d1), n2 = std::sqrt(l.d2d2), n3 = std::sqrt(n3s);
  double e0 = sc.EA[0], e1 = sc.EA[1], e2 = sc.EA[2], e3 = sc.EA[3];
  if (c.rational()) {
    const PowerSpan& s = c.spans()[span];
    const int p = s.degree, cols = s.cols;
    const double tau = u - s.uc;
    double w[kMaxDeriv + 1] = {0, 0, 0, 0};
    for (int k = 0; k <= std::min(kMaxDeriv, p); ++k)
      w[k] = std::abs(detail::horner<double>(s.coef.data() + s.offset(k) + dim, p + 1 - k, cols, tau));
    const double w0 = w[0] - sc.EW[0];  // lower bound of |w|
    if (!(w0 > 0)) return inf;          // weight indistinguishable from zero
    double n0s = 0;
    for (int d = 0; d < dim; ++d) n0s += b[d] * b[d];
    const double n0 = std::sqrt(n0s);
    const double* EW = sc.EW;
    const double* EA = sc.EA;
    e0 = (EA[0] + n0 * EW[0]) / w0 + 2 * eps * n0;
    e1 = (EA[1] + n1 * EW[0] + EW[1] * n0 + w[1] * e0 + 3 * eps * (w[0] * n1 + w[1] * n0)) / w0;
    e2 = (EA[2] + n2 * EW[0] + 2 * (EW[1] * n1 + w[1] * e1) + EW[2] * n0 + w[2] * e0 +
          4 * eps * (w[0] * n2 + 2 * w[1] * n1 + w[2] * n0)) /
         w0;
    e3 = (EA[3] + n3 * EW[0] + 3 * (EW[1] * n2 + w[1] * e2) + 3 * (EW[2] * n1 + w[2] * e1) + EW[3] * n0 +
          w[3] * e0 + 5 * eps * (w[0] * n3 + 3 * w[1] * n2 + 3 * w[2] * n1 + w[3] * n0)) /
         w0;
  }
  const double de = dim * eps;
  auto dot_err = [de](double nx, double ex, double ny, double ey) { return nx * ey + ny * ex + ex * ey + de * nx * ny; };
  const double E11 = dot_err(n1, e1, n1, e1), E12 = dot_err(n1, e1, n2, e2), E22 = dot_err(n2, e2, n2, e2);
  const double E13 = dot_err(n1, e1, n3, e3), E23 = dot_err(n2, e2, n3, e3);
  const double v = l.d1d1;
  if (!(v > 2 * E11)) return inf;  // |r'|^2 indistinguishable from zero
  const double a12 = std::abs(l.d1d2), a13 = std::abs(l.d1d3), a23 = std::abs(l.d2d3);
  const double G = std::max(0.0, l.d1d1 * l.d2d2 - l.d1d2 * l.d1d2);
  const double Gp = std::abs(2 * l.d1d1 * l.d2d3 - 2 * l.d1d2 * l.d1d3);
  const double eG = l.d2d2 * E11 + v * E22 + E11 * E22 + 2 * a12 * E12 + E12 * E12 +
                    3 * eps * (v * l.d2d2 + l.d1d2 * l.d1d2);
  const double eGp = 2 * (a23 * E11 + v * E23 + E11 * E23 + a13 * E12 + a12 * E13 + E12 * E13) +
                     6 * eps * (v * a23 + a12 * a13);
  const double rho = E11 / v;
  const double r3 = 1 / ((1 - rho) * (1 - rho) * (1 - rho)), r4 = r3 / (1 - rho);
  const double v3 = v * v * v, v4 = v3 * v;
  const double T1 = Gp / v3, T2 = 6 * G * a12 / v4;
  const double err1 = ((Gp + eGp) * r3 - Gp) / v3;
  const double err2 = 6 * ((G + eG) * (a12 + E12) * r4 - G * a12) / v4;
  return err1 + err2 + 8 * eps * (T1 + T2);
}

double cross2(const Curve& c, int span, double u, double* kappa_out) {
  double b[6];
  c.eval_span(span, u, 2, b);
  const double cr = b[2] * b[5] - b[3] * b[4];
  if (kappa_out) {
    const double v = std::hypot(b[2], b[3]);
    *kappa_out = std::abs(cr) / (v * v * v);
  }
  return cr;
}

double bbox_diag(const Curve& c) {
  const auto& P = c.spline().ctrl;
  return (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm();
}

// Bisection on a function with a sign change on [a,b] (fa = f(a) sign), to width tol.
template <class F>
double bisect(F f, double a, double b, double fa, double tol) {
  while (b - a > tol) {
    const double m = 0.5 * (a + b);
    if (m <= a || m >= b) break;
    const double fm = f(m);
    if ((fm > 0) == (fa > 0) && fm != 0) a = m;
    else b = m;
  }
  return 0.5 * (a + b);
}

}  // namespace

double curvature(const Curve& c, double u) { return kappa_of(products(c, c.find_span(u), u)); }

double signed_curvature(const Curve& c, double u) {
  if (c.dim() != 2) throw GeometryError("signed_curvature: curve is not planar (dim != 2)");
  double b[6];
  c.eval(u, 2, b);
  const double v = std::hypot(b[2], b[3]);
  return (b[2] * b[5] - b[3] * b[4]) / (v * v * v);
}

CurvatureSqDerivative curvature_sq_derivative(const Curve& c, int span, double u) {
  EvalBuf b(c.dim());
  c.eval_span(span, u, 3, b.p);
  SpanScales sc;
  span_scales(c, span, sc);
  const Local l = products_of(b.p, c.dim());
  return {dk2(l), dk2_error_bound(c, span, u, b.p, l, sc)};
}

std::vector<CurvatureExtremum> curvature_extrema(const Curve& c, const SplitOptions& o) {
  std::vector<CurvatureExtremum> out;
  if (c.degree() == 1) return out;  // every span a straight segment: kappa = 0
  const double floor = 1e-10 / std::max(bbox_diag(c), 1e-300);
  const int M = std::max(2, o.samples_per_span);
  const int dim = c.dim();
  struct S {
    double u, f;
    Local l;  // kappa_of(l) where needed
    int span;
    bool zero;  // |f| within noise_factor x its rounding-error bound: no sign
  };
  std::vector<S> seq;
  const auto& spans = c.spans();
  seq.reserve(spans.size() * (M + 1));
  EvalBuf b(dim);
  SpanScales sc;
  long long evals = 0;
  for (int si = 0; si < static_cast<int>(spans.size()); ++si) {
    if (o.noise_factor > 0) span_scales(c, si, sc);
    for (int j = 0; j <= M; ++j) {
      const double u = (j == M) ? spans[si].u1 : spans[si].u0 + (spans[si].u1 - spans[si].u0) * j / M;
      c.eval_span(si, u, 3, b.p);
      const Local l = products_of(b.p, dim);
      const double f = dk2(l);
      const bool zero =
          o.noise_factor > 0 ? std::abs(f) <= o.noise_factor * dk2_error_bound(c, si, u, b.p, l, sc) : f == 0;
      seq.push_back({u, f, l, si, zero});
      ++evals;
    }
  }
  // A sign change: two samples with signs (not zero) of opposite sign and only zeros between them.
  // Inside that run the root is placed between the first sample whose computed value no longer has
  // the first one's sign and its predecessor: bisection if both are in one span, the knot if they are
  // on either side of one, the sample itself if its value is exactly 0. Without zeros this is the pair
  // of neighbouring samples (the plain scan's rule); a run of zeros wider than a few samples means
  // kappa is constant to rounding there and any point of it is an extremum to working precision.
  size_t last = seq.size();  // last sample with a sign
  for (size_t i = 0; i < seq.size(); ++i) {
    if (seq[i].zero) continue;
    if (last < seq.size() && (seq[i].f > 0) != (seq[last].f > 0)) {
      const bool pos = seq[last].f > 0;
      size_t m = last + 1;
      while (m < i && (seq[m].f > 0) == pos && seq[m].f != 0) ++m;
      const S &a = seq[m - 1], &z = seq[m];
      CurvatureExtremum e;
      e.maximum = pos;
      bool keep = true;
      const double ak = kappa_of(a.l), zk = kappa_of(z.l);
      if (z.f == 0) {  // exactly zero sample at the sign change
        e.u = z.u;
        e.kappa = zk;
        keep = zk >= floor;
      } else if (std::max(ak, zk) < floor) {
        keep = false;  // straight: kappa is rounding noise
      } else if (a.span != z.span) {  // sign change across a knot (left and right limits)
        e.u = a.u;
        e.at_knot = true;
        e.kappa = std::max(ak, zk);
      } else {
        const int si = a.span;
        e.u = bisect(
            [&](double u) {
              ++evals;
              return dk2(products(c, si, u));
            },
            a.u, z.u, a.f, o.u_tol);
        e.kappa = kappa_of(products(c, si, e.u));
      }
      if (keep && (o.minima || e.maximum)) out.push_back(e);
    }
    last = i;
  }
  if (o.stats) o.stats->dk2_evals += evals;
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.u < y.u; });
  return out;
}

std::vector<double> inflection_points(const Curve& c, const SplitOptions& o) {
  std::vector<double> out;
  if (c.dim() != 2 || c.degree() == 1) return out;  // degree 1: straight spans, no inflection
  const double floor = 1e-10 / std::max(bbox_diag(c), 1e-300);
  const int M = std::max(2, o.samples_per_span);
  const auto& spans = c.spans();
  long long evals = 0;
  // kappa at a sample, needed only where the sign changes (then computed again, identically)
  auto kappa_at = [&](int si, double u) {
    double k;
    cross2(c, si, u, &k);
    return k;
  };
  double prev_cr = 0, prev_u = 0;
  int prev_si = -1;
  for (int si = 0; si < static_cast<int>(spans.size()); ++si) {
    double pu = spans[si].u0, pc = 0;
    for (int j = 0; j <= M; ++j) {
      const double u = (j == M) ? spans[si].u1 : spans[si].u0 + (spans[si].u1 - spans[si].u0) * j / M;
      const double cr = cross2(c, si, u, nullptr);
      ++evals;
      if (j == 0) {
        // Across the knot from the previous span (curvature continuous for C2 curves; a jump in
        // sign at a knot is an inflection located at the knot).
        if (prev_si >= 0 && prev_cr != 0 && cr != 0 && (prev_cr > 0) != (cr > 0) &&
            std::max(kappa_at(prev_si, prev_u), kappa_at(si, u)) >= floor)
          out.push_back(u);
      } else if (pc != 0 && cr != 0 && (pc > 0) != (cr > 0) && std::max(kappa_at(si, pu), kappa_at(si, u)) >= floor) {
        out.push_back(bisect(
            [&](double x) {
              ++evals;
              return cross2(c, si, x, nullptr);
            },
            pu, u, pc, o.u_tol));
      }
      pu = u;
      pc = cr;
    }
    prev_cr = pc;
    prev_u = pu;
    prev_si = si;
  }
  if (o.stats) o.stats->cross_evals += evals;
  return out;
}

std::vector<double> split_params(const Curve& c, const SplitOptions& o) {
  std::vector<double> u;
  for (const auto& e : curvature_extrema(c, o)) u.push_back(e.u);
  if (o.inflections)
    for (double x : inflection_points(c, o)) u.push_back(x);
  std::sort(u.begin(), u.end());
  std::vector<double> out;
  const double sep = 10 * o.u_tol;
  for (double x : u) {
    if (x - c.u_begin() <= sep || c.u_end() - x <= sep) continue;
    if (!out.empty() && x - out.back() <= sep) continue;
    out.push_back(x);
  }
  return out;
}

std::vector<Unit> split_units(const Curve& c, const ArcLength& al, const SplitOptions& o) {
  std::vector<double> b = split_params(c, o);
  b.insert(b.begin(), c.u_begin());
  b.push_back(c.u_end());
  std::vector<Unit> out;
  double s_prev = 0;
  for (size_t i = 0; i + 1 < b.size(); ++i) {
    Unit un;
    un.u0 = b[i];
    un.u1 = b[i + 1];
    un.s0 = s_prev;
    un.s1 = s_prev + al.length(un.u0, un.u1);
    s_prev = un.s1;
    un.length = un.s1 - un.s0;
    // One-sided values inside the unit (curvature may be discontinuous at C1 knots).
    const int s0 = c.find_span(un.u0);
    int s1 = c.find_span(un.u1);
    if (s1 > 0 && c.spans()[s1].u0 == un.u1) --s1;
    un.kappa0 = kappa_of(products(c, s0, un.u0));
    un.kappa1 = kappa_of(products(c, s1, un.u1));
    un.kappa_max = std::max(un.kappa0, un.kappa1);
    un.u_kappa_max = un.kappa0 >= un.kappa1 ? un.u0 : un.u1;
    un.kind = un.kappa1 < un.kappa0 ? UnitKind::Accelerate
                                    : (un.kappa1 > un.kappa0 ? UnitKind::Decelerate : UnitKind::Constant);
    out.push_back(un);
  }
  return out;
}

}  // namespace traj::geo
