#include "reconstruct/marching_cubes.h"

#include "core/error.h"
#include "core/flat_hash.h"
#include "core/progress.h"
#include "reconstruct/cube_table.h"
#include "reconstruct/hole_filling.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

namespace scan2lod {
namespace {

constexpr std::uint64_t kAxisStep[3] = {1ull, 1ull << 20, 1ull << 40};

std::uint64_t corner_key_of(std::uint64_t cube_key, int corner) {
  return cube_key + (corner & 1) * kAxisStep[0] + ((corner >> 1) & 1) * kAxisStep[1] +
         ((corner >> 2) & 1) * kAxisStep[2];
}

void check_points(const OrientedPoints& points) {
  if (points.size() == 0) throw InputError("", "no input points: nothing to reconstruct");
  if (points.normals.size() != points.size()) throw InputError("", "input points lack normals");
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points.positions[i].allFinite())
      throw InputError("", "input point " + std::to_string(i) + " has non-finite coordinates");
    if (!points.normals[i].allFinite())
      throw InputError("", "input point " + std::to_string(i) + " has a non-finite normal");
  }
}

// The face (axis, side) of a cube that holds both local edges, or -1.
int shared_face(int e0, int e1) {
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      bool both = true;
      for (int e : {e0, e1})
        for (int end = 0; end < 2; ++end) both &= ((edge_corner(e, end) >> axis) & 1) == side;
      if (both) return axis * 2 + side;
    }
  return -1;
}

struct UnionFind {
  std::vector<std::int32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::int32_t find(std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::int32_t a, std::int32_t b) { parent[find(a)] = find(b); }
};

// The sparse grid and the surface on it, built in stages: seed cubes, surface
// following, piece removal, hole closing, and the final emission.
class SurfaceBuilder {
 public:
  SurfaceBuilder(const OrientedPoints& points, const ReconstructOptions& options)
      : points_(points),
        options_(options),
        threads_(options.threads > 0 ? options.threads : omp_get_max_threads()),
        grid_(make_cube_grid(bounds(points.positions), options.resolution)),
        h_(float(grid_.cube_size)),
        index_(points),
        have_spacing_(points.spacing.size() == points.size()) {}

  const CubeGrid& grid() const { return grid_; }
  const PointIndex& index() const { return index_; }
  std::size_t cube_count() const { return cube_keys_.size(); }
  std::size_t corner_count() const { return corner_keys_.size(); }
  std::size_t grown_cubes() const { return std::size_t(std::count(grown_.begin(), grown_.end(), 1)); }
  std::size_t usable_cubes() const { return std::size_t(std::count(usable_.begin(), usable_.end(), 1)); }

  // Cubes that hold points, grown by `margin`, then every cube the surface
  // leads into across a face, while its centre stays within reach of the data.
  std::size_t follow_surface(Progress& progress) {
    add_seed_cubes();
    std::size_t rounds = 0;
    for (std::size_t begin = 0; begin < cube_keys_.size(); ++rounds) {
      const std::size_t end = cube_keys_.size();
      if (begin > 0) judge_reach(begin, end);
      evaluate_corners(begin, end, options_.distance, &progress);
      for (std::size_t c = begin; c < end; ++c)
        if (usable_[c]) add_crossed_neighbours(c);
      begin = end;
    }
    return rounds - 1;
  }

