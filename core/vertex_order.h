// One vertex order for a mesh, whatever order its vertices came in.
#pragma once

#include <scan2lod/core/types.h>

namespace scan2lod {

// Renumbers `mesh`'s vertices in Morton order of their positions (over the
// mesh's bounds, ties by position, normal and colour) and drops those no
// triangle uses; rewrites the triangles to match. Two meshes that hold the
// same triangles over the same vertex values, numbered differently (a
// surface welded from bricks and the same surface made in core), come out
// the same, but for vertices equal in every value. Morton order also keeps a
// neighbourhood's vertices near in memory. Every index must be valid.
void order_vertices(TriangleMesh* mesh);

}  // namespace scan2lod
