#include "lod/extract.h"

#include <algorithm>

namespace scan2lod {

void extract_lod(const McOctree& tree, const LodArray& lod, std::size_t priority,
                 std::vector<std::uint8_t>* expanded, std::vector<Triangle>* triangles) {
  priority = std::min(priority, lod.full());
  triangles->clear();
  expanded->resize(tree.size(), 0);
  auto emit = [&](std::int32_t node) {
    const Triangle* first = tree.triangles.data() + tree.first_triangle[node];
    triangles->insert(triangles->end(), first, first + tree.triangle_counts[node]);
  };
  if (priority == 0) {
    emit(0);
    return;
  }
  for (std::size_t i = 0; i < priority; ++i) (*expanded)[lod.order[i]] = 1;
  for (std::size_t i = 0; i < priority; ++i) {
    const std::int32_t node = lod.order[i];
    for (int c = 0; c < tree.child_counts[node]; ++c) {
      const std::int32_t child = tree.first_child[node] + c;
      if (!(*expanded)[child]) emit(child);
    }
  }
  if (priority == lod.full())
    triangles->insert(triangles->end(), tree.patch_triangles.begin(), tree.patch_triangles.end());
  for (std::size_t i = 0; i < priority; ++i) (*expanded)[lod.order[i]] = 0;
}

TriangleMesh compact_lod(const McOctree& tree, const std::vector<Triangle>& triangles) {
  TriangleMesh mesh;
  std::vector<std::int32_t> remap(tree.positions.size(), -1);
  mesh.triangles.reserve(triangles.size());
  for (const Triangle& t : triangles) {
    Triangle out;
    for (int k = 0; k < 3; ++k) {
      std::int32_t& r = remap[t[k]];
      if (r < 0) {
        r = std::int32_t(mesh.positions.size());
        mesh.positions.push_back(tree.positions[t[k]]);
        if (!tree.normals.empty()) mesh.normals.push_back(tree.normals[t[k]]);
        if (!tree.colors.empty()) mesh.colors.push_back(tree.colors[t[k]]);
      }
      out[k] = r;
    }
    mesh.triangles.push_back(out);
  }
  return mesh;
}

}  // namespace scan2lod
