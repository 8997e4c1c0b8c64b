#include "planner/profile.hpp"

#include <algorithm>
#include <cmath>

namespace traj::plan {

double change_time(double dv, double A, double J) {
  if (dv <= 0) return 0;
  if (dv >= A * A / J) return dv / A + A / J;
  return 2 * std::sqrt(dv / J);
}

double change_distance(double v0, double v1, double A, double J) {
  return 0.5 * (v0 + v1) * change_time(std::fabs(v1 - v0), A, J);
}

double reachable(double v0, double L, double A, double J, double vmax) {
  if (vmax <= v0) return vmax;
  if (change_distance(v0, vmax, A, J) <= L) return vmax;
  double lo = v0, hi = vmax;
  for (int it = 0; it < 200 && hi - lo > 1e-12 * std::max(1.0, hi); ++it) {
    const double mid = 0.5 * (lo + hi);
    (change_distance(v0, mid, A, J) <= L ? lo : hi) = mid;
  }
  return lo;
}

double append_change(std::vector<Piece>& out, double t, double s, double v0, double v1, double A, double J) {
  const double dv = std::fabs(v1 - v0);
  if (dv <= 0) return t;
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

std::vector<Piece> plan_blocks(std::vector<Station>& st, const std::vector<double>& cap, double A, double J) {
  const size_t n = st.size();
  for (auto& x : st) x.v = x.vmax;
  if (n == 0) return {};
  // backward pass: able to slow down to the next station's speed
  for (size_t i = n - 1; i-- > 0;) {
    const double L = st[i + 1].s - st[i].s;
    st[i].v = std::min(st[i].v, reachable(st[i + 1].v, L, A, J, st[i].v));
  }
  // forward pass: reachable from the previous station
  for (size_t i = 1; i < n; ++i) {
    const double L = st[i].s - st[i - 1].s;
    st[i].v = std::min(st[i].v, reachable(st[i - 1].v, L, A, J, st[i].v));
  }
  std::vector<Piece> out;
  double t = 0;
  for (size_t i = 0; i + 1 < n; ++i) {
    const double s0 = st[i].s, L = st[i + 1].s - s0;
    const double va = st[i].v, vb = st[i + 1].v;
    const double lo_peak = std::max(va, vb);
    double vp = std::max(cap[i], lo_peak);
    auto need = [&](double v) { return change_distance(va, v, A, J) + change_distance(v, vb, A, J); };
    if (need(vp) > L) {
      double lo = lo_peak, hi = vp;
      for (int it = 0; it < 200 && hi - lo > 1e-12 * std::max(1.0, hi); ++it) {
        const double mid = 0.5 * (lo + hi);
        (need(mid) <= L ? lo : hi) = mid;
      }
      vp = lo;
    }
    double s = s0;
    t = append_change(out, t, s, va, vp, A, J);
    s = s0 + change_distance(va, vp, A, J);
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
    t = append_change(out, t, s, vp, vb, A, J);
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
