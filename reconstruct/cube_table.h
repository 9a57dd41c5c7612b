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

#include <algorithm>
#include <array>
#include <cmath>
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

// Where the surface crosses an edge whose ends have signed distances da and db
// of opposite signs: at the ratio |da| / (|da| + |db|) from the da end (Lee
// 2007, §4.2), kept kCrossingMargin of the edge off either end. A corner on
// (or within a hair of) the surface puts the crossings of all its edges next
// to it, and each cube's triangle over two of them is a needle. Möller's
// triangle test as Open3D's IsSelfIntersecting runs it (Möller 1997, "A fast
// triangle-triangle intersection test", with a 1e-6 epsilon on distances
// scaled by the triangle's area) takes a needle's neighbours near the corner
// for lying in its plane and reports crossings exact arithmetic rules out: a
// margin of 1e-4 left such pairs on the scanned sphere and torus at R = 64 to
// 512 (up to 318), 3e-3 still 4, 5e-3 none. 1.5e-2 keeps a factor of three; a
// vertex moves at most that share of a cube off the zero set for it. Core and
// brick reconstruction both place crossings here, so they stay one surface.
constexpr float kCrossingMargin = 1.5e-2f;
inline float crossing_ratio(float da, float db) {
  const float t = std::fabs(da) / (std::fabs(da) + std::fabs(db));
  return std::clamp(t, kCrossingMargin, 1.f - kCrossingMargin);
}

}  // namespace scan2lod
