#include <scan2lod/lod/octree/model_pack.h>

#include <scan2lod/core/error.h>
#include <scan2lod/lod/octree/octree_build.h>
#include <scan2lod/reconstruct/cube_table.h>

#include <algorithm>
#include <stdexcept>

namespace scan2lod {

namespace {

int octant_of(std::uint64_t key) {
  int x, y, z;
  unpack_key(key, &x, &y, &z);
  return (x & 1) + 2 * (y & 1) + 4 * (z & 1);
}

std::uint8_t child_mask(const OctreeNodes& nodes, std::size_t node, std::int32_t* next) {
  if (nodes.first_child[node] < 0) return 0;
  if (nodes.first_child[node] != *next) throw std::logic_error("pack_octree: the nodes are not breadth-first");
  std::uint8_t mask = 0;
  int last = -1;
  for (std::int32_t c = nodes.first_child[node], end = c + nodes.child_counts[node]; c < end; ++c) {
    const int o = octant_of(nodes.keys[std::size_t(c)]);
    if (o <= last) throw std::logic_error("pack_octree: children are not in octant order");
    mask |= std::uint8_t(1u << o);
    last = o;
  }
  *next += nodes.child_counts[node];
  return mask;
}

// Which of the case's triangles the node's own triangles are, in order.
std::uint8_t triangle_mask(const McOctree& tree, std::size_t node) {
  const CubeCase& cc = cube_cases()[tree.nodes.cases[node]];
  const auto& ev = tree.nodes.edge_vertices[node];
  const Triangle* own = tree.triangles.data() + tree.nodes.first_triangle[node];
  std::uint8_t mask = 0;
  int k = 0;
  for (int t = 0; t < cc.triangle_count && k < tree.nodes.triangle_counts[node]; ++t) {
    const Triangle from_case = {ev[cc.triangles[t][0]], ev[cc.triangles[t][1]], ev[cc.triangles[t][2]]};
    if (own[k] != from_case) continue;
    if (t >= 8) throw std::logic_error("pack_octree: a case with more than 8 triangles");
    mask |= std::uint8_t(1u << t);
    ++k;
  }
  if (k != tree.nodes.triangle_counts[node]) throw std::logic_error("pack_octree: triangles not from the node's case");
  return mask;
}

// An internal node keeps all its case's triangles, each as the three edges
// whose vertices it joins (PackedOctree::own_cuts).
std::uint8_t own_cuts(const McOctree& tree, std::size_t node, std::vector<std::uint16_t>* cuts) {
  const CubeCase& cc = cube_cases()[tree.nodes.cases[node]];
  const auto& ev = tree.nodes.edge_vertices[node];
  const Triangle* own = tree.triangles.data() + tree.nodes.first_triangle[node];
  if (tree.nodes.triangle_counts[node] != cc.triangle_count)
    throw std::logic_error("pack_octree: an internal node without all its case's triangles");
  for (int t = 0; t < cc.triangle_count; ++t) {
    std::uint16_t cut = 0;
    for (int k = 0; k < 3; ++k) {
      const auto e = std::find(ev.begin(), ev.end(), own[t][k]);
      if (own[t][k] < 0 || e == ev.end()) throw std::logic_error("pack_octree: a triangle off its node's edges");
      cut |= std::uint16_t((e - ev.begin()) << (4 * k));
    }
    cuts->push_back(cut);
  }
  return std::uint8_t((1u << cc.triangle_count) - 1u);
}

// The level ranges of breadth-first nodes: level l is [begin[l], begin[l + 1]).
std::vector<std::int32_t> level_ranges(const OctreeNodes& nodes, int depth) {
  std::vector<std::int32_t> begin(std::size_t(depth) + 2, std::int32_t(nodes.size()));
  for (std::size_t i = nodes.size(); i-- > 0;) begin[nodes.levels[i]] = std::int32_t(i);
  for (int l = depth; l >= 0; --l) begin[l] = std::min(begin[l], begin[l + 1]);
  return begin;
}

}  // namespace

PackedOctree pack_octree(const McOctree& tree) {
  const OctreeNodes& nodes = tree.nodes;
  const std::size_t n = nodes.size(), internal = tree.internal_nodes();
  PackedOctree p;
  p.child_masks.resize(n);
  p.edge_masks.resize(n);
  p.triangle_masks.resize(n);
  std::int32_t next = 1;
  for (std::size_t i = 0; i < n; ++i) {
    p.child_masks[i] = child_mask(nodes, i, &next);
    for (int e = 0; e < 12; ++e)
      if (nodes.edge_vertices[i][e] >= 0) {
        p.edge_masks[i] |= std::uint16_t(1u << e);
        p.edge_vertices.push_back(nodes.edge_vertices[i][e]);
      }
  }
  // Triangles from the leaves' level up, each level's nodes in order.
  const std::vector<std::int32_t> begin = level_ranges(nodes, tree.depth);
  std::int32_t expected = 0;
  for (int level = tree.depth; level >= 0; --level)
    for (std::int32_t i = begin[level]; i < begin[level + 1]; ++i) {
      if (nodes.first_triangle[i] != expected) throw std::logic_error("pack_octree: triangles not laid out leaves first");
      p.triangle_masks[i] = level < tree.depth ? own_cuts(tree, std::size_t(i), &p.own_cuts)
                                               : triangle_mask(tree, std::size_t(i));
      expected += nodes.triangle_counts[i];
    }
  if (std::size_t(expected) != tree.triangles.size()) throw std::logic_error("pack_octree: triangles no node owns");
  p.sub_edge_masks.resize(internal);
  for (std::size_t i = 0; i < internal; ++i)
    for (int e = 0; e < kSubEdges; ++e)
      if (tree.transitions.sub_edge_vertices[i][e] >= 0) {
        p.sub_edge_masks[i] |= std::uint64_t(1) << e;
        p.sub_edge_vertices.push_back(tree.transitions.sub_edge_vertices[i][e]);
      }
  return p;
}

namespace {

// Keys, levels, parents and children from the child masks.
void unpack_nodes(const std::vector<std::uint8_t>& masks, int depth, const std::string& source, OctreeNodes* nodes) {
  auto bad = [&](const std::string& what) { throw InputError(source, "inconsistent model: " + what); };
  const std::size_t n = masks.size();
  if (n == 0) bad("the octree has no nodes");
  resize_for_load(&nodes->keys, n);
  resize_for_load(&nodes->levels, n);
  resize_for_load(&nodes->parents, n);
  resize_for_load(&nodes->first_child, n);
  resize_for_load(&nodes->child_counts, n);
  std::fill(nodes->first_child.begin(), nodes->first_child.end(), -1);
  nodes->parents[0] = -1;
  std::size_t next = 1;
  for (std::size_t i = 0; i < n; ++i) {
    if (!masks[i]) continue;
    if (i >= next) bad("section 'CHLD': node " + std::to_string(i) + " is no node's child");
    if (nodes->levels[i] >= depth) bad("section 'CHLD': node " + std::to_string(i) + " has children below the leaves");
    int x, y, z;
    unpack_key(nodes->keys[i], &x, &y, &z);
    nodes->first_child[i] = std::int32_t(next);
    for (int o = 0; o < 8; ++o) {
      if (!((masks[i] >> o) & 1)) continue;
      if (next >= n) bad("section 'CHLD' names more children than its " + std::to_string(n) + " nodes");
      nodes->keys[next] = pack_key(std::uint64_t(2 * x + (o & 1)), std::uint64_t(2 * y + ((o >> 1) & 1)),
                                   std::uint64_t(2 * z + ((o >> 2) & 1)));
      nodes->levels[next] = std::uint8_t(nodes->levels[i] + 1);
      nodes->parents[next] = std::int32_t(i);
      ++nodes->child_counts[i];
      ++next;
    }
  }
  if (next != n) bad("section 'CHLD' names " + std::to_string(next - 1) + " children for " + std::to_string(n) + " nodes");
}

// Vertices on the edges (or sub-edges) each mask names, node by node.
template <std::size_t kEdges, class Mask, class Out>
void unpack_masked(const std::vector<Mask>& masks, const std::vector<std::int32_t>& packed, const char* mask_tag,
                   const char* packed_tag, const std::string& source, Out* out) {
  auto bad = [&](const std::string& what) { throw InputError(source, "inconsistent model: " + what); };
  resize_for_load(out, masks.size());
  std::size_t next = 0;
  for (std::size_t i = 0; i < masks.size(); ++i) {
    if (kEdges < 64 && (std::uint64_t(masks[i]) >> kEdges))
      bad("section '" + std::string(mask_tag) + "': node " + std::to_string(i) + " names an edge past " +
          std::to_string(kEdges));
    (*out)[i].fill(-1);
    for (std::uint64_t bits = std::uint64_t(masks[i]); bits; bits &= bits - 1) {
      if (next >= packed.size())
        bad("section '" + std::string(packed_tag) + "' holds fewer vertices than '" + mask_tag + "' names");
      (*out)[i][std::size_t(__builtin_ctzll(bits))] = packed[next++];
    }
  }
  if (next != packed.size())
    bad("section '" + std::string(packed_tag) + "' holds " + std::to_string(packed.size()) + " vertices, '" +
        mask_tag + "' names " + std::to_string(next));
}

void unpack_triangles(const std::vector<std::uint8_t>& masks, const std::string& source, McOctree* tree) {
  OctreeNodes& nodes = tree->nodes;
  const std::vector<std::int32_t> begin = level_ranges(nodes, tree->depth);
  resize_for_load(&nodes.first_triangle, nodes.size());
  resize_for_load(&nodes.triangle_counts, nodes.size());
  std::size_t total = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) total += std::size_t(__builtin_popcount(masks[i]));
  tree->triangles.clear();
  tree->triangles.reserve(total);
  for (int level = tree->depth; level >= 0; --level)
    for (std::int32_t i = begin[level]; i < begin[level + 1]; ++i) {
      const CubeCase& cc = cube_cases()[nodes.cases[i]];
      if (masks[i] >> cc.triangle_count)
        throw InputError(source, "inconsistent model: section 'TMSK': node " + std::to_string(i) +
                                     " names a triangle its case lacks");
      const auto& ev = nodes.edge_vertices[i];
      nodes.first_triangle[i] = std::int32_t(tree->triangles.size());
      for (int t = 0; t < cc.triangle_count; ++t)
        if ((masks[i] >> t) & 1)
          tree->triangles.push_back({ev[cc.triangles[t][0]], ev[cc.triangles[t][1]], ev[cc.triangles[t][2]]});
      nodes.triangle_counts[i] = std::uint8_t(tree->triangles.size() - std::size_t(nodes.first_triangle[i]));
    }
}

// The internal nodes' triangles from their cuts, in the order pack_octree
// wrote them (coarser levels after finer ones, as the triangles lie).
void unpack_own_cuts(const std::vector<std::uint16_t>& cuts, const std::string& source, McOctree* tree) {
  auto bad = [&](const std::string& what) { throw InputError(source, "inconsistent model: section 'OWNC': " + what); };
  const OctreeNodes& nodes = tree->nodes;
  const std::vector<std::int32_t> begin = level_ranges(nodes, tree->depth);
  const std::size_t first = tree->depth > 0 ? std::size_t(nodes.first_triangle[std::size_t(begin[tree->depth - 1])]) : 0;
  if (tree->depth == 0 || cuts.size() != tree->triangles.size() - first)
    bad(std::to_string(cuts.size()) + " triangles for the internal nodes' " +
        std::to_string(tree->triangles.size() - first));
  for (int level = tree->depth - 1; level >= 0; --level)
    for (std::int32_t i = begin[level]; i < begin[level + 1]; ++i) {
      const auto& ev = nodes.edge_vertices[std::size_t(i)];
      for (std::int32_t t = nodes.first_triangle[i], end = t + nodes.triangle_counts[i]; t < end; ++t) {
        const std::uint16_t cut = cuts[std::size_t(t) - first];
        const int e[3] = {cut & 15, (cut >> 4) & 15, (cut >> 8) & 15};
        if ((cut >> 12) || e[0] >= 12 || e[1] >= 12 || e[2] >= 12 || ev[e[0]] < 0 || ev[e[1]] < 0 || ev[e[2]] < 0 ||
            e[0] == e[1] || e[1] == e[2] || e[0] == e[2])
          bad("triangle " + std::to_string(t) + " of node " + std::to_string(i) +
              " names edges that are not three of the node's crossed edges");
        tree->triangles[std::size_t(t)] = {ev[e[0]], ev[e[1]], ev[e[2]]};
      }
    }
}

}  // namespace