  // Triangulates every usable cube with all corners defined and a sign change.
  // triangle_cube and triangle_slot say which cube, and which of its case's
  // triangles, each mesh triangle is.
  void emit(CubeNodes* leaves, TriangleMesh* mesh, std::vector<std::int32_t>* triangle_cube,
            std::vector<std::uint8_t>* triangle_slot) {
    const auto& table = cube_cases();
    *leaves = CubeNodes{};
    *mesh = TriangleMesh{};
    triangle_cube->clear();
    triangle_slot->clear();
    leaves->grid = grid_;
    std::vector<std::int32_t>& source = leaf_cube_;
    source.clear();
    emitting_.assign(cube_keys_.size(), 0);
    for (std::size_t c = 0; c < cube_keys_.size(); ++c) {
      std::uint8_t mask;
      if (!usable_[c] || !cube_case(c, &mask) || mask == 0 || mask == 255) continue;
      if ((masks_[c] & ((1u << table[mask].triangle_count) - 1)) == 0) continue;
      leaves->cube_keys.push_back(cube_keys_[c]);
      leaves->cases.push_back(mask);
      leaves->triangle_masks.push_back(masks_[c]);
      leaves->corners.push_back(cube_corners_[c]);
      source.push_back(std::int32_t(c));
      emitting_[c] = 1;
    }
    // One shared vertex per crossed grid edge, keyed by its lower corner and axis.
    FlatHashMap edge_index(leaves->size() * 2);
    leaves->edge_vertices.resize(leaves->size());
    leaves->edge_ratios.resize(leaves->size());
    for (std::size_t l = 0; l < leaves->size(); ++l) {
      const CubeCase& cc = table[leaves->cases[l]];
      auto& ev = leaves->edge_vertices[l];
      auto& er = leaves->edge_ratios[l];
      ev.fill(-1);
      er.fill(0.f);
      for (int e = 0; e < 12; ++e) {
        if (!(cc.edge_mask >> e & 1)) continue;
        const int a = edge_corner(e, 0), b = edge_corner(e, 1);
        const float da = corner_distances_[leaves->corners[l][a]];
        const float db = corner_distances_[leaves->corners[l][b]];
        // Ratio of |distances| (seed §4.2), kept off the corners so no triangle collapses.
        const float t = std::clamp(std::fabs(da) / (std::fabs(da) + std::fabs(db)), 1e-4f, 1.f - 1e-4f);
        er[e] = t;
        const std::uint64_t lower = corner_key_of(leaves->cube_keys[l], a);
        const std::int32_t fresh = std::int32_t(mesh->positions.size());
        const std::int32_t id = edge_index.insert((lower << 2) | std::uint64_t(e / 4), fresh);
        if (id == fresh) {
          int x, y, z;
          unpack_key(lower, &x, &y, &z);
          Vec3f p = grid_.corner_position(x, y, z);
          p[e / 4] += t * h_;
          mesh->positions.push_back(p);
        }
        ev[e] = id;
      }
      for (int t = 0; t < cc.triangle_count; ++t) {
        if (!(leaves->triangle_masks[l] >> t & 1)) continue;
        mesh->triangles.push_back({ev[cc.triangles[t][0]], ev[cc.triangles[t][1]], ev[cc.triangles[t][2]]});
        triangle_cube->push_back(source[l]);
        triangle_slot->push_back(std::uint8_t(t));
      }
    }
    // Only the corners of emitting cubes are kept with the leaves.
    std::vector<std::int32_t> remap(corner_keys_.size(), -1);
    for (auto& corners : leaves->corners) {
      for (std::int32_t& id : corners) {
        if (remap[id] < 0) {
          remap[id] = std::int32_t(leaves->corner_keys.size());
          leaves->corner_keys.push_back(corner_keys_[id]);
          leaves->corner_distances.push_back(corner_distances_[id]);
          if (points_.has_colors()) leaves->corner_colors.push_back(points_.colors[corner_nearest_[id]]);
        }
        id = remap[id];
      }
    }
  }

