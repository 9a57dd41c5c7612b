#include "lod/mc_octree.h"

#include "core/error.h"
#include "core/flat_hash.h"
#include "core/mesh_edges.h"
#include "reconstruct/cube_table.h"
#include "reconstruct/mesh_field.h"
#include "reconstruct/signed_distance.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <functional>
#include <future>
#include <limits>
#include <memory>
#include <numeric>

namespace scan2lod {
namespace {

constexpr std::uint64_t kAxisStep[3] = {1ull, 1ull << 20, 1ull << 40};

std::uint64_t parent_key(std::uint64_t key) {
  int x, y, z;
  unpack_key(key, &x, &y, &z);
  return pack_key(std::uint64_t(x) >> 1, std::uint64_t(y) >> 1, std::uint64_t(z) >> 1);
}

// Leaf-lattice key of corner c of the node with `key` on a level whose cubes
// span 2^shift leaf cubes.
std::uint64_t corner_lattice_key(std::uint64_t key, int shift, int c) {
  int x, y, z;
  unpack_key(key, &x, &y, &z);
  const std::uint64_t size = 1ull << shift;
  return pack_key((std::uint64_t(x) << shift) + (c & 1) * size, (std::uint64_t(y) << shift) + ((c >> 1) & 1) * size,
                  (std::uint64_t(z) << shift) + ((c >> 2) & 1) * size);
}

// Signs on the leaf lattice: the leaves' own where they have them, else
// inferred from the tree (see `Inference`), else the field's, each point
// decided once. The octree asks for some ten million signs; they sit as bits
// in 16^3 bricks under a dense directory, because a hash map's cache miss per
// lookup was most of the transitions' time. Distances, which only leaf-edge
// interpolation needs, stay in a hash map.
class LatticeSigns {
 public:
  // Infers a point's sign from the tree, given a node that holds the point;
  // false when it cannot.
  using Inference = std::function<bool(std::uint64_t key, std::int32_t node, bool* inside)>;

  // `dropped[i]`: corner i's sign only shaped pieces that clean-up removed; the
  // field decides it instead.
  LatticeSigns(const CubeNodes& leaves, const SignedDistanceField& field, const std::vector<std::uint8_t>& dropped)
      : grid_(leaves.grid), field_(field), side_((leaves.grid.resolution >> kBrickShift) + 1),
        directory_(std::size_t(side_) * side_ * side_, -1), value_index_(leaves.corner_keys.size() * 2) {
    for (std::size_t i = 0; i < leaves.corner_keys.size(); ++i)
      if (!dropped[i]) store(leaves.corner_keys[i], leaves.corner_distances[i]);
  }

  void set_inference(Inference infer) { infer_ = std::move(infer); }

