// One group of the cluster hierarchy simplified by half-edge collapse under
// generalized quadrics (Garland and Heckbert, *Simplifying Surfaces with Color
// and Texture using Quadric Error Metrics*, 1998): positions, normals and
// colours in one quadric, so attributes survive at every level. Vertices the
// group shares with others are locked; the scan's real boundaries slide along
// themselves under boundary constraint planes.
//
// Our own collapse loop, not OpenMesh's Decimater: see the measurement in
// lod/README.md ("Why not OpenMesh's Decimater").
#pragma once

#include "core/types.h"

#include <cstdint>
#include <vector>

namespace scan2lod {

// What the simplifier reads of the mesh: shared by every group.
struct SimplifyInput {
  ArrayView<Vec3f> positions;
  ArrayView<Vec3f> normals;  // empty or one per position
  ArrayView<Rgb> colors;     // empty or one per position
  // locked[v] != 0: v is shared with another group and must not move.
  const std::vector<std::uint8_t>* locked = nullptr;
  float scale = 1;           // 1 / the mesh's diagonal: quadrics see a unit-sized mesh
  float normal_weight = 0;   // see ClusterOptions
  float color_weight = 0;
};

struct SimplifiedGroup {
  std::vector<Triangle> triangles;  // into the same positions
  // Measured, in the mesh's units: the largest distance from a removed vertex
  // to the triangles around the vertex it went to.
  float error = 0;
};

// Simplifies `triangles` (welded: vertices at one position share one index)
// towards `target` triangles. Triangles OpenMesh cannot hold as a manifold
// (a third face on an edge) are kept as they are, their vertices locked.
SimplifiedGroup simplify_group(const std::vector<Triangle>& triangles, std::size_t target,
                               const SimplifyInput& input);

// Per-thread scratch of the group simplifiers: global vertex -> group vertex,
// at least `vertices` long and all -1 between groups (one per thread, shared
// by both simplifiers: at 10^8 points it is 100 MB).
std::vector<int>& group_local_index(std::size_t vertices);

}  // namespace scan2lod
