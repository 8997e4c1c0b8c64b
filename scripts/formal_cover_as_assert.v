// SPDX-License-Identifier: Apache-2.0
// Yosys techmap for scripts/formal.sh: each cover(c) becomes assert(!c), so
// that a bounded model checker's counterexample is a trace reaching c.
(* techmap_celltype = "$cover" *)
module _cover_as_assert (A, EN);
  input A, EN;
  \$assert _TECHMAP_REPLACE_ (.A(!A), .EN(EN));
endmodule
