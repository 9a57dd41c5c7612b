// One group of the cluster hierarchy simplified by edge collapse under
// generalized quadrics (Garland and Heckbert, *Simplifying Surfaces with Color
// and Texture using Quadric Error Metrics*, 1998): positions, normals and
// colours in one quadric, so attributes survive at every level, and each
// merged vertex placed where that quadric is least, attributes with it.
// Vertices the group shares with others are locked; the scan's real
// boundaries slide along themselves under boundary constraint planes.
//
// Our own collapse loop, not OpenMesh's Decimater: see the measurement in
// lod/README.md ("Why not OpenMesh's Decimater").
#pragma once

#include <scan2lod/core/types.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

// What the simplifier reads of the mesh: shared by every group.
struct SimplifyInput {
  JoinedView<Vec3f> positions;
  JoinedView<Vec3f> normals;  // empty or one per position
  JoinedView<Rgb> colors;     // empty or one per position
  // locked[v] != 0: v is shared with another group and must not move.
  const std::vector<std::uint8_t>* locked = nullptr;
  float scale = 1;           // 1 / the mesh's diagonal: quadrics see a unit-sized mesh
  float normal_weight = 0;   // see ClusterOptions
  float color_weight = 0;
  // A collapse places the vertex at its quadric's minimum (a new vertex);
  // false keeps one of the edge's ends (half-edge collapse, no new vertex).
  bool optimal_placement = true;
};

struct SimplifiedGroup {
  // Into the same positions, or -1 - i into added_* for a vertex the
  // simplification placed anew.
  std::vector<Triangle> triangles;
  std::vector<Vec3f> added_positions;
  std::vector<Vec3f> added_normals;  // when the input has normals
  std::vector<Rgb> added_colors;     // when the input has colours
  // Measured, in the mesh's units: the largest distance from a removed vertex
  // to the triangles around the vertex it went to.
  float error = 0;
};

// Simplifies `triangles` (welded: vertices at one position share one index)
// towards `target` triangles. Triangles OpenMesh cannot hold as a manifold
// (a third face on an edge) are kept as they are, their vertices locked.
SimplifiedGroup simplify_group(const std::vector<Triangle>& triangles, std::size_t target,
                               const SimplifyInput& input);

}  // namespace scan2lod
