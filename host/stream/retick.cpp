// SPDX-License-Identifier: Apache-2.0
#include "stream/retick.hpp"

#include <algorithm>
#include <cmath>

namespace traj::stream {
namespace {

// p(x) * (alpha x + beta), coefficients of x^j.
std::vector<mpq_class> times_linear(const std::vector<mpq_class>& p, const mpq_class& alpha, const mpq_class& beta) {
  std::vector<mpq_class> r(p.size() + 1, 0);
  for (size_t j = 0; j < p.size(); ++j) {
    r[j] += p[j] * beta;
    r[j + 1] += p[j] * alpha;
  }
  return r;
}

// sum_i d_i C(k, i) as coefficients of k^j.
std::vector<mpq_class> newton_to_power(const std::vector<mpz_class>& d) {
  std::vector<mpq_class> p(d.size(), 0);
  std::vector<mpq_class> falling{1};  // k (k-1) ... (k-i+1) / i!
  for (size_t i = 0; i < d.size(); ++i) {
    for (size_t j = 0; j < falling.size(); ++j) p[j] += mpq_class(d[i]) * falling[j];
    falling = times_linear(falling, mpq_class(1, i + 1), mpq_class(-mpz_class(i), i + 1));
  }
  return p;
}

// p(beta + alpha m) as coefficients of m^j (Horner).
std::vector<mpq_class> substitute(const std::vector<mpq_class>& p, const mpq_class& alpha, const mpq_class& beta) {
  std::vector<mpq_class> r{p.back()};
  for (size_t j = p.size() - 1; j-- > 0;) {
    r = times_linear(r, alpha, beta);
    r[0] += p[j];
  }
  return r;
}

}  // namespace

uint32_t engine_ticks_per_tick(double period, double max_engine_tick) {
  if (!(max_engine_tick > 0) || !(period > max_engine_tick)) return 1;
  // The tolerance keeps 2 ms at 1 ms from becoming 3 through a rounding.
  return static_cast<uint32_t>(std::ceil(period / max_engine_tick * (1 - 1e-12)));
}

Reticker::Reticker(const Header& coarse, uint32_t n) : fine_(coarse), n_(n), compiler_(coarse.format()) {
  if (coarse.has_bcu()) throw StreamError("re-ticking a stream with BCU segments is not supported (FD only)");
  if (n < 1) throw StreamError("re-ticking: n = 0 engine ticks per tick");
  fine_.period = coarse.period / n;
  const fd::Format& f = compiler_.format();
  longest_ = std::min<uint64_t>(f.max_ticks, fd::Compiler::longest_segment(f.degree, f.guard_bits, f.tol_lsb));
  if (longest_ < 1)
    throw StreamError("re-ticking: the stream's format (guard_bits " + std::to_string(f.guard_bits) +
                      ") holds no segment within the error budget");
}

// P(k) of record r for one axis, coefficients of k^j (register units).
std::vector<mpq_class> Reticker::coarse_polynomial(const Record& r, int axis) const {
  const std::vector<mpz_class>& reg = r.regs[static_cast<size_t>(axis)];
  const int N = fine_.degree;
  if (r.ticks < static_cast<uint32_t>(N)) {
    const mpz_class near_wrap = mpz_class(1) << (fine_.width - 3);
    for (int i = static_cast<int>(r.ticks) + 1; i <= N; ++i)
      if (abs(reg[static_cast<size_t>(i)]) >= near_wrap)
        throw StreamError("re-ticking: segment " + std::to_string(r.seq) + " (K=" + std::to_string(r.ticks) +
                          " ticks, fewer than the degree " + std::to_string(N) + ") axis " + std::to_string(axis) +
                          ": r[" + std::to_string(i) + "] is within a factor 4 of the register's range, so it "
                          "may have wrapped and the path between its ticks is not known: plan at a shorter tick");
    return newton_to_power(reg);
  }
  // The engine's states at k = 0..N are in range: their differences are the
  // true ones, whatever the compiler wrapped.
  std::vector<mpz_class> y(static_cast<size_t>(N) + 1);
  for (int m = 0; m <= N; ++m) {
    mpz_class v = 0;
    for (int i = 0; i <= N; ++i) v += reg[static_cast<size_t>(i)] * fd::binom(static_cast<uint64_t>(m), i);
    fd::wrap_to_width(v, fine_.width);
    y[static_cast<size_t>(m)] = v;
  }
  std::vector<mpz_class> d(y.size());
  for (int i = 0; i <= N; ++i) {
    d[static_cast<size_t>(i)] = y[0];
    for (int m = 0; m + i < N; ++m) y[static_cast<size_t>(m)] = y[static_cast<size_t>(m) + 1] - y[static_cast<size_t>(m)];
  }
  return newton_to_power(d);
}

void Reticker::add(const Record& r, std::vector<Record>& out) {
  if (r.is_bcu()) throw StreamError("segment " + std::to_string(r.seq) + ": a BCU segment cannot be re-ticked");
  const std::string where = "segment " + std::to_string(r.seq);
  const int A = fine_.axes;
  std::vector<std::vector<mpq_class>> P(static_cast<size_t>(A));
  for (int a = 0; a < A; ++a) P[static_cast<size_t>(a)] = coarse_polynomial(r, a);
  const uint64_t total = uint64_t(r.ticks) * n_;
  const uint64_t pieces = (total + longest_ - 1) / longest_;
  const mpq_class alpha(1, n_);
  uint64_t s = 0;
  for (uint64_t p = 0; p < pieces; ++p) {
    const uint64_t len = total / pieces + (p < total % pieces ? 1 : 0);
    fd::ExactTarget t;
    t.ticks = len;
    const mpq_class beta(mpz_class(std::to_string(s)), mpz_class(n_));
    for (int a = 0; a < A; ++a) t.q.push_back(substitute(P[static_cast<size_t>(a)], alpha, beta));
    fd::Compiled c;
    try {
      c = compiler_.compile_target(t, end_.empty() ? nullptr : &end_,
                                   where + " at " + std::to_string(n_) + " engine ticks per tick");
    } catch (const fd::CompileError& e) {
      throw StreamError(std::string("re-ticking: ") + e.what());
    }
    bound_lsb_ = std::max(bound_lsb_, c.bound_lsb);
    Record f;
    f.ticks = static_cast<uint32_t>(len);
    f.kind = RecordKind::kFd;
    f.seq = seq_++;
    f.regs = std::move(c.regs);
    out.push_back(std::move(f));
    end_ = std::move(c.end);
    s += len;
  }
}

ReadResult retick(const ReadResult& coarse, uint32_t n) {
  if (!coarse.complete) throw StreamError("re-ticking an incomplete stream: " + coarse.error);
  Reticker rt(coarse.header, n);
  ReadResult fine;
  fine.header = rt.header();
  for (const Record& r : coarse.records) rt.add(r, fine.records);
  fine.complete = true;
  return fine;
}

}  // namespace traj::stream
