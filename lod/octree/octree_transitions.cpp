// Phase 5 of build_mc_octree: what crack patching needs of each node above
// the leaves (lod/octree/octree_build.h, lod/octree/transition.h).
#include <scan2lod/lod/octree/octree_build.h>
#include <scan2lod/lod/octree/transition.h>

namespace scan2lod {
namespace octree_build {
namespace {

// The signs at a node's 27 local lattice points that its children's cases
// give (the points are the children's corners): bit p of the result's first
// is set where point p is known, of its second where it is inside.
std::pair<std::uint32_t, std::uint32_t> child_signs(const McOctree& tree, std::int32_t node,
                                                    const std::vector<std::uint8_t>& cases_are_signs) {
  const OctreeNodes& nodes = tree.nodes;
  int x, y, z;
  unpack_key(nodes.keys[node], &x, &y, &z);
  std::uint32_t known = 0, inside = 0;
  for (std::int32_t c = nodes.first_child[node], stop = c + nodes.child_counts[node]; c < stop; ++c) {
    if (!cases_are_signs[std::size_t(c)]) continue;
    int cx, cy, cz;
    unpack_key(nodes.keys[std::size_t(c)], &cx, &cy, &cz);
    const int octant = (cx - 2 * x) + 3 * (cy - 2 * y) + 9 * (cz - 2 * z);  // its lowest lattice point
    for (int k = 0; k < 8; ++k) {
      const int p = octant + (k & 1) + 3 * ((k >> 1) & 1) + 9 * ((k >> 2) & 1);
      known |= 1u << p;
      inside |= std::uint32_t((nodes.cases[std::size_t(c)] >> k) & 1) << p;
    }
  }
  return {known, inside};
}

// One level's nodes: their boundary signs, the sub-edges that cross, the
// vertices on them, and their neighbours.
void level_transitions(int level, std::int32_t begin, std::int32_t end,
                       const std::vector<std::uint8_t>& cases_are_signs, LatticeSigns* signs, EdgeResolver* resolver,
                       McOctree* tree) {
  OctreeTransitions& tr = tree->transitions;
  const int shift = tree->depth - level;
  // The children's cases give most of the 27 signs; the lattice only the rest.
  std::vector<std::uint32_t> covered(std::size_t(end - begin), 0);
  std::vector<std::uint64_t> points;
  std::vector<std::int32_t> point_nodes;
  for (std::int32_t node = begin; node < end; ++node) {
    const auto [known, inside] = child_signs(*tree, node, cases_are_signs);
    covered[std::size_t(node - begin)] = known;
    tr.boundary_inside[node] = inside;
    for (int p = 0; p < 27; ++p)
      if (!((known >> p) & 1)) {
        points.push_back(local_lattice_key(tree->nodes.keys[node], shift, p));
        point_nodes.push_back(node);
      }
  }
  signs->ensure(points, &point_nodes);
  const auto& sub_edges = transition_sub_edges();
  std::vector<std::uint64_t> edges;
  std::vector<std::pair<std::int32_t, int>> slots;
  std::size_t next_point = 0;
  for (std::int32_t node = begin; node < end; ++node) {
    std::uint32_t inside = tr.boundary_inside[node];
    for (int p = 0; p < 27; ++p)
      if (!((covered[std::size_t(node - begin)] >> p) & 1)) inside |= std::uint32_t(signs->inside(points[next_point++])) << p;
    tr.boundary_inside[node] = inside;
    tr.sub_edge_vertices[node].fill(-1);
    for (int e = 0; e < kSubEdges; ++e) {
      const SubEdge& se = sub_edges[e];
      if (((inside >> se.a) & 1) == ((inside >> se.b) & 1)) continue;
      const int axis = (se.b - se.a) == 1 ? 0 : (se.b - se.a) == 3 ? 1 : 2;
      edges.push_back((local_lattice_key(tree->nodes.keys[node], shift, se.a) << 2) | std::uint64_t(axis));
      slots.push_back({node, e});
    }
    find_neighbours(node, tree);
  }
  std::vector<std::int32_t> vertices;
  resolver->resolve(level + 1, edges, slots, &vertices);
  for (std::size_t i = 0; i < slots.size(); ++i) tr.sub_edge_vertices[slots[i].first][slots[i].second] = vertices[i];
}

}  // namespace

void transition_data(const LevelBegin& level_begin, const std::vector<std::uint8_t>& cases_are_signs,
                     LatticeSigns* signs, EdgeResolver* edges, McOctree* tree) {
  const int depth = tree->depth;
  const std::size_t internal = std::size_t(level_begin[depth]);
  tree->transitions.boundary_inside.assign(internal, 0);
  tree->transitions.sub_edge_vertices.resize(internal);
  tree->transitions.neighbours.resize(internal);
  for (int level = 0; level < depth; ++level)
    level_transitions(level, level_begin[level], level_begin[level + 1], cases_are_signs, signs, edges, tree);
}

}  // namespace octree_build
}  // namespace scan2lod
