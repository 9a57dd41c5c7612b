#include <scan2lod/reconstruct/marching_cubes.h>

#include <scan2lod/core/error.h>
#include <scan2lod/core/flat_hash.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/core/stopwatch.h>
#include <scan2lod/core/union_find.h>
#include <scan2lod/reconstruct/brick_surface.h>
#include <scan2lod/reconstruct/cube_table.h>
#include <scan2lod/reconstruct/hole_filling.h>
#include <scan2lod/reconstruct/open_loops.h>
#include <scan2lod/reconstruct/resolution_guard.h>
#include <scan2lod/spatial/point_index.h>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

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

// The sparse grid and the surface on it, built in stages: seed cubes, surface
// following, one emission, then piece removal and hole closing as local edits
// of that surface, and a final compaction (finish).
class SurfaceBuilder {
 public:
  // expected_cubes: the guard's estimate of the cubes the surface touches, to
  // size the grid's arrays once rather than grow (and page-fault) them again.
  // region: the cubes this builder may add (a brick's own), or null for the
  // whole grid. Cubes outside it that the surface leads into are kept as
  // requests for the builder that owns them (take_brick_surface).
  SurfaceBuilder(const OrientedPoints& points, const ReconstructOptions& options, double expected_cubes,
                 const CubeGrid& grid, const CubeRegion* region = nullptr, float far_bound = 0)
      : expected_cubes_(std::size_t(std::min(expected_cubes, 1e9))),
        points_(points),
        options_(options),
        threads_(options.threads > 0 ? options.threads : omp_get_max_threads()),
        grid_(grid),
        region_(region ? std::optional<CubeRegion>(*region) : std::nullopt),
        h_(float(grid_.cube_size)),
        index_(points),
        have_spacing_(points.spacing.size() == points.size()) {
    if (region) far_bound_ = far_bound;
  }

  const CubeGrid& grid() const { return grid_; }
  const PointIndex& index() const { return index_; }
  std::size_t cube_count() const { return cube_keys_.size(); }
  std::size_t corner_count() const { return corner_keys_.size(); }
  float needed_radius() const { return needed_radius_; }
  std::size_t grown_cubes() const { return std::size_t(std::count(grown_.begin(), grown_.end(), 1)); }
  std::size_t usable_cubes() const { return std::size_t(std::count(usable_.begin(), usable_.end(), 1)); }

  // Cubes that hold points, grown by `margin`, then every cube the surface
  // leads into across a face, while its centre stays within reach of the data.
  // `followed`: cubes another brick's surface leads into; they join as if
  // reached by following (judged by reach, unlike seeds).
  std::size_t follow_surface(Progress* progress, const std::vector<std::uint64_t>& followed = {}) {
    add_seed_cubes();
    const std::size_t seeds = cube_keys_.size();
    for (std::uint64_t key : followed)
      if (in_region(key)) add_cube(key);
    std::size_t rounds = 0;
    for (std::size_t begin = 0; begin < cube_keys_.size(); ++rounds) {
      const std::size_t end = cube_keys_.size();
      judge_reach(std::max(begin, seeds), end);
      evaluate_corners(begin, end, options_.distance, progress);
      for (std::size_t c = begin; c < end; ++c)
        if (usable_[c]) add_crossed_neighbours(c);
      begin = end;
    }
    return rounds - 1;
  }

  // Triangulates the given cubes, appending to the surface: each usable cube
  // with all corners defined, a sign change and a kept case triangle becomes a
  // leaf. Vertices on grid edges are shared with the leaves emitted before.
  // Returns the first new leaf; the new ones run to leaf_count().
  std::size_t emit(const std::vector<std::int32_t>& cubes) {
    const std::size_t first = leaf_cube_.size();
    leaf_of_.resize(cube_keys_.size(), -1);
    select_leaves(cubes);
    const std::size_t end = leaf_cube_.size();
    resize_with_room(end, &leaf_edge_vertices_, &leaf_edge_ratios_, &leaf_first_triangle_);
    place_ratios(first, end);
    share_vertices(first, end);
    write_triangles(first, end);
    return first;
  }

  std::size_t leaf_count() const { return leaf_cube_.size(); }

