// Topology of an indexed triangle mesh: the counts that tell whether a
// reconstruction is a closed, manifold, single-piece surface (Euler
// characteristic 2 per sphere-like component, no boundary, no edge shared by
// more than two triangles), and the connected-component helpers used to clean
// up stray pieces.
//
// Edges are undirected pairs of vertex indices, so topology follows the index
// buffer, not positions: weld a triangle soup (e.g. PCL's marching cubes)
// before measuring it. A triangle that repeats an index has no surface; it is
// counted in `degenerate_triangles` and otherwise ignored.
#pragma once

#include <scan2lod/core/types.h>

#include <cstddef>
#include <vector>

namespace scan2lod {

struct MeshTopology {
  std::size_t vertices = 0;              // positions.size()
  std::size_t triangles = 0;             // triangles.size()
  std::size_t referenced_vertices = 0;   // vertices used by a non-collapsed triangle
  std::size_t edges = 0;                 // distinct undirected edges
  std::size_t boundary_edges = 0;        // edges used by exactly one triangle
  std::size_t boundary_loops = 0;        // connected components of the boundary-edge graph
  std::size_t non_manifold_edges = 0;    // edges used by more than two triangles
  std::size_t components = 0;            // triangles connected through shared vertices
  std::size_t largest_component_triangles = 0;
  std::size_t degenerate_triangles = 0;  // repeated index or zero area
  long euler_characteristic = 0;         // referenced_vertices - edges + non-collapsed triangles
};

// Counts the topology of `mesh`.
// @param[in] mesh  #F triangles indexing #V positions; every index must lie in
//   [0, #V) (throws InputError naming the triangle otherwise).
// @return the counts above. Runs in O(#F log #F) time (one sort of 3#F edge
//   keys) and O(#V + #F) memory; ~1M triangles take a fraction of a second.
MeshTopology mesh_topology(const TriangleMesh& mesh);

// Labels each triangle with its connected component (triangles sharing a
// vertex are connected).
// @param[in] mesh  as for mesh_topology.
// @param[out] count  if not null, receives the number of components.
// @return #F ids in [0, count), numbered in order of each component's first
//   triangle; -1 for triangles that repeat an index.
std::vector<int> triangle_components(const TriangleMesh& mesh, int* count = nullptr);

// Removes components smaller than a fraction of the mesh, e.g. the floating
// specks marching cubes leaves around noisy scans.
// @param[in] mesh  as for mesh_topology.
// @param[in] min_fraction  a component is kept if it has at least
//   min_fraction * #F triangles; 0 keeps all of them.
// @return the kept triangles (in their original order) with the vertices they
//   reference compacted, carrying normals and colors along. Triangles that
//   repeat an index belong to no component and are dropped.
TriangleMesh drop_small_components(const TriangleMesh& mesh, double min_fraction);

// True if triangle t repeats an index or has zero area (its corners are
// collinear in float arithmetic); such triangles carry no surface.
bool triangle_is_degenerate(const TriangleMesh& mesh, std::size_t t);

// Throws InputError if a triangle indexes outside [0, #V).
void check_triangle_indices(const TriangleMesh& mesh);

}  // namespace scan2lod
