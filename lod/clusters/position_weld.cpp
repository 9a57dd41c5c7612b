#include <scan2lod/lod/clusters/position_weld.h>

#include <scan2lod/core/sort_on_cores.h>

#include <numeric>

namespace scan2lod {

std::vector<std::int32_t> weld_positions(ArrayView<Vec3f> positions, int threads) {
  std::vector<std::int32_t> order(positions.size()), weld(positions.size());
  std::iota(order.begin(), order.end(), 0);
  auto less = [&](std::int32_t a, std::int32_t b) {
    const Vec3f &p = positions[std::size_t(a)], &q = positions[std::size_t(b)];
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return a < b;
  };
  sort_on_cores(order.begin(), order.end(), threads, less);
  for (std::size_t i = 0; i < order.size(); ++i) {
    const bool same = i > 0 && positions[std::size_t(order[i])] == positions[std::size_t(order[i - 1])];
    weld[std::size_t(order[i])] = same ? weld[std::size_t(order[i - 1])] : order[i];
  }
  return weld;
}

}  // namespace scan2lod