  // Makes sure every key has a sign: inferred where `nodes` (a node holding
  // each key) allow it, the rest in one batched field call.
  void ensure(const std::vector<std::uint64_t>& keys, const std::vector<std::int32_t>* nodes = nullptr) {
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

  // The distance at key (the field's where the sign was inferred).
  float exact(std::uint64_t key) {
    float v = 0.f;
    if (!value(key, &v)) {
      query({key});
      value(key, &v);
    }
    return v;
  }

  // The distance at key when the leaves or the field gave one.
  bool value(std::uint64_t key, float* v) const {
    const std::int32_t at = value_index_.find(key);
    if (at < 0) return false;
    *v = values_[std::size_t(at)];
    return true;
  }

  bool known(std::uint64_t key) const { return bit(key, 0); }
  bool inside(std::uint64_t key) const { return bit(key, kWordsPerBitset); }

 private:
  static constexpr int kBrickShift = 4;  // 16^3 points a brick
  static constexpr std::size_t kWordsPerBitset = std::size_t(1) << (3 * kBrickShift - 6);

  // Where a key's bits are: its brick's slot in the directory, and the word
  // (within the brick's known bits; its inside bits follow them) and bit.
  struct Spot {
    std::size_t brick, word;
    std::uint64_t mask;
  };
  Spot spot(std::uint64_t key) const {
    int x, y, z;
    unpack_key(key, &x, &y, &z);
    constexpr int mask = (1 << kBrickShift) - 1;
    const std::size_t local = std::size_t(x & mask) + (std::size_t(y & mask) << kBrickShift) +
                              (std::size_t(z & mask) << (2 * kBrickShift));
    return {std::size_t(x >> kBrickShift) +
                std::size_t(side_) * (std::size_t(y >> kBrickShift) + std::size_t(side_) * std::size_t(z >> kBrickShift)),
            local >> 6, std::uint64_t(1) << (local & 63)};
  }
  bool bit(std::uint64_t key, std::size_t offset) const {
    const Spot s = spot(key);
    const std::int32_t b = directory_[s.brick];
    return b >= 0 && (bits_[std::size_t(b) * 2 * kWordsPerBitset + s.word + offset] & s.mask);
  }
  void set(std::uint64_t key, bool in) {
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
  void store(std::uint64_t key, float d) {
    value_index_.assign(key, std::int32_t(values_.size()));
    values_.push_back(d);
    set(key, d < 0.f);
  }

  void query(const std::vector<std::uint64_t>& fresh) {
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

  const CubeGrid& grid_;
  const SignedDistanceField& field_;
  int side_;                             // bricks along each axis
  std::vector<std::int32_t> directory_;  // brick -> its index in bits_, or -1
  std::vector<std::uint64_t> bits_;
  FlatHashMap value_index_;
  std::vector<float> values_;
  Inference infer_;
};

// The edge length of a node's cube.
double node_size(const McOctree& tree, std::size_t node) {
  return tree.grid.cube_size * double(1 << (tree.depth - tree.levels[node]));
}

// A triangle's corners relative to the grid origin, in double: sums of second
// moments over thousands of triangles keep their digits.
std::array<Eigen::Vector3d, 3> corners_of(const McOctree& tree, const Triangle& t) {
  const Eigen::Vector3d origin = tree.grid.origin;
  return {tree.positions[t[0]].cast<double>() - origin, tree.positions[t[1]].cast<double>() - origin,
          tree.positions[t[2]].cast<double>() - origin};
}

// Sums over the leaf triangles under each node, bottom-up.
struct LeafSums {
  double area = 0.0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();   // exact area moments
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d planes = Eigen::Matrix3d::Zero();  // their planes' quadric: sum of a n n^T
  Eigen::Vector3d offsets = Eigen::Vector3d::Zero();  // and of a n (n . p)

  LeafSums& operator+=(const LeafSums& o) {
    area += o.area;
    first += o.first;
    second += o.second;
    planes += o.planes;
    offsets += o.offsets;
    return *this;
  }
};

std::vector<LeafSums> leaf_sums(const McOctree& tree, std::size_t internal) {
  // Only the nodes above the leaves (the first `internal`) keep sums: a
  // leaf's go straight to its parent (200 bytes a node, 57 MB for all at
  // R = 256).
  const std::size_t n = tree.size();
  std::vector<LeafSums> sums(internal);
  for (std::size_t node = n; node-- > internal;) {  // the order of the pass below
    LeafSums s;
    for (std::int32_t t = 0; t < tree.triangle_counts[node]; ++t) {
      const auto v = corners_of(tree, tree.triangles[std::size_t(tree.first_triangle[node] + t)]);
      const Eigen::Vector3d area_normal = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]);
      const double a = area_normal.norm();
      if (a <= 0.0) continue;
      const Eigen::Vector3d sum = v[0] + v[1] + v[2], unit = area_normal / a;
      s.area += a;
      s.first += a / 3.0 * sum;
      s.second += a / 12.0 * (v[0] * v[0].transpose() + v[1] * v[1].transpose() + v[2] * v[2].transpose() +
                              sum * sum.transpose());
      s.planes += a * unit * unit.transpose();
      s.offsets += a * unit * unit.dot(v[0]);
    }
    sums[std::size_t(tree.parents[node])] += s;
  }
  for (std::size_t node = internal; node-- > 1;) {  // parents come before children
    sums[std::size_t(tree.parents[node])] += sums[node];
  }
  return sums;
}

// A node's own triangles: their area, and the sums of their area normals and of
// their area-weighted centroids (relative to the grid origin).
struct OwnSurface {
  double area = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero(), centre = Eigen::Vector3d::Zero();
};

OwnSurface own_surface(const McOctree& tree, std::size_t node) {
  OwnSurface own;
  for (std::int32_t t = 0; t < tree.triangle_counts[node]; ++t) {
    const auto v = corners_of(tree, tree.triangles[std::size_t(tree.first_triangle[node] + t)]);
    const Eigen::Vector3d area_normal = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]);
    own.area += area_normal.norm();
    own.normal += area_normal;
    own.centre += area_normal.norm() * (v[0] + v[1] + v[2]) / 3.0;
  }
  return own;
}

// The LOD metric of every node above the leaves (0 for leaves).
void compute_metrics(LodMetric metric, const std::vector<LeafSums>& sums, McOctree* tree) {
  const std::size_t n = tree->size();
  tree->metrics.assign(n, 0.f);
  if (metric == LodMetric::kAreaDifference) {
    for (std::size_t node = 0; node < n; ++node) {
      if (tree->is_leaf(node)) continue;
      double children = 0.0;
      for (int c = 0; c < tree->child_counts[node]; ++c)
        children += own_surface(*tree, std::size_t(tree->first_child[node] + c)).area;
      tree->metrics[node] = float(children - own_surface(*tree, node).area);
    }
    return;
  }
  // Deviation: area times the RMS distance of the leaf surface from the plane
  // of the node's own triangles, or from its best-fitting plane where the node
  // has none; plus the surface the node adds or drops (a thin part it misses, a
  // sheet the leaves lack) at a quarter of its size. The own plane sees a node
  // whose cube is tilted or off the leaves as well as one over a bend: at 80 %
  // of the bunny's triangles it halved the error that the best-fitting plane's
  // residual alone left. Ranked per triangle the expansion adds.
  for (std::size_t node = 0; node < n; ++node) {
    if (tree->is_leaf(node)) continue;
    const LeafSums& leaf = sums[node];
    const OwnSurface own = own_surface(*tree, node);
    double deviation = 0.25 * std::fabs(leaf.area - own.area) * node_size(*tree, node);
    if (leaf.area > 0.0) {  // else a sheet over leaves that emit nothing
      double squared;       // sum of area x squared distance
      if (own.area > 0.0 && own.normal.norm() > 0.0) {
        const Eigen::Vector3d unit = own.normal.normalized();
        const double offset = unit.dot(own.centre / own.area);
        squared = unit.dot(leaf.second * unit) - 2.0 * offset * unit.dot(leaf.first) + offset * offset * leaf.area;
      } else {
        const Eigen::Matrix3d covariance = leaf.second - leaf.first * leaf.first.transpose() / leaf.area;
        squared = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly).eigenvalues()[0];
      }
      deviation += std::sqrt(leaf.area * std::max(0.0, squared));
    }
    int children = 0;
    for (int c = 0; c < tree->child_counts[node]; ++c)
      children += tree->triangle_counts[std::size_t(tree->first_child[node] + c)];
    tree->metrics[node] = float(deviation / double(std::max(1, children - int(tree->triangle_counts[node]))));
  }
}

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

