// SPDX-License-Identifier: Apache-2.0
#include "planner/profile.hpp"

#include <algorithm>
#include <stdexcept>
#include <cmath>

namespace traj::plan {

// The jerk of a change of dv: J, or lower where a change at J would have
// jerk phases (t_j) shorter than tau.
double phase_jerk(double dv, double A, double J, double tau) {
  if (tau <= 0 || std::min(std::sqrt(dv / J), A / J) >= tau) return J;
  return std::min(dv / (tau * tau), A / tau);
}

double change_time(double dv, double A, double J, double tau) {
  if (dv <= 0) return 0;
  J = phase_jerk(dv, A, J, tau);
  if (dv >= A * A / J) return dv / A + A / J;
  return 2 * std::sqrt(dv / J);
}

double change_distance(double v0, double v1, double A, double J, double tau) {
  return 0.5 * (v0 + v1) * change_time(std::fabs(v1 - v0), A, J, tau);
}

double reachable(double v0, double L, double A, double J, double vmax, double tau) {
  if (vmax <= v0) return vmax;
  if (change_distance(v0, vmax, A, J, tau) <= L) return vmax;
  // Solve change_distance(v0, v1) = L for v1 in closed form.
  //  jerk-limited (dv < A^2/J): x = sqrt(dv/J)... with y = sqrt(dv):
  //    (2 v0 + y^2) y / sqrt(J) = L  ->  y^3 + 2 v0 y - L sqrt(J) = 0 (one real root)
  //  acceleration-limited (dv >= A^2/J):
  //    (v1^2 - v0^2)/A + (v0 + v1) A/J = 2L  ->  v1^2 + (A^2/J) v1 + v0 A^2/J - v0^2 - 2 L A = 0
  const double sJ = std::sqrt(J);
  const double p = 2 * v0, q = -L * sJ;
  const double disc = std::sqrt(q * q / 4 + p * p * p / 27);
  double y = std::cbrt(-q / 2 + disc) + std::cbrt(-q / 2 - disc);
  // one Newton polish (cancellation when p^3 dominates)
  for (int it = 0; it < 3; ++it) {
    const double f = y * y * y + p * y + q, fp = 3 * y * y + p;
    if (fp > 0) y -= f / fp;
  }
  double v1 = v0 + y * y;
  if (y * y >= A * A / J) {
    const double b = A * A / J, c = v0 * A * A / J - v0 * v0 - 2 * L * A;
    v1 = 0.5 * (-b + std::sqrt(b * b - 4 * c));
  }
  // with phases of tau at a lower jerk (phase_jerk): distance (2 v0 + dv) tau
  if (tau > 0 && v1 - v0 < J * tau * tau) v1 = v0 + std::max(0.0, L / tau - 2 * v0);
  v1 = std::min(std::max(v1, v0), vmax);
  // guard the rounding (never beyond L): shrink by 1e-12 relative steps a few
  // times, else bisect on [v0, v1]
  for (int it = 0; it < 4 && v1 > v0 && change_distance(v0, v1, A, J, tau) > L; ++it) v1 = v0 + (v1 - v0) * (1 - 1e-12);
  if (v1 > v0 && change_distance(v0, v1, A, J, tau) > L) {
    double lo = v0, hi = v1;
    for (int it = 0; it < 200 && hi - lo > 1e-13 * std::max(1.0, hi); ++it) {
      const double mid = 0.5 * (lo + hi);
      (change_distance(v0, mid, A, J, tau) <= L ? lo : hi) = mid;
    }
    v1 = lo;
  }
  return v1;
}

double append_change(std::vector<Piece>& out, double t, double s, double v0, double v1, double A, double J,
                     double tau) {
  const double dv = std::fabs(v1 - v0);
  if (dv <= 0) return t;
  J = phase_jerk(dv, A, J, tau);
  const double sgn = v1 > v0 ? 1.0 : -1.0;
  double tj, ta;
  if (dv >= A * A / J) {
    tj = A / J;
    ta = dv / A - A / J;
  } else {
    tj = std::sqrt(dv / J);
    ta = 0;
  }
  double v = v0, a = 0;
  auto push = [&](double T, double j) {
    if (T <= 0) return;
    Piece p;
    p.t0 = t;
    p.T = T;
    p.s0 = s;
    p.v0 = v;
    p.a0 = a;
    p.j = j;
    out.push_back(p);
    s = p.s(T);
    v = p.v(T);
    a = p.a(T);
    t += T;
  };
  push(tj, sgn * J);
  push(ta, 0);
  push(tj, -sgn * J);
  return t;
}

std::vector<Piece> plan_blocks(std::vector<Station>& st, const std::vector<double>& cap, double A, double J,
                               double tau) {
  return plan_blocks(st, cap, std::vector<double>(st.empty() ? 0 : st.size() - 1, A), J, tau);
}

std::vector<Piece> plan_blocks(std::vector<Station>& st, const std::vector<double>& cap, const std::vector<double>& A,
                               double J, double tau) {
  std::vector<BlockMemo> memo;
  std::vector<char> changed;
  return plan_blocks(st, cap, A, J, memo, changed, tau);
}

std::vector<Piece> plan_blocks(std::vector<Station>& st, const std::vector<double>& cap,
                               const std::vector<double>& Ab, double J, std::vector<BlockMemo>& memo,
                               std::vector<char>& changed, double tau) {
  const size_t n = st.size();
  if (cap.size() + 1 < n || Ab.size() + 1 < n)
    throw std::invalid_argument("plan_blocks: one cap and one acceleration per block needed");
  std::vector<BlockMemo> old;
  old.swap(memo);
  changed.assign(n > 0 ? n - 1 : 0, 1);
  memo.reserve(changed.size());
  size_t mj = 0;  // old memo entries are sorted by s0
  for (auto& x : st) x.v = x.vmax;
  if (n == 0) return {};
  // backward pass: able to slow down to the next station's speed
  for (size_t i = n - 1; i-- > 0;) {
    const double L = st[i + 1].s - st[i].s;
    st[i].v = std::min(st[i].v, reachable(st[i + 1].v, L, Ab[i], J, st[i].v, tau));
  }
  // forward pass: reachable from the previous station
  for (size_t i = 1; i < n; ++i) {
    const double L = st[i].s - st[i - 1].s;
    st[i].v = std::min(st[i].v, reachable(st[i - 1].v, L, Ab[i - 1], J, st[i].v, tau));
  }
  std::vector<Piece> out;
  out.reserve(7 * (n - 1));  // at most 3 + 1 + 3 pieces per block
  double t = 0;
  for (size_t i = 0; i + 1 < n; ++i) {
    const double s0 = st[i].s, L = st[i + 1].s - s0, A = Ab[i];
    const double va = st[i].v, vb = st[i + 1].v;
    const double lo_peak = std::max(va, vb);
    double vp = std::max(cap[i], lo_peak);
    auto need = [&](double v) { return change_distance(va, v, A, J, tau) + change_distance(v, vb, A, J, tau); };
    while (mj < old.size() && old[mj].s0 < s0) ++mj;
    const double s1 = st[i + 1].s;
    if (mj < old.size() && old[mj].s0 == s0 && old[mj].s1 == s1 && old[mj].va == va && old[mj].vb == vb &&
        old[mj].cap == cap[i] && old[mj].A == A) {
      vp = old[mj].vp;
      changed[i] = 0;
    } else if (need(vp) > L) {
      // need() is increasing in v on [lo_peak, cap]: secant steps inside a
      // shrinking bracket (falls back to bisection), to 1e-12 relative
      double lo = lo_peak, hi = vp, flo = need(lo) - L, fhi = need(hi) - L;
      for (int it = 0; it < 100 && hi - lo > 1e-12 * std::max(1.0, hi); ++it) {
        double m = (fhi != flo) ? lo - flo * (hi - lo) / (fhi - flo) : 0.5 * (lo + hi);
        if (!(m > lo && m < hi) || it % 3 == 2) m = 0.5 * (lo + hi);
        const double fm = need(m) - L;
        if (fm <= 0) {
          lo = m;
          flo = fm;
        } else {
          hi = m;
          fhi = fm;
        }
      }
      vp = lo;
    }
    memo.push_back({s0, s1, va, vb, cap[i], A, vp});
    double s = s0;
    t = append_change(out, t, s, va, vp, A, J, tau);
    s = s0 + change_distance(va, vp, A, J, tau);
    const double cruise = L - need(vp);
    if (cruise > 0 && vp > 0) {
      Piece p;
      p.t0 = t;
      p.T = cruise / vp;
      p.s0 = s;
      p.v0 = vp;
      out.push_back(p);
      t += p.T;
      s += cruise;
    }
    t = append_change(out, t, s, vp, vb, A, J, tau);
  }
  return out;
}

int piece_at(const std::vector<Piece>& p, double t, int hint) {
  int i = std::clamp(hint, 0, static_cast<int>(p.size()) - 1);
  while (i + 1 < static_cast<int>(p.size()) && t >= p[i + 1].t0) ++i;
  while (i > 0 && t < p[i].t0) --i;
  return i;
}

}  // namespace traj::plan
