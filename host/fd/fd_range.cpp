// SPDX-License-Identifier: Apache-2.0
// The long double range check of the forward-difference compiler's fast paths
// (see detail/fd_internal.hpp): power-basis bound first, then the Bernstein
// coefficients with an a-priori error bound.
#include <algorithm>
#include <cmath>

#include "fd/detail/fd_internal.hpp"

namespace traj::fd::detail {
namespace {

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


}  // namespace

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

}  // namespace traj::fd::detail
