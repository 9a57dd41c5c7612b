// Phase 2 of build_mc_octree: the signs at lattice points (lod/octree/octree_build.h).
#include <scan2lod/core/mesh_edges.h>
#include <scan2lod/lod/octree/octree_build.h>
#include <scan2lod/reconstruct/cube_table.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scan2lod {
namespace octree_build {

// Leaf corners whose every crossing edge holds a vertex that no kept triangle
// uses: inside-out specks around one lattice point (a speck of the scan's field
// the clean-up dropped as a small piece). Coarse nodes that read such a corner's
// sign would rebuild part of the speck, open, against leaves that emit none of
// it: on the bunny at R = 256 that was most of the boundary loops levels had
// beyond the full mesh's.
std::vector<std::uint8_t> dropped_corners(const CubeNodes& leaves, const TriangleMesh& mesh) {
  std::vector<std::uint8_t> used(mesh.positions.size(), 0);
  for (const Triangle& t : mesh.triangles)
    for (std::int32_t v : t) used[std::size_t(v)] = 1;
  // Bit 0: the corner ends an edge whose vertex is unused; bit 1: a used one.
  std::vector<std::uint8_t> seen(leaves.corner_keys.size(), 0);
  for (std::size_t l = 0; l < leaves.size(); ++l)
    for (int e = 0; e < 12; ++e) {
      const std::int32_t v = leaves.edge_vertices[l][e];
      if (v < 0) continue;
      const std::uint8_t bit = used[std::size_t(v)] ? 2 : 1;
      for (int end = 0; end < 2; ++end) seen[std::size_t(leaves.corners[l][edge_corner(e, end)])] |= bit;
    }
  for (std::uint8_t& s : seen) s = s == 1;
  return seen;
}

LatticeSigns::LatticeSigns(const CubeNodes& leaves, const SignedDistanceField& field,
                           const std::vector<std::uint8_t>& dropped)
    : grid_(leaves.grid), field_(field), side_((leaves.grid.resolution >> kBrickShift) + 1),
      directory_(std::size_t(side_) * side_ * side_, -1), value_index_(leaves.corner_keys.size() * 2) {
  for (std::size_t i = 0; i < leaves.corner_keys.size(); ++i)
    if (!dropped[i]) store(leaves.corner_keys[i], leaves.corner_distances[i]);
}

void LatticeSigns::ensure(const std::vector<std::uint64_t>& keys, const std::vector<std::int32_t>* nodes) {
  std::vector<std::uint64_t> fresh;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const std::uint64_t k = keys[i];
    if (known(k)) continue;
    bool in;
    if (nodes && infer_ && infer_(k, (*nodes)[i], &in)) {
      set(k, in);
      continue;
    }
    fresh.push_back(k);
  }
  std::sort(fresh.begin(), fresh.end());
  fresh.erase(std::unique(fresh.begin(), fresh.end()), fresh.end());
  query(fresh);
}

float LatticeSigns::exact(std::uint64_t key) {
  float v = 0.f;
  if (!value(key, &v)) {
    query({key});
    value(key, &v);
  }
  return v;
}

LatticeSigns::Spot LatticeSigns::spot(std::uint64_t key) const {
  int x, y, z;
  unpack_key(key, &x, &y, &z);
  constexpr int mask = (1 << kBrickShift) - 1;
  const std::size_t local = std::size_t(x & mask) + (std::size_t(y & mask) << kBrickShift) +
                            (std::size_t(z & mask) << (2 * kBrickShift));
  return {std::size_t(x >> kBrickShift) +
              std::size_t(side_) * (std::size_t(y >> kBrickShift) + std::size_t(side_) * std::size_t(z >> kBrickShift)),
          local >> 6, std::uint64_t(1) << (local & 63)};
}

void LatticeSigns::set(std::uint64_t key, bool in) {
  const Spot s = spot(key);
  std::int32_t& b = directory_[s.brick];
  if (b < 0) {
    b = std::int32_t(bits_.size() / (2 * kWordsPerBitset));
    bits_.resize(bits_.size() + 2 * kWordsPerBitset, 0);
  }
  const std::size_t word = std::size_t(b) * 2 * kWordsPerBitset + s.word;
  bits_[word] |= s.mask;
  if (in) bits_[word + kWordsPerBitset] |= s.mask;
}

void LatticeSigns::store(std::uint64_t key, float d) {
  value_index_.assign(key, std::int32_t(values_.size()));
  values_.push_back(d);
  set(key, d < 0.f);
}

void LatticeSigns::query(const std::vector<std::uint64_t>& fresh) {
  if (fresh.empty()) return;
  std::vector<Vec3f> positions(fresh.size());
  for (std::size_t i = 0; i < fresh.size(); ++i) {
    int x, y, z;
    unpack_key(fresh[i], &x, &y, &z);
    positions[i] = grid_.corner_position(x, y, z);
  }
  std::vector<float> d;
  field_(positions, &d);
  for (std::size_t i = 0; i < fresh.size(); ++i) store(fresh[i], std::isnan(d[i]) ? 1.f : d[i]);
}