  // Drops pieces of the surface with fewer than `fraction` of its triangles:
  // the specks and fins that noisy scans leave off thin edges. A piece can share
  // a cube with a kept one, so pieces are dropped triangle by triangle, through
  // the cube's mask of kept case triangles.
  std::size_t drop_small_pieces(const TriangleMesh& mesh, const std::vector<std::int32_t>& triangle_cube,
                                const std::vector<std::uint8_t>& triangle_slot, double fraction) {
    if (fraction <= 0.0 || mesh.triangles.empty()) return 0;
    UnionFind uf(mesh.positions.size());
    for (const Triangle& t : mesh.triangles) uf.unite(t[0], t[1]), uf.unite(t[1], t[2]);
    std::vector<std::int32_t> size(mesh.positions.size(), 0);
    for (const Triangle& t : mesh.triangles) ++size[uf.find(t[0])];
    const double limit = fraction * double(mesh.triangles.size());
    std::size_t dropped = 0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      if (size[uf.find(mesh.triangles[t][0])] >= limit) continue;
      masks_[triangle_cube[t]] &= std::uint16_t(~(1u << triangle_slot[t]));
      ++dropped;
    }
    return dropped;
  }

  // One round of hole closing: every cube across an open face of a boundary
  // loop of at most `max_edges` edges is made usable, its missing corners
  // evaluated under relaxed distance limits. Returns the number of cubes added.
  std::size_t grow_into_small_holes(const CubeNodes& leaves, std::size_t vertex_count, std::size_t max_edges) {
    const std::vector<OpenEdge> open = open_edges(leaves);
    if (open.empty()) return 0;
    UnionFind loops(vertex_count);
    for (const OpenEdge& e : open) loops.unite(e.a, e.b);
    std::vector<std::int32_t> loop_edges(vertex_count, 0);
    for (const OpenEdge& e : open) ++loop_edges[loops.find(e.a)];
    // Each hole keeps one id across rounds: a loop inherits the ids of the grown
    // cubes on its rim, and ids that meet in one loop are merged.
    std::vector<std::int32_t> loop_hole(vertex_count, -1);
    for (const OpenEdge& e : open) {
      const std::int32_t root = loops.find(e.a);
      if (std::size_t(loop_edges[root]) > max_edges) continue;
      if (loop_hole[root] < 0) loop_hole[root] = new_hole();
      if (hole_of_[e.cube] >= 0) unite_holes(loop_hole[root], hole_of_[e.cube]);
    }
    std::vector<std::int32_t> grow;
    for (const OpenEdge& e : open) {
      const std::int32_t root = loops.find(e.a);
      if (loop_hole[root] < 0) continue;
      std::uint64_t key;
      if (!neighbour_key(e.cube, e.face, &key)) continue;
      std::int32_t id = cube_index_.find(key);
      if (id < 0) {
        add_cube(key);
        id = std::int32_t(cube_keys_.size() - 1);
        usable_[id] = 0;
      }
      std::uint8_t mask;
      if (grown_[id] || (usable_[id] && cube_case(std::size_t(id), &mask))) continue;
      grow.push_back(id);
      hole_of_[id] = loop_hole[root];
    }
    std::sort(grow.begin(), grow.end());
    grow.erase(std::unique(grow.begin(), grow.end()), grow.end());
    if (grow.empty()) return 0;
    SignedDistanceOptions relaxed = options_.distance;
    relaxed.max_distance *= 2.f;
    for (std::int32_t c : grow) usable_[c] = 1, grown_[c] = 1;
    evaluate_corners_of(grow, relaxed, nullptr);
    return grow.size();
  }

  // Keeps the cubes grown into a hole only where the hole closed: the cubes of a
  // hole that still has an open edge are given up, since the surface they added
  // would only be a lip around a hole that stays.
  std::size_t give_up_open_growth(const CubeNodes& leaves) {
    std::vector<std::uint8_t> open(hole_parent_.size(), 0);
    for (const OpenEdge& e : open_edges(leaves)) {
      if (hole_of_[e.cube] >= 0) open[find_hole(hole_of_[e.cube])] = 1;
      const std::int32_t n = neighbour(e.cube, e.face);
      if (n >= 0 && hole_of_[n] >= 0) open[find_hole(hole_of_[n])] = 1;
    }
    std::size_t given_up = 0;
    for (std::size_t c = 0; c < cube_keys_.size(); ++c)
      if (grown_[c] && open[find_hole(hole_of_[c])]) usable_[c] = 0, grown_[c] = 0, ++given_up;
    return given_up;
  }

 private:
  std::int32_t new_hole() {
    hole_parent_.push_back(std::int32_t(hole_parent_.size()));
    return hole_parent_.back();
  }
  std::int32_t find_hole(std::int32_t h) {
    while (hole_parent_[h] != h) h = hole_parent_[h] = hole_parent_[hole_parent_[h]];
    return h;
  }
  void unite_holes(std::int32_t a, std::int32_t b) { hole_parent_[find_hole(a)] = find_hole(b); }

  struct OpenEdge {
    std::int32_t a, b;  // mesh vertices
    std::int32_t cube;
    int face;           // axis * 2 + side
  };

  // Edges of the surface used by one triangle, found cube by cube: a triangle
  // edge on a cube face is open when the cube across that face emits nothing
  // (two cubes sharing a face always join its crossings the same way).
  std::vector<OpenEdge> open_edges(const CubeNodes& leaves) const {
    static const auto face_of = [] {
      std::array<std::array<std::int8_t, 12>, 12> f{};
      for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j) f[i][j] = std::int8_t(i == j ? -1 : shared_face(i, j));
      return f;
    }();
    const auto& table = cube_cases();
    std::vector<OpenEdge> open;
    for (std::size_t l = 0; l < leaves.size(); ++l) {
      const CubeCase& cc = table[leaves.cases[l]];
      const std::int32_t cube = leaf_cube_[l];
      for (int t = 0; t < cc.triangle_count; ++t) {
        if (!(leaves.triangle_masks[l] >> t & 1)) continue;
        for (int k = 0; k < 3; ++k) {
          const int e0 = cc.triangles[t][k], e1 = cc.triangles[t][(k + 1) % 3];
          const int face = face_of[e0][e1];
          if (face < 0) continue;
          const std::int32_t n = neighbour(cube, face);
          if (n >= 0 && emitting_[n]) continue;
          open.push_back({leaves.edge_vertices[l][e0], leaves.edge_vertices[l][e1], cube, face});
        }
      }
    }
    return open;
  }

  // The key of the cube across a face; false when that is outside the grid.
  bool neighbour_key(std::int32_t c, int face, std::uint64_t* key) const {
    const int axis = face / 2, side = face % 2;
    int xyz[3];
    unpack_key(cube_keys_[c], &xyz[0], &xyz[1], &xyz[2]);
    const int n = xyz[axis] + (side ? 1 : -1);
    if (n < 0 || n >= grid_.resolution) return false;
    *key = side ? cube_keys_[c] + kAxisStep[axis] : cube_keys_[c] - kAxisStep[axis];
    return true;
  }

  // The cube across a face, or -1 when it is outside the grid or not yet known.
  std::int32_t neighbour(std::int32_t c, int face) const {
    std::uint64_t key;
    return neighbour_key(c, face, &key) ? cube_index_.find(key) : -1;
  }

  void add_seed_cubes() {
    const int R = grid_.resolution;
    std::vector<std::uint64_t> seeds(points_.size());
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (std::size_t i = 0; i < points_.size(); ++i) {
      Vec3d g = (points_.positions[i].cast<double>() - grid_.origin) / grid_.cube_size;
      int c[3];
      for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor(g[a])), 0, R - 1);
      seeds[i] = pack_key(c[0], c[1], c[2]);
    }
    std::sort(seeds.begin(), seeds.end());
    seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
    const int m = options_.margin;
    cube_index_.reserve(seeds.size() * (m > 0 ? 4 : 1) * 5 / 4);
    corner_index_.reserve(seeds.size() * 2);
    for (std::uint64_t key : seeds) {
      int x, y, z;
      unpack_key(key, &x, &y, &z);
      for (int dz = -m; dz <= m; ++dz)
        for (int dy = -m; dy <= m; ++dy)
          for (int dx = -m; dx <= m; ++dx) {
            const int nx = x + dx, ny = y + dy, nz = z + dz;
            if (nx < 0 || ny < 0 || nz < 0 || nx >= R || ny >= R || nz >= R) continue;
            add_cube(pack_key(nx, ny, nz));
          }
    }
  }

  void add_cube(std::uint64_t key) {
    const std::int32_t id = std::int32_t(cube_keys_.size());
    if (cube_index_.insert(key, id) != id) return;
    cube_keys_.push_back(key);
    usable_.push_back(1);
    grown_.push_back(0);
    hole_of_.push_back(-1);
    masks_.push_back(0xffff);
    cube_corners_.emplace_back();
    cube_corners_.back().fill(-1);
  }

  // Cubes reached by following are usable while their centre is near a point.
  void judge_reach(std::size_t begin, std::size_t end) {
    std::vector<Vec3f> centres(end - begin);
    for (std::size_t c = begin; c < end; ++c) {
      int x, y, z;
      unpack_key(cube_keys_[c], &x, &y, &z);
      centres[c - begin] = grid_.corner_position(x, y, z) + Vec3f::Constant(0.5f * h_);
    }
    std::vector<std::int32_t> nn(centres.size());
    std::vector<float> d2(centres.size());
    index_.knn(centres.data(), centres.size(), 1, nn.data(), d2.data(), threads_);
    for (std::size_t i = 0; i < centres.size(); ++i) {
      const float limit = options_.reach * scale(nn[i]);
      usable_[begin + i] = d2[i] <= limit * limit;
    }
  }

  float scale(std::int32_t point) const {
    return std::max(h_, have_spacing_ ? points_.spacing[point] : 0.f);
  }

  void evaluate_corners(std::size_t begin, std::size_t end, const SignedDistanceOptions& distance,
                        Progress* progress) {
    std::vector<std::int32_t> cubes;
    for (std::size_t c = begin; c < end; ++c)
      if (usable_[c]) cubes.push_back(std::int32_t(c));
    evaluate_corners_of(cubes, distance, progress);
  }

  // Gives the cubes their corners; corners never seen, or still undefined, are
  // evaluated (in chunks, so progress moves while FLANN works).
  void evaluate_corners_of(const std::vector<std::int32_t>& cubes, const SignedDistanceOptions& distance,
                           Progress* progress) {
    std::vector<std::int32_t> todo;
    for (std::int32_t c : cubes) {
      for (int k = 0; k < 8; ++k) {
        const std::uint64_t ck = corner_key_of(cube_keys_[c], k);
        const std::int32_t fresh = std::int32_t(corner_keys_.size());
        const std::int32_t id = corner_index_.insert(ck, fresh);
        if (id == fresh) {
          corner_keys_.push_back(ck);
          corner_distances_.push_back(std::numeric_limits<float>::quiet_NaN());
          corner_nearest_.push_back(-1);
          corner_relaxed_.push_back(0);
          todo.push_back(id);
        } else if (std::isnan(corner_distances_[id]) && distance.max_distance > options_.distance.max_distance) {
          todo.push_back(id);
        }
        cube_corners_[c][k] = id;
      }
    }
    std::sort(todo.begin(), todo.end());
    todo.erase(std::unique(todo.begin(), todo.end()), todo.end());
    const std::uint8_t relaxed = distance.max_distance > options_.distance.max_distance;
    const std::size_t chunk = 1 << 16;
    std::vector<Vec3f> queries;
    std::vector<float> d;
    std::vector<std::int32_t> nearest;
    for (std::size_t b = 0; b < todo.size(); b += chunk) {
      const std::size_t e = std::min(todo.size(), b + chunk);
      queries.resize(e - b);
      for (std::size_t i = b; i < e; ++i) {
        int x, y, z;
        unpack_key(corner_keys_[todo[i]], &x, &y, &z);
        queries[i - b] = grid_.corner_position(x, y, z);
      }
      signed_distances(points_, index_, queries, h_, distance, threads_, &d, &nearest);
      for (std::size_t i = b; i < e; ++i) {
        corner_distances_[todo[i]] = d[i - b];
        corner_relaxed_[todo[i]] = relaxed;
        corner_nearest_[todo[i]] = nearest[i - b];
      }
      if (progress) progress->advance(e - b);
    }
  }

  // A face with a sign change on defined corners leads into the neighbouring
  // cube, which must be evaluated too or the surface would end there.
  void add_crossed_neighbours(std::size_t c) {
    int xyz[3];
    unpack_key(cube_keys_[c], &xyz[0], &xyz[1], &xyz[2]);
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        int inside = 0, defined = 0;
        for (int k = 0; k < 8; ++k) {
          if (((k >> axis) & 1) != side) continue;
          const float d = corner_distances_[cube_corners_[c][k]];
          if (std::isnan(d)) break;
          ++defined;
          inside += d < 0.f;
        }
        if (defined != 4 || inside == 0 || inside == 4) continue;
        const int n = xyz[axis] + (side ? 1 : -1);
        if (n < 0 || n >= grid_.resolution) continue;
        add_cube(side ? cube_keys_[c] + kAxisStep[axis] : cube_keys_[c] - kAxisStep[axis]);
      }
    }
  }

  // Corners defined only under the relaxed limits of hole closing serve the
  // cubes grown into holes, not the cubes around them.
  bool cube_case(std::size_t c, std::uint8_t* mask) const {
    *mask = 0;
    for (int k = 0; k < 8; ++k) {
      const std::int32_t id = cube_corners_[c][k];
      if (id < 0 || std::isnan(corner_distances_[id])) return false;
      if (corner_relaxed_[id] && !grown_[c]) return false;
      *mask |= std::uint8_t(corner_distances_[id] < 0.f) << k;
    }
    return true;
  }

  const OrientedPoints& points_;
  const ReconstructOptions& options_;
  const int threads_;
  const CubeGrid grid_;
  const float h_;
  PointIndex index_;
  const bool have_spacing_;

  FlatHashMap cube_index_;
  std::vector<std::uint64_t> cube_keys_;
  std::vector<std::uint8_t> usable_;
  std::vector<std::uint16_t> masks_;  // kept triangles of the cube's case
  std::vector<std::array<std::int32_t, 8>> cube_corners_;
  FlatHashMap corner_index_;
  std::vector<std::uint64_t> corner_keys_;
  std::vector<float> corner_distances_;
  std::vector<std::int32_t> corner_nearest_;
  std::vector<std::uint8_t> corner_relaxed_;
  std::vector<std::uint8_t> grown_;  // added by hole closing
  std::vector<std::int32_t> hole_of_;      // per cube: the hole it was grown into, or -1
  std::vector<std::int32_t> hole_parent_;  // union-find over hole ids
  std::vector<std::int32_t> leaf_cube_;  // of the last emission
  std::vector<std::uint8_t> emitting_;   // of the last emission, per cube
};

}  // namespace

