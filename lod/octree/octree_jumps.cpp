// Phase 6 of build_mc_octree: vertices where the field jumps (lod/octree/octree_build.h).
//
// Beyond an open rim the signed distance to the mesh never reaches zero: its
// sign flips where the closest point's pseudo-normal turns away, with the
// distance to the rim on both sides. Marching cubes takes that flip for a
// surface, so a coarse node over a rim reached out to its cube's faces (flaps
// as large as the node), and behind an open scan the flips closed a shell.
// Such a crossing is known by its ends (octree_edges.cpp) and is pulled to
// the mesh here, to half a leaf cube from its closest point: the coarse
// node's surface then ends along the rim.
#include <scan2lod/lod/octree/octree_build.h>

namespace scan2lod {
namespace octree_build {

void pull_jump_vertices(const std::vector<std::int32_t>& jumps, const ClosestPoints& closest, McOctree* tree) {
  if (jumps.empty()) return;
  auto& positions = tree->vertices.positions;
  std::vector<Vec3f> at(jumps.size()), to;
  for (std::size_t i = 0; i < jumps.size(); ++i) at[i] = positions[std::size_t(jumps[i])];
  closest(at, &to);
  // Distance d from the mesh becomes reach * d / (reach + d): under half a
  // leaf cube, and still increasing, so that vertices in line with one
  // closest point stay apart (no triangle loses its area).
  const float reach = 0.5f * float(tree->grid.cube_size);
  for (std::size_t i = 0; i < jumps.size(); ++i) {
    const Vec3f offset = at[i] - to[i];
    positions[std::size_t(jumps[i])] = to[i] + offset * (reach / (reach + offset.norm()));
  }
}

}  // namespace octree_build
}  // namespace scan2lod