SignHazards::SignHazards(const TriangleMesh& mesh, const std::vector<Triangle>& patches) {
  const MeshEdges edges = mesh_edges(mesh.triangles, mesh.positions.size());
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges.uses[e] == 1) add_segment(mesh.positions[std::size_t(edges.ends[e][0])], mesh.positions[std::size_t(edges.ends[e][1])]);
  for (const Triangle& t : patches)
    for (int k = 0; k < 3; ++k) {
      add_segment(mesh.positions[t[k]], mesh.positions[t[(k + 1) % 3]]);
      add_segment(mesh.positions[t[k]], (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.f);
    }
  if (points_.positions.empty()) return;
  index_ = std::make_unique<PointIndex>(points_);
  // Boxes around the points of each cell of an 8^3 grid over them.
  Eigen::AlignedBox3f all;
  for (const Vec3f& q : points_.positions) all.extend(q);
  const Vec3f cell = (all.sizes() / 8.f).cwiseMax(1e-12f);
  std::vector<Eigen::AlignedBox3f> cells(512);
  for (const Vec3f& q : points_.positions) {
    const Eigen::Array3i c = ((q - all.min()).array() / cell.array()).cast<int>().min(7);
    cells[std::size_t(c[0] + 8 * c[1] + 64 * c[2])].extend(q);
  }
  for (const auto& box : cells)
    if (!box.isEmpty()) boxes_.push_back(box);
}

SignHazards::~SignHazards() = default;

bool SignHazards::farther_than(const Vec3f& p, double distance) const {
  if (!index_) return true;
  // Most points are far from every box: no tree search for them (the search
  // per node was a third of the octree's sign lookups).
  double nearest_box = std::numeric_limits<double>::max();
  for (const auto& box : boxes_) nearest_box = std::min(nearest_box, double(box.exteriorDistance(p)));
  if (nearest_box > distance + gap_) return true;
  std::int32_t nearest;
  float squared;
  index_->knn(&p, 1, 1, &nearest, &squared, 1);
  return std::sqrt(double(squared)) > distance + gap_;
}

// Its ends and midpoint: any point of it is within a quarter of its length of one.
void SignHazards::add_segment(const Vec3f& a, const Vec3f& b) {
  points_.positions.push_back(a);
  points_.positions.push_back(b);
  points_.positions.push_back((a + b) * 0.5f);
  gap_ = std::max(gap_, 0.25 * double((b - a).norm()));
}

// The deepest node at or below `node` whose cube holds the point `key`.
std::int32_t TreeSignInference::deepest_holding(std::uint64_t key, std::int32_t node) const {
  const OctreeNodes& nodes = tree_.nodes;
  int px, py, pz;
  unpack_key(key, &px, &py, &pz);
  for (;;) {
    if (nodes.first_child[node] < 0) return -1;  // a leaf's corner the leaves dropped
    const int child_shift = tree_.depth - nodes.levels[node] - 1;
    auto within = [&](int p, int lo) { return p >= (lo << child_shift) && p <= ((lo + 1) << child_shift); };
    std::int32_t next = -1;
    for (std::int32_t c = nodes.first_child[node], end = c + nodes.child_counts[node]; c < end && next < 0; ++c) {
      int cx, cy, cz;
      unpack_key(nodes.keys[c], &cx, &cy, &cz);
      if (within(px, cx) && within(py, cy) && within(pz, cz)) next = c;
    }
    if (next < 0) return node;
    node = next;
  }
}

bool TreeSignInference::operator()(std::uint64_t key, std::int32_t node, bool* inside) {
  node = deepest_holding(key, node);
  if (node < 0) return false;
  const int shift = tree_.depth - tree_.nodes.levels[node];
  int x, y, z;
  unpack_key(tree_.nodes.keys[node], &x, &y, &z);
  const int half = 1 << (shift - 1);
  const int cx = (x << shift) + half, cy = (y << shift) + half, cz = (z << shift) + half;
  const std::uint64_t centre = pack_key(cx, cy, cz);
  if (!signs_.known(centre)) return false;
  std::int8_t& usable = centre_usable_[std::size_t(node)];
  if (usable == 0) {
    // Every point of the child cube is within its diagonal of the centre,
    // and the centre, a corner of a child with surface, is within that
    // child's diagonal of the surface (unless the field said nearer).
    const double cell = tree_.grid.cube_size;
    const double diagonal = std::sqrt(3.0) * cell * half;
    float v = 0.f;
    const double to_surface = signs_.value(centre, &v) ? std::fabs(v) : diagonal;
    usable = hazards_.farther_than(tree_.grid.corner_position(cx, cy, cz), to_surface + 2.0 * diagonal + 2.0 * cell)
                 ? 1 : -1;
  }
  if (usable < 0) return false;
  *inside = signs_.inside(centre);
  return true;
}

}  // namespace octree_build
}  // namespace scan2lod
