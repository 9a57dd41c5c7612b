// Metro-style distance between two triangulated surfaces (Cignoni, Rocchini,
// Scopigno, "Metro: measuring error on simplified surfaces", 1998): sample one
// surface uniformly by area, take each sample's exact distance to the other
// surface, and summarise. Doing it in both directions gives the symmetric
// (Hausdorff-like) error that tells a hole in one mesh from a bump in the other.
//
// Nearest triangles are found by Embree through Open3D's RaycastingScene; the
// distance to that triangle is then recomputed in double, so small distances
// keep their relative precision.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/measure/topology.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace scan2lod {

struct DistanceStats {
  double mean = 0;
  double rms = 0;
  double p95 = 0;  // nearest-rank 95th percentile
  double max = 0;
  std::size_t samples = 0;
};

struct CompareOptions {
  // Samples per direction; 0 means max(10 * triangles of the sampled mesh, 100000).
  std::size_t samples = 0;
  // Seeds the sampling of A; B uses a stream derived from it. Same seed, same numbers.
  std::uint64_t seed = 1;
};

struct SurfaceComparison {
  DistanceStats a_to_b;  // samples on A, distances to B
  DistanceStats b_to_a;
  double diagonal = 0;   // diagonal of the box around B's triangles, the scale for relative errors
  MeshTopology a, b;
};

// Draws points uniformly by area over the mesh's triangles.
// @param[in] mesh  #F triangles; zero-area ones are never chosen.
// @param[in] count  number of points.
// @param[in] seed  the same seed gives the same points (std::mt19937_64 and an
//   area CDF, no platform-dependent distributions).
// @return count points on the surface. Throws InputError if the mesh has no
//   triangle with non-zero area.
std::vector<Vec3f> sample_surface(const TriangleMesh& mesh, std::size_t count, std::uint64_t seed);

// Exact unsigned distance from each point to the surface.
// @param[in] points  #Q query points.
// @param[in] surface  triangles to measure against. Degenerate triangles
//   (see triangle_is_degenerate) are skipped: Open3D aborts on them, and their
//   points lie on edges that neighbouring triangles usually cover.
// @return #Q distances. Throws InputError if the surface has no triangle with
//   non-zero area. Memory beyond the scene is bounded: queries go in chunks.
std::vector<float> distances_to_surface(const std::vector<Vec3f>& points,
                                        const TriangleMesh& surface);

// Summarises distances. Takes the vector by value because the percentile
// reorders it. An empty vector gives all zeros.
DistanceStats distance_stats(std::vector<float> d);

// Two-sided Metro comparison of A against B, plus both meshes' topology.
// Throws InputError if either mesh has no triangles.
SurfaceComparison compare_surfaces(const TriangleMesh& a, const TriangleMesh& b,
                                   const CompareOptions& options = {});

}  // namespace scan2lod
