// Keeping only the vertices that triangles use: what turns an index buffer
// into the shared vertex arrays (a level of a LOD model, a chain of levels)
// into a self-contained mesh.
#pragma once

#include <scan2lod/core/array_view.h>
#include <scan2lod/core/types.h>

#include <vector>

namespace scan2lod {

// Returns the vertices (positions, and normals/colours where those arrays are
// not empty) that the triangle lists in `lists` use, in first-use order, and
// rewrites every list to index the returned mesh. The returned mesh's own
// triangles are left empty. Every index must be < positions.size().
TriangleMesh compact_mesh(ArrayView<Vec3f> positions, ArrayView<Vec3f> normals,
                          ArrayView<Rgb> colors, const std::vector<std::vector<Triangle>*>& lists);

// The numbering compact_mesh uses, for callers that compact many times over
// one vertex array: rewrites `triangles` to new ids in first-use order, from
// used->size() on, and appends each newly used vertex's old id to `used`.
// `remap` has an entry per vertex, -1 where not used yet; the caller resets
// the entries `used` names once done with it.
void renumber_used(std::vector<Triangle>* triangles, std::vector<std::int32_t>* remap,
                   std::vector<std::int32_t>* used);

}  // namespace scan2lod
