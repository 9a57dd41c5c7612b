// Keeping only the vertices that triangles use: what turns an index buffer
// into the shared vertex arrays (a level of a LOD model, a chain of levels)
// into a self-contained mesh.
#pragma once

#include "core/types.h"

#include <vector>

namespace scan2lod {

// Returns the vertices (positions, and normals/colours where those arrays are
// not empty) that the triangle lists in `lists` use, in first-use order, and
// rewrites every list to index the returned mesh. The returned mesh's own
// triangles are left empty. Every index must be < positions.size().
TriangleMesh compact_mesh(const std::vector<Vec3f>& positions, const std::vector<Vec3f>& normals,
                          const std::vector<Rgb>& colors, const std::vector<std::vector<Triangle>*>& lists);

}  // namespace scan2lod
