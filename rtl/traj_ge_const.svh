// SPDX-License-Identifier: Apache-2.0
// trajcore: x >= k for a constant k, as AND/OR logic. Included inside a
// module (one copy per module that uses it).
//
// Why: synthesis turns `x >= k` into a subtraction whose sums go unused. On
// the iCE40 that is a carry chain of a logic cell per bit, with nothing
// else in those cells, for a comparison a few LUTs decide: with k constant,
// the recurrence below (bit i decides unless x and k agree there) folds
// into an AND/OR tree of x's bits, which maps to about width / 3 LUTs.
// x >= k over bits i..0: x[i] > k[i], or x[i] == k[i] and x >= k over
// bits i-1..0 (true over no bits).
function automatic logic traj_ge_const(input logic [31:0] x, input logic [31:0] k);
  logic ge;
  ge = 1'b1;
  for (int i = 0; i < 32; i++) ge = k[i] ? (x[i] && ge) : (x[i] || ge);
  traj_ge_const = ge;
endfunction
