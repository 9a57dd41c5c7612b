// What a reconstruction at resolution R will cost, known before it allocates:
// the sparse grid follows the surface, so its cubes grow as the surface's area
// over the cube's area (x4 per doubling of R), whatever the number of points.
// The area is read off the points' occupancy of a coarse grid.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/reconstruct/cube_grid.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace scan2lod {

struct ReconstructionEstimate {
  int resolution = 0;
  double cubes = 0;    // cubes the surface will touch
  double bytes = 0;    // peak memory of reconstruct(), points and kd-tree included
  double seconds = 0;  // wall time of reconstruct() on `threads` cores of a 2020s server core
};

// @param[in] points      the input (positions and, if present, spacing)
// @param[in] resolution  R, cubes per side
// @param[in] threads     cores the work is spread over (0: all)
// Costs O(#points) time and memory, whatever R.
ReconstructionEstimate estimate_reconstruction(const OrientedPoints& points, int resolution, int threads = 0);

// The points' occupancy of the coarse grids the estimate reads the area off,
// taken as points stream by (a spool too large for memory).
class CoarseOccupancy {
 public:
  explicit CoarseOccupancy(const Aabb& box);
  void add(const Vec3f& p);
  // The estimate for `points` points (all of them added).
  ReconstructionEstimate estimate(std::size_t points, int resolution, int threads = 0) const;

  // The occupied cells of every level, as bits; and those of another
  // occupancy over the same box added (the points of another share).
  std::vector<std::uint64_t> bits() const;
  void add_bits(const std::vector<std::uint64_t>& bits);

 private:
  struct Level {
    CubeGrid grid;
    std::vector<std::uint64_t> bits;  // a bit per cell: some point lies in it
    std::size_t cells = 0;
  };
  std::vector<Level> levels_;  // the coarse grids, finest first
};

// Peak bytes of marching cubes over `cubes` touched cubes from `points` points
// (the model behind estimate_reconstruction, for a brick of the grid).
double reconstruction_bytes(double points, double cubes);

// The memory this process may use: physical memory, or its cgroup's limit when lower.
double machine_memory_bytes();

// A size in binary units as --memory takes them: "400 MiB", "12 GiB".
std::string binary_size(double bytes);

// What this process may still take: the kernel's MemAvailable (or the
// cgroup's limit less its usage, when lower), less a tenth as a margin.
double available_memory_bytes();

// Throws InputError when the estimate at options' resolution exceeds
// `memory_bytes` (0: machine_memory_bytes()), before anything is allocated for
// the grid. The message gives the estimate and the largest power-of-two R whose
// estimate fits. Returns the estimate when it fits.
ReconstructionEstimate check_resolution_fits(const OrientedPoints& points, int resolution, int threads, double memory_bytes = 0);

// When the input's points (a mesh's vertices, or scans' samples) lie more than
// 4 cubes apart, marching cubes at R only re-samples the surface between them
// at great cost: a 453-vertex mesh at R = 256 gives half a million triangles.
// Returns a warning naming the spacing and a resolution whose cubes match it, or "".
std::string coarse_input_advice(const OrientedPoints& points, int resolution);
// The same from the median spacing and the box's longest side.
std::string coarse_input_advice(double median_spacing, double extent, int resolution);

}  // namespace scan2lod
