// The marching-cubes case table, generated rather than transcribed so that it is
// topologically consistent by construction (Lee 2007, §4.2 uses the classic
// 15-case table, whose complementary cases disagree on ambiguous faces and leave
// holes).
//
// Numbering. Corner c sits at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1).
// Edge e runs along axis a = e / 4 from its lower corner; j = e % 4 gives the
// other two axes' offsets: bit 0 for axis (a + 1) % 3, bit 1 for axis (a + 2) % 3.
// A case is the 8-bit mask of corners that are inside (negative distance).
//
// Consistency. On each face the crossings are joined by a rule that depends on
// that face's four signs only (an ambiguous face separates its inside corners),
// so two cubes sharing a face always join the same crossings. Each cube's face
// segments close into loops, and each loop is fanned into triangles, so the
// surface is a 2-manifold wherever all cubes emit. Triangles face outward
// (counter-clockwise seen from the positive side).
#pragma once

#include <array>
#include <cstdint>

namespace scan2lod {

struct CubeCase {
  std::uint8_t triangle_count = 0;
  std::array<std::array<std::uint8_t, 3>, 12> triangles{};  // local edge ids
  std::uint16_t edge_mask = 0;                               // edges that carry a vertex
};

// The table for all 256 cases.
const std::array<CubeCase, 256>& cube_cases();

// Corner offsets and the two corners of each edge.
constexpr std::array<int, 3> corner_offset(int c) { return {c & 1, (c >> 1) & 1, (c >> 2) & 1}; }
// End 0: the lower corner, 1: the upper. Edge e runs along axis e / 4; bits 0
// and 1 of e % 4 are its coordinates on the next two axes. Inline: the octree
// build calls it in its inner loops.
constexpr int edge_corner(int edge, int end) {
  const int axis = edge / 4, j = edge % 4;
  int o[3] = {0, 0, 0};
  o[axis] = end;
  o[(axis + 1) % 3] = j & 1;
  o[(axis + 2) % 3] = (j >> 1) & 1;
  return o[0] | (o[1] << 1) | (o[2] << 2);
}

}  // namespace scan2lod
