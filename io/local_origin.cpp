#include <scan2lod/io/local_origin.h>

#include <algorithm>
#include <cmath>

namespace scan2lod {
namespace {

constexpr double kFloatTolerance = 1e-6;  // of the bounding box's diagonal

struct Box {
  Vec3d min = Vec3d::Constant(INFINITY), max = Vec3d::Constant(-INFINITY);
  bool empty() const { return !(min.array() <= max.array()).all(); }
  double diagonal() const { return empty() ? 0 : (max - min).norm(); }
};

Box finite_bounds(const std::vector<Vec3d>& positions) {
  Box box;
  for (const Vec3d& p : positions)
    if (p.allFinite()) box.min = box.min.cwiseMin(p), box.max = box.max.cwiseMax(p);
  return box;
}

}  // namespace

bool floats_hold(const std::vector<Vec3d>& positions) {
  const double tolerance = kFloatTolerance * finite_bounds(positions).diagonal();
  for (const Vec3d& p : positions)
    for (int k = 0; k < 3; ++k)
      if (std::isfinite(p[k]) && std::fabs(double(float(p[k])) - p[k]) > tolerance) return false;
  return true;
}

double float_rounding(const Vec3d& low, const Vec3d& high) {
  const float largest = float(std::max(low.cwiseAbs().maxCoeff(), high.cwiseAbs().maxCoeff()));
  return 0.5 * (double(std::nextafter(largest, INFINITY)) - double(largest));
}

bool floats_hold(const Vec3d& low, const Vec3d& high) {
  return float_rounding(low, high) <= kFloatTolerance * (high - low).norm();
}

Vec3d local_origin(const std::vector<Vec3d>& positions) {
  if (floats_hold(positions)) return Vec3d::Zero();
  const Box box = finite_bounds(positions);
  const Vec3d centre = 0.5 * (box.min + box.max);
  const double diagonal = box.diagonal();
  if (!(diagonal > 0)) return centre;
  const double step = std::exp2(std::floor(std::log2(diagonal)));
  Vec3d origin;
  for (int k = 0; k < 3; ++k) origin[k] = std::round(centre[k] / step) * step;
  return origin;
}

std::vector<Vec3f> positions_about(const std::vector<Vec3d>& positions, const Vec3d& origin) {
  std::vector<Vec3f> local(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) local[i] = (positions[i] - origin).cast<float>();
  return local;
}

}  // namespace scan2lod
