#include <scan2lod/spatial/points_near.h>

#include <cmath>
#include <cstdint>

namespace scan2lod {
namespace {

constexpr std::int64_t kAxisCells = std::int64_t(1) << 21;

std::uint64_t cell_key(std::int64_t x, std::int64_t y, std::int64_t z) {
  return std::uint64_t(x) | std::uint64_t(y) << 21 | std::uint64_t(z) << 42;
}

}  // namespace

QueryNeighbourhood::QueryNeighbourhood(const std::vector<Vec3f>& queries, double radius)
    : cell_(std::max(radius, 1e-30)), marked_(queries.size() * 27) {
  if (queries.empty()) return;
  empty_ = false;
  // A point within the radius of a query lies in the query's cell or one of
  // its 26 neighbours: all are marked.
  low_ = high_ = queries.front().cast<double>();
  for (const Vec3f& q : queries) low_ = low_.cwiseMin(q.cast<double>()), high_ = high_.cwiseMax(q.cast<double>());
  low_.array() -= 2 * cell_;
  high_.array() += 2 * cell_;
  every_cell_ = (high_ - low_).maxCoeff() / cell_ >= double(kAxisCells - 4);
  if (every_cell_) return;
  for (const Vec3f& q : queries) {
    std::int64_t c[3];
    cell_of(q.cast<double>(), c);
    for (std::int64_t dz = -1; dz <= 1; ++dz)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dx = -1; dx <= 1; ++dx) marked_.insert(cell_key(c[0] + dx, c[1] + dy, c[2] + dz), 1);
  }
}

bool QueryNeighbourhood::cell_of(const Vec3d& p, std::int64_t out[3]) const {
  for (int k = 0; k < 3; ++k) {
    out[k] = std::int64_t(std::floor((p[k] - low_[k]) / cell_));
    if (out[k] < 0 || out[k] >= kAxisCells) return false;
  }
  return true;
}

bool QueryNeighbourhood::near(const Vec3f& point) const {
  if (empty_) return false;
  const Vec3d p = point.cast<double>();
  if ((p.array() < low_.array()).any() || (p.array() > high_.array()).any()) return false;
  if (every_cell_) return true;
  std::int64_t c[3];
  return cell_of(p, c) && marked_.find(cell_key(c[0], c[1], c[2])) >= 0;
}

}  // namespace scan2lod
