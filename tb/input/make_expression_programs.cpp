// SPDX-License-Identifier: Apache-2.0
// Writes random programs of parameters and expressions for the cross-check
// against rs274 (input.crosscheck.expressions): settings of numbered and
// named parameters (several on a line: they read the values before it),
// then moves whose coordinates and feeds are expressions of every binary
// operator (precedence and left-associativity: chains without brackets),
// unary function, unary sign, and parameter reference (#n, ##n, #[expr],
// #<name>, EXISTS). Most operands keep the functions in their domains; a few
// programs divide by zero or read an unset parameter and are refused by both.
//
// usage: make_expression_programs <directory> <count> [seed]
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
    set_.clear();
    names_.clear();
    std::string p = "G21 G90 G17\n";
    const int lines = 4 + pick(8);
    for (int k = 0; k < lines; ++k) {
      if (chance(0.45)) {
        // one to three settings on a line
        const int n = 1 + pick(3);
        std::vector<std::string> now;
        for (int i = 0; i < n; ++i) {
          std::string target;
          if (chance(0.5)) {
            target = "#" + std::to_string(1 + pick(6));
          } else {
            target = "#<" + std::string(chance(0.5) ? "len" : "Off set") + std::to_string(pick(3)) + ">";
          }
          p += target + " = " + expr(2) + " ";
          now.push_back(target);
        }
        p += "\n";
        for (const auto& t : now) (t[1] == '<' ? names_ : set_).push_back(t);
      } else {
        p += std::string(chance(0.3) ? "G0" : "G1") + " X" + expr(3) + " Y" + expr(2) + " Z" + expr(1) +
             " F[" + std::to_string(50 + pick(500)) + " + ABS" + bracket(expr(1)) + "]\n";
      }
    }
    return p + "M2\n";
  }

 private:
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }
  bool chance(double p) { return std::uniform_real_distribution<double>(0, 1)(rng_) < p; }
  static std::string bracket(const std::string& e) { return "[" + e + "]"; }

  std::string number() {
    char b[32];
    std::snprintf(b, sizeof b, "%.*f", pick(4), std::uniform_real_distribution<double>(-20, 20)(rng_));
    return b;
  }

  std::string leaf() {
    const int k = pick(10);
    if (k < 5 || (set_.empty() && names_.empty())) return number();
    if (k < 8 && !set_.empty()) return set_[pick(static_cast<int>(set_.size()))];
    if (k == 8 && !set_.empty()) return "#[" + set_[pick(static_cast<int>(set_.size()))].substr(1) + " + 0]";
    if (!names_.empty()) return names_[pick(static_cast<int>(names_.size()))];
    return "EXISTS[#<len" + std::to_string(pick(3)) + ">]";
  }

  // a value: leaf, bracketed chain, function, or signed value
  std::string expr(int depth) {
    if (depth <= 0) return leaf();
    const int k = pick(10);
    if (k < 3) return leaf();
    if (k < 7) {
      // a chain of operators without inner brackets: precedence decides
      static const char* ops[] = {"+", "-", "*", "/", "MOD", "**", "EQ", "NE", "GT", "GE", "LT", "LE", "AND", "OR",
                                  "XOR"};
      std::string e = expr(depth - 1);
      const int n = 1 + pick(3);
      for (int i = 0; i < n; ++i) {
        const std::string op = ops[pick(15)];
        // powers of a small magnitude by a small whole number stay finite and defined
        const std::string rhs = op == "**" ? std::to_string(pick(4)) : expr(depth - 1);
        if (op == "**") e = "ABS" + bracket(e) + " MOD 3";
        e += " " + op + " " + rhs;
      }
      return bracket(e);
    }
    if (k < 9) {
      static const char* fns[] = {"ABS", "COS", "SIN", "FIX", "FUP", "ROUND", "EXP", "SQRT", "LN", "ATAN", "ACOS",
                                  "TAN"};
      const std::string f = fns[pick(12)];
      const std::string a = expr(depth - 1);
      if (f == "EXP") return "EXP[" + a + " MOD 5]";
      if (f == "SQRT") return "SQRT[ABS" + bracket(a) + "]";
      if (f == "LN") return "LN[ABS" + bracket(a) + " + 1]";
      if (f == "ATAN") return "ATAN" + bracket(a) + "/" + bracket(expr(depth - 1));
      if (f == "ACOS") return "ACOS[SIN" + bracket(a) + "]";
      return f + bracket(a);
    }
    return std::string(chance(0.5) ? "-" : "+") + expr(depth - 1);
  }

  std::mt19937 rng_;
  std::vector<std::string> set_, names_;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s <directory> <count> [seed]\n", argv[0]);
    return 2;
  }
  const int count = std::atoi(argv[2]);
  Gen g(argc > 3 ? static_cast<unsigned>(std::atoi(argv[3])) : 1u);
  for (int i = 0; i < count; ++i) {
    const std::string path = std::string(argv[1]) + "/expr_" + std::to_string(i) + ".ngc";
    std::ofstream(path) << g.program();
  }
  return 0;
}
