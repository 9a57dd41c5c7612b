// Morton (Z-order) codes: three 20-bit coordinates interleaved, so that
// sorting by code keeps neighbours in space near each other in order.
#pragma once

#include <cstdint>

namespace scan2lod {

// The low 20 bits of v spread to every third bit of 60.
inline std::uint64_t spread_bits(std::uint64_t v) {
  v &= 0xfffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

inline std::uint64_t morton_code(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
  return spread_bits(x) | spread_bits(y) << 1 | spread_bits(z) << 2;
}

}  // namespace scan2lod
