#include <scan2lod/acquisition/mesh_points.h>

#include <cassert>
#include <cmath>

namespace scan2lod {

OrientedPoints mesh_to_oriented_points(const TriangleMesh& mesh) {
  const std::size_t n = mesh.positions.size();
  // Sums in double: a vertex of a fine mesh gathers many tiny cross products.
  std::vector<Vec3d> normal_sum(n, Vec3d::Zero());
  std::vector<double> edge_sum(n, 0.0);
  std::vector<std::uint32_t> edge_count(n, 0);
  for (const Triangle& t : mesh.triangles) {
    assert(t[0] >= 0 && t[1] >= 0 && t[2] >= 0);
    assert(std::size_t(t[0]) < n && std::size_t(t[1]) < n && std::size_t(t[2]) < n);
    const Vec3d a = mesh.positions[t[0]].cast<double>();
    const Vec3d b = mesh.positions[t[1]].cast<double>();
    const Vec3d c = mesh.positions[t[2]].cast<double>();
    const Vec3d area_normal = (b - a).cross(c - a);  // length = twice the area
    const double ab = (b - a).norm(), bc = (c - b).norm(), ca = (a - c).norm();
    const double at_corner[3] = {ab + ca, ab + bc, bc + ca};
    for (int k = 0; k < 3; ++k) {
      normal_sum[t[k]] += area_normal;
      edge_sum[t[k]] += at_corner[k];
      edge_count[t[k]] += 2;
    }
  }

  OrientedPoints points;
  const bool colored = mesh.colors.size() == n && n > 0;
  points.positions.reserve(n);
  points.normals.reserve(n);
  points.spacing.reserve(n);
  if (colored) points.colors.reserve(n);
  for (std::size_t v = 0; v < n; ++v) {
    if (edge_count[v] == 0) continue;  // no triangle uses it
    const double length = normal_sum[v].norm();
    if (!(length > 0) || !std::isfinite(length)) continue;
    points.positions.push_back(mesh.positions[v]);
    points.normals.push_back((normal_sum[v] / length).cast<float>());
    points.spacing.push_back(float(edge_sum[v] / edge_count[v]));
    if (colored) points.colors.push_back(mesh.colors[v]);
  }
  return points;
}

}  // namespace scan2lod
