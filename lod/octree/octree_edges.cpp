// Phase 3 of build_mc_octree: edge resolution (lod/octree/octree_build.h).
#include <scan2lod/lod/octree/octree_build.h>
#include <scan2lod/reconstruct/cube_table.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace scan2lod {
namespace octree_build {

// The vertex on a leaf-lattice edge (lower corner << 2 | axis): the vertex of
// a leaf around that edge, else one added on it earlier, else -1. Only walks
// that reach the leaves ask, so the up to four leaves are looked up then
// rather than every leaf edge indexed beforehand.
std::int32_t EdgeResolver::leaf_edge_vertex(std::uint64_t edge) const {
  int x, y, z;
  unpack_key(edge >> 2, &x, &y, &z);
  const int axis = int(edge & 3);
  for (int e = 4 * axis; e < 4 * axis + 4; ++e) {
    const int c = edge_corner(e, 0);  // the edge's lower end, as a corner of the cube
    const int cx = x - (c & 1), cy = y - ((c >> 1) & 1), cz = z - ((c >> 2) & 1);
    if (cx < 0 || cy < 0 || cz < 0) continue;
    const std::int32_t l = leaf_index_.find(pack_key(std::uint64_t(cx), std::uint64_t(cy), std::uint64_t(cz)));
    if (l >= 0 && leaves_.edge_vertices[std::size_t(l)][e] >= 0) return leaves_.edge_vertices[std::size_t(l)][e];
  }
  return added_on_edge_.find(edge);
}

// The distance is 1-Lipschitz: where the surface crosses an edge, its ends'
// distances add up to at most the edge's length. A larger sum is a jump of
// the sign alone (beyond an open rim, where the pseudo-normal flips).
constexpr float kJumpFactor = 1.5f;

// A vertex added on a leaf edge no leaf crosses, where the distances at its
// ends interpolate to zero.
std::int32_t EdgeResolver::interpolated_vertex(std::uint64_t edge) {
  const std::uint64_t lower = edge >> 2;
  const int axis = int(edge & 3);
  const std::uint64_t upper = lower + kAxisStep[axis];
  const float da = signs_.exact(lower), db = signs_.exact(upper);
  const float t = crossing_ratio(da, db);
  int x, y, z;
  unpack_key(lower, &x, &y, &z);
  Vec3f p = tree_.grid.corner_position(x, y, z);
  p[axis] += t * float(tree_.grid.cube_size);
  const std::int32_t v = std::int32_t(tree_.vertices.positions.size());
  tree_.vertices.positions.push_back(p);
  added_on_edge_.insert(edge, v);
  if (std::fabs(da) + std::fabs(db) > kJumpFactor * float(tree_.grid.cube_size)) jumps_.push_back(v);
  return v;
}

void EdgeResolver::resolve(int level, const std::vector<std::uint64_t>& edges,
                           const std::vector<std::pair<std::int32_t, int>>& slots, std::vector<std::int32_t>* out) {
  const int depth = tree_.depth;
  out->assign(edges.size(), -1);
  std::vector<std::uint64_t> current = edges;  // edge key at the level being walked
  std::vector<std::size_t> open(edges.size());
  std::iota(open.begin(), open.end(), 0);
  struct Step {
    std::size_t edge;
    int level;
    std::uint64_t key;  // the half the walk took, an edge of `level`
  };
  std::vector<Step> steps;  // every walk's halves, to remember once resolved
  steps.reserve(edges.size());
  // All open walks go down one level at a time, so that each level's signs
  // come in one batch.
  for (int l = level; l < depth && !open.empty(); ++l) {
    const int half_shift = depth - l - 1;
    std::vector<std::uint64_t> mids;
    std::vector<std::int32_t> mid_nodes;
    mids.reserve(open.size() * 2);
    mid_nodes.reserve(open.size() * 2);
    for (std::size_t i : open) {
      const std::uint64_t lower = current[i] >> 2;
      const int axis = int(current[i] & 3);
      mids.push_back(lower);
      mids.push_back(lower + (kAxisStep[axis] << half_shift));
      mid_nodes.insert(mid_nodes.end(), 2, slots[i].first);
    }
    signs_.ensure(mids, &mid_nodes);
    std::vector<std::size_t> still;
    for (std::size_t i : open) {
      const std::uint64_t lower = current[i] >> 2;
      const int axis = int(current[i] & 3);
      const std::uint64_t mid = lower + (kAxisStep[axis] << half_shift);
      const std::uint64_t half_lower = signs_.inside(lower) != signs_.inside(mid) ? lower : mid;
      current[i] = (half_lower << 2) | std::uint64_t(axis);
      steps.push_back({i, l + 1, current[i]});
      const std::int32_t known = memo_[std::size_t(l + 1)].find(current[i]);
      if (known >= 0) (*out)[i] = known;
      else still.push_back(i);
    }
    open.swap(still);
  }
  for (std::size_t i : open) {
    // A leaf edge: the mesh's vertex, or one interpolated where no leaf has it.
    const std::int32_t v = leaf_edge_vertex(current[i]);
    (*out)[i] = v >= 0 ? v : interpolated_vertex(current[i]);
  }
  for (std::size_t i = 0; i < edges.size(); ++i) memo_[std::size_t(level)].insert(edges[i], (*out)[i]);
  for (const Step& step : steps) memo_[std::size_t(step.level)].insert(step.key, (*out)[step.edge]);
}

}  // namespace octree_build
}  // namespace scan2lod
