// A signed distance to a triangle mesh, for lattice points the leaves lack.
// The octree samples it at coarse corners, so its coarse levels approximate the
// finished mesh (pieces dropped, holes closed) rather than re-deriving a
// surface, ghosts included, from the scan points.
#pragma once

#include "core/types.h"
#include "reconstruct/signed_distance.h"

namespace scan2lod {

// |p - c| where c is the closest point of `mesh` (Open3D RaycastingScene),
// signed by the angle-weighted pseudo-normal of the face, edge or vertex that
// holds c: exact inside/outside wherever the mesh is closed and manifold.
// Throws InputError when the mesh has no triangle with area.
SignedDistanceField mesh_distance_field(const TriangleMesh& mesh);

}  // namespace scan2lod
