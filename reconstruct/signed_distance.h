// Signed distance from oriented points at cube corners (Lee 2007, §4.2), with the
// closest points found by an exact kd-tree (spatial/point_index.h). Positive
// outside, negative inside.
#pragma once

#include <scan2lod/core/types.h>

#include <functional>
#include <string>

namespace scan2lod {

enum class DistanceMethod {
  closest,  // sign((v - p)·n_p) * |v - p| with p the closest point (Lee 2007, §4.2)
  hoppe,    // (v - p)·n_p, the closest point's tangent plane (Hoppe et al. 1992)
  planes,   // Gaussian-weighted mean of the k closest points' tangent-plane distances
};

// "closest", "hoppe" or "planes"; "seed", the name of "closest" in earlier
// releases, is kept.
DistanceMethod parse_distance_method(const std::string& name);
const char* distance_method_name(DistanceMethod method);

struct SignedDistanceOptions {
  // planes averages overlapping scans' tangent planes and measures best on the
  // bunny (see README, "Accuracy"), so it is the default.
  DistanceMethod method = DistanceMethod::planes;
  int neighbours = 12;  // k for planes
  // Gaussian width for planes, in units of max(cube size, local sample spacing).
  float kernel_width = 1.0f;
  // A corner whose closest point is farther than this many max(cube size, local
  // sample spacing) is undefined: no surface is invented far from the data.
  float max_distance = 4.0f;
};

class PointIndex;  // spatial/point_index.h

// Signed distance at each query position.
// @param[in]  points     oriented points (spacing optional: empty = cube size)
// @param[in]  index      PointIndex over points
// @param[in]  queries    #Q positions
// @param[in]  cube_size  the grid's cube edge length
// @param[out] distance   #Q signed distances; NaN where undefined
// @param[out] nearest    #Q indices of the closest point (for attributes)
// @param[in,out] scratch    optional buffers kept between calls by a caller
//                           that queries in many batches (no page faults anew)
struct DistanceScratch {
  std::vector<std::int32_t> indices;
  std::vector<float> squared_distances;
};
// @param[out] needed     optional: #Q radii within which every point that
//                        decides the query's value lies (its closest point when
//                        undefined; else the k-th closest, or where the kernel's
//                        weight is exactly 0 in float if nearer). A caller that
//                        holds every point within that radius of the query has
//                        the value the whole point set gives (brick builds).
void signed_distances(const OrientedPoints& points, const PointIndex& index,
                      const std::vector<Vec3f>& queries, float cube_size,
                      const SignedDistanceOptions& options, int threads,
                      std::vector<float>* distance, std::vector<std::int32_t>* nearest,
                      DistanceScratch* scratch = nullptr, std::vector<float>* needed = nullptr);

// Squared distance past which a Gaussian weight exp(-(d² - d0²) / σ²) of
// float is exactly 0: 105 σ² beyond d0² (exp(-x) underflows past x ≈ 103.97).
inline float zero_weight_squared(float d0_squared, float sigma) { return d0_squared + 105.f * sigma * sigma; }

}  // namespace scan2lod

namespace scan2lod {

// Signed distances at the given positions (positive outside), never NaN.
using SignedDistanceField =
    std::function<void(const std::vector<Vec3f>& positions, std::vector<float>* distances)>;

// The signed distance of `options` anywhere, without the distance limit: for
// lattice points far from the data, such as the octree's coarse corners.
// points and index must outlive the returned function.
SignedDistanceField unlimited_distance_field(const OrientedPoints& points, const PointIndex& index,
                                             const SignedDistanceOptions& options, float cube_size);

}  // namespace scan2lod
