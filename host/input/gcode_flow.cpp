// SPDX-License-Identifier: Apache-2.0
#include "input/gcode_flow.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <initializer_list>

#include "input/toolpath.hpp"

namespace traj::input::gcode {
namespace {

constexpr int kLocalParameters = 30;       // #1..#30 belong to a call
constexpr size_t kMaxCallDepth = 9;        // nested calls, as LinuxCNC allows
constexpr long long kMaxTurns = 1000000;   // turns of one run of a loop (a bound for any input)

// What the program has met under a label: its opening line (LinuxCNC keeps
// one per label for the whole run; a label opens one construct only).
struct Label {
  OKeyword kind = OKeyword::kSub;
  size_t index = 0;         // the opening line
  long long repeats = -1;   // a repeat's turns left; -1: counted when it starts
  long long turns = 0;
};

struct Call {
  std::string sub;                            // its label
  size_t back = 0;                            // the caller's next line
  std::map<int, double> saved_numbered;       // the caller's #1..#30 that were set
  std::map<std::string, double> saved_named;  // the caller's own named parameters
};

bool local_name(const std::string& n) { return n.empty() || n[0] != '_'; }

}  // namespace

struct GcodeFlow::Impl {
  std::istream& in;
  std::string file;
  Parameters& params;
  // The program's lines: a window from store_first, and the bodies of the
  // subroutines (kept from their definition on).
  std::deque<std::string> store;
  size_t store_first = 0, lines_read = 0;
  std::map<size_t, std::string> kept;
  size_t pc = 0;  // index of the next line (line number - 1)
  std::map<std::string, Label> labels;
  std::map<std::string, size_t> open_loops;  // loops running forward: label -> opening line
  std::vector<Call> calls;
  // LinuxCNC's control state: the label skipped to (nothing runs but its
  // O-word lines), the if-branch flag, the break and continue flags, the
  // subroutine being defined.
  std::string skipping;
  bool executed_if = true, doing_break = false, doing_continue = false;
  std::string defining;
  size_t defining_from = 0;

  Impl(std::istream& i, std::string f, Parameters& p) : in(i), file(std::move(f)), params(p) {}

  [[noreturn]] void fail(int line, const std::string& word, const std::string& why) const {
    throw InputError(file + ":" + std::to_string(line) + ": " + word + ": " + why);
  }

  bool get(size_t i, std::string& out) {
    if (const auto k = kept.find(i); k != kept.end()) {
      out = k->second;
      return true;
    }
    while (lines_read <= i) {
      std::string t;
      if (!std::getline(in, t)) return false;
      if (!t.empty() && t.back() == '\r') t.pop_back();
      store.push_back(std::move(t));
      ++lines_read;
    }
    if (i < store_first) fail(static_cast<int>(i + 1), "O-word", "internal: the line is no longer held");
    out = store[i - store_first];
    return true;
  }

  bool in_sub_body(size_t i) const { return kept.count(i) > 0; }

  // Drops the lines nothing can come back to: before the next line, the
  // callers' return lines, the loops running forward and a definition.
  void trim() {
    size_t keep = in_sub_body(pc) ? lines_read : pc;
    for (const Call& c : calls)
      if (!in_sub_body(c.back)) keep = std::min(keep, c.back);
    for (const auto& [label, start] : open_loops)
      if (!in_sub_body(start)) keep = std::min(keep, start);
    if (!defining.empty()) keep = std::min(keep, defining_from);
    while (store_first < keep && !store.empty()) {
      store.pop_front();
      ++store_first;
    }
  }

  double value(const OLine& o, int line) {
    const auto v = o_values(o, line, file, params);
    if (v.size() != 1) fail(line, o.text, "takes one value, [expression]");
    return v[0];
  }

  void no_value(const OLine& o, int line) {
    if (!o_values(o, line, file, params).empty()) fail(line, o.text, "takes no value");
  }

  // The label's construct, which must be one of `kinds` (LinuxCNC's "no matching" errors).
  Label& construct(const OLine& o, int line, std::initializer_list<OKeyword> kinds, const char* what) {
    const auto it = labels.find(o.label);
    if (it == labels.end()) fail(line, o.text, std::string("no opening line of its kind (") + what + ") before it");
    if (std::find(kinds.begin(), kinds.end(), it->second.kind) == kinds.end())
      fail(line, o.text, std::string("the label O") + o.label + " is another construct's (line " +
                             std::to_string(it->second.index + 1) + "), not of the kind: " + what);
    return it->second;
  }

