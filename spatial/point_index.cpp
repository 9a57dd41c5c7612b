#include <scan2lod/spatial/point_index.h>

#include <scan2lod/core/error.h>

#include <flann/flann.hpp>
#include <omp.h>

#include <algorithm>
#include <vector>

namespace scan2lod {
namespace {

constexpr std::size_t kParallelMinimum = 8192;

// Orders each row's neighbours by (squared distance, index): FLANN returns
// equal distances in the order its tree met them, which differs between a
// point set and a subset of it (a brick), and so would a value that sums them.
void order_ties(std::int32_t* idx, float* d2, int k) {
  for (int i = 1; i < k; ++i)
    for (int j = i; j > 0 && d2[j] == d2[j - 1] && idx[j] >= 0 && (idx[j - 1] < 0 || idx[j] < idx[j - 1]); --j)
      std::swap(idx[j], idx[j - 1]);
}

}  // namespace

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

}  // namespace scan2lod
