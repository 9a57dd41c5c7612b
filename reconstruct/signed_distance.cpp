#include <scan2lod/reconstruct/signed_distance.h>

#include <scan2lod/core/error.h>
#include <scan2lod/spatial/point_index.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scan2lod {
namespace {
constexpr std::size_t kParallelMinimum = 8192;
}  // namespace

DistanceMethod parse_distance_method(const std::string& name) {
  if (name == "closest" || name == "seed") return DistanceMethod::closest;
  if (name == "hoppe") return DistanceMethod::hoppe;
  if (name == "planes") return DistanceMethod::planes;
  throw InputError("", "unknown distance method '" + name + "': expected closest, hoppe or planes");
}

const char* distance_method_name(DistanceMethod method) {
  switch (method) {
    case DistanceMethod::closest: return "closest";
    case DistanceMethod::hoppe: return "hoppe";
    case DistanceMethod::planes: return "planes";
  }
  return "?";
}

void signed_distances(const OrientedPoints& points, const PointIndex& index,
                      const std::vector<Vec3f>& queries, float cube_size,
                      const SignedDistanceOptions& options, int threads,
                      std::vector<float>* distance, std::vector<std::int32_t>* nearest,
                      DistanceScratch* scratch, std::vector<float>* needed) {
  const std::size_t n = queries.size();
  const int k = options.method == DistanceMethod::planes
                    ? std::max(1, std::min<int>(options.neighbours, int(points.size())))
                    : 1;
  DistanceScratch local;
  DistanceScratch& buffers = scratch ? *scratch : local;
  std::vector<std::int32_t>& idx = buffers.indices;
  std::vector<float>& d2 = buffers.squared_distances;
  // Not value-initialised: knn writes every entry.
  if (idx.size() < n * std::size_t(k)) idx.resize(n * std::size_t(k));
  if (d2.size() < n * std::size_t(k)) d2.resize(n * std::size_t(k));
  index.knn(queries.data(), n, k, idx.data(), d2.data(), threads);
  distance->assign(n, std::numeric_limits<float>::quiet_NaN());
  nearest->assign(n, -1);
  if (needed) needed->assign(n, std::numeric_limits<float>::infinity());
  const bool have_spacing = points.spacing.size() == points.size();
  const bool have_confidence = points.confidence.size() == points.size();
  const int nthreads = n < kParallelMinimum ? 1 : threads > 0 ? threads : omp_get_max_threads();
#pragma omp parallel for schedule(static) num_threads(nthreads)
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t* id = &idx[i * k];
    const float* dd = &d2[i * k];
    const std::int32_t p0 = id[0];
    if (p0 < 0) continue;
    const float scale = std::max(cube_size, have_spacing ? points.spacing[p0] : 0.f);
    const float limit = options.max_distance * scale;
    if (needed) (*needed)[i] = std::sqrt(dd[0]);
    if (dd[0] > limit * limit) continue;
    (*nearest)[i] = p0;
    const Vec3f& v = queries[i];
    const Vec3f offset = v - points.positions[p0];
    const float plane = offset.dot(points.normals[p0]);
    switch (options.method) {
      case DistanceMethod::closest:
        (*distance)[i] = std::copysign(offset.norm(), plane);
        break;
      case DistanceMethod::hoppe:
        (*distance)[i] = plane;
        break;
      case DistanceMethod::planes: {
        const float sigma = options.kernel_width * scale;
        const float inv = 1.0f / (sigma * sigma);
        double sum = 0.0, weight = 0.0;
        for (int j = 0; j < k && id[j] >= 0; ++j) {
          float w = std::exp(-(dd[j] - dd[0]) * inv);  // shifted: no underflow far out
          if (have_confidence) w *= points.confidence[id[j]];
          sum += double(w) * (v - points.positions[id[j]]).dot(points.normals[id[j]]);
          weight += w;
        }
        (*distance)[i] = weight > 0.0 ? float(sum / weight) : plane;
        if (needed) {
          // With fewer points than neighbours asked for, the whole set may hold more.
          const float kth = id[k - 1] >= 0 && k == options.neighbours ? dd[k - 1]
                                                                      : std::numeric_limits<float>::infinity();
          (*needed)[i] = std::sqrt(std::min(kth, zero_weight_squared(dd[0], sigma)));
        }
        break;
      }
    }
  }
}

SignedDistanceField unlimited_distance_field(const OrientedPoints& points, const PointIndex& index,
                                             const SignedDistanceOptions& options, float cube_size) {
  SignedDistanceOptions unlimited = options;
  unlimited.max_distance = std::numeric_limits<float>::infinity();
  // Far from the data only the sign matters, and the nearest few planes give it:
  // a wide k-nearest search from far away is the costliest part of the octree.
  unlimited.neighbours = std::min(unlimited.neighbours, 4);
  return [&points, &index, unlimited, cube_size](const std::vector<Vec3f>& q, std::vector<float>* d) {
    std::vector<std::int32_t> nearest;
    signed_distances(points, index, q, cube_size, unlimited, 0, d, &nearest);
  };
}

}  // namespace scan2lod