  // An opening line (if, while, repeat): its label's first line, or this one again.
  Label& opening(const OLine& o, int line, size_t here) {
    const auto [it, fresh] = labels.try_emplace(o.label, Label{o.keyword, here});
    const bool do_end = o.keyword == OKeyword::kWhile && it->second.kind == OKeyword::kDo;
    if (!fresh && it->second.index != here && !do_end)
      fail(line, o.text, "the label is used again (first in line " + std::to_string(it->second.index + 1) + ")");
    return it->second;
  }

  void back_to(Label& l, const OLine& o, int line) {
    if (++l.turns > kMaxTurns) fail(line, o.text, "the loop turned more than 1 000 000 times");
    pc = l.index;
  }

  void define(const OLine& o, int line, size_t here) {
    if (!calls.empty()) fail(line, o.text, "a subroutine cannot be defined inside a call");
    if (labels.count(o.label)) fail(line, o.text, "the label is used again (a subroutine is defined once)");
    no_value(o, line);
    labels[o.label] = Label{OKeyword::kSub, here};
    defining = o.label;
    defining_from = here;
    skipping = o.label;  // its body runs when it is called
  }

  void end_definition(size_t here) {
    for (size_t i = defining_from; i <= here; ++i) {
      std::string t;
      get(i, t);
      kept[i] = std::move(t);
    }
    defining.clear();
    skipping.clear();
  }

  void call(const OLine& o, int line) {
    const auto args = o_values(o, line, file, params);
    if (args.size() > kLocalParameters) fail(line, o.text, "takes at most 30 values");
    const auto it = labels.find(o.label);
    if (it == labels.end() || it->second.kind != OKeyword::kSub)
      fail(line, o.text, "the subroutine is not defined before the call (subroutine files are not read)");
    if (calls.size() >= kMaxCallDepth) fail(line, o.text, "calls nested more than 9 deep (LinuxCNC's limit)");
    Call c;
    c.sub = o.label;
    c.back = pc;
    for (int n = 1; n <= kLocalParameters; ++n) {
      if (const auto p = params.numbered.find(n); p != params.numbered.end()) c.saved_numbered[n] = p->second;
      params.numbered[n] = n <= static_cast<int>(args.size()) ? args[static_cast<size_t>(n - 1)] : 0;
    }
    for (auto p = params.named.begin(); p != params.named.end();) {
      if (local_name(p->first)) {
        c.saved_named.insert(*p);
        p = params.named.erase(p);
      } else {
        ++p;
      }
    }
    calls.push_back(std::move(c));
    skipping.clear();
    pc = it->second.index + 1;
  }

  void leave(const OLine& o, int line) {
    if (calls.empty()) fail(line, o.text, "outside a subroutine");
    const Call& c = calls.back();
    if (o.keyword == OKeyword::kEndsub && o.label != c.sub) fail(line, o.text, "inside the call of O" + c.sub);
    const auto v = o_values(o, line, file, params);
    if (v.size() > 1) fail(line, o.text, "takes at most one value");
    for (int n = 1; n <= kLocalParameters; ++n) params.numbered.erase(n);
    for (const auto& [n, x] : c.saved_numbered) params.numbered[n] = x;
    for (auto p = params.named.begin(); p != params.named.end();)
      p = local_name(p->first) ? params.named.erase(p) : std::next(p);
    for (const auto& p : c.saved_named) params.named.insert(p);
    params.named["_VALUE_RETURNED"] = v.empty() ? 0 : 1;
    params.named["_VALUE"] = v.empty() ? 0 : v[0];
    pc = c.back;
    calls.pop_back();
    skipping.clear();
  }

  void loop_ends(const OLine& o) {
    open_loops.erase(o.label);
    labels[o.label].turns = 0;
  }

