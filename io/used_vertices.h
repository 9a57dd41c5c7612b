// What the mesh writers write: only the vertices some triangle uses. A
// reconstruction keeps a vertex on every crossed edge of its leaf cubes, which
// the octree needs even where clean-up dropped the triangles over it; a file
// has no use for such vertices, and tools count them as defects.
#pragma once

#include <scan2lod/core/types.h>

#include <optional>
#include <vector>

namespace scan2lod {

struct UsedVertices {
  TriangleMesh vertices;                     // the used vertices; its `triangles` are left empty
  std::vector<std::vector<Triangle>> lists;  // each input list renumbered into `vertices`
};

// The vertices of `mesh` (positions, and normals/colours where present) that a
// triangle of `lists` uses, in their original order, with every list
// renumbered; nullopt when every vertex is used already, so that the common
// case costs one pass over the triangles and no copy. `mesh.triangles` counts
// only when it is one of `lists`. Every index must be < mesh.positions.size().
std::optional<UsedVertices> drop_unused_vertices(const TriangleMesh& mesh,
                                                 const std::vector<const std::vector<Triangle>*>& lists);

}  // namespace scan2lod
