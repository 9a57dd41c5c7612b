// The bricks' shares of the surface welded into one, and the clean-up that
// reconstruct() does on its surface done again on the welded one, decision
// for decision: small pieces dropped, small holes closed by marching on into
// the cubes across them (corners evaluated under relaxed limits, by whoever
// holds the points near them), growth given up where a hole stays open, and
// rim triangles over what marching cubes could not close.
//
// The surface is held as its leaves (emitting cube, case, kept case
// triangles) with their triangles, over vertices keyed by lattice edge.
#pragma once

#include <scan2lod/core/flat_hash.h>
#include <scan2lod/core/index_hash.h>
#include <scan2lod/core/types.h>
#include <scan2lod/reconstruct/cube_grid.h>

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace scan2lod {

// Signed distances at lattice corners (packed keys) under the relaxed limits
// of hole closing; NaN where undefined.
using CornerEvaluator = std::function<void(const std::vector<std::uint64_t>& corners, std::vector<float>* distances)>;

class WeldedSurface {
 public:
  // `threads`: for the sorts and scans of the whole surface (0: every core);
  // the surface is the same on any count.
  explicit WeldedSurface(const CubeGrid& grid, int threads = 0);
  WeldedSurface(const WeldedSurface&) = delete;  // leaf_index_ points into it
  WeldedSurface& operator=(const WeldedSurface&) = delete;

  // Room for the bricks' shares, counted before they are added: growth by
  // doubling held up to twice the surface.
  void reserve(std::size_t vertices, std::size_t leaves, std::size_t triangles, bool colored);
  // Phase 1: one brick's share. Vertices on shared brick faces come from
  // both; they are one vertex after weld().
  void add_vertices(const std::vector<std::uint64_t>& edges, const std::vector<Vec3f>& positions,
                    const std::vector<Rgb>& colors);
  // `triangles`: each leaf's case triangles in order, indexing this brick's
  // vertices (the last add_vertices()).
  void add_leaves(const std::vector<std::uint64_t>& cubes, const std::vector<std::uint8_t>& cases,
                  const std::vector<Triangle>& triangles);
  void weld();

  std::size_t live_triangles() const { return live_triangles_; }
  std::size_t leaves() const { return leaf_cube_.size(); }
  std::size_t grown_cubes() const;  // grown into holes and kept

  // Phase 2: as SurfaceBuilder does (marching_cubes.cpp). Returns triangles
  // dropped, cubes grown, cubes given up.
  std::size_t drop_small_pieces(double fraction);
  std::size_t grow_into_small_holes(std::size_t max_edges, const CornerEvaluator& evaluate);
  std::size_t give_up_open_growth();

  // Phase 3: the mesh, triangles in Morton order of their cubes (then slot), vertices in lattice
  // edge order (those no live triangle uses included, as in core), and the
  // open edges as half-edges for fill_small_holes. Vertices added by growth
  // are listed in `new_vertices` for their colours. The surface is empty
  // afterwards: its memory goes before the mesh is worked on.
  void finish(TriangleMesh* mesh, std::vector<std::array<std::int32_t, 2>>* boundary,
              std::vector<std::int32_t>* new_vertices);

 private:
  struct OpenEdge {
    std::int32_t a, b;  // vertices, in the triangle's order
    std::int32_t leaf;
    int face;
  };
  std::int32_t vertex_of(std::uint64_t edge) const;
  std::int32_t add_grown_vertex(std::uint64_t edge, const Vec3f& position);
  std::uint16_t full_mask(std::int32_t leaf) const;
  template <class Visit>
  void for_each_triangle(std::int32_t leaf, Visit visit) const;
  bool emitting(std::uint64_t cube) const;
  bool neighbour_key(std::uint64_t cube, int face, std::uint64_t* key) const;
  void append_open_edges(std::int32_t leaf, std::vector<OpenEdge>* out) const;
  void find_open_edges();
  // Open edges change only at changed leaves, at live neighbours of dead
  // ones, and at leaves that had open edges: only those are looked at.
  void refresh_open_edges(std::vector<std::int32_t> look, const std::vector<std::int32_t>& dead);
  std::int32_t new_hole();
  std::int32_t find_hole(std::int32_t h);

  CubeGrid grid_;
  float h_;
  int threads_ = 1;
  // Vertices: sorted unique lattice edges after weld(); growth appends.
  std::vector<std::uint64_t> vertex_edge_;
  std::vector<Vec3f> positions_;
  std::vector<Rgb> colors_;
  FlatHashMap grown_vertex_{64};  // lattice edge -> vertex, for vertices growth added
  std::size_t welded_vertices_ = 0;
  // Leaves: in the bricks' order; growth appends.
  std::vector<std::uint64_t> leaf_cube_;
  std::vector<std::uint8_t> leaf_case_;
  std::vector<std::uint16_t> leaf_mask_;  // kept case triangles
  std::vector<std::uint32_t> leaf_first_;  // its case triangles start here in triangles_
  std::vector<Triangle> triangles_;
  std::size_t leaf_vertex_base_ = 0;       // add_leaves(): where the last brick's vertices begin
  std::vector<std::uint8_t> leaf_alive_;
  IndexHash leaf_index_{&leaf_cube_};      // cube -> leaf
  std::size_t live_triangles_ = 0;
  // Hole closing: cubes grown (emitting or not), their holes, corner values.
  FlatHashMap grown_{64};                  // cube -> its hole id
  std::vector<std::uint64_t> grown_list_;
  std::vector<std::int32_t> hole_parent_;
  FlatHashMap corner_index_{64};           // corner -> into corner_values_
  std::vector<float> corner_values_;
  std::vector<OpenEdge> open_;
};

}  // namespace scan2lod
