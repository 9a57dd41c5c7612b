// Closes small holes of a triangle mesh with triangles over the vertices of
// their rims: a minimum-area triangulation of each boundary loop (Liepa 2003,
// "Filling holes in meshes", without its refinement and fairing steps).
// Marching cubes cannot close a hole whose zero set runs off into the object
// (occluded creases in range scans); this closes it without new vertices.
#pragma once

#include "core/types.h"

#include <vector>

namespace scan2lod {

// @param[in] mesh       oriented, edge-manifold triangle mesh
// @param[in] max_edges  loops with more edges are the data's own holes and stay
// @return the triangles to add, oriented consistently with the mesh. Loops that
//   pass twice through a vertex, and diagonals that already are mesh edges, are
//   skipped, so adding the result keeps the mesh edge-manifold.
std::vector<Triangle> fill_small_holes(const TriangleMesh& mesh, std::size_t max_edges);

}  // namespace scan2lod