// Moves each centre vertex to where the leaf triangles' planes under its node
// meet best (the quadric of seed 000's generalized quadrics, with the
// directions the planes do not pin down, eigenvalues under a tenth of the
// largest, left where they were): on a bend the fan's apex then sits off the
// surface, as far as its flat triangles need, instead of on it. At most half
// the node's size from the mean of the node's crossings. This made projecting
// the centre onto the field's zero set first redundant (without it the bunny's
// levels at R = 256 moved by at most 0.3 % of their error from 5 % up, and
// two field queries per node went).
void fit_centres(const std::vector<LeafSums>& sums, McOctree* tree) {
  const Eigen::Vector3d origin = tree->grid.origin;
  for (std::size_t node = 0; node < tree->internal_nodes(); ++node) {
    const std::int32_t v = tree->centre_vertices[node];
    if (v < 0) continue;
    const Eigen::Vector3d x0 = tree->positions[v].cast<double>() - origin;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(sums[node].planes);
    const Eigen::Vector3d values = solver.eigenvalues();
    const Eigen::Vector3d residual = sums[node].offsets - sums[node].planes * x0;
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k)
      if (values[k] > 0.1 * values[2] && values[k] > 0.0)
        step += solver.eigenvectors().col(k) * (solver.eigenvectors().col(k).dot(residual) / values[k]);
    const double size = node_size(*tree, node), limit = 0.5 * size;
    if (step.norm() > limit) step *= limit / step.norm();
    // Where the planes meet at one of the node's own crossings (a corner of
    // the surface), the fan's two triangles there would have no area: the
    // step is halved until the centre keeps clear of every crossing.
    auto clear_of_crossings = [&](const Eigen::Vector3d& x) {
      const Vec3f p = (x + origin).cast<float>();
      auto clear = [&](std::int32_t c) { return c < 0 || (tree->positions[std::size_t(c)] - p).norm() > 1e-3 * size; };
      return std::all_of(tree->edge_vertices[node].begin(), tree->edge_vertices[node].end(), clear) &&
             std::all_of(tree->sub_edge_vertices[node].begin(), tree->sub_edge_vertices[node].end(), clear);
    };
    for (int tries = 0; tries < 4 && !clear_of_crossings(x0 + step); ++tries) step *= 0.5;
    tree->positions[v] = (x0 + step + origin).cast<float>();
  }
}

// Moves centres whose transition fans would fold. A fan triangle whose side
// on the loop runs against the loop (seen from the centre) faces the wrong
// way: at R = 64 such triangles made every fold of the bunny's levels with
// normals more than 150 degrees apart. The loops depend on which neighbours
// are finer, so each node is tried on representative configurations (each
// face fine alone, every face fine; an edge split alone changed no fold's
// count on the bunny at R = 64 or 256, and cost 12 more); a centre that
// flips fewer fan triangles there replaces the fitted one: the nearest point
// where every fan triangle faces its loop's way (cyclic projections onto those
// half-spaces), else points towards the mean of the node's crossings or a
// loop's mean. Extraction still only reads the centre's index.
void unfold_centres(McOctree* tree) {
  // A finer node across each face alone, then across all six.
  std::vector<std::uint32_t> configurations;
  std::uint32_t all_faces = 0;
  for (const int c : splitting_cells())
    if (const std::uint32_t splits = cell_splits()[std::size_t(c)]; splits >> 12) {
      configurations.push_back(splits);
      all_faces |= splits;
    }
  configurations.push_back(all_faces);

  struct Side {
    Eigen::Vector3d a, b;  // a loop segment, in loop order
    int loop;
  };
  const std::int64_t internal = std::int64_t(tree->internal_nodes());
  // Each node moves only its own centre, which no other node's loops hold.
#pragma omp parallel
  {
    std::vector<Side> sides;
    std::vector<Eigen::Vector3d> loop_normals, loop_means;
    std::vector<int> loop_sizes;
    std::vector<Triangle> fans;
#pragma omp for schedule(dynamic, 256)
    for (std::int64_t node_index = 0; node_index < internal; ++node_index) {
      const std::size_t node = std::size_t(node_index);
      const std::int32_t centre = tree->centre_vertices[node];
      if (centre < 0) continue;
      sides.clear();
      loop_normals.clear();
      loop_means.clear();
      loop_sizes.clear();
      for (const std::uint32_t splits : configurations) {
        fans.clear();
        triangulate_transition({tree->boundary_inside[node], tree->edge_vertices[node].data(),
                                tree->sub_edge_vertices[node].data(), centre, std::uint8_t(splits >> 12),
                                std::uint16_t(splits & 0xfff)},
                               &fans);
        // A fan's triangles are (centre, loop[k + 1], loop[k]), one after
        // another: a loop ends where a triangle does not start at the last
        // one's loop[k + 1].
        const Triangle* previous = nullptr;
        for (const Triangle& t : fans) {
          if (t[0] != centre) continue;
          if (!previous || t[2] != (*previous)[1]) {
            loop_normals.push_back(Eigen::Vector3d::Zero());
            loop_means.push_back(Eigen::Vector3d::Zero());
            loop_sizes.push_back(0);
          }
          previous = &t;
          const Eigen::Vector3d a = tree->positions[t[1]].cast<double>(), b = tree->positions[t[2]].cast<double>();
          loop_normals.back() += a.cross(b);  // the loop's vector area, whatever the centre
          loop_means.back() += a;
          ++loop_sizes.back();
          sides.push_back({a, b, int(loop_normals.size()) - 1});
        }
      }
      for (std::size_t l = 0; l < loop_normals.size(); ++l) {
        loop_normals[l].normalize();
        loop_means[l] /= loop_sizes[l];
      }
      if (sides.empty()) continue;
      auto flips = [&](const Eigen::Vector3d& c) {
        int count = 0;
        for (const Side& s : sides) count += (s.a - c).cross(s.b - c).dot(loop_normals[std::size_t(s.loop)]) < 0.0;
        return count;
      };
      const Eigen::Vector3d fitted = tree->positions[centre].cast<double>();
      int best = flips(fitted);
      if (best == 0) continue;
      const double size = node_size(*tree, node);
      std::vector<Eigen::Vector3d> candidates;
      Eigen::Vector3d c = fitted;
      for (int round = 0; round < 100; ++round) {
        bool moved = false;
        for (const Side& s : sides) {
          // Side a -> b faces its loop's way from c when g . c + h > 0.
          const Eigen::Vector3d& n = loop_normals[std::size_t(s.loop)];
          const Eigen::Vector3d g = (s.a - s.b).cross(n);
          const double h = s.a.cross(s.b).dot(n), margin = 1e-3 * size * (s.a - s.b).norm(), value = g.dot(c) + h;
          if (value < margin && g.squaredNorm() > 0.0) c += (margin - value) / g.squaredNorm() * g, moved = true;
        }
        if (!moved) break;
      }
      candidates.push_back(c);
      Eigen::Vector3d own = Eigen::Vector3d::Zero();
      int count = 0;
      for (std::int32_t v : tree->edge_vertices[node])
        if (v >= 0) own += tree->positions[v].cast<double>(), ++count;
      if (count == 0)
        for (std::int32_t v : tree->sub_edge_vertices[node])
          if (v >= 0) own += tree->positions[v].cast<double>(), ++count;
      own /= double(std::max(1, count));
      for (double t : {0.25, 0.5, 0.75, 1.0}) candidates.push_back(fitted + t * (own - fitted));
      candidates.insert(candidates.end(), loop_means.begin(), loop_means.end());
      for (const Eigen::Vector3d& candidate : candidates) {
        const int f = flips(candidate);
        if (f < best) best = f, tree->positions[centre] = candidate.cast<float>();
      }
    }
  }
}

