// SPDX-License-Identifier: Apache-2.0
// traj::bcu::Format: the number format of the BCU generator (rtl/traj_bcu_gen.sv,
// hls/traj_bcu_gen.hpp) as the host sees it. Header-only (no link dependency),
// so that the segment stream (host/stream) can carry and check it.
#pragma once
#include <sstream>
#include <stdexcept>
#include <string>

namespace traj::bcu {

struct Format {
  int axes = 3;          // 1..8
  int chunk_width = 32;  // stream word width, 8..64
  int ctrl_width = 40;   // control value width (two's complement)
  int guard_bits = 9;    // control bits below the output LSB
  int out_width = 32;    // sample width, >= ctrl_width - guard_bits + (guard_bits > 0)
  int max_depth = 12;    // largest d
  int frac_bits = 16;    // F: output LSB = 2^-F input units
  // stream words per value: the datapath digits, ceil((ctrl_width + 3*max_depth)/chunk_width)
  int words_per_value() const { return (ctrl_width + 3 * max_depth + chunk_width - 1) / chunk_width; }
  // Throws std::invalid_argument ("traj::bcu: Format.<field> = ... out of range ...").
  void validate() const {
    std::ostringstream m;
    if (axes < 1 || axes > 8) m << "Format.axes = " << axes << " out of range 1..8";
    else if (chunk_width < 8 || chunk_width > 64)
      m << "Format.chunk_width = " << chunk_width << " out of range 8..64";
    else if (max_depth < 1 || max_depth > 30)
      m << "Format.max_depth = " << max_depth << " out of range 1..30";
    else if (ctrl_width < 2 || ctrl_width + 3 * max_depth > 128)
      m << "Format.ctrl_width = " << ctrl_width << " out of range 2.." << 128 - 3 * max_depth
        << " (ctrl_width + 3*max_depth <= 128)";
    else if (guard_bits < 0 || guard_bits > ctrl_width - 2)
      m << "Format.guard_bits = " << guard_bits << " out of range 0.." << ctrl_width - 2;
    else if (out_width < ctrl_width - guard_bits + (guard_bits > 0) || out_width > 64)
      m << "Format.out_width = " << out_width << " out of range "
        << ctrl_width - guard_bits + (guard_bits > 0) << "..64";
    else if (words_per_value() * chunk_width > 128)
      m << "Format: ceil((ctrl_width + 3*max_depth)/chunk_width)*chunk_width = "
        << words_per_value() * chunk_width << " > 128 (datapath limit)";
    else if (frac_bits < -64 || frac_bits > 200)
      m << "Format.frac_bits = " << frac_bits << " out of range -64..200";
    else
      return;
    throw std::invalid_argument("traj::bcu: " + m.str());
  }
};

}  // namespace traj::bcu
