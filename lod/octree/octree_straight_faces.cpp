// Phase 12 of build_mc_octree: the node faces whose crossings include three
// in line (lod/octree/octree_build.h, lod/octree/transition.h).
#include <scan2lod/lod/octree/octree_build.h>
#include <scan2lod/lod/octree/transition.h>

namespace scan2lod {
namespace octree_build {

void find_straight_faces(ArrayView<Vec3f> positions, McOctree* tree) {
  OctreeTransitions& tr = tree->transitions;
  const std::size_t internal = tr.size();
  tr.straight_faces.assign(internal, 0);
  for (std::size_t node = 0; node < internal; ++node)
    tr.straight_faces[node] =
        straight_faces(tree->nodes.edge_vertices[node].data(), tr.sub_edge_vertices[node].data(), positions.data());
}

}  // namespace octree_build
}  // namespace scan2lod
