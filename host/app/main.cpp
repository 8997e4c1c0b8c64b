// trajcore: command-line tool.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include "demo.hpp"

int main(int argc, char** argv) {
  CLI::App app{"trajcore: FPGA motion-trajectory core, host toolchain"};
  app.require_subcommand(1);

  traj::app::DemoOptions demo;
  auto* d = app.add_subcommand("demo",
                               "Built-in demo: a circle of three 120-degree cubic Bezier segments, compiled to "
                               "forward-difference segments and run through the Verilated engine");
  d->add_option("--radius", demo.radius, "circle radius, mm")->check(CLI::PositiveNumber);
  d->add_option("--feed", demo.feed, "nominal feed along the circle, mm/s")->check(CLI::PositiveNumber);
  d->add_option("--period", demo.period, "tick period, s")->check(CLI::PositiveNumber);
  d->add_option("--pieces", demo.pieces, "time segments per 120-degree arc")->check(CLI::Range(1, 1000));
  d->add_option("--frac-bits", demo.frac_bits, "output fraction bits (1 LSB = 2^-F mm)")->check(CLI::Range(0, 30));
  d->add_option("--csv", demo.csv, "where to write the samples (CSV)");
  d->add_option("--tick-gap", demo.tick_gap, "clock cycles between ticks in the simulation")->check(CLI::Range(1, 1000000));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (*d) return traj::app::run_demo(demo);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "trajcore: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
