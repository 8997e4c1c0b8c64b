// SPDX-License-Identifier: Apache-2.0
// Writes random programs of O-words (subroutines and control flow) for the
// cross-check against rs274 (input.crosscheck.control_flow): subroutines with
// arguments, local named parameters, nested calls, return values (return and
// endsub, with and without a value), if/elseif/else, while, do-while and
// repeat loops (counted by global parameters, so that every loop ends) with
// break and continue inside ifs (while loops; do loops break only: after a
// continue of a do loop LinuxCNC's interpreter keeps its continue flag set,
// and a later loop can then run forever; repeat loops have neither, as in
// LinuxCNC), nested to depth 3, each construct writing
// moves whose coordinates read the counters and the returned values. About
// one program in eight is broken on purpose (a label that does not match,
// an endif or endwhile missing, a call of a subroutine not defined, a break
// outside its loop, a caller's local parameter read in a subroutine) and is
// refused by both.
//
// usage: make_flow_programs <directory> <count> [seed]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace {

class Gen {
 public:
  explicit Gen(unsigned seed) : rng_(seed) {}

  std::string program() {
    label_ = 100;
    counters_.clear();
    do_loops_.clear();
    subs_ = 0;
    broken_ = chance(0.125) ? 1 + pick(5) : 0;
    std::string p = "G21 G90 G17\n#<_acc> = 0\n#<top> = 1.5\n";
    const int nsubs = pick(3);
    for (int s = 0; s < nsubs; ++s) p += sub(s);
    p += block(0, -1);
    if (broken_ == 3) p += "o<nowhere> call [1]\n";
    if (broken_ == 4) p += "o" + std::to_string(label_++) + " break\n";
    return p + "M2\n";
  }