std::vector<Vec3f> vertex_normals(const TriangleMesh& mesh) {
  std::vector<Vec3f> normals(mesh.positions.size(), Vec3f::Zero());
  for (const Triangle& t : mesh.triangles) {
    const Vec3f& a = mesh.positions[t[0]];
    const Vec3f n = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);  // |n| = 2 area
    for (int k = 0; k < 3; ++k) normals[t[k]] += n;
  }
  for (Vec3f& n : normals) {
    const float l = n.norm();
    n = l > 0.f ? Vec3f(n / l) : Vec3f::Zero();
  }
  return normals;
}

Reconstruction reconstruct(const OrientedPoints& points, const ReconstructOptions& options) {
  check_points(points);
  Reconstruction result;
  ReconstructStats& stats = result.stats;
  stats.points = points.size();
  using clock = std::chrono::steady_clock;
  auto lap = [t = clock::now()]() mutable {
    const auto now = clock::now();
    const double s = std::chrono::duration<double>(now - t).count();
    t = now;
    return s;
  };
  SurfaceBuilder builder(points, options);
  stats.seconds_index = lap();
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  {
    Progress progress("signed distances", points.size());
    stats.following_rounds = builder.follow_surface(progress);
  }
  stats.seconds_distances = lap();
  TriangleMesh& mesh = result.mesh;
  std::vector<std::int32_t> triangle_cube;
  std::vector<std::uint8_t> triangle_slot;
  builder.emit(&result.leaves, &mesh, &triangle_cube, &triangle_slot);
  stats.seconds_emit = lap();
  auto drop_pieces = [&] {
    if (options.min_piece <= 0.0) return;
    const std::size_t dropped = builder.drop_small_pieces(mesh, triangle_cube, triangle_slot, options.min_piece);
    stats.triangles_dropped += dropped;
    if (dropped) builder.emit(&result.leaves, &mesh, &triangle_cube, &triangle_slot);
  };
  drop_pieces();
  if (options.max_hole > 0.0) {
    const std::size_t max_edges = std::size_t(options.max_hole * options.resolution);
    for (int round = 0; round < options.hole_rounds; ++round) {
      const std::size_t grown = builder.grow_into_small_holes(result.leaves, mesh.positions.size(), max_edges);
      if (grown == 0) break;
      builder.emit(&result.leaves, &mesh, &triangle_cube, &triangle_slot);
    }
    if (builder.give_up_open_growth(result.leaves) > 0)
      builder.emit(&result.leaves, &mesh, &triangle_cube, &triangle_slot);
    stats.cubes_hole_closing = builder.grown_cubes();
    drop_pieces();
    // What marching on could not close gets triangles over its rim.
    const std::vector<Triangle> patch = fill_small_holes(mesh, max_edges);
    result.leaves.patch_triangles = patch;
    mesh.triangles.insert(mesh.triangles.end(), patch.begin(), patch.end());
    stats.patch_triangles = patch.size();
  }
  stats.seconds_cleanup = lap();
  stats.cubes_touched = builder.usable_cubes();
  stats.corners_evaluated = builder.corner_count();
  stats.cubes_emitting = result.leaves.size();

  mesh.normals = vertex_normals(mesh);
  if (points.has_colors()) {
    // Vertex colour: Gaussian-weighted mean of the nearest points' colours.
    const int k = std::min<int>(8, int(points.size()));
    std::vector<std::int32_t> idx(mesh.positions.size() * k);
    std::vector<float> d2(mesh.positions.size() * k);
    builder.index().knn(mesh.positions.data(), mesh.positions.size(), k, idx.data(), d2.data(), threads);
    mesh.colors.resize(mesh.positions.size());
    const float h = float(builder.grid().cube_size);
    const float inv = 1.f / (h * h);
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      float sum[3] = {0, 0, 0}, wsum = 0;
      for (int j = 0; j < k; ++j) {
        const std::int32_t p = idx[v * k + j];
        if (p < 0) break;
        const float w = std::exp(-(d2[v * k + j] - d2[v * k]) * inv);
        for (int ch = 0; ch < 3; ++ch) sum[ch] += w * points.colors[p][ch];
        wsum += w;
      }
      for (int ch = 0; ch < 3; ++ch)
        mesh.colors[v][ch] = std::uint8_t(std::clamp(sum[ch] / wsum + 0.5f, 0.f, 255.f));
    }
  }
  stats.seconds_attributes = lap();
  return result;
}

}  // namespace scan2lod