void unpack_octree(const PackedOctree& packed, const std::string& source, McOctree* tree) {
  auto bad = [&](const std::string& what) { throw InputError(source, "inconsistent model: " + what); };
  if (tree->depth < 0 || tree->depth > 19)
    bad("resolution " + std::to_string(tree->grid.resolution) + " is not 2^depth for depth " + std::to_string(tree->depth));
  unpack_nodes(packed.child_masks, tree->depth, source, &tree->nodes);
  const std::size_t n = tree->nodes.size(), internal = packed.sub_edge_masks.size();
  auto per_node = [&](const char* tag, std::size_t count) {
    if (count != n)
      bad("section '" + std::string(tag) + "' has " + std::to_string(count) + " entries for the " + std::to_string(n) +
          " nodes of 'CHLD'");
  };
  per_node("CASE", tree->nodes.cases.size());
  per_node("EDGM", packed.edge_masks.size());
  per_node("TMSK", packed.triangle_masks.size());
  // The internal nodes come first: the transitions index them by node.
  for (std::size_t i = 0; i < n; ++i)
    if ((i < internal) != (tree->nodes.first_child[i] >= 0))
      bad("section 'SUBM' has " + std::to_string(internal) + " entries, but node " + std::to_string(i) +
          (i < internal ? " is a leaf" : " has children"));
  // One thread: bench/lod/lod_bench.cpp loads in a parent that forks
  // afterwards, and libgomp's pool does not survive a fork.
  unpack_masked<12>(packed.edge_masks, packed.edge_vertices, "EDGM", "EDGP", source, &tree->nodes.edge_vertices);
  unpack_triangles(packed.triangle_masks, source, tree);
  if (!packed.own_cuts.empty()) unpack_own_cuts(packed.own_cuts, source, tree);
  unpack_masked<kSubEdges>(packed.sub_edge_masks, packed.sub_edge_vertices, "SUBM", "SUBP", source,
                           &tree->transitions.sub_edge_vertices);
  resize_for_load(&tree->transitions.neighbours, internal);
  for (std::size_t i = 0; i < internal; ++i) octree_build::find_neighbours(std::int32_t(i), tree);
}

}  // namespace scan2lod