  // One O-word line, as LinuxCNC's interpreter runs it. While it skips to a
  // label, only that label's lines run.
  void run(const OLine& o, int line, size_t here) {
    // A return belongs to the subroutine it is in, whatever its label.
    const std::string& label =
        o.keyword == OKeyword::kReturn ? (calls.empty() ? defining : calls.back().sub) : o.label;
    if (!skipping.empty() && label != skipping) return;
    if (!defining.empty()) {  // a body is read, not run: only its endsub counts
      if (o.keyword == OKeyword::kSub) fail(line, o.text, "subroutines cannot be nested (O" + defining + " is open)");
      if (o.keyword == OKeyword::kEndsub) end_definition(here);
      return;
    }
    switch (o.keyword) {
      case OKeyword::kSub: return define(o, line, here);
      case OKeyword::kCall: return call(o, line);
      case OKeyword::kEndsub:
      case OKeyword::kReturn: return leave(o, line);
      case OKeyword::kIf: {
        opening(o, line, here);
        executed_if = value(o, line) != 0;
        skipping = executed_if ? "" : o.label;
        return;
      }
      case OKeyword::kElseif: {
        construct(o, line, {OKeyword::kIf}, "if");
        const bool go = value(o, line) != 0;
        if (executed_if) {
          skipping = o.label;
        } else if (go) {
          skipping.clear();
          executed_if = true;
        }
        return;
      }
      case OKeyword::kElse:
        construct(o, line, {OKeyword::kIf}, "if");
        no_value(o, line);
        if (executed_if) {
          skipping = o.label;
        } else if (skipping == o.label) {
          skipping.clear();
          executed_if = true;
        }
        return;
      case OKeyword::kEndif:
        construct(o, line, {OKeyword::kIf}, "if");
        no_value(o, line);
        skipping.clear();
        executed_if = true;
        return;
      case OKeyword::kDo:
        no_value(o, line);
        skipping.clear();
        labels.try_emplace(o.label, Label{OKeyword::kDo, here});
        open_loops[o.label] = labels[o.label].index;
        return;
      case OKeyword::kWhile: {
        Label& l = opening(o, line, here);
        const bool go = value(o, line) != 0;
        skipping.clear();
        if (l.kind == OKeyword::kDo) {  // the end of a do loop
          if (go && !doing_break) {
            back_to(l, o, line);
          } else {
            doing_break = false;
            loop_ends(o);
          }
        } else if (go) {
          open_loops[o.label] = here;
        } else {
          skipping = o.label;
        }
        return;
      }
      case OKeyword::kRepeat: {
        Label& l = opening(o, line, here);
        const double k = value(o, line);
        skipping.clear();
        if (l.kind != OKeyword::kRepeat) return;
        if (l.repeats == -1) {
          if (k > static_cast<double>(kMaxTurns)) fail(line, o.text, "more than 1 000 000 turns");
          l.repeats = static_cast<long long>(std::floor(k + 0.5));
        }
        if (l.repeats > 0) {
          --l.repeats;
          open_loops[o.label] = here;
        } else {
          skipping = o.label;
          l.repeats = -1;
        }
        return;
      }
      case OKeyword::kBreak:
        construct(o, line, {OKeyword::kWhile, OKeyword::kDo}, "while or do loop");
        no_value(o, line);
        skipping = o.label;
        doing_break = true;
        return;
      case OKeyword::kContinue:
        construct(o, line, {OKeyword::kWhile, OKeyword::kDo}, "while or do loop");
        no_value(o, line);
        if (skipping == o.label) return;
        skipping = o.label;
        doing_continue = true;
        return;
      case OKeyword::kEndwhile:
      case OKeyword::kEndrepeat: {
        const bool w = o.keyword == OKeyword::kEndwhile;
        Label& l = construct(o, line, {w ? OKeyword::kWhile : OKeyword::kRepeat}, w ? "while" : "repeat");
        no_value(o, line);
        if (skipping == o.label) {
          skipping.clear();
          if (!doing_continue) return loop_ends(o);
          doing_continue = false;
        }
        back_to(l, o, line);
        return;
      }
    }
  }
};

GcodeFlow::GcodeFlow(std::istream& in, std::string file, Parameters& params)
    : impl_(std::make_unique<Impl>(in, std::move(file), params)) {}

GcodeFlow::~GcodeFlow() = default;

bool GcodeFlow::next(std::string& text, int& line) {
  Impl& m = *impl_;
  for (std::string t;;) {
    m.trim();
    const size_t here = m.pc;
    if (!m.get(here, t)) {
      if (!m.defining.empty())
        m.fail(static_cast<int>(m.defining_from + 1), "O" + m.defining + " sub", "no endsub before the end of the file");
      if (!m.skipping.empty())
        m.fail(static_cast<int>(m.labels[m.skipping].index + 1), "O" + m.skipping,
               "its closing line (endif, endwhile, endrepeat, while) is missing before the end of the file");
      line = static_cast<int>(m.lines_read);  // the end is after the file's last line, whatever ran last
      return false;
    }
    ++m.pc;
    const int no = static_cast<int>(here + 1);
    const auto o = o_line(t, no, m.file);
    if (!o) {
      if (!m.skipping.empty()) continue;
      text = std::move(t);
      line = no;
      return true;
    }
    m.run(*o, no, here);
  }
}

}  // namespace traj::input::gcode
