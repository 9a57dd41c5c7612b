// Marching cubes over one brick of the grid: the share of the surface whose
// cubes lie in a box of cubes, computed from the brick's points and a halo of
// neighbours wide enough that every corner's signed distance is the one the
// whole point set gives (brick_reconstruction.h). Vertices carry their global
// lattice edge and leaves their cube, so bricks weld exactly.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/reconstruct/cube_grid.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

struct ReconstructOptions;

// The cubes [lo, hi) per axis, in grid coordinates.
struct CubeRegion {
  int lo[3] = {0, 0, 0};
  int hi[3] = {0, 0, 0};
};

struct BrickSurface {
  std::vector<std::uint64_t> vertex_edges;   // lattice edge of each vertex: lower corner key << 2 | axis
  std::vector<Vec3f> positions;
  std::vector<Rgb> colors;                   // empty without colour input
  // The emitting cubes (keys) and their cases (cube_table.h).
  std::vector<std::uint64_t> leaf_cubes;
  std::vector<std::uint8_t> leaf_cases;
  std::vector<Triangle> triangles;  // each leaf's case triangles in turn, into the vertices above
  // Cubes outside the region that the surface leads into (sorted): the
  // owning brick must follow from them too.
  std::vector<std::uint64_t> requests;
  // The region's cubes on its faces that were added, sorted: a request for
  // one of them is already answered.
  std::vector<std::uint64_t> border_cubes;
  // The halo this brick needed: every point that decides one of its values
  // lies within it (signed_distances' `needed`). A brick run with a smaller
  // halo must run again with this one.
  float needed_halo = 0;
  std::size_t cubes_touched = 0, corners_evaluated = 0, following_rounds = 0;
};

// Follows and emits the surface in `region` only: seeds are the cubes of
// `points` (own and halo) grown by the margin, clipped to the region, then
// `followed` (requests from neighbouring bricks). No pieces are dropped and
// no holes closed: those are decided on the welded whole.
// @param[in] points  the brick's points with their halo, normals outward
// @param[in] expected_cubes  the cubes the brick's surface is expected to touch (sizes its arrays once)
// @param[in] far_bound       no point outside the halo reaches farther into the region than this
BrickSurface reconstruct_brick(const OrientedPoints& points, const CubeGrid& grid, const CubeRegion& region,
                               const std::vector<std::uint64_t>& followed, double expected_cubes, float far_bound,
                               const ReconstructOptions& options);

// Vertex colours: the Gaussian-weighted mean of the 8 nearest points' colours
// (width: the cube size). Empty when the points have none. `needed`, when
// given, receives each vertex's radius as signed_distances() gives it.
class PointIndex;
std::vector<Rgb> vertex_colors(const OrientedPoints& points, const PointIndex& index,
                               const std::vector<Vec3f>& positions, float cube_size, int threads,
                               std::vector<float>* needed = nullptr);

}  // namespace scan2lod
