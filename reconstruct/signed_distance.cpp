#include "reconstruct/signed_distance.h"

#include "core/error.h"

#include <flann/flann.hpp>
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

struct PointIndex::Impl {
  flann::Matrix<float> data;
  flann::Index<flann::L2_Simple<float>> index;
  explicit Impl(const OrientedPoints& points)
      : data(const_cast<float*>(points.positions.front().data()), points.size(), 3),
        index(data, flann::KDTreeSingleIndexParams(12)) {
    index.buildIndex();
  }
};

PointIndex::PointIndex(const OrientedPoints& points) {
  if (points.size() == 0) throw InputError("", "no input points: nothing to reconstruct");
  impl_ = std::make_unique<Impl>(points);
}

PointIndex::~PointIndex() = default;

namespace {

// Orders each row's neighbours by (squared distance, index): FLANN returns
// equal distances in the order its tree met them, which differs between a
// point set and a subset of it (a brick), and so would a value that sums them.
void order_ties(std::int32_t* idx, float* d2, int k) {
  for (int i = 1; i < k; ++i)
    for (int j = i; j > 0 && d2[j] == d2[j - 1] && idx[j] >= 0 && (idx[j - 1] < 0 || idx[j] < idx[j - 1]); --j)
      std::swap(idx[j], idx[j - 1]);
}

}  // namespace

void PointIndex::knn(const Vec3f* queries, std::size_t count, int k, std::int32_t* indices,
                     float* squared_distances, int threads) const {
  if (count == 0) return;
  flann::SearchParams params;
  // Small batches (late surface-following rounds) are not worth waking threads.
  params.cores = count < kParallelMinimum ? 1 : threads > 0 ? threads : omp_get_max_threads();
  params.sorted = true;
  const int points = int(impl_->data.rows);
  auto search = [&](const Vec3f* q, std::size_t n, int kk, std::int32_t* idx, float* d2) {
    flann::Matrix<float> qm(const_cast<float*>(q->data()), n, 3);
    flann::Matrix<int> im(idx, n, std::size_t(kk));
    flann::Matrix<float> dm(d2, n, std::size_t(kk));
    impl_->index.knnSearch(qm, im, dm, std::size_t(kk), params);
  };
  if (k >= points) {
    search(queries, count, k, indices, squared_distances);
    for (std::size_t i = 0; i < count; ++i) order_ties(indices + i * k, squared_distances + i * k, k);
    return;
  }
  // One neighbour more tells whether the k-th is tied with points left out:
  // then the tied ones are fetched and the lowest indices kept, so that the
  // k nearest are one set whatever tree found them.
  const int wide = k + 1;
  thread_local std::vector<std::int32_t> idx;
  thread_local std::vector<float> d2;
  idx.resize(count * std::size_t(wide));
  d2.resize(count * std::size_t(wide));
  search(queries, count, wide, idx.data(), d2.data());
  std::vector<std::size_t> tied;
  for (std::size_t i = 0; i < count; ++i) {
    std::int32_t* row = &idx[i * wide];
    float* dist = &d2[i * wide];
    if (row[k] >= 0 && dist[k] == dist[k - 1]) tied.push_back(i);
    order_ties(row, dist, k);
    std::copy(row, row + k, indices + i * k);
    std::copy(dist, dist + k, squared_distances + i * k);
  }
  for (std::size_t i : tied) {
    std::vector<std::int32_t> more;
    std::vector<float> dist;
    for (int m = 2 * wide;; m = std::min(points, 2 * m)) {
      more.assign(std::size_t(m), -1);
      dist.assign(std::size_t(m), 0.f);
      search(queries + i, 1, m, more.data(), dist.data());
      if (m == points || dist[std::size_t(m - 1)] > squared_distances[i * k + k - 1]) break;
    }
    order_ties(more.data(), dist.data(), int(more.size()));
    std::copy(more.begin(), more.begin() + k, indices + i * k);
    std::copy(dist.begin(), dist.begin() + k, squared_distances + i * k);
  }
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
