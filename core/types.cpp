#include <scan2lod/core/types.h>

#include <Eigen/Geometry>

#include <algorithm>

namespace scan2lod {

bool in_line(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const Vec3d ad = a.cast<double>(), ab = b.cast<double>() - ad, ac = c.cast<double>() - ad, bc = ac - ab;
  const double longest = std::max({ab.squaredNorm(), ac.squaredNorm(), bc.squaredNorm()});
  return ab.cross(ac).squaredNorm() <= 1e-12 * longest * longest;
}

Aabb bounds(ArrayView<Vec3f> points) {
  Aabb box;
  for (const Vec3f& p : points) box.extend(p);
  return box;
}

void OrientedPoints::append(const OrientedPoints& other) {
  auto merge = [&](auto& mine, const auto& theirs, auto fill) {
    if (mine.empty() && theirs.empty()) return;
    if (mine.empty() && !positions.empty()) mine.assign(positions.size(), fill);
    if (theirs.empty()) mine.insert(mine.end(), other.size(), fill);
    else mine.insert(mine.end(), theirs.begin(), theirs.end());
  };
  merge(colors, other.colors, Rgb{200, 200, 200});
  merge(confidence, other.confidence, 1.0f);
  merge(spacing, other.spacing, 0.0f);
  positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  normals.insert(normals.end(), other.normals.begin(), other.normals.end());
}

}  // namespace scan2lod
