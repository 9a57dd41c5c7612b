// The undirected edges of a triangle list, numbered, with how many triangles
// use each. Edges are bucketed under their smaller vertex (a counting sort),
// so no hash map is built: the octree, its numbering and the mesh field each
// needed these for 0.4-1.3 M triangle sides, and a hash map's cache miss per
// side was most of their cost.
#pragma once

#include <scan2lod/core/array_view.h>
#include <scan2lod/core/types.h>

#include <array>
#include <cstdint>
#include <vector>

namespace scan2lod {

struct MeshEdges {
  std::vector<std::int32_t> uses;                         // per edge: triangles using it
  std::vector<std::array<std::int32_t, 3>> of_triangle;  // edge of side k (corners k and k + 1)
  std::vector<std::array<std::int32_t, 2>> ends;          // per edge: its vertices, smaller first

  std::size_t size() const { return uses.size(); }
};

// Edges of `triangles`, whose indices are below `vertex_count`.
MeshEdges mesh_edges(const std::vector<Triangle>& triangles, std::size_t vertex_count);

// Mean length of the triangles' sides (each shared edge counted per side),
// over every `stride`-th triangle; 0 without triangles. A level's scale: what
// its detail spans on screen.
double mean_edge_length(ArrayView<Vec3f> positions, const std::vector<Triangle>& triangles,
                        std::size_t stride = 1);

}  // namespace scan2lod
