// Closes small holes of a triangle mesh with triangles over the vertices of
// their rims: a minimum-area triangulation of each boundary loop (Liepa 2003,
// "Filling holes in meshes", without its refinement and fairing steps).
// Marching cubes cannot close a hole whose zero set runs off into the object
// (occluded creases in range scans); this closes it without new vertices.
#pragma once

#include <scan2lod/core/types.h>

#include <array>
#include <vector>

namespace scan2lod {

// @param[in] mesh       oriented, edge-manifold triangle mesh
// @param[in] max_edges  loops with more edges are the data's own holes and stay
// @return the triangles to add, oriented consistently with the mesh. Loops that
//   pass twice through a vertex, and diagonals that already are mesh edges, are
//   skipped, so adding the result keeps the mesh edge-manifold.
std::vector<Triangle> fill_small_holes(const TriangleMesh& mesh, std::size_t max_edges);

// The same, given the mesh's boundary: every half-edge a -> b that one triangle
// uses, in that triangle's order (any order of edges). Only the boundary's
// loops and the triangles at their vertices are looked at, so a caller that
// keeps its boundary current pays for the holes, not the surface.
std::vector<Triangle> fill_small_holes(const TriangleMesh& mesh,
                                       const std::vector<std::array<std::int32_t, 2>>& boundary,
                                       std::size_t max_edges);

}  // namespace scan2lod