 private:
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }
  bool chance(double p) { return std::uniform_real_distribution<double>(0, 1)(rng_) < p; }
  std::string num(int lo, int hi) { return std::to_string(lo + pick(hi - lo + 1)); }

  // a move reading the counters in scope and the accumulator
  std::string move() {
    std::string x = "[#<_acc> * 0.5 + " + num(0, 9) + "]";
    for (const auto& c : counters_)
      if (chance(0.5)) x = "[" + x + " + #<" + c + ">]";
    return "G1 X" + x + " Y[" + num(-5, 5) + " + #<_acc>] Z" + num(-2, 2) + " F" + num(100, 900) + "\n";
  }

  std::string bump() { return "#<_acc> = [#<_acc> + " + num(1, 3) + "]\n"; }

  std::string call() {
    if (subs_ == 0) return move();
    const int s = pick(subs_);
    std::string c = "o<s" + std::to_string(s) + "> call";
    for (int a = 0, n = pick(3); a < n; ++a) c += " [" + num(-3, 6) + " + #<_acc>]";
    return c + "\nG1 X[#<_value> + 1] Y#<_value_returned> F300\n";
  }

  std::string sub(int s) {
    const std::string name = "<s" + std::to_string(s) + ">";
    std::string p = "o" + name + " sub\n";
    p += "#<t> = [#1 + #2 * 2]\n";
    p += "G1 X#1 Y#2 Z#3 F" + num(200, 800) + "\n";
    if (broken_ == 5 && s == 0) p += "G1 X#<top>\n";  // the caller's local: not seen here
    if (s > 0 && chance(0.6)) p += "o<s" + std::to_string(pick(s)) + "> call [#<t>] [#1]\nG1 Y#<_value> F400\n";
    const std::string l = std::to_string(label_++);
    p += "o" + l + " if [#1 GT " + num(0, 4) + "]\n";
    p += "  o" + l + " return [#<t> * " + num(1, 3) + "]\n";
    p += "o" + l + " endif\n";
    p += "G1 X#<t> F500\n";
    subs_ = s + 1;
    return p + "o" + name + " endsub" + (chance(0.5) ? " [#2 - " + num(0, 5) + "]" : "") + "\n";
  }

  // a run of statements inside the loop labelled `loop` (-1: none)
  std::string block(int depth, int loop) {
    std::string p;
    const int n = 1 + pick(depth == 0 ? 5 : 3);
    for (int k = 0; k < n; ++k) {
      const int what = depth >= 3 ? pick(2) : pick(7);
      switch (what) {
        case 0: p += move(); break;
        case 1: p += bump() + (chance(0.5) ? call() : move()); break;
        case 2: p += if_(depth, loop); break;
        case 3: p += while_(depth); break;
        case 4: p += do_(depth); break;
        case 5: p += repeat_(depth); break;
        default: p += call(); break;
      }
    }
    return p;
  }

  // break or continue of the loop `loop` under a condition on the accumulator
  std::string exit_of(int loop) {
    const std::string l = std::to_string(label_++);
    const bool do_loop = std::find(do_loops_.begin(), do_loops_.end(), loop) != do_loops_.end();
    return "o" + l + " if [[#<_acc> MOD " + num(2, 5) + "] EQ 0]\n  o" + std::to_string(loop) +
           (do_loop || chance(0.5) ? " break\n" : " continue\n") + "o" + l + " endif\n";
  }

  std::string if_(int depth, int loop) {
    const std::string l = "o" + std::to_string(label_++);
    std::string p = l + " if [#<_acc> GT " + num(0, 12) + "]\n" + block(depth + 1, loop);
    if (loop >= 0 && chance(0.5)) p += exit_of(loop);
    for (int e = 0, n = pick(3); e < n; ++e) p += l + " elseif [#<_acc> LT " + num(0, 12) + "]\n" + block(depth + 1, loop);
    if (chance(0.5)) p += l + " else\n" + block(depth + 1, loop);
    if (broken_ == 2 && depth == 0) return p;  // no endif
    return p + (broken_ == 1 && depth == 0 ? "o9999" : l) + " endif\n";
  }

  std::string counted(const std::string& c, int loop, int depth) {
    counters_.push_back(c);
    std::string p = "#<" + c + "> = [#<" + c + "> + 1]\n" + bump();
    if (loop >= 0 && chance(0.6)) p += exit_of(loop);
    p += block(depth + 1, loop);
    counters_.pop_back();
    return p;
  }

  std::string while_(int depth) {
    const int n = label_++;
    const std::string l = "o" + std::to_string(n), c = "_c" + std::to_string(n);
    std::string p = "#<" + c + "> = 0\n" + l + " while [#<" + c + "> LT " + num(0, 4) + "]\n";
    p += counted(c, n, depth);
    if (broken_ == 2 && depth == 0) return p;  // no endwhile
    return p + l + " endwhile\n";
  }

  std::string do_(int depth) {
    const int n = label_++;
    const std::string l = "o" + std::to_string(n), c = "_c" + std::to_string(n);
    do_loops_.push_back(n);
    std::string p = "#<" + c + "> = 0\n" + l + " do\n" + counted(c, n, depth);
    return p + l + " while [#<" + c + "> LT " + num(1, 4) + "]\n";
  }

  std::string repeat_(int depth) {
    const int n = label_++;
    const std::string l = "o" + std::to_string(n), c = "_c" + std::to_string(n);
    std::string p = "#<" + c + "> = 0\n" + l + " repeat [" + num(0, 4) + "]\n" + counted(c, -1, depth);
    return p + l + " endrepeat\n";
  }

  std::mt19937 rng_;
  int label_ = 100, subs_ = 0, broken_ = 0;
  std::vector<std::string> counters_;
  std::vector<int> do_loops_;  // labels of do loops: no continue (below)
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: make_flow_programs <directory> <count> [seed]\n");
    return 2;
  }
  const std::string dir = argv[1];
  const int count = std::atoi(argv[2]);
  Gen g(argc > 3 ? static_cast<unsigned>(std::strtoul(argv[3], nullptr, 10)) : 1u);
  for (int i = 0; i < count; ++i) {
    char name[64];
    std::snprintf(name, sizeof name, "/flow_%03d.ngc", i);
    std::ofstream(dir + name) << g.program();
  }
  return 0;
}
