// Phase 4 of build_mc_octree: every node's marching cube (lod/octree/octree_build.h).
#include <scan2lod/lod/octree/octree_build.h>
#include <scan2lod/reconstruct/cube_table.h>

namespace scan2lod {
namespace octree_build {
namespace {

// A leaf's case and edge vertices are the reconstruction's own.
void leaf_cases(const CubeNodes& leaves, const FlatHashMap& leaf_index, std::int32_t begin, std::int32_t end,
                OctreeNodes* nodes) {
  for (std::int32_t node = begin; node < end; ++node) {
    const std::int32_t l = leaf_index.find(nodes->keys[node]);
    nodes->cases[node] = leaves.cases[l];
    nodes->edge_vertices[node] = leaves.edge_vertices[l];
  }
}

// A coarse node's case is the lattice's signs at its corners, and each
// crossed edge's vertex is resolved down to a leaf edge.
void coarse_cases(int level, std::int32_t begin, std::int32_t end, LatticeSigns* signs, EdgeResolver* resolver,
                  McOctree* tree) {
  OctreeNodes& nodes = tree->nodes;
  const int shift = tree->depth - level;
  const auto& table = cube_cases();
  std::vector<std::uint64_t> corners;
  std::vector<std::int32_t> corner_nodes;
  corners.reserve(std::size_t(end - begin) * 8);
  corner_nodes.reserve(std::size_t(end - begin) * 8);
  for (std::int32_t node = begin; node < end; ++node)
    for (int c = 0; c < 8; ++c) {
      corners.push_back(corner_lattice_key(nodes.keys[node], shift, c));
      corner_nodes.push_back(node);
    }
  signs->ensure(corners, &corner_nodes);
  std::vector<std::uint64_t> edges;
  std::vector<std::pair<std::int32_t, int>> slots;
  for (std::int32_t node = begin; node < end; ++node) {
    std::uint8_t mask = 0;
    for (int c = 0; c < 8; ++c) mask |= std::uint8_t(signs->inside(corners[std::size_t(node - begin) * 8 + c])) << c;
    nodes.cases[node] = mask;
    nodes.edge_vertices[node].fill(-1);
    for (int e = 0; e < 12; ++e) {
      if (!(table[mask].edge_mask >> e & 1)) continue;
      edges.push_back((corner_lattice_key(nodes.keys[node], shift, edge_corner(e, 0)) << 2) | std::uint64_t(e / 4));
      slots.push_back({node, e});
    }
  }
  std::vector<std::int32_t> vertices;
  resolver->resolve(level, edges, slots, &vertices);
  for (std::size_t i = 0; i < slots.size(); ++i) nodes.edge_vertices[slots[i].first][slots[i].second] = vertices[i];
}

// Each node's own triangles from its case; a leaf keeps only the triangles
// the reconstruction's clean-up kept.
void own_triangles(const CubeNodes& leaves, const FlatHashMap& leaf_index, bool leaf_level, std::int32_t begin,
                   std::int32_t end, const std::vector<std::uint8_t>& dropped, std::vector<std::uint8_t>* cases_are_signs,
                   McOctree* tree) {
  OctreeNodes& nodes = tree->nodes;
  const auto& table = cube_cases();
  for (std::int32_t node = begin; node < end; ++node) {
    const CubeCase& cc = table[nodes.cases[node]];
    const std::int32_t l = leaf_level ? leaf_index.find(nodes.keys[node]) : -1;
    if (l >= 0)
      for (std::int32_t corner : leaves.corners[std::size_t(l)])
        (*cases_are_signs)[std::size_t(node)] &= !dropped[std::size_t(corner)];
    nodes.first_triangle[node] = std::int32_t(tree->triangles.size());
    for (int t = 0; t < cc.triangle_count; ++t) {
      if (l >= 0 && !(leaves.triangle_masks[l] >> t & 1)) continue;
      const auto& ev = nodes.edge_vertices[node];
      tree->triangles.push_back({ev[cc.triangles[t][0]], ev[cc.triangles[t][1]], ev[cc.triangles[t][2]]});
    }
    nodes.triangle_counts[node] = std::uint8_t(tree->triangles.size() - std::size_t(nodes.first_triangle[node]));
  }
}

}  // namespace

std::vector<std::uint8_t> cases_and_triangles(const CubeNodes& leaves, const FlatHashMap& leaf_index,
                                              const LevelBegin& level_begin, const std::vector<std::uint8_t>& dropped,
                                              LatticeSigns* signs, EdgeResolver* edges, McOctree* tree) {
  const int depth = tree->depth;
  std::vector<std::uint8_t> cases_are_signs(tree->size(), 1);
  for (int level = depth; level >= 0; --level) {
    const std::int32_t begin = level_begin[level], end = level_begin[level + 1];
    if (level == depth) leaf_cases(leaves, leaf_index, begin, end, &tree->nodes);
    else coarse_cases(level, begin, end, signs, edges, tree);
    own_triangles(leaves, leaf_index, level == depth, begin, end, dropped, &cases_are_signs, tree);
  }
  return cases_are_signs;
}

}  // namespace octree_build
}  // namespace scan2lod