// Groups the hole patches by hole (triangles joined by shared edges) and gives
// each group the parents of the leaves along its rim.
void group_patches(const std::vector<Triangle>& patches, McOctree* tree) {
  tree->patch_triangles.clear();
  tree->patch_group_first = {0};
  tree->patch_needs_first = {0};
  tree->patch_needs.clear();
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
      for (std::int32_t t = 0; t < tree->triangle_counts[node]; ++t) {
        const Triangle& tri = tree->triangles[std::size_t(tree->first_triangle[node] + t)];
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
    if (leaf >= 0) needs[find(rim_triangle[i])].push_back(tree->parents[leaf]);
  }
  std::vector<std::vector<std::int32_t>> members(patches.size());
  for (std::size_t t = 0; t < patches.size(); ++t) members[find(std::int32_t(t))].push_back(std::int32_t(t));
  for (std::size_t g = 0; g < patches.size(); ++g) {
    if (members[g].empty()) continue;
    for (std::int32_t t : members[g]) tree->patch_triangles.push_back(patches[t]);
    tree->patch_group_first.push_back(std::int32_t(tree->patch_triangles.size()));
    auto& need = needs[g];
    std::sort(need.begin(), need.end());
    need.erase(std::unique(need.begin(), need.end()), need.end());
    tree->patch_needs.insert(tree->patch_needs.end(), need.begin(), need.end());
    tree->patch_needs_first.push_back(std::int32_t(tree->patch_needs.size()));
  }
}

}  // namespace

