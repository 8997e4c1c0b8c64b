// SPDX-License-Identifier: Apache-2.0
// Writes random drilling programs for the cross-check against rs274
// (input.crosscheck.canned_cycles): G73, G81 and G83 blocks with and without
// G98/G99, R, Z, Q and L, continued by blocks of axis words alone, between
// G0, G1, G80, G90 and G91, in mm and in inches. Many are refused (by rs274
// and read_gcode alike: an axis word with no cycle in effect, a Q or R no
// block uses); those accepted exercise the cycles' levels, clear planes and
// pecks in every order.
//
// usage: make_cycle_programs <directory> <count> [seed]
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>

namespace {

std::string num(char letter, double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%c%.3f", letter, v);
  return b;
}

std::string program(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  auto in = [&](double lo, double hi) { return lo + (hi - lo) * u(rng); };
  const bool inch = u(rng) < 0.3;
  std::string p = std::string(inch ? "G20" : "G21") + "\nG90 G17 F" + (inch ? "6" : "150") + "\nG0 X0 Y0 " +
                  num('Z', in(-2, 20)) + "\n";
  bool absolute = true;
  const int blocks = 3 + static_cast<int>(u(rng) * 10);
  static const char* kinds[] = {"G81", "G83", "G73", "", "", "", "G0", "G80", "G91", "G90", "G1"};
  for (int k = 0; k < blocks; ++k) {
    const std::string c = kinds[std::uniform_int_distribution<int>(0, 10)(rng)];
    if (c == "G0") {
      p += "G0 " + num('Z', in(-3, 20)) + "\n";
    } else if (c == "G1") {
      p += "G1 " + num('X', in(-5, 5)) + " " + num('Z', in(-3, 20)) + "\n";
    } else if (c == "G80" || c == "G90" || c == "G91") {
      p += c + "\n";
      if (c != "G80") absolute = c == "G90";
    } else {
      std::string b;
      if (u(rng) < 0.5) b += u(rng) < 0.5 ? "G98 " : "G99 ";
      if (!c.empty()) b += c + " ";
      if (u(rng) < 0.8) b += num('X', in(-5, 5)) + " ";
      if (u(rng) < 0.5) b += num('Y', in(-5, 5)) + " ";
      const double r = absolute ? in(-1, 6) : in(-8, 4), z = absolute ? r - in(0.5, 6) : -in(0.5, 6);
      if (!c.empty() || u(rng) < 0.3) b += num('R', r) + " ";
      if (!c.empty() || u(rng) < 0.3) b += num('Z', z) + " ";
      if (c == "G83" || c == "G73") b += num('Q', in(0.3, 2.5)) + " ";
      if (u(rng) < 0.25) b += "L" + std::to_string(2 + static_cast<int>(u(rng) * 3)) + " ";
      if (b.empty()) continue;  // a continuation block with no word
      b.pop_back();
      p += b + "\n";
    }
  }
  return p + "M2\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: make_cycle_programs <directory> <count> [seed]\n");
    return 2;
  }
  const std::string dir = argv[1];
  const int count = std::atoi(argv[2]);
  std::mt19937 rng(argc > 3 ? static_cast<unsigned>(std::atoi(argv[3])) : 7u);
  for (int n = 0; n < count; ++n) {
    char name[32];
    std::snprintf(name, sizeof name, "/cycles_%03d.ngc", n);
    std::ofstream(dir + name) << program(rng);
  }
  return 0;
}
