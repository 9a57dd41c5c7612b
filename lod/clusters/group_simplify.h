// One group of the cluster hierarchy simplified by edge collapse under
// generalized quadrics (Garland and Heckbert, *Simplifying Surfaces with Color
// and Texture using Quadric Error Metrics*, 1998): positions, normals and
// colours in one quadric, so attributes survive at every level, and each
// merged vertex placed where that quadric is least, attributes with it.
// Vertices the group shares with others are locked; the scan's real
// boundaries slide along themselves under boundary constraint planes.
//
// Our own collapse loop, not OpenMesh's Decimater: see the measurement in
// lod/README.md ("Why not OpenMesh's Decimater").
#pragma once

#include <scan2lod/core/types.h>

#include <array>
#include <cstdint>
#include <vector>

namespace scan2lod {

// What the simplifier reads of the mesh: shared by every group.
struct SimplifyInput {
  JoinedView<Vec3f> positions;
  JoinedView<Vec3f> normals;  // empty or one per position
  JoinedView<Rgb> colors;     // empty or one per position
  // locked[v] != 0: v is shared with another group and must not move
  // (null: none is).
  const std::vector<std::uint8_t>* locked = nullptr;
  float scale = 1;           // 1 / the mesh's diagonal: quadrics see a unit-sized mesh
  float normal_weight = 0;   // see ClusterOptions
  float color_weight = 0;
  // A collapse places the vertex at its quadric's minimum (a new vertex);
  // false keeps one of the edge's ends (half-edge collapse, no new vertex).
  bool optimal_placement = true;
};

struct SimplifiedGroup {
  // Into the same positions, or -1 - i into added_* for a vertex the
  // simplification placed anew.
  std::vector<Triangle> triangles;
  std::vector<Vec3f> added_positions;
  std::vector<Vec3f> added_normals;  // when the input has normals
  std::vector<Rgb> added_colors;     // when the input has colours
  // Per triangle, which of the input's non-degenerate triangles it was.
  std::vector<std::uint32_t> kept;
  // Measured, in the mesh's units: the largest distance from a removed or
  // moved vertex to the triangles around the vertex that stands for it, and
  // the mean of those distances.
  float error = 0;
  float mean_error = 0;
};

// A group's collapses, cheapest first, kept in order so that the group can
// be taken at any step without simplifying it again: a group that folded
// over itself is taken a few steps back.
class CollapseSequence {
 public:
  std::size_t steps() const { return to_.size(); }
  // Live triangles after the first `step` collapses.
  std::size_t triangles_at(std::size_t step) const { return step == 0 ? triangles_.size() : live_[step - 1]; }
  // The most steps that leave at least `triangles`.
  std::size_t step_keeping(std::size_t triangles) const;
  // The group after its first `step` collapses (at most steps()).
  SimplifiedGroup take(std::size_t step, const SimplifyInput& input) const;

 private:
  friend CollapseSequence simplify_steps(const std::vector<Triangle>&, std::size_t, const SimplifyInput&);
  int dim_ = 3;
  std::vector<std::array<int, 3>> triangles_;  // the group's, in local vertices
  std::vector<std::int32_t> global_;           // local vertex -> mesh vertex
  std::vector<double> origin_;                 // each local vertex's point, dim_ each
  // Per collapse: `from` went onto `to`, which moved to dim_ values of
  // `at_` (position in units of 1 / scale, then normal and colour where
  // weighted), leaving live_.
  std::vector<int> from_, to_;
  std::vector<double> at_;
  std::vector<std::uint32_t> live_;
};

// Simplifies `triangles` (welded: vertices at one position share one index)
// by edge collapse, cheapest first, until `floor` triangles are left or no
// collapse is allowed, keeping every collapse in order. Triangles that cannot be held
// as a manifold (a third face on an edge) stay as they are, their vertices
// locked.
CollapseSequence simplify_steps(const std::vector<Triangle>& triangles, std::size_t floor,
                                const SimplifyInput& input);

// The same, taken at `target` triangles.
SimplifiedGroup simplify_group(const std::vector<Triangle>& triangles, std::size_t target,
                               const SimplifyInput& input);

}  // namespace scan2lod
