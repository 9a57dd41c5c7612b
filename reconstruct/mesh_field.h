// A signed distance to a triangle mesh, for lattice points the leaves lack.
// The octree samples it at coarse corners, so its coarse levels approximate the
// finished mesh (pieces dropped, holes closed) rather than re-deriving a
// surface, ghosts included, from the scan points.
#pragma once

#include "core/types.h"
#include "reconstruct/signed_distance.h"

namespace scan2lod {

// |p - c| signed by the side of c's smooth normal, where c is the closest point
// of `mesh` (Open3D RaycastingScene); the normal is interpolated from the
// vertex normals (mesh.normals, or area-weighted ones when empty).
// Throws InputError when the mesh has no triangle with area.
SignedDistanceField mesh_distance_field(const TriangleMesh& mesh);

}  // namespace scan2lod
