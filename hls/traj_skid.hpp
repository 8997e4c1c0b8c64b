// SPDX-License-Identifier: Apache-2.0
// trajcore hls: register slice (2-entry skid buffer) for a valid/ready
// stream. Cycle-accurate model of rtl/traj_skid.sv (the contract is there):
// ready, valid and data are registers; a word offered while the output holds
// one that is not taken waits in the skid register. Reset clears the valid
// bits, the data registers keep their value.
#pragma once

#include "traj_common.hpp"

namespace traj {

class Skid {
 public:
  struct Regs {
    bool out_v_q = false, sk_v_q = false;
    u128 out_d_q = 0, sk_d_q = 0;
  };
  struct Next {
    bool valid;
    u128 data;
  };

  bool ready() const { return !r_.sk_v_q; }
  bool valid() const { return r_.out_v_q; }
  u128 data() const { return r_.out_d_q; }
  const Regs& regs() const { return r_; }

  // The next state of valid() and data() (the RTL's valid_d_o, data_d_o).
  Next next(bool valid_i, u128 data_i, bool ready_i) const {
    const bool load_out = !r_.out_v_q || ready_i;
    if (!load_out) return {true, r_.out_d_q};
    if (r_.sk_v_q) return {true, r_.sk_d_q};
    return {valid_i, valid_i ? data_i : r_.out_d_q};
  }

  void clock(bool rst_n, bool valid_i, u128 data_i, bool ready_i) {
    const bool load_out = !r_.out_v_q || ready_i;
    const Next nx = next(valid_i, data_i, ready_i);
    Regs n = r_;
    n.out_v_q = nx.valid;
    n.out_d_q = nx.data;
    if (load_out) n.sk_v_q = false;
    else if (valid_i && !r_.sk_v_q) {
      n.sk_v_q = true;
      n.sk_d_q = data_i;
    }
    if (!rst_n) {
      n.out_v_q = false;
      n.sk_v_q = false;
    }
    r_ = n;
  }

 private:
  Regs r_{};
};

}  // namespace traj
