// Writes version-4 segment streams for the CLI tests of `trajcore sim` (the
// fd_cubic format: 3 axes, cubic, 64-bit registers, 16-bit chunks, 32 guard
// bits, F = 16, 1 ms, mm):
//   make_stream long <K> <out.trj>   one segment of K ticks, 1 LSB per tick on x
//   make_stream bad-k <out.trj>      3 segments; segment 1's K = 2^32-1 (CRC re-sealed)
//   make_stream jump <out.trj>       3 segments; segment 2's y starts 1 register LSB off (CRC re-sealed)
//   make_stream swap <out.trj>       3 segments; records 1 and 2 swapped (each intact)
#include <zlib.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "stream/segment_stream.hpp"

using namespace traj::stream;

namespace {

Header cubic() {
  Header h;
  h.axes = 3;
  h.degree = 3;
  h.width = 64;
  h.chunk_width = 16;
  h.guard_bits = 32;
  h.frac_bits = 16;
  h.period = 1e-3;
  h.units = "mm";
  return h;
}

// Three segments of 10 ticks, each starting where the previous one ends
// (constant speed: r0 advances by 10 r1).
std::vector<uint8_t> three(const Header& h) {
  std::vector<uint8_t> b = encode_header(h);
  const mpz_class v = mpz_class(1) << 32;  // 1 LSB per tick
  for (uint32_t s = 0; s < 3; ++s) {
    Record r;
    r.ticks = 10;
    r.seq = s;
    r.regs.assign(3, std::vector<mpz_class>(4, 0));
    for (int a = 0; a < 3; ++a) {
      r.regs[a][0] = (mpz_class(1) << 31) + v * (10 * s);
      r.regs[a][1] = v;
    }
    const auto e = encode_record(h, r);
    b.insert(b.end(), e.begin(), e.end());
  }
  const auto e = encode_end(3, 30);
  b.insert(b.end(), e.begin(), e.end());
  return b;
}

void reseal(std::vector<uint8_t>& b, size_t off, size_t n) {
  const uint32_t c = static_cast<uint32_t>(crc32(crc32(0L, Z_NULL, 0), &b[off], static_cast<uInt>(n - 4)));
  for (int i = 0; i < 4; ++i) b[off + n - 4 + i] = static_cast<uint8_t>(c >> (8 * i));
}

int usage() {
  std::fprintf(stderr, "usage: make_stream long <K> <out.trj> | bad-k|jump|swap <out.trj>\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return usage();
  const std::string kind = argv[1];
  const Header h = cubic();
  if (kind == "long") {
    if (argc != 4) return usage();
    Record r;
    r.ticks = static_cast<uint32_t>(std::strtoul(argv[2], nullptr, 10));
    r.regs.assign(3, std::vector<mpz_class>(4, 0));
    for (auto& ax : r.regs) ax[0] = mpz_class(1) << 31;
    r.regs[0][1] = mpz_class(1) << 32;
    write_file(argv[3], h, {r});
    return 0;
  }
  std::vector<uint8_t> b = three(h);
  const size_t rb = record_size(h, RecordKind::kFd);
  auto off = [&](size_t i) { return size_t(kHeaderBytes) + i * rb; };
  if (kind == "bad-k") {
    for (int i = 0; i < 4; ++i) b[off(1) + 4 + i] = 0xFF;
    reseal(b, off(1), rb);
  } else if (kind == "jump") {
    b[off(2) + 12 + 4 * 8] ^= 1;  // axis 1's r[0], lowest byte
    reseal(b, off(2), rb);
  } else if (kind == "swap") {
    for (size_t i = 0; i < rb; ++i) std::swap(b[off(1) + i], b[off(2) + i]);
  } else {
    return usage();
  }
  std::ofstream o(argv[2], std::ios::binary);
  o.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  return o ? 0 : 1;
}