  // Drops pieces of the surface with fewer than `fraction` of its triangles:
  // the specks and fins that noisy scans leave off thin edges. A piece can share
  // a cube with a kept one, so pieces are dropped triangle by triangle, through
  // the cube's mask of kept case triangles; a cube left with none stops being a
  // leaf. Returns the number of triangles dropped.
  std::size_t drop_small_pieces(double fraction) {
    if (fraction <= 0.0 || live_triangles_ == 0) return 0;
    UnionFind& uf = vertex_sets_;
    uf.parent.resize(positions_.size());
    std::iota(uf.parent.begin(), uf.parent.end(), 0);
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      if (triangle_alive_[t]) uf.unite(triangles_[t][0], triangles_[t][1]), uf.unite(triangles_[t][1], triangles_[t][2]);
    std::vector<std::int32_t>& size = scratch_counts_;
    size.assign(positions_.size(), 0);
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      if (triangle_alive_[t]) ++size[uf.find(triangles_[t][0])];
    const double limit = fraction * double(live_triangles_);
    std::vector<std::int32_t> touched;
    std::size_t dropped = 0;
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
      if (!triangle_alive_[t] || size[uf.find(triangles_[t][0])] >= limit) continue;
      const std::int32_t l = triangle_leaf_[t];
      masks_[leaf_cube_[l]] &= std::uint16_t(~(1u << triangle_slot_[t]));
      triangle_alive_[t] = 0;
      touched.push_back(l);
      ++dropped;
    }
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    const auto& table = cube_cases();
    std::vector<std::int32_t> dead;
    for (std::int32_t l : touched)
      if ((masks_[leaf_cube_[l]] & ((1u << table[leaf_case_[l]].triangle_count) - 1)) == 0) dead.push_back(l);
    live_triangles_ -= dropped;
    kill_leaves(dead);
    refresh_open_edges(touched, dead);
    return dropped;
  }

  // One round of hole closing: every cube across an open face of a boundary
  // loop of at most `max_edges` edges is made usable, its missing corners
  // evaluated under relaxed distance limits, and emitted. Returns the number
  // of cubes added.
  std::size_t grow_into_small_holes(std::size_t max_edges) {
    if (open_.empty()) return 0;
    const OpenLoops loops = open_loops(open_);
    // Each hole keeps one id across rounds: a loop inherits the ids of the grown
    // cubes on its rim, and ids that meet in one loop are merged.
    std::vector<std::int32_t> loop_hole(loops.edges.size(), -1);
    for (std::size_t i = 0; i < open_.size(); ++i) {
      const OpenEdge& e = open_[i];
      const std::int32_t root = loops.loop[i];
      if (std::size_t(loops.edges[root]) > max_edges) continue;
      if (loop_hole[root] < 0) loop_hole[root] = new_hole();
      if (hole_of_[e.cube] >= 0) unite_holes(loop_hole[root], hole_of_[e.cube]);
    }
    std::vector<std::int32_t> grow;
    for (std::size_t i = 0; i < open_.size(); ++i) {
      const OpenEdge& e = open_[i];
      const std::int32_t root = loops.loop[i];
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
      // A cube across the edges of two holes joins them: one outcome, whatever
      // order the edges came in (bricks weld theirs in another).
      if (hole_of_[id] >= 0) unite_holes(loop_hole[root], hole_of_[id]);
      else hole_of_[id] = loop_hole[root];
    }
    std::sort(grow.begin(), grow.end());
    grow.erase(std::unique(grow.begin(), grow.end()), grow.end());
    if (grow.empty()) return 0;
    SignedDistanceOptions relaxed = options_.distance;
    relaxed.max_distance *= 2.f;
    for (std::int32_t c : grow) usable_[c] = 1, grown_[c] = 1, grown_list_.push_back(c);
    evaluate_corners_of(grow, relaxed, nullptr);
    const std::size_t first = emit(grow);
    std::vector<std::int32_t> fresh(leaf_count() - first);
    std::iota(fresh.begin(), fresh.end(), std::int32_t(first));
    refresh_open_edges(fresh, {});
    return grow.size();
  }

  // Keeps the cubes grown into a hole only where the hole closed: the cubes of a
  // hole that still has an open edge are given up, since the surface they added
  // would only be a lip around a hole that stays.
  std::size_t give_up_open_growth() {
    std::vector<std::uint8_t> open(hole_parent_.size(), 0);
    for (const OpenEdge& e : open_) {
      if (hole_of_[e.cube] >= 0) open[find_hole(hole_of_[e.cube])] = 1;
      const std::int32_t n = neighbour(e.cube, e.face);
      if (n >= 0 && hole_of_[n] >= 0) open[find_hole(hole_of_[n])] = 1;
    }
    std::vector<std::int32_t> dead;
    std::size_t given_up = 0;
    for (std::int32_t c : grown_list_) {
      if (!grown_[c] || !open[find_hole(hole_of_[c])]) continue;
      usable_[c] = 0, grown_[c] = 0, ++given_up;
      const std::int32_t l = c < std::int32_t(leaf_of_.size()) ? leaf_of_[c] : -1;
      if (l >= 0 && leaf_alive_[l]) dead.push_back(l);
    }
    for (std::int32_t l : dead) {
      const std::size_t end = std::size_t(l) + 1 < leaf_count() ? leaf_first_triangle_[l + 1] : triangles_.size();
      for (std::size_t t = leaf_first_triangle_[l]; t < end; ++t)
        if (triangle_alive_[t]) triangle_alive_[t] = 0, --live_triangles_;
    }
    kill_leaves(dead);
    refresh_open_edges({}, dead);
    return given_up;
  }

  // The leaves and mesh of the live surface, compacted: dead leaves, triangles
  // and vertices left out, corners kept only where a leaf uses them, each in
  // its present order. Compacts the builder's own arrays in place and moves
  // them out, so nothing surface-sized is allocated again; the builder holds
  // no surface afterwards. `boundary` receives the open edges as mesh half-edges.
  void finish(CubeNodes* leaves, TriangleMesh* mesh, std::vector<std::array<std::int32_t, 2>>* boundary) {
    std::vector<std::int32_t> vertex_remap(positions_.size(), 0), corner_remap(corner_keys_.size(), 0);
    for (std::size_t l = 0; l < leaf_count(); ++l) {
      if (!leaf_alive_[l]) continue;
      for (std::int32_t v : leaf_edge_vertices_[l])
        if (v >= 0) vertex_remap[v] = 1;
      for (std::int32_t c : cube_corners_[leaf_cube_[l]]) corner_remap[c] = 1;
    }
    const std::size_t vertices = number_kept(&vertex_remap), corners = number_kept(&corner_remap);
    *leaves = CubeNodes{};
    leaves->grid = grid_;
    compact_leaves(vertex_remap, corner_remap, leaves);
    // Kept items move down (new index <= old), so compaction in place is safe.
    for (std::size_t v = 0; v < positions_.size(); ++v)
      if (vertex_remap[v] >= 0) positions_[vertex_remap[v]] = positions_[v];
    positions_.resize(vertices);
    mesh->positions = std::move(positions_);
    if (points_.has_colors()) leaves->corner_colors.resize(corners);
    for (std::size_t c = 0; c < corner_keys_.size(); ++c) {
      const std::int32_t to = corner_remap[c];
      if (to < 0) continue;
      if (points_.has_colors()) leaves->corner_colors[to] = points_.colors[corner_nearest_[c]];
      corner_keys_[to] = corner_keys_[c];
      corner_distances_[to] = corner_distances_[c];
    }
    corner_keys_.resize(corners);
    corner_distances_.resize(corners);
    leaves->corner_keys = std::move(corner_keys_);
    leaves->corner_distances = std::move(corner_distances_);
    std::size_t kept = 0;
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      if (triangle_alive_[t])
        triangles_[kept++] = {vertex_remap[triangles_[t][0]], vertex_remap[triangles_[t][1]],
                              vertex_remap[triangles_[t][2]]};
    triangles_.resize(kept);
    mesh->triangles = std::move(triangles_);
    boundary->clear();
    for (const OpenEdge& e : open_) boundary->push_back({vertex_remap[e.a], vertex_remap[e.b]});
  }

  // The emitted surface as a brick's share of the whole: vertices keyed by
  // their lattice edge and leaves by their cube, so that bricks weld and
  // order the same whatever their size; the cubes the surface leads into
  // outside the region; and the region's touched border cubes.
  void take_brick_surface(BrickSurface* out) {
    *out = BrickSurface{};
    out->vertex_edges.assign(positions_.size(), 0);
    for (std::size_t l = 0; l < leaf_count(); ++l) {
      const std::uint64_t cube_key = cube_keys_[leaf_cube_[l]];
      for (int e = 0; e < 12; ++e) {
        const std::int32_t v = leaf_edge_vertices_[l][e];
        if (v >= 0) out->vertex_edges[v] = (corner_key_of(cube_key, edge_corner(e, 0)) << 2) | std::uint64_t(e / 4);
      }
    }
    out->positions = std::move(positions_);
    // Nothing is dropped in a brick: every leaf keeps all its case triangles, in slot order.
    for (std::size_t l = 0; l < leaf_count(); ++l) {
      out->leaf_cubes.push_back(cube_keys_[leaf_cube_[l]]);
      out->leaf_cases.push_back(leaf_case_[l]);
    }
    out->triangles = std::move(triangles_);
    std::sort(requests_.begin(), requests_.end());
    requests_.erase(std::unique(requests_.begin(), requests_.end()), requests_.end());
    out->requests = std::move(requests_);
    for (std::uint64_t key : cube_keys_) {
      int xyz[3];
      unpack_key(key, &xyz[0], &xyz[1], &xyz[2]);
      bool border = false;
      for (int a = 0; a < 3; ++a) border |= xyz[a] == region_->lo[a] || xyz[a] + 1 == region_->hi[a];
      if (border) out->border_cubes.push_back(key);
    }
    std::sort(out->border_cubes.begin(), out->border_cubes.end());
  }

  // Open edges of every leaf, found once after the first emission; later
  // changes refresh them locally.
  void find_open_edges() {
    open_.clear();
    for (std::size_t l = 0; l < leaf_count(); ++l)
      if (leaf_alive_[l]) append_open_edges(std::int32_t(l), &open_);
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
    std::int32_t a, b;  // vertices, in the order of the triangle using the edge
    std::int32_t cube;
    int face;           // axis * 2 + side
  };

  // Turns flags (1: kept) into new indices in the same order, -1 for dropped;
  // returns the number kept.
  static std::size_t number_kept(std::vector<std::int32_t>* remap) {
    std::int32_t next = 0;
    for (std::int32_t& r : *remap) r = r ? next++ : -1;
    return std::size_t(next);
  }

  // The live leaves, in order, moved into `leaves` with vertices and corners
  // renumbered.
  void compact_leaves(const std::vector<std::int32_t>& vertex_remap, const std::vector<std::int32_t>& corner_remap,
                      CubeNodes* leaves) {
    const std::size_t alive = std::size_t(std::count(leaf_alive_.begin(), leaf_alive_.end(), 1));
    leaves->cube_keys.resize(alive);
    leaves->cases.resize(alive);
    leaves->triangle_masks.resize(alive);
    leaves->corners.resize(alive);
    std::size_t n = 0;
    for (std::size_t l = 0; l < leaf_count(); ++l) {
      if (!leaf_alive_[l]) continue;
      const std::int32_t c = leaf_cube_[l];
      leaves->cube_keys[n] = cube_keys_[c];
      leaves->cases[n] = leaf_case_[l];
      leaves->triangle_masks[n] = masks_[c];
      for (int k = 0; k < 8; ++k) leaves->corners[n][k] = corner_remap[cube_corners_[c][k]];
      for (int e = 0; e < 12; ++e) {
        const std::int32_t v = leaf_edge_vertices_[l][e];
        leaf_edge_vertices_[n][e] = v >= 0 ? vertex_remap[v] : -1;
      }
      leaf_edge_ratios_[n] = leaf_edge_ratios_[l];
      ++n;
    }
    leaf_edge_vertices_.resize(alive);
    leaf_edge_ratios_.resize(alive);
    leaves->edge_vertices = std::move(leaf_edge_vertices_);
    leaves->edge_ratios = std::move(leaf_edge_ratios_);
  }

  // Grows a buffer's capacity ahead of need: the first emission is most of the
  // surface, hole closing adds a little, and a reallocation here would copy
  // and page-fault the whole array again.
  template <class T>
  static void reserve_room(std::vector<T>* v, std::size_t needed) {
    if (v->capacity() >= needed) return;
    v->reserve(needed + needed / 8 + 1024);
  }

  // Each vector resized to `size`, with room to grow (reserve_room).
  template <class... V>
  static void resize_with_room(std::size_t size, V*... vectors) {
    (reserve_room(vectors, size), ...);
    (vectors->resize(size), ...);
  }

  // Appends the cubes that emit as leaves: usable, all corners defined, a sign
  // change, and a kept case triangle. Cubes are judged on both cores.
  void select_leaves(const std::vector<std::int32_t>& cubes) {
    const auto& table = cube_cases();
    std::vector<std::uint8_t>& cases = scratch_cases_;
    cases.assign(cubes.size(), 0);  // 0: not a leaf (case 0 never emits)
#pragma omp parallel for schedule(static) num_threads(cubes.size() > 4096 ? threads_ : 1)
    for (std::size_t i = 0; i < cubes.size(); ++i) {
      const std::int32_t c = cubes[i];
      std::uint8_t mask;
      if (leaf_of_[c] >= 0 || !usable_[c] || !cube_case(std::size_t(c), &mask) || mask == 0 || mask == 255)
        continue;
      if ((masks_[c] & ((1u << table[mask].triangle_count) - 1)) == 0) continue;
      cases[i] = mask;
    }
    const std::size_t count = leaf_cube_.size() + cubes.size() - std::size_t(std::count(cases.begin(), cases.end(), 0));
    reserve_room(&leaf_cube_, count);
    reserve_room(&leaf_case_, count);
    reserve_room(&leaf_alive_, count);
    for (std::size_t i = 0; i < cubes.size(); ++i) {
      if (!cases[i]) continue;
      leaf_of_[cubes[i]] = std::int32_t(leaf_cube_.size());
      leaf_cube_.push_back(cubes[i]);
      leaf_case_.push_back(cases[i]);
      leaf_alive_.push_back(1);
    }
  }

  // Appends the kept case triangles of leaves [first, end), numbered first so
  // that both cores can write them.
  void write_triangles(std::size_t first, std::size_t end) {
    const auto& table = cube_cases();
    const std::size_t before = triangles_.size();
    std::size_t total = before;
    for (std::size_t l = first; l < end; ++l) {
      leaf_first_triangle_[l] = std::uint32_t(total);
      const std::uint32_t kept = masks_[leaf_cube_[l]] & ((1u << table[leaf_case_[l]].triangle_count) - 1);
      total += std::size_t(__builtin_popcount(kept));
    }
    resize_with_room(total, &triangles_, &triangle_leaf_, &triangle_slot_);
    reserve_room(&triangle_alive_, total);
    triangle_alive_.resize(total, 1);
#pragma omp parallel for schedule(static) num_threads(end - first > 4096 ? threads_ : 1)
    for (std::size_t l = first; l < end; ++l) {
      const CubeCase& cc = table[leaf_case_[l]];
      const auto& ev = leaf_edge_vertices_[l];
      std::size_t at = leaf_first_triangle_[l];
      for (int t = 0; t < cc.triangle_count; ++t) {
        if (!(masks_[leaf_cube_[l]] >> t & 1)) continue;
        triangles_[at] = {ev[cc.triangles[t][0]], ev[cc.triangles[t][1]], ev[cc.triangles[t][2]]};
        triangle_leaf_[at] = std::int32_t(l);
        triangle_slot_[at] = std::uint8_t(t);
        ++at;
      }
    }
    live_triangles_ += total - before;
  }

  // Fills the leaves' edge_ratios: each vertex at the ratio of the corners'
  // |distance| along its edge (Lee 2007, §4.2), kept off the corners so that no
  // triangle degenerates into a needle (crossing_ratio). Leaves are
  // independent: both cores.
  void place_ratios(std::size_t first, std::size_t end) {
    const auto& table = cube_cases();
#pragma omp parallel for schedule(static) num_threads(end - first > 4096 ? threads_ : 1)
    for (std::size_t l = first; l < end; ++l) {
      const CubeCase& cc = table[leaf_case_[l]];
      const auto& corners = cube_corners_[leaf_cube_[l]];
      auto& er = leaf_edge_ratios_[l];
      er.fill(0.f);
      for (int e = 0; e < 12; ++e) {
        if (!(cc.edge_mask >> e & 1)) continue;
        const float da = corner_distances_[corners[edge_corner(e, 0)]];
        const float db = corner_distances_[corners[edge_corner(e, 1)]];
        er[e] = crossing_ratio(da, db);
      }
    }
  }

  // One shared vertex per crossed grid edge, keyed by its lower corner and axis.
  void share_vertices(std::size_t first, std::size_t end) {
    const auto& table = cube_cases();
    // Only the first emission is large enough to show.
    std::optional<Progress> progress;
    if (end - first > (1u << 20)) progress.emplace("marching cubes", end - first);
    // About one new vertex per leaf on a surface.
    edge_index_.reserve(positions_.size() + 2 * (end - first));
    reserve_room(&positions_, positions_.size() + 2 * (end - first));
    for (std::size_t l = first; l < end; ++l) {
      const CubeCase& cc = table[leaf_case_[l]];
      auto& ev = leaf_edge_vertices_[l];
      ev.fill(-1);
      const std::uint64_t cube_key = cube_keys_[leaf_cube_[l]];
      for (int e = 0; e < 12; ++e) {
        if (!(cc.edge_mask >> e & 1)) continue;
        const std::uint64_t lower = corner_key_of(cube_key, edge_corner(e, 0));
        const std::int32_t fresh = std::int32_t(positions_.size());
        const std::int32_t id = edge_index_.insert((lower << 2) | std::uint64_t(e / 4), fresh);
        if (id == fresh) {
          int x, y, z;
          unpack_key(lower, &x, &y, &z);
          Vec3f p = grid_.corner_position(x, y, z);
          p[e / 4] += leaf_edge_ratios_[l][e] * h_;
          positions_.push_back(p);
        }
        ev[e] = id;
      }
      if (progress && (l - first) % 65536 == 65535) progress->advance(65536);
    }
  }

  bool emitting(std::int32_t cube) const {
    if (cube < 0 || std::size_t(cube) >= leaf_of_.size()) return false;
    const std::int32_t l = leaf_of_[cube];
    return l >= 0 && leaf_alive_[l];
  }

  void kill_leaves(const std::vector<std::int32_t>& dead) {
    for (std::int32_t l : dead) leaf_alive_[l] = 0, leaf_of_[leaf_cube_[l]] = -1;
  }

  // Edges of the surface used by one triangle of leaf l: a triangle edge on a
  // cube face is open when the cube across that face emits nothing (two cubes
  // sharing a face always join its crossings the same way).
  void append_open_edges(std::int32_t l, std::vector<OpenEdge>* open) const {
    static const auto face_of = [] {
      std::array<std::array<std::int8_t, 12>, 12> f{};
      for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j) f[i][j] = std::int8_t(i == j ? -1 : shared_face(i, j));
      return f;
    }();
    const CubeCase& cc = cube_cases()[leaf_case_[l]];
    const std::int32_t cube = leaf_cube_[l];
    const auto& ev = leaf_edge_vertices_[l];
    for (int t = 0; t < cc.triangle_count; ++t) {
      if (!(masks_[cube] >> t & 1)) continue;
      for (int k = 0; k < 3; ++k) {
        const int e0 = cc.triangles[t][k], e1 = cc.triangles[t][(k + 1) % 3];
        const int face = face_of[e0][e1];
        if (face < 0 || emitting(neighbour(cube, face))) continue;
        open->push_back({ev[e0], ev[e1], cube, face});
      }
    }
  }

  // Open edges change only at leaves that changed, at live neighbours of dead
  // leaves, and at leaves that had open edges (a new neighbour may close them):
  // only those are looked at again.
  void refresh_open_edges(const std::vector<std::int32_t>& changed, const std::vector<std::int32_t>& dead) {
    std::vector<std::int32_t> look = changed;
    for (const OpenEdge& e : open_) look.push_back(leaf_of_[e.cube]);
    for (std::int32_t l : dead)
      for (int face = 0; face < 6; ++face) {
        const std::int32_t n = neighbour(leaf_cube_[l], face);
        if (emitting(n)) look.push_back(leaf_of_[n]);
      }
    std::sort(look.begin(), look.end());
    look.erase(std::unique(look.begin(), look.end()), look.end());
    open_.clear();
    for (std::int32_t l : look)
      if (l >= 0 && leaf_alive_[l]) append_open_edges(l, &open_);
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
    const std::size_t cubes = std::max(seeds.size() * (m > 0 ? 4 : 1), expected_cubes_) * 5 / 4;
    // The hash tables are filled when reserved: only the seeds' share up front.
    cube_index_.reserve(seeds.size() * (m > 0 ? 4 : 1) * 5 / 4);
    corner_index_.reserve(seeds.size() * 2);
    reserve_room(&usable_, cubes);
    reserve_room(&grown_, cubes);
    reserve_room(&cube_keys_, cubes);
    reserve_room(&masks_, cubes);
    reserve_room(&cube_corners_, cubes);
    reserve_room(&hole_of_, cubes);
    reserve_room(&corner_keys_, cubes * 2);
    reserve_room(&corner_distances_, cubes * 2);
    reserve_room(&corner_nearest_, cubes * 2);
    reserve_room(&corner_relaxed_, cubes * 2);
    for (std::uint64_t key : seeds) {
      int x, y, z;
      unpack_key(key, &x, &y, &z);
      for (int dz = -m; dz <= m; ++dz)
        for (int dy = -m; dy <= m; ++dy)
          for (int dx = -m; dx <= m; ++dx) {
            const int nx = x + dx, ny = y + dy, nz = z + dz;
            if (nx < 0 || ny < 0 || nz < 0 || nx >= R || ny >= R || nz >= R) continue;
            if (in_region(pack_key(nx, ny, nz))) add_cube(pack_key(nx, ny, nz));
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
    if (begin >= end) return;
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
      if (region_) need(std::min(std::sqrt(d2[i]), far_bound_));
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
    std::vector<Vec3f>& queries = scratch_queries_;
    std::vector<float>& d = scratch_distances_;
    std::vector<std::int32_t>& nearest = scratch_nearest_;
    for (std::size_t b = 0; b < todo.size(); b += chunk) {
      const std::size_t e = std::min(todo.size(), b + chunk);
      queries.resize(e - b);
      for (std::size_t i = b; i < e; ++i) {
        int x, y, z;
        unpack_key(corner_keys_[todo[i]], &x, &y, &z);
        queries[i - b] = grid_.corner_position(x, y, z);
      }
      signed_distances(points_, index_, queries, h_, distance, threads_, &d, &nearest, &distance_scratch_,
                       region_ ? &scratch_needed_ : nullptr);
      if (region_)
        for (std::size_t i = 0; i < e - b; ++i)
          need(std::isnan(d[i]) ? std::min(scratch_needed_[i], far_bound_) : scratch_needed_[i]);
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
        const std::uint64_t key = side ? cube_keys_[c] + kAxisStep[axis] : cube_keys_[c] - kAxisStep[axis];
        if (in_region(key)) add_cube(key);
        else requests_.push_back(key);
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

  // A brick's values are the whole point set's where its halo holds every
  // point within this radius of every query it made.
  void need(float radius) { needed_radius_ = std::max(needed_radius_, radius); }

  bool in_region(std::uint64_t key) const {
    if (!region_) return true;
    int xyz[3];
    unpack_key(key, &xyz[0], &xyz[1], &xyz[2]);
    for (int a = 0; a < 3; ++a)
      if (xyz[a] < region_->lo[a] || xyz[a] >= region_->hi[a]) return false;
    return true;
  }

  const std::size_t expected_cubes_;
  const OrientedPoints& points_;
  const ReconstructOptions& options_;
  const int threads_;
  const CubeGrid grid_;
  const std::optional<CubeRegion> region_;
  std::vector<std::uint64_t> requests_;  // cubes outside the region the surface leads into
  // No point outside a brick's halo reaches farther into it than this: a query
  // whose closest point lies farther may take it as undefined.
  float far_bound_ = std::numeric_limits<float>::infinity();
  float needed_radius_ = 0;
  std::vector<float> scratch_needed_;
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
  std::vector<std::int32_t> grown_list_;   // every cube ever grown, in order

  // The surface: leaves and triangles are appended as cubes emit; removal
  // only marks them, and finish() compacts once.
  std::vector<std::int32_t> leaf_of_;     // per cube: its leaf, or -1
  std::vector<std::int32_t> leaf_cube_;
  std::vector<std::uint8_t> leaf_case_;
  std::vector<std::uint8_t> leaf_alive_;
  std::vector<std::array<std::int32_t, 12>> leaf_edge_vertices_;
  std::vector<std::array<float, 12>> leaf_edge_ratios_;
  std::vector<std::uint32_t> leaf_first_triangle_;  // its triangles run to the next leaf's first
  FlatHashMap edge_index_{1 << 16};      // (lower corner, axis) -> vertex
  std::vector<Vec3f> positions_;
  std::vector<Triangle> triangles_;
  std::vector<std::int32_t> triangle_leaf_;
  std::vector<std::uint8_t> triangle_slot_;  // which of its case's triangles
  std::vector<std::uint8_t> triangle_alive_;
  std::size_t live_triangles_ = 0;
  std::vector<OpenEdge> open_;           // the surface's open edges, kept current
  UnionFind vertex_sets_{0};
  std::vector<std::int32_t> scratch_counts_;
  std::vector<std::uint8_t> scratch_cases_;
  // Buffers of the corner evaluations, kept across batches and rounds.
  std::vector<Vec3f> scratch_queries_;
  std::vector<float> scratch_distances_;
  std::vector<std::int32_t> scratch_nearest_;
  DistanceScratch distance_scratch_;
};

}  // namespace

std::vector<Vec3f> vertex_normals(const TriangleMesh& mesh) {
  // Summed in double, where a vertex's few float face normals add up
  // exactly: the same normal in whatever order the triangles come, so a
  // surface welded from bricks gets the in-core normals bit for bit (in
  // float, 54 % of a scan's vertices differed in the last bit, and the
  // cluster hierarchy's collapses with them).
  std::vector<Vec3d> sums(mesh.positions.size(), Vec3d::Zero());
  for (const Triangle& t : mesh.triangles) {
    const Vec3f& a = mesh.positions[t[0]];
    const Vec3f n = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);  // |n| = 2 area
    for (int k = 0; k < 3; ++k) sums[t[k]] += n.cast<double>();
  }
  std::vector<Vec3f> normals(mesh.positions.size(), Vec3f::Zero());
  for (std::size_t v = 0; v < sums.size(); ++v) {
    const double l = sums[v].norm();
    if (l > 0) normals[v] = (sums[v] / l).cast<float>();
  }
  return normals;
}

namespace {

// Pieces and holes: drops small pieces, closes small holes by marching on into
// the cubes across them (giving up where a hole stays open), drops pieces
// again, and lays rim triangles over what marching cubes could not close.
// Works on the open edges and the cubes around them, never the whole surface,
// apart from the linear passes that find pieces and compact the result.
void clean_up(SurfaceBuilder& builder, const ReconstructOptions& options, Reconstruction* result) {
  ReconstructStats& stats = result->stats;
  Progress progress("pieces and holes", std::size_t(std::max(0, options.hole_rounds)) + 4);
  if (options.min_piece > 0.0) stats.triangles_dropped += builder.drop_small_pieces(options.min_piece);
  progress.advance();
  const std::size_t max_edges = std::size_t(options.max_hole * options.resolution);
  if (options.max_hole > 0.0) {
    for (int round = 0; round < options.hole_rounds; ++round) {
      progress.advance();
      if (builder.grow_into_small_holes(max_edges) == 0) break;
    }
    builder.give_up_open_growth();
    stats.cubes_hole_closing = builder.grown_cubes();
    if (options.min_piece > 0.0) stats.triangles_dropped += builder.drop_small_pieces(options.min_piece);
  }
  progress.advance();
  std::vector<std::array<std::int32_t, 2>> boundary;
  stats.corners_evaluated = builder.corner_count();
  builder.finish(&result->leaves, &result->mesh, &boundary);
  progress.advance();
  if (options.max_hole > 0.0) {
    // What marching on could not close gets triangles over its rim.
    const std::vector<Triangle> patch = fill_small_holes(result->mesh, boundary, max_edges);
    result->leaves.patch_triangles = patch;
    result->mesh.triangles.insert(result->mesh.triangles.end(), patch.begin(), patch.end());
    stats.patch_triangles = patch.size();
  }
}

}  // namespace

std::string no_surface_message(const Reconstruction& r, int resolution, const std::string& resolution_flag) {
  return "no surface at resolution " + std::to_string(resolution) + ": " + std::to_string(r.stats.points) +
         " points, " + std::to_string(r.stats.cubes_touched) +
         " cubes near them, none crossed by the surface (too few or too sparse points for this resolution: try a "
         "coarser " + resolution_flag + ")";
}

Reconstruction reconstruct(const OrientedPoints& points, const ReconstructOptions& options) {
  check_points(points);
  Reconstruction result;
  ReconstructStats& stats = result.stats;
  stats.points = points.size();
  Stopwatch watch;
  auto lap = [&watch] { return watch.lap(); };
  const CubeGrid grid = make_cube_grid(bounds(points.positions), options.resolution);  // checks the resolution first
  const ReconstructionEstimate estimate =
      check_resolution_fits(points, options.resolution, options.threads, options.memory_limit);
  const std::string advice = coarse_input_advice(points, options.resolution);
  if (!advice.empty()) result.warnings.push_back(advice);
  SurfaceBuilder builder(points, options, estimate.cubes, grid);
  stats.seconds_index = lap();
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  {
    // About two corners per cube touched.
    Progress progress("signed distances", std::size_t(2.0 * estimate.cubes) + 1);
    stats.following_rounds = builder.follow_surface(&progress);
  }
  stats.seconds_distances = lap();
  TriangleMesh& mesh = result.mesh;
  std::vector<std::int32_t> all(builder.cube_count());
  std::iota(all.begin(), all.end(), 0);
  builder.emit(all);
  builder.find_open_edges();
  stats.seconds_emit = lap();
  clean_up(builder, options, &result);
  stats.seconds_cleanup = lap();
  stats.cubes_touched = builder.usable_cubes();
  stats.cubes_emitting = result.leaves.size();

  mesh.normals = vertex_normals(mesh);
  mesh.colors = vertex_colors(points, builder.index(), mesh.positions, float(builder.grid().cube_size), threads);
  stats.seconds_attributes = lap();
  return result;
}

std::vector<Rgb> vertex_colors(const OrientedPoints& points, const PointIndex& index,
                               const std::vector<Vec3f>& positions, float cube_size, int threads,
                               std::vector<float>* needed) {
  std::vector<Rgb> colors;
  if (!points.has_colors() || positions.empty()) return colors;
  const int k = std::min<int>(8, int(points.size()));
  std::vector<std::int32_t> idx(positions.size() * k);
  std::vector<float> d2(positions.size() * k);
  index.knn(positions.data(), positions.size(), k, idx.data(), d2.data(), threads);
  colors.resize(positions.size());
  const float inv = 1.f / (cube_size * cube_size);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t v = 0; v < positions.size(); ++v) {
    float sum[3] = {0, 0, 0}, wsum = 0;
    for (int j = 0; j < k; ++j) {
      const std::int32_t p = idx[v * k + j];
      if (p < 0) break;
      const float w = std::exp(-(d2[v * k + j] - d2[v * k]) * inv);
      for (int ch = 0; ch < 3; ++ch) sum[ch] += w * points.colors[p][ch];
      wsum += w;
    }
    for (int ch = 0; ch < 3; ++ch) colors[v][ch] = std::uint8_t(std::clamp(sum[ch] / wsum + 0.5f, 0.f, 255.f));
  }
  if (needed) {
    needed->resize(positions.size());
    for (std::size_t v = 0; v < positions.size(); ++v) {
      const float kth = k == 8 ? d2[v * k + k - 1] : std::numeric_limits<float>::infinity();
      (*needed)[v] = std::sqrt(std::min(kth, zero_weight_squared(d2[v * k], cube_size)));
    }
  }
  return colors;
}

BrickSurface reconstruct_brick(const OrientedPoints& points, const CubeGrid& grid, const CubeRegion& region,
                               const std::vector<std::uint64_t>& followed, double expected_cubes, float far_bound,
                               const ReconstructOptions& options) {
  BrickSurface out;
  if (points.size() == 0) return out;  // no point: no corner is defined
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  SurfaceBuilder builder(points, options, expected_cubes, grid, &region, far_bound);
  out.following_rounds = builder.follow_surface(nullptr, followed);
  std::vector<std::int32_t> all(builder.cube_count());
  std::iota(all.begin(), all.end(), 0);
  builder.emit(all);
  const std::size_t touched = builder.usable_cubes(), corners = builder.corner_count();
  builder.take_brick_surface(&out);
  out.cubes_touched = touched;
  out.corners_evaluated = corners;
  out.needed_halo = builder.needed_radius();
  std::vector<float> needed;
  out.colors = vertex_colors(points, builder.index(), out.positions, float(grid.cube_size), threads, &needed);
  for (float r : needed) out.needed_halo = std::max(out.needed_halo, r);
  return out;
}

}  // namespace scan2lod
