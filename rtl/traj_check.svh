// SPDX-License-Identifier: Apache-2.0
// trajcore: elaboration-time parameter check that Verilator, Yosys and Icarus 11
// all honour. Verilator and Yosys stop on $error in a generate block at
// elaboration; Icarus 11 rejects elaboration tasks there, so it gets an initial
// $fatal, which stops the simulation at time 0 before any cycle runs.
//   `TRAJ_PARAM_CHECK(g_label, <condition that must hold>, "message")
`ifndef TRAJ_CHECK_SVH
`define TRAJ_CHECK_SVH
`ifdef __ICARUS__
`define TRAJ_PARAM_CHECK(label, ok, msg) \
  if (!(ok)) begin : label \
    initial $fatal(1, msg); \
  end
`else
`define TRAJ_PARAM_CHECK(label, ok, msg) \
  if (!(ok)) begin : label \
    $error(msg); \
  end
`endif
`endif
