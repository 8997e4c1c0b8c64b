// SPDX-License-Identifier: Apache-2.0
// Per evaluated point: arithmetic operations and measured cost of De Boor-Cox vs the power basis
// ([NURBS] claims 71.1% fewer operations for the power basis, cubic, "points and their derivatives").
//  1. Operation counts with an instrumented scalar (kernels::Cnt: adds, multiplies, divides counted
//     separately), position + derivatives up to order nd, degrees 3/5/7, 2 and 3 axes.
//  2. Time per point (std::chrono, best of 5 runs of 1e6 random parameters; span search included in
//     both, non-rational cubic in 3-D with 60 control points).
//  3. Instructions per point from valgrind callgrind, if valgrind is installed: this program re-runs
//     itself as a driver (--driver deboor|power|none N) under callgrind; (Ir(mode) - Ir(none)) / N.
// Usage: bench_eval_ops [--short] [--no-valgrind]
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include "eval_kernels.hpp"
#include "geometry/geometry.hpp"

using namespace traj::geo;

namespace {

BSpline random_cubic(int p, int dim, int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  BSpline b;
  b.degree = p;
  b.ctrl.resize(n, dim);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < dim; ++d) b.ctrl(i, d) = 100 * U(rng);
  b.knots.resize(n + p + 1);
  std::vector<double> in(n - p - 1);
  for (auto& t : in) t = U(rng);
  std::sort(in.begin(), in.end());
  for (int i = 0; i <= p; ++i) {
    b.knots[i] = 0;
    b.knots[n + i] = 1;
  }
  for (int i = 0; i < n - p - 1; ++i) b.knots[p + 1 + i] = in[i];
  return b;
}

std::vector<double> row_major(const BSpline& b) {
  std::vector<double> P(b.n_ctrl() * b.dim());
  for (int i = 0; i < b.n_ctrl(); ++i)
    for (int d = 0; d < b.dim(); ++d) P[i * b.dim() + d] = b.ctrl(i, d);
  return P;
}

int knot_span(const BSpline& b, double u) {
  const double* U = b.knots.data();
  const int n = b.n_ctrl();
  int s = static_cast<int>(std::upper_bound(U + b.degree, U + n, u) - U) - 1;
  return std::clamp(s, b.degree, n - 1);
}

void count_table() {
  using kernels::Cnt;
  std::printf("Operation count per evaluated point (instrumented scalar; a = adds/subtracts, m = multiplies, d = divides;\n"
              "span search not counted). Reduction = 1 - (power total) / (De Boor-Cox total).\n");
  std::printf("%3s %4s %3s | %6s %6s %6s %7s | %6s %6s %6s %7s | %9s\n", "p", "axes", "nd", "DBC a", "m", "d", "total",
              "PB a", "m", "d", "total", "reduction");
  for (int p : {3, 5, 7})
    for (int dim : {2, 3})
      for (int nd = 0; nd <= 3; ++nd) {
        const BSpline b = random_cubic(p, dim, p + 9, 7);
        const Curve c(b);
        const auto P = row_major(b);
        const double u = 0.4321;
        std::array<Cnt, 32> out;
        Cnt::reset();
        kernels::deboor_eval<Cnt>(b, P.data(), knot_span(b, u), Cnt(u), nd, out.data());
        const long long da = Cnt::adds, dm = Cnt::muls, dd = Cnt::divs;
        Cnt::reset();
        kernels::power_eval<Cnt>(c.spans()[c.find_span(u)], dim, Cnt(u), nd, out.data());
        const long long pa = Cnt::adds, pm = Cnt::muls, pd = Cnt::divs;
        const double red = 1.0 - double(pa + pm + pd) / double(da + dm + dd);
        std::printf("%3d %4d %3d | %6lld %6lld %6lld %7lld | %6lld %6lld %6lld %7lld | %8.1f%%\n", p, dim, nd, da, dm, dd,
                    da + dm + dd, pa, pm, pd, pa + pm + pd, 100 * red);
      }
}

struct Setup {
  BSpline b;
  Curve c;
  std::vector<double> P, us;
  Setup(int N) : b(random_cubic(3, 3, 60, 11)), c(b), P(row_major(b)) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> U(0, 1);
    us.resize(N);
    for (auto& u : us) u = U(rng);
  }
};

volatile double g_sink;

double run_mode(const Setup& s, const std::string& mode, int nd) {
  double acc = 0, out[32];
  if (mode == "deboor") {
    for (double u : s.us) {
      kernels::deboor_eval<double>(s.b, s.P.data(), knot_span(s.b, u), u, nd, out);
      acc += out[0] + out[3 * nd];
    }
  } else if (mode == "power") {
    for (double u : s.us) {
      s.c.eval(u, nd, out);  // the library path (span search + Horner tables)
      acc += out[0] + out[3 * nd];
    }
  } else {
    for (double u : s.us) acc += u;
  }
  g_sink = acc;
  return acc;
}

void time_table(bool quick, bool valgrind, const char* self) {
  const int N = quick ? 100000 : 1000000;
  const Setup s(N);
  std::printf("\nTime per point (cubic, 3 axes, 60 control points, %d random u, best of 5; span search included):\n", N);
  std::printf("%3s | %14s %14s | %9s", "nd", "De Boor-Cox ns", "power ns", "reduction");
  if (valgrind) std::printf(" | %12s %12s %9s", "DBC instr", "power instr", "reduction");
  std::printf("\n");
  for (int nd = 0; nd <= 3; ++nd) {
    double best[2] = {1e300, 1e300};
    const char* modes[2] = {"deboor", "power"};
    for (int r = 0; r < 5; ++r)
      for (int m = 0; m < 2; ++m) {
        const auto t0 = std::chrono::steady_clock::now();
        run_mode(s, modes[m], nd);
        const auto t1 = std::chrono::steady_clock::now();
        best[m] = std::min(best[m], std::chrono::duration<double, std::nano>(t1 - t0).count() / N);
      }
    std::printf("%3d | %14.1f %14.1f | %8.1f%%", nd, best[0], best[1], 100 * (1 - best[1] / best[0]));
    if (valgrind) {
      const int Nv = 20000;
      auto ir = [&](const char* mode) -> double {
        const std::string cmd = std::string("valgrind --tool=callgrind --callgrind-out-file=/dev/null ") + self +
                                " --driver " + mode + " " + std::to_string(Nv) + " " + std::to_string(nd) + " 2>&1";
        FILE* f = popen(cmd.c_str(), "r");
        if (!f) return -1;
        char line[512];
        double v = -1;
        while (std::fgets(line, sizeof line, f))
          if (const char* q = std::strstr(line, "Collected :")) v = std::strtod(q + 11, nullptr);
        pclose(f);
        return v;
      };
      const double base = ir("none"), d = ir("deboor"), p = ir("power");
      const double di = (d - base) / Nv, pi = (p - base) / Nv;
      std::printf(" | %12.1f %12.1f %8.1f%%", di, pi, 100 * (1 - pi / di));
    }
    std::printf("\n");
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 5 && std::strcmp(argv[1], "--driver") == 0) {  // callgrind driver
    const Setup s(std::atoi(argv[3]));
    run_mode(s, argv[2], std::atoi(argv[4]));
    return 0;
  }
  bool quick = false, valgrind = true;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--short") == 0) quick = true;
    if (std::strcmp(argv[i], "--no-valgrind") == 0) valgrind = false;
  }
  if (valgrind) valgrind = std::system("valgrind --version > /dev/null 2>&1") == 0;
  count_table();
  time_table(quick, valgrind && !quick, argv[0]);
  return 0;
}
