// SPDX-License-Identifier: Apache-2.0
// The library's fast paths against its general ones:
//  * Curve::eval_span (specialised kernel detail::eval_span_fixed: 1..3 axes, degree 1..5, rational or
//    not) against Curve::eval_span_general (runtime-sized Horner + rational_derivatives): bitwise
//    equal, every derivative order 0..3, random splines, parameters inside and outside the span;
//  * detail::eval_power_span (what bench_eval_ops counts) against detail::eval_power_span_general.
// Both paths perform the same floating-point operations in the same order, so the results must be
// identical bit for bit (no ulp tolerance).
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "geometry/curve.hpp"
#include "test_util.hpp"

using traj::geo::Curve;

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST(GeometryFastEval, SpecialisedKernelBitwiseEqualsGeneral) {
  std::mt19937_64 rng(geotest::seed());
  std::uniform_real_distribution<double> U01(0.0, 1.0);
  long long compared = 0, specialised_curves = 0;
  for (int dim = 1; dim <= 4; ++dim)
    for (int p = 1; p <= 7; ++p)
      for (int rat = 0; rat <= 1; ++rat)
        for (int rep = 0; rep < 4; ++rep) {
          const int n = p + 1 + static_cast<int>(U01(rng) * 6);
          const auto rs = geotest::random_spline(rng, p, dim, n, rat == 1);
          const Curve c(rs.lib);
          if (traj::geo::detail::fixed_kernel<double>(dim, rat == 1, p)) ++specialised_curves;
          const auto& spans = c.spans();
          for (int si = 0; si < static_cast<int>(spans.size()); ++si) {
            const double h = spans[si].u1 - spans[si].u0;
            for (int t = 0; t < 40; ++t) {
              // mostly inside the span, some on its ends, some outside (the polynomial is extended)
              double u = spans[si].u0 + h * (1.2 * U01(rng) - 0.1);
              if (t == 0) u = spans[si].u0;
              if (t == 1) u = spans[si].u1;
              for (int nd = 0; nd <= 3; ++nd) {
                double fast[4 * 4], gen[4 * 4];
                std::fill(fast, fast + 16, -7.0);
                std::fill(gen, gen + 16, -7.0);
                c.eval_span(si, u, nd, fast);
                c.eval_span_general(si, u, nd, gen);
                for (int i = 0; i < (nd + 1) * dim; ++i) {
                  ASSERT_TRUE(same_bits(fast[i], gen[i]))
                      << "dim " << dim << " p " << p << " rational " << rat << " span " << si << " u " << u
                      << " nd " << nd << " entry " << i << ": " << fast[i] << " vs " << gen[i];
                  ++compared;
                }
                for (int i = (nd + 1) * dim; i < 16; ++i) EXPECT_EQ(fast[i], -7.0) << "wrote past nd";
              }
            }
          }
          // The non-rational kernel as the benchmark instantiates it (eval_power_span).
          if (rat == 0) {
            const double u = c.u_begin() + (c.u_end() - c.u_begin()) * U01(rng);
            const auto& s = spans[c.find_span(u)];
            double a[16], b[16];
            traj::geo::detail::eval_power_span<double>(s, dim, u, 3, a);
            traj::geo::detail::eval_power_span_general<double>(s, dim, u, 3, b);
            for (int i = 0; i < 4 * dim; ++i) ASSERT_TRUE(same_bits(a[i], b[i]));
          }
        }
  EXPECT_EQ(specialised_curves, 3 * 5 * 2 * 4);  // dims 1..3 x degrees 1..5 x {rational, not} x 4
  std::printf("compared %lld values bitwise\n", compared);
}
