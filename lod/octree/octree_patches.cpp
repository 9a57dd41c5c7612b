// Phase 10 of build_mc_octree: the leaves' hole patches, grouped by hole
// (lod/octree/octree_build.h).
#include <scan2lod/core/mesh_edges.h>
#include <scan2lod/lod/octree/octree_build.h>

#include <algorithm>
#include <numeric>

namespace scan2lod {
namespace octree_build {

void group_patches(const std::vector<Triangle>& patches, McOctree* tree) {
  tree->patches.triangles.clear();
  tree->patches.group_first = {0};
  tree->patches.needs_first = {0};
  tree->patches.needs.clear();
  if (patches.empty()) return;
  // Edge -> patch triangles (up to 2) and edge -> leaf node.
  std::vector<std::pair<std::uint64_t, std::int32_t>> patch_edges;
  for (std::size_t t = 0; t < patches.size(); ++t)
    for (int k = 0; k < 3; ++k) patch_edges.push_back({edge_key(patches[t][k], patches[t][(k + 1) % 3]), std::int32_t(t)});
  std::sort(patch_edges.begin(), patch_edges.end());
  std::vector<std::int32_t> group(patches.size());
  std::iota(group.begin(), group.end(), 0);
  auto find = [&](std::int32_t x) {
    while (group[x] != x) x = group[x] = group[group[x]];
    return x;
  };
  std::vector<std::uint64_t> rim;  // edges used by one patch triangle
  std::vector<std::int32_t> rim_triangle;
  // Sorted, so the (one or two) uses of an edge are adjacent.
  for (std::size_t i = 0; i < patch_edges.size(); ++i) {
    const bool same_as_next = i + 1 < patch_edges.size() && patch_edges[i + 1].first == patch_edges[i].first;
    const bool same_as_previous = i > 0 && patch_edges[i - 1].first == patch_edges[i].first;
    if (same_as_next) group[find(patch_edges[i + 1].second)] = find(patch_edges[i].second);
    if (!same_as_next && !same_as_previous) rim.push_back(patch_edges[i].first), rim_triangle.push_back(patch_edges[i].second);
  }
  FlatHashMap edge_leaf(rim.size() * 2 + 16);
  {
    std::vector<std::uint64_t> sorted_rim = rim;
    std::sort(sorted_rim.begin(), sorted_rim.end());
    for (std::size_t node = 0; node < tree->size(); ++node) {
      if (!tree->is_leaf(node)) continue;
      for (std::int32_t t = 0; t < tree->nodes.triangle_counts[node]; ++t) {
        const Triangle& tri = tree->triangles[std::size_t(tree->nodes.first_triangle[node] + t)];
        for (int k = 0; k < 3; ++k) {
          const std::uint64_t e = edge_key(tri[k], tri[(k + 1) % 3]);
          if (std::binary_search(sorted_rim.begin(), sorted_rim.end(), e)) edge_leaf.insert(e, std::int32_t(node));
        }
      }
    }
  }
  std::vector<std::vector<std::int32_t>> needs(patches.size());
  for (std::size_t i = 0; i < rim.size(); ++i) {
    const std::int32_t leaf = edge_leaf.find(rim[i]);
    if (leaf >= 0) needs[find(rim_triangle[i])].push_back(tree->nodes.parents[leaf]);
  }
  std::vector<std::vector<std::int32_t>> members(patches.size());
  for (std::size_t t = 0; t < patches.size(); ++t) members[find(std::int32_t(t))].push_back(std::int32_t(t));
  for (std::size_t g = 0; g < patches.size(); ++g) {
    if (members[g].empty()) continue;
    for (std::int32_t t : members[g]) tree->patches.triangles.push_back(patches[t]);
    tree->patches.group_first.push_back(std::int32_t(tree->patches.triangles.size()));
    auto& need = needs[g];
    std::sort(need.begin(), need.end());
    need.erase(std::unique(need.begin(), need.end()), need.end());
    tree->patches.needs.insert(tree->patches.needs.end(), need.begin(), need.end());
    tree->patches.needs_first.push_back(std::int32_t(tree->patches.needs.size()));
  }
}


}  // namespace octree_build
}  // namespace scan2lod
