// The marching-cube octree's build: a short sequence of named phases, each in
// its own file (lod/octree/octree_build.h lists them).
#include <scan2lod/lod/octree/mc_octree.h>

#include <scan2lod/core/error.h>
#include <scan2lod/lod/octree/octree_build.h>
#include <scan2lod/reconstruct/mesh_field.h>

#include <algorithm>
#include <future>

namespace scan2lod {
namespace octree_build {

namespace {

std::uint64_t parent_key(std::uint64_t key) {
  int x, y, z;
  unpack_key(key, &x, &y, &z);
  return pack_key(std::uint64_t(x) >> 1, std::uint64_t(y) >> 1, std::uint64_t(z) >> 1);
}

// The keys of every level, from the leaves' up: each level's parents, sorted.
std::vector<std::vector<std::uint64_t>> keys_per_level(const CubeNodes& leaves, int depth) {
  std::vector<std::vector<std::uint64_t>> level_keys(std::size_t(depth) + 1);
  level_keys[depth] = leaves.cube_keys;
  std::sort(level_keys[depth].begin(), level_keys[depth].end());
  for (int level = depth - 1; level >= 0; --level) {
    auto& keys = level_keys[level];
    keys.reserve(level_keys[level + 1].size() / 3 + 1);
    for (std::uint64_t k : level_keys[level + 1]) keys.push_back(parent_key(k));
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  }
  return level_keys;
}

void add_node(int level, std::uint64_t key, std::int32_t parent, OctreeNodes* nodes, FlatHashMap* index) {
  const std::int32_t id = std::int32_t(nodes->keys.size());
  nodes->keys.push_back(key);
  nodes->levels.push_back(std::uint8_t(level));
  nodes->parents.push_back(parent);
  nodes->first_child.push_back(-1);
  nodes->child_counts.push_back(0);
  index->insert(key, id);
}

}  // namespace

LevelBegin build_skeleton(const CubeNodes& leaves, McOctree* tree) {
  const int depth = tree->depth;
  const std::vector<std::vector<std::uint64_t>> level_keys = keys_per_level(leaves, depth);
  OctreeNodes& nodes = tree->nodes;
  // Ordered top-down, so that children are contiguous.
  std::vector<FlatHashMap> node_index(std::size_t(depth) + 1);
  LevelBegin level_begin(std::size_t(depth) + 2, 0);
  add_node(0, level_keys[0].front(), -1, &nodes, &node_index[0]);
  for (int level = 0; level < depth; ++level) {
    level_begin[level + 1] = std::int32_t(nodes.keys.size());
    std::vector<std::pair<std::int32_t, std::uint64_t>> children;
    children.reserve(level_keys[level + 1].size());
    for (std::uint64_t k : level_keys[level + 1]) children.push_back({node_index[level].find(parent_key(k)), k});
    std::sort(children.begin(), children.end());
    for (auto [parent, key] : children) {
      if (nodes.first_child[parent] < 0) nodes.first_child[parent] = std::int32_t(nodes.keys.size());
      ++nodes.child_counts[parent];
      add_node(level + 1, key, parent, &nodes, &node_index[level + 1]);
    }
  }
  level_begin[depth + 1] = std::int32_t(nodes.keys.size());
  const std::size_t n = nodes.size();
  nodes.cases.assign(n, 0);
  nodes.edge_vertices.resize(n);
  nodes.first_triangle.assign(n, 0);
  nodes.triangle_counts.assign(n, 0);
  nodes.metrics.assign(n, 0.f);
  return level_begin;
}

}  // namespace octree_build

McOctree build_mc_octree(const CubeNodes& leaves, const TriangleMesh& mesh, const MeshField& field,
                         const OctreeOptions& options) {
  using namespace octree_build;
  if (leaves.size() == 0) throw InputError("", "no leaf cube nodes: the reconstruction is empty");
  McOctree tree;
  tree.grid = leaves.grid;
  while ((1 << tree.depth) < leaves.grid.resolution) ++tree.depth;
  tree.vertices.positions.assign(mesh.positions.begin(), mesh.positions.end());
  tree.vertices.normals.assign(mesh.normals.begin(), mesh.normals.end());
  tree.vertices.colors.assign(mesh.colors.begin(), mesh.colors.end());
  tree.mesh_vertices = mesh.positions.size();

  const LevelBegin level_begin = build_skeleton(leaves, &tree);
  FlatHashMap leaf_index(leaves.size());
  for (std::size_t l = 0; l < leaves.size(); ++l) leaf_index.insert(leaves.cube_keys[l], std::int32_t(l));

  const std::vector<std::uint8_t> dropped = dropped_corners(leaves, mesh);
  LatticeSigns signs(leaves, field.distance, dropped);
  const SignHazards hazards(mesh, leaves.patch_triangles);
  TreeSignInference inference(tree, signs, hazards);
  signs.set_inference(std::ref(inference));
  EdgeResolver edges(leaves, leaf_index, &signs, &tree);

  const std::size_t first_added = tree.vertices.size();
  const std::vector<std::uint8_t> cases_are_signs =
      cases_and_triangles(leaves, leaf_index, level_begin, dropped, &signs, &edges, &tree);
  transition_data(level_begin, cases_are_signs, &signs, &edges, &tree);
  pull_jump_vertices(edges.jumps(), field.closest, &tree);
  added_vertex_attributes(first_added, &tree);
  level_vertices(mesh, level_begin, &tree);
  own_triangulations(field, level_begin, &tree);
  const std::vector<LeafSums> sums = leaf_sums(tree, std::size_t(level_begin[tree.depth]));
  compute_metrics(options.metric, sums, &tree);
  group_patches(leaves.patch_triangles, &tree);
  centre_vertices(sums, &tree);
  find_straight_faces(tree.vertices.positions, &tree);
  return tree;
}

McOctree build_mc_octree(const Reconstruction& reconstruction, const OctreeOptions& options) {
  // The field's setup, which builds Open3D's BVH, takes a quarter of a
  // second at R = 256: on a second thread it overlaps the octree's skeleton,
  // which needs no field.
  const TriangleMesh& mesh = reconstruction.mesh;
  std::shared_future<MeshField> ready = std::async(std::launch::async, [&mesh] { return mesh_field(mesh); }).share();
  MeshField field;
  field.distance = [ready](const std::vector<Vec3f>& q, std::vector<float>* d) { ready.get().distance(q, d); };
  field.closest = [ready](const std::vector<Vec3f>& q, std::vector<Vec3f>* c) { ready.get().closest(q, c); };
  return build_mc_octree(reconstruction.leaves, mesh, field, options);
}

}  // namespace scan2lod
