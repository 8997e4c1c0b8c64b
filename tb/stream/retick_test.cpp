// stream::Reticker: a stream re-compiled at n engine ticks per tick, checked
// against an independent reference: the coarse records' own Newton sums
// sum_i r_i C(k, i) evaluated in exact rationals at the fractional coarse
// tick k = j/n of every fine tick j (the Reticker goes through the power
// basis and compile_target; the fine states come from running the engine's
// difference recurrence tick by tick). Streams: the raster planned at 2 ms
// and 3 ms by the real planner, and hand-made segments shorter than the
// degree.
#include <gtest/gtest.h>

#include "fd/fd_compiler.hpp"
#include "input/raster.hpp"
#include "job/streaming.hpp"
#include "stream/retick.hpp"

namespace traj::stream {
namespace {

ReadResult planned_raster(size_t pieces, double period) {
  job::JobConfig cfg;
  cfg.machine.period = period;
  input::RasterSource src(pieces);
  ReadResult r;
  r.header = cfg.machine.header();
  job::run_streaming(src, cfg, job::StreamOptions{}, [&](const fd::Compiled& c, const plan::TimeSegment&) {
    Record rec{c.ticks, c.regs};
    rec.seq = static_cast<uint32_t>(r.records.size());
    r.records.push_back(rec);
  });
  r.complete = true;
  return r;
}

// C(k, i) for rational k, directly from the product.
mpq_class binom_q(const mpq_class& k, int i) {
  mpq_class v = 1;
  for (int j = 0; j < i; ++j) v = v * (k - j) / (j + 1);
  return v;
}

mpz_class wrapped(mpz_class v, int width) {
  fd::wrap_to_width(v, width);
  return v;
}

struct Compared {
  uint64_t fine_ticks = 0, coarse_ticks = 0;
  double max_state_err_lsb = 0;     // fine state - P(j/n), output LSB
  long max_sample_diff = 0;         // |fine sample - coarse sample| at the coarse ticks
};

// Runs both streams tick by tick (every `stride`-th fine tick compared).
Compared compare(const ReadResult& coarse, const ReadResult& fine, uint32_t n, uint64_t stride) {
  const Header& h = coarse.header;
  const mpz_class guard = mpz_class(1) << h.guard_bits;
  Compared out;
  size_t fi = 0;
  uint64_t fk = 0;  // tick within fine record fi
  std::vector<std::vector<mpz_class>> freg = fine.records.at(0).regs;
  auto advance_fine = [&] {
    for (auto& ax : freg)
      for (size_t i = 0; i + 1 < ax.size(); ++i) ax[i] = wrapped(ax[i] + ax[i + 1], h.width);
    if (++fk == fine.records[fi].ticks && fi + 1 < fine.records.size()) {
      ++fi;
      fk = 0;
      for (size_t a = 0; a < freg.size(); ++a) {
        EXPECT_EQ(freg[a][0], wrapped(fine.records[fi].regs[a][0], h.width)) << "fine record " << fi << " jumps";
        freg[a] = fine.records[fi].regs[a];
      }
    }
    ++out.fine_ticks;
  };
  for (const Record& r : coarse.records) {
    for (uint64_t k = 0; k < r.ticks; ++k) {
      for (uint32_t s = 0; s < n; ++s) {
        if ((out.fine_ticks % stride) == 0 || s == 0)
          for (size_t a = 0; a < freg.size(); ++a) {
            mpq_class p = 0;  // the coarse engine's polynomial at k + s/n
            for (size_t i = 0; i < r.regs[a].size(); ++i)
              p += mpq_class(r.regs[a][i]) * binom_q(mpq_class(mpz_class(std::to_string(k * n + s)), n), int(i));
            mpq_class e = (mpq_class(wrapped(freg[a][0], h.width)) - p) / mpq_class(guard);
            out.max_state_err_lsb = std::max(out.max_state_err_lsb, std::fabs(e.get_d()));
            if (s == 0) {
              mpz_class cs = wrapped(mpz_class(p), h.width), fs = wrapped(freg[a][0], h.width);
              mpz_class csam, fsam;
              mpz_fdiv_q_2exp(csam.get_mpz_t(), cs.get_mpz_t(), h.guard_bits);
              mpz_fdiv_q_2exp(fsam.get_mpz_t(), fs.get_mpz_t(), h.guard_bits);
              out.max_sample_diff = std::max(out.max_sample_diff, std::labs(mpz_class(fsam - csam).get_si()));
            }
          }
        advance_fine();
      }
      ++out.coarse_ticks;
    }
  }
  return out;
}

TEST(Retick, EngineTicksPerTick) {
  EXPECT_EQ(engine_ticks_per_tick(1e-3), 1u);
  EXPECT_EQ(engine_ticks_per_tick(250e-6), 1u);
  EXPECT_EQ(engine_ticks_per_tick(2e-3), 2u);
  EXPECT_EQ(engine_ticks_per_tick(1.5e-3), 2u);
  EXPECT_EQ(engine_ticks_per_tick(5e-3), 5u);
  EXPECT_EQ(engine_ticks_per_tick(5e-3, 0), 1u);
}

TEST(Retick, OneTickPerTickIsTheSameStream) {
  const ReadResult coarse = planned_raster(2, 1e-3);
  const ReadResult fine = retick(coarse, 1);
  ASSERT_GE(coarse.records.size(), 10u);
  ASSERT_EQ(fine.records.size(), coarse.records.size());
  for (size_t i = 0; i < coarse.records.size(); ++i) {
    EXPECT_EQ(fine.records[i].ticks, coarse.records[i].ticks);
    EXPECT_EQ(fine.records[i].regs, coarse.records[i].regs) << "record " << i;
  }
}

void check_planned(double period, uint32_t n) {
  const ReadResult coarse = planned_raster(2, period);
  Reticker rt(coarse.header, n);
  EXPECT_DOUBLE_EQ(rt.header().period, period / n);
  ReadResult fine;
  fine.header = rt.header();
  for (const Record& r : coarse.records) rt.add(r, fine.records);
  fine.complete = true;
  EXPECT_LE(rt.bound_lsb(), 0.5);
  // the stream's own writer accepts it: sequence, K bounds, continuity
  EXPECT_NO_THROW(for (const Record& r : fine.records) encode_record(fine.header, r));
  Continuity chain(fine.header);
  for (const Record& r : fine.records) {
    int axis = -1;
    ASSERT_EQ(chain.check(r, axis), "") << "record " << r.seq;
    chain.advance(r);
  }
  const Compared c = compare(coarse, fine, n, 7);
  EXPECT_EQ(c.fine_ticks, c.coarse_ticks * n);
  EXPECT_LE(c.max_state_err_lsb, 0.5) << "fine state against the coarse polynomial";
  EXPECT_LE(c.max_sample_diff, 1) << "fine samples at the coarse ticks";
  std::printf("    %.0e s, n=%u: %zu -> %zu records, %llu ticks; state error <= %.3g LSB, samples differ <= %ld LSB\n",
              period, n, coarse.records.size(), fine.records.size(),
              static_cast<unsigned long long>(c.fine_ticks), c.max_state_err_lsb, c.max_sample_diff);
}

TEST(Retick, PlannedRasterAt2msOnA1msEngine) { check_planned(2e-3, 2); }
TEST(Retick, PlannedRasterAt3msOnA750usEngine) { check_planned(3e-3, 4); }

// Segments of 1..3 ticks at degree 5 (K < degree: the registers as read),
// then a longer one, at n = 4.
TEST(Retick, SegmentsShorterThanTheDegree) {
  fd::Format f{1, 5, 64, 16, 24, 16};
  fd::Compiler comp(f);
  ReadResult coarse;
  coarse.header = Header::from(f, 4e-3, "mm");
  std::vector<mpz_class> end;
  const double coefs[][6] = {{1.0, 20, 300, -4e4, 1e6, -2e7}, {0, 5, 0, 0, 0, 3e9}, {0, -8, 100, 0, 0, 0},
                             {0, 1, 0, 0, 2e8, 0}};
  const uint64_t ks[] = {3, 1, 2, 40};
  for (int s = 0; s < 4; ++s) {
    fd::PolySegment seg;
    seg.h = 4e-3;
    seg.ticks = ks[s];
    seg.coef = {std::vector<double>(coefs[s], coefs[s] + 6)};
    if (s > 0)  // the previous end: r0 = (x 2^F + 1/2) 2^G
      seg.coef[0][0] = mpq_class((mpq_class(end[0]) - mpq_class(mpz_class(1) << (f.guard_bits - 1))) /
                                 mpq_class(mpz_class(1) << (f.guard_bits + f.frac_bits)))
                           .get_d();
    const fd::Compiled c = comp.compile(seg, s ? &end : nullptr);
    Record r{c.ticks, c.regs};
    r.seq = static_cast<uint32_t>(s);
    coarse.records.push_back(r);
    end = c.end;
  }
  coarse.complete = true;
  const ReadResult fine = retick(coarse, 4);
  const Compared c = compare(coarse, fine, 4, 1);
  EXPECT_EQ(c.fine_ticks, 46u * 4);
  EXPECT_LE(c.max_state_err_lsb, 0.5);
  EXPECT_LE(c.max_sample_diff, 1);
}

// A one-tick quintic whose r[5] exceeds the 64-bit register (wrapped by the
// compiler): its path between ticks is not known from the stream, refused
// with the segment named.
TEST(Retick, RefusesAShortSegmentThatMayHaveWrapped) {
  fd::Format f{1, 5, 64, 16, 24, 16};
  fd::Compiler comp(f);
  fd::PolySegment seg;
  seg.h = 4e-3;
  seg.ticks = 1;
  seg.coef = {{0, 1, 0, 0, 0, 1e17}};
  const fd::Compiled c = comp.compile(seg);
  ReadResult coarse;
  coarse.header = Header::from(f, 4e-3, "mm");
  coarse.records.push_back(Record{c.ticks, c.regs});
  coarse.complete = true;
  try {
    retick(coarse, 4);
    FAIL() << "accepted";
  } catch (const StreamError& e) {
    EXPECT_NE(std::string(e.what()).find("segment 0 (K=1 ticks"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("may have wrapped"), std::string::npos) << e.what();
  }
}

TEST(Retick, RefusesBcuStreams) {
  Header h;
  h.bcu_ctrl_width = 40;
  EXPECT_THROW(Reticker(h, 2), StreamError);
}

}  // namespace
}  // namespace traj::stream
