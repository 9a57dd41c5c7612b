// A signed distance to a triangle mesh, for lattice points the leaves lack.
// The octree samples it at coarse corners, so its coarse levels approximate the
// finished mesh (pieces dropped, holes closed) rather than re-deriving a
// surface, ghosts included, from the scan points; and the closest points, to
// which it pulls vertices where the distance's sign flips beyond an open rim.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/reconstruct/signed_distance.h>

#include <functional>
#include <vector>

namespace scan2lod {

// The closest point of a mesh to each query point.
using ClosestPoints = std::function<void(const std::vector<Vec3f>& queries, std::vector<Vec3f>* closest)>;

// Two queries against one Open3D RaycastingScene of a mesh:
// - distance: |p - c| where c is the closest point of the mesh, signed by the
//   angle-weighted pseudo-normal of the face, edge or vertex that holds c:
//   exact inside/outside wherever the mesh is closed and manifold;
// - closest: c itself.
struct MeshField {
  SignedDistanceField distance;
  ClosestPoints closest;
};

// Throws InputError when the mesh has no triangle with area.
MeshField mesh_field(const TriangleMesh& mesh);

}  // namespace scan2lod