// Where the mesh field's sign may turn without a surface: along the mesh's rim
// (its boundary edges) and over hole patches; as points, searched with FLANN.
class SignHazards {
 public:
  SignHazards(const TriangleMesh& mesh, const std::vector<Triangle>& patches) {
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

  // Whether every hazard is farther than `distance` from p.
  bool farther_than(const Vec3f& p, double distance) const {
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

 private:
  // Its ends and midpoint: any point of it is within a quarter of its length of one.
  void add_segment(const Vec3f& a, const Vec3f& b) {
    points_.positions.push_back(a);
    points_.positions.push_back(b);
    points_.positions.push_back((a + b) * 0.5f);
    gap_ = std::max(gap_, 0.25 * double((b - a).norm()));
  }

  OrientedPoints points_;
  std::vector<Eigen::AlignedBox3f> boxes_;
  double gap_ = 0.0;
  std::unique_ptr<PointIndex> index_;
};

McOctree build_mc_octree(const CubeNodes& leaves, const TriangleMesh& mesh, const SignedDistanceField& field,
                         const OctreeOptions& options) {
  if (leaves.size() == 0) throw InputError("", "no leaf cube nodes: the reconstruction is empty");
  const int R = leaves.grid.resolution;
  int depth = 0;
  while ((1 << depth) < R) ++depth;
  McOctree tree;
  tree.grid = leaves.grid;
  tree.depth = depth;
  tree.positions = mesh.positions;
  tree.normals = mesh.normals;
  tree.colors = mesh.colors;
  tree.mesh_vertices = mesh.positions.size();

  // Keys per level, bottom-up; then ordered top-down so children are contiguous.
  std::vector<std::vector<std::uint64_t>> level_keys(depth + 1);
  level_keys[depth] = leaves.cube_keys;
  std::sort(level_keys[depth].begin(), level_keys[depth].end());
  for (int level = depth - 1; level >= 0; --level) {
    auto& keys = level_keys[level];
    keys.reserve(level_keys[level + 1].size() / 3 + 1);
    for (std::uint64_t k : level_keys[level + 1]) keys.push_back(parent_key(k));
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  }
  FlatHashMap leaf_index(leaves.size());
  for (std::size_t l = 0; l < leaves.size(); ++l) leaf_index.insert(leaves.cube_keys[l], std::int32_t(l));

  std::vector<FlatHashMap> node_index(depth + 1);
  std::vector<std::int32_t> level_begin(depth + 2, 0);
  auto add_node = [&](int level, std::uint64_t key, std::int32_t parent) {
    const std::int32_t id = std::int32_t(tree.keys.size());
    tree.keys.push_back(key);
    tree.levels.push_back(std::uint8_t(level));
    tree.parents.push_back(parent);
    tree.first_child.push_back(-1);
    tree.child_counts.push_back(0);
    node_index[level].insert(key, id);
  };
  add_node(0, level_keys[0].front(), -1);
  for (int level = 0; level < depth; ++level) {
    level_begin[level + 1] = std::int32_t(tree.keys.size());
    std::vector<std::pair<std::int32_t, std::uint64_t>> children;
    children.reserve(level_keys[level + 1].size());
    for (std::uint64_t k : level_keys[level + 1]) children.push_back({node_index[level].find(parent_key(k)), k});
    std::sort(children.begin(), children.end());
    for (auto [parent, key] : children) {
      if (tree.first_child[parent] < 0) tree.first_child[parent] = std::int32_t(tree.keys.size());
      ++tree.child_counts[parent];
      add_node(level + 1, key, parent);
    }
  }
  level_begin[depth + 1] = std::int32_t(tree.keys.size());
  const std::size_t n = tree.size();
  tree.cases.assign(n, 0);
  tree.edge_vertices.resize(n);
  tree.first_triangle.assign(n, 0);
  tree.triangle_counts.assign(n, 0);
  tree.metrics.assign(n, 0.f);

  // The vertex on a leaf-lattice edge (lower corner << 2 | axis): the vertex
  // of a leaf around that edge, else one added on it earlier, else -1. Only
  // walks that reach the leaves ask, so the up to four leaves are looked up
  // then rather than every leaf edge indexed beforehand.
  FlatHashMap added_on_edge(1024);
  auto edge_vertex = [&](std::uint64_t edge) {
    int x, y, z;
    unpack_key(edge >> 2, &x, &y, &z);
    const int axis = int(edge & 3);
    for (int e = 4 * axis; e < 4 * axis + 4; ++e) {
      const int c = edge_corner(e, 0);  // the edge's lower end, as a corner of the cube
      const int cx = x - (c & 1), cy = y - ((c >> 1) & 1), cz = z - ((c >> 2) & 1);
      if (cx < 0 || cy < 0 || cz < 0) continue;
      const std::int32_t l = leaf_index.find(pack_key(std::uint64_t(cx), std::uint64_t(cy), std::uint64_t(cz)));
      if (l >= 0 && leaves.edge_vertices[std::size_t(l)][e] >= 0) return leaves.edge_vertices[std::size_t(l)][e];
    }
    return added_on_edge.find(edge);
  };

  const std::vector<std::uint8_t> dropped = dropped_corners(leaves, mesh);
  LatticeSigns signs(leaves, field, dropped);
  // A point in a child cube the tree lacks has no leaf around it: no surface
  // crosses that cube, so the point takes the sign of the cube's corner at the
  // parent's centre, which the parent's children already hold (Fig. 5.2 gives
  // parents their children's signs the same way). Near the mesh's rim or a
  // hole patch the mesh field's sign can turn inside such a cube without a
  // surface (beyond a rim, or across a patch no leaf holds): there the field
  // is asked.
  const SignHazards hazards(mesh, leaves.patch_triangles);
  std::vector<std::int8_t> centre_usable(n, 0);  // 1 yes, -1 no, 0 not yet known
  const double cell = tree.grid.cube_size;
  signs.set_inference([&](std::uint64_t key, std::int32_t node, bool* inside) {
    int px, py, pz;
    unpack_key(key, &px, &py, &pz);
    for (;;) {  // down to the deepest node holding the point
      if (tree.first_child[node] < 0) return false;  // a leaf's corner the leaves dropped
      const int child_shift = depth - tree.levels[node] - 1;
      auto within = [&](int p, int lo) { return p >= (lo << child_shift) && p <= ((lo + 1) << child_shift); };
      std::int32_t next = -1;
      for (std::int32_t c = tree.first_child[node], end = c + tree.child_counts[node]; c < end && next < 0; ++c) {
        int cx, cy, cz;
        unpack_key(tree.keys[c], &cx, &cy, &cz);
        if (within(px, cx) && within(py, cy) && within(pz, cz)) next = c;
      }
      if (next < 0) break;
      node = next;
    }
    const int shift = depth - tree.levels[node];
    int x, y, z;
    unpack_key(tree.keys[node], &x, &y, &z);
    const int half = 1 << (shift - 1);
    const int cx = (x << shift) + half, cy = (y << shift) + half, cz = (z << shift) + half;
    const std::uint64_t centre = pack_key(cx, cy, cz);
    if (!signs.known(centre)) return false;
    std::int8_t& usable = centre_usable[std::size_t(node)];
    if (usable == 0) {
      // Every point of the child cube is within its diagonal of the centre,
      // and the centre, a corner of a child with surface, is within that
      // child's diagonal of the surface (unless the field said nearer).
      const double diagonal = std::sqrt(3.0) * cell * half;
      float v = 0.f;
      const double to_surface = signs.value(centre, &v) ? std::fabs(v) : diagonal;
      usable = hazards.farther_than(tree.grid.corner_position(cx, cy, cz), to_surface + 2.0 * diagonal + 2.0 * cell)
                   ? 1 : -1;
    }
    if (usable < 0) return false;
    *inside = signs.inside(centre);
    return true;
  });
  const auto& table = cube_cases();
  const std::size_t first_new_vertex = tree.positions.size();
  // Coarse edges resolved so far, per level: (lower lattice corner << 2 | axis) -> vertex.
  std::vector<FlatHashMap> edge_memo(depth + 1);

  // The vertex on each given level-`level` edge whose ends' signs differ: the
  // half that changes sign, recursively, down to a leaf edge.
  // slots[i].first: the node whose edge or sub-edge edges[i] is, which holds
  // the points its walk asks signs of.
  auto resolve_edges = [&](int level, const std::vector<std::uint64_t>& edges,
                           const std::vector<std::pair<std::int32_t, int>>& slots, std::vector<std::int32_t>* out) {
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
      signs.ensure(mids, &mid_nodes);
      std::vector<std::size_t> still;
      for (std::size_t i : open) {
        const std::uint64_t lower = current[i] >> 2;
        const int axis = int(current[i] & 3);
        const std::uint64_t mid = lower + (kAxisStep[axis] << half_shift);
        const std::uint64_t half_lower = signs.inside(lower) != signs.inside(mid) ? lower : mid;
        current[i] = (half_lower << 2) | std::uint64_t(axis);
        steps.push_back({i, l + 1, current[i]});
        const std::int32_t known = edge_memo[l + 1].find(current[i]);
        if (known >= 0) (*out)[i] = known;
        else still.push_back(i);
      }
      open.swap(still);
    }
    for (std::size_t i : open) {
      // A leaf edge: the mesh's vertex, or one interpolated where no leaf has it.
      std::int32_t v = edge_vertex(current[i]);
      if (v < 0) {
        const std::uint64_t lower = current[i] >> 2;
        const int axis = int(current[i] & 3);
        const std::uint64_t upper = lower + kAxisStep[axis];
        const float da = signs.exact(lower), db = signs.exact(upper);
        const float t = std::clamp(std::fabs(da) / (std::fabs(da) + std::fabs(db)), 1e-4f, 1.f - 1e-4f);
        int x, y, z;
        unpack_key(lower, &x, &y, &z);
        Vec3f p = tree.grid.corner_position(x, y, z);
        p[axis] += t * float(tree.grid.cube_size);
        v = std::int32_t(tree.positions.size());
        tree.positions.push_back(p);
        added_on_edge.insert(current[i], v);
      }
      (*out)[i] = v;
    }
    for (std::size_t i = 0; i < edges.size(); ++i) edge_memo[level].insert(edges[i], (*out)[i]);
    for (const Step& step : steps) edge_memo[step.level].insert(step.key, (*out)[step.edge]);
  };

  // Whether a node's case bits are the lattice's signs at its corners: all but
  // leaves with a corner the field decided (a dropped one).
  std::vector<std::uint8_t> cases_are_signs(n, 1);

  // Cases, edge vertices and triangles, level by level from the leaves up.
  for (int level = depth; level >= 0; --level) {
    const int shift = depth - level;
    const std::int32_t begin = level_begin[level], end = level_begin[level + 1];
    if (level == depth) {
      for (std::int32_t node = begin; node < end; ++node) {
        const std::int32_t l = leaf_index.find(tree.keys[node]);
        tree.cases[node] = leaves.cases[l];
        tree.edge_vertices[node] = leaves.edge_vertices[l];
      }
    } else {
      std::vector<std::uint64_t> corners;
      std::vector<std::int32_t> corner_nodes;
      corners.reserve(std::size_t(end - begin) * 8);
      corner_nodes.reserve(std::size_t(end - begin) * 8);
      for (std::int32_t node = begin; node < end; ++node)
        for (int c = 0; c < 8; ++c) {
          corners.push_back(corner_lattice_key(tree.keys[node], shift, c));
          corner_nodes.push_back(node);
        }
      signs.ensure(corners, &corner_nodes);
      std::vector<std::uint64_t> edges;
      std::vector<std::pair<std::int32_t, int>> slots;
      for (std::int32_t node = begin; node < end; ++node) {
        std::uint8_t mask = 0;
        for (int c = 0; c < 8; ++c) mask |= std::uint8_t(signs.inside(corners[std::size_t(node - begin) * 8 + c])) << c;
        tree.cases[node] = mask;
        tree.edge_vertices[node].fill(-1);
        for (int e = 0; e < 12; ++e) {
          if (!(table[mask].edge_mask >> e & 1)) continue;
          edges.push_back((corner_lattice_key(tree.keys[node], shift, edge_corner(e, 0)) << 2) | std::uint64_t(e / 4));
          slots.push_back({node, e});
        }
      }
      std::vector<std::int32_t> vertices;
      resolve_edges(level, edges, slots, &vertices);
      for (std::size_t i = 0; i < slots.size(); ++i) tree.edge_vertices[slots[i].first][slots[i].second] = vertices[i];
    }
    for (std::int32_t node = begin; node < end; ++node) {
      const CubeCase& cc = table[tree.cases[node]];
      const std::int32_t l = level == depth ? leaf_index.find(tree.keys[node]) : -1;
      if (l >= 0)
        for (std::int32_t corner : leaves.corners[std::size_t(l)]) cases_are_signs[std::size_t(node)] &= !dropped[std::size_t(corner)];
      tree.first_triangle[node] = std::int32_t(tree.triangles.size());
      for (int t = 0; t < cc.triangle_count; ++t) {
        if (l >= 0 && !(leaves.triangle_masks[l] >> t & 1)) continue;
        const auto& ev = tree.edge_vertices[node];
        tree.triangles.push_back({ev[cc.triangles[t][0]], ev[cc.triangles[t][1]], ev[cc.triangles[t][2]]});
      }
      tree.triangle_counts[node] = std::uint8_t(tree.triangles.size() - std::size_t(tree.first_triangle[node]));
    }
  }

  // Transition data for the nodes above the leaves: signs and crossings on the
  // boundary refined to the next level, and the neighbouring nodes.
  const std::int32_t internal = level_begin[depth];
  tree.boundary_inside.assign(std::size_t(internal), 0);
  tree.sub_edge_vertices.resize(std::size_t(internal));
  tree.neighbours.resize(std::size_t(internal));
  const auto& sub_edges = transition_sub_edges();
  auto lattice_key = [&](std::uint64_t key, int shift, int p) {
    int x, y, z;
    unpack_key(key, &x, &y, &z);
    const std::uint64_t half = 1ull << (shift - 1);
    return pack_key((std::uint64_t(x) << shift) + (p % 3) * half, (std::uint64_t(y) << shift) + (p / 3 % 3) * half,
                    (std::uint64_t(z) << shift) + (p / 9) * half);
  };
  for (int level = 0; level < depth; ++level) {
    const int shift = depth - level;
    const std::int32_t begin = level_begin[level], end = level_begin[level + 1];
    // The 27 points are the children's corners: an existing child's case
    // gives its 8 signs; the lattice only the rest.
    std::vector<std::uint32_t> covered(std::size_t(end - begin), 0);
    std::vector<std::uint64_t> points;
    std::vector<std::int32_t> point_nodes;
    for (std::int32_t node = begin; node < end; ++node) {
      int x, y, z;
      unpack_key(tree.keys[node], &x, &y, &z);
      std::uint32_t known = 0, inside = 0;
      for (std::int32_t c = tree.first_child[node], stop = c + tree.child_counts[node]; c < stop; ++c) {
        if (!cases_are_signs[std::size_t(c)]) continue;
        int cx, cy, cz;
        unpack_key(tree.keys[std::size_t(c)], &cx, &cy, &cz);
        const int octant = (cx - 2 * x) + 3 * (cy - 2 * y) + 9 * (cz - 2 * z);  // its lowest lattice point
        for (int k = 0; k < 8; ++k) {
          const int p = octant + (k & 1) + 3 * ((k >> 1) & 1) + 9 * ((k >> 2) & 1);
          known |= 1u << p;
          inside |= std::uint32_t((tree.cases[std::size_t(c)] >> k) & 1) << p;
        }
      }
      covered[std::size_t(node - begin)] = known;
      tree.boundary_inside[node] = inside;
      for (int p = 0; p < 27; ++p)
        if (!((known >> p) & 1)) {
          points.push_back(lattice_key(tree.keys[node], shift, p));
          point_nodes.push_back(node);
        }
    }
    signs.ensure(points, &point_nodes);
    std::vector<std::uint64_t> edges;
    std::vector<std::pair<std::int32_t, int>> slots;
    std::size_t next_point = 0;
    for (std::int32_t node = begin; node < end; ++node) {
      std::uint32_t inside = tree.boundary_inside[node];
      for (int p = 0; p < 27; ++p)
        if (!((covered[std::size_t(node - begin)] >> p) & 1)) inside |= std::uint32_t(signs.inside(points[next_point++])) << p;
      tree.boundary_inside[node] = inside;
      tree.sub_edge_vertices[node].fill(-1);
      for (int e = 0; e < kSubEdges; ++e) {
        const SubEdge& se = sub_edges[e];
        if (((inside >> se.a) & 1) == ((inside >> se.b) & 1)) continue;
        const int axis = (se.b - se.a) == 1 ? 0 : (se.b - se.a) == 3 ? 1 : 2;
        edges.push_back((lattice_key(tree.keys[node], shift, se.a) << 2) | std::uint64_t(axis));
        slots.push_back({node, e});
      }
      int x, y, z;
      unpack_key(tree.keys[node], &x, &y, &z);
      // A neighbour is a child of the parent or of one of the parent's
      // neighbours (found a level earlier): a scan of at most 8 children
      // instead of a hash lookup.
      const std::int32_t parent = tree.parents[node];
      for (int c = 0; c < 27; ++c) {
        if (parent < 0) {
          tree.neighbours[node][c] = c == 13 ? node : -1;
          continue;
        }
        const int nx = x + c % 3 - 1, ny = y + c / 3 % 3 - 1, nz = z + c / 9 - 1;
        // >> 1 rounds -1 down to -1: outside the parent's lattice too.
        const int up = ((nx >> 1) - (x >> 1) + 1) + 3 * ((ny >> 1) - (y >> 1) + 1) + 9 * ((nz >> 1) - (z >> 1) + 1);
        const std::int32_t above = tree.neighbours[std::size_t(parent)][up];
        std::int32_t found = -1;
        if (above >= 0) {
          const std::uint64_t key = pack_key(std::uint64_t(nx), std::uint64_t(ny), std::uint64_t(nz));
          for (std::int32_t k = tree.first_child[above], end = k + tree.child_counts[above]; k < end; ++k)
            if (tree.keys[std::size_t(k)] == key) found = k;
        }
        tree.neighbours[node][c] = found;
      }
    }
    std::vector<std::int32_t> vertices;
    resolve_edges(level + 1, edges, slots, &vertices);
    for (std::size_t i = 0; i < slots.size(); ++i) tree.sub_edge_vertices[slots[i].first][slots[i].second] = vertices[i];
  }

  const std::vector<LeafSums> sums = leaf_sums(tree, std::size_t(internal));
  compute_metrics(options.metric, sums, &tree);

  // Added vertices take normals from the triangles around them, colours from
  // their neighbours.
  const std::size_t total = tree.positions.size();
  if (total > first_new_vertex) {
    tree.normals.resize(total, Vec3f::Zero());
    std::vector<Vec3f> colour_sum(total, Vec3f::Zero());
    std::vector<float> colour_count(total, 0.f);
    const bool colours = !tree.colors.empty();
    if (colours) tree.colors.resize(total, Rgb{0, 0, 0});
    for (const Triangle& t : tree.triangles) {
      const Vec3f nrm = (tree.positions[t[1]] - tree.positions[t[0]]).cross(tree.positions[t[2]] - tree.positions[t[0]]);
      for (int k = 0; k < 3; ++k) {
        if (std::size_t(t[k]) < first_new_vertex) continue;
        tree.normals[t[k]] += nrm;
        for (int j = 1; j < 3 && colours; ++j) {
          const std::int32_t other = t[(k + j) % 3];
          if (std::size_t(other) >= first_new_vertex) continue;
          colour_sum[t[k]] += Vec3f(tree.colors[other][0], tree.colors[other][1], tree.colors[other][2]);
          colour_count[t[k]] += 1.f;
        }
      }
    }
    for (std::size_t v = first_new_vertex; v < total; ++v) {
      tree.normals[v] = tree.normals[v].norm() > 0.f ? Vec3f(tree.normals[v].normalized()) : Vec3f::UnitZ();
      if (colours && colour_count[v] > 0.f) {
        const Vec3f c = colour_sum[v] / colour_count[v];
        tree.colors[v] = Rgb{std::uint8_t(c[0] + 0.5f), std::uint8_t(c[1] + 0.5f), std::uint8_t(c[2] + 0.5f)};
      }
    }
  }
  group_patches(leaves.patch_triangles, &tree);

  // Each node above the leaves gets a centre vertex for its transition fans:
  // the mean of its own crossings (of its boundary's where it has none), then
  // fitted to the leaves' planes below (fit_centres).
  tree.centre_vertices.assign(std::size_t(internal), -1);
  for (std::int32_t node = 0; node < internal; ++node) {
    Vec3f p = Vec3f::Zero(), nrm = Vec3f::Zero(), colour = Vec3f::Zero();
    int count = 0;
    auto add = [&](std::int32_t v) {
      if (v < 0) return;
      p += tree.positions[v];
      nrm += tree.normals[v];
      if (!tree.colors.empty()) colour += Vec3f(tree.colors[v][0], tree.colors[v][1], tree.colors[v][2]);
      ++count;
    };
    for (std::int32_t v : tree.edge_vertices[node]) add(v);
    if (count == 0)
      for (std::int32_t v : tree.sub_edge_vertices[node]) add(v);
    if (count == 0) continue;  // nothing crosses its boundary: it never needs a fan
    tree.centre_vertices[node] = std::int32_t(tree.positions.size());
    tree.positions.push_back(p / float(count));
    tree.normals.push_back(nrm.norm() > 0.f ? Vec3f(nrm.normalized()) : Vec3f::UnitZ());
    if (!tree.colors.empty()) {
      const Vec3f c = colour / float(count);
      tree.colors.push_back(Rgb{std::uint8_t(c[0] + 0.5f), std::uint8_t(c[1] + 0.5f), std::uint8_t(c[2] + 0.5f)});
    }
  }
  fit_centres(sums, &tree);
  unfold_centres(&tree);
  return tree;
}

McOctree build_mc_octree(const Reconstruction& reconstruction, const OctreeOptions& options) {
  // The field's setup, which builds Open3D's BVH, takes a quarter of a
  // second at R = 256: on a second thread it overlaps the octree's skeleton,
  // which needs no field.
  const TriangleMesh& mesh = reconstruction.mesh;
  std::shared_future<SignedDistanceField> ready =
      std::async(std::launch::async, [&mesh] { return mesh_distance_field(mesh); }).share();
  const SignedDistanceField field = [ready](const std::vector<Vec3f>& q, std::vector<float>* d) { ready.get()(q, d); };
  return build_mc_octree(reconstruction.leaves, mesh, field, options);
}

}  // namespace scan2lod
