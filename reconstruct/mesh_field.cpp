#include "reconstruct/mesh_field.h"

#include "core/error.h"
#include "reconstruct/marching_cubes.h"

#include <open3d/core/Tensor.h>
#include <open3d/t/geometry/RaycastingScene.h>

#include <cstring>
#include <memory>

namespace scan2lod {

SignedDistanceField mesh_distance_field(const TriangleMesh& mesh) {
  namespace o3c = open3d::core;
  struct State {
    open3d::t::geometry::RaycastingScene scene;
    std::vector<Triangle> triangles;
    std::vector<Vec3f> positions, normals;
  };
  auto state = std::make_shared<State>();
  state->positions = mesh.positions;
  state->normals = mesh.normals.size() == mesh.positions.size() ? mesh.normals : vertex_normals(mesh);
  // Debian's Open3D asserts on zero-area triangles (ENVIRONMENT.md).
  for (const Triangle& t : mesh.triangles) {
    const Vec3f& a = mesh.positions[t[0]];
    if ((mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).squaredNorm() > 0.f) state->triangles.push_back(t);
  }
  if (state->triangles.empty()) throw InputError("", "the mesh has no triangle with area to measure a distance to");
  o3c::Tensor vertices = o3c::Tensor::Empty({std::int64_t(mesh.positions.size()), 3}, o3c::Float32);
  std::memcpy(vertices.GetDataPtr<float>(), mesh.positions.data(), mesh.positions.size() * sizeof(Vec3f));
  o3c::Tensor indices = o3c::Tensor::Empty({std::int64_t(state->triangles.size()), 3}, o3c::UInt32);
  auto* idx = indices.GetDataPtr<std::uint32_t>();
  for (std::size_t t = 0; t < state->triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) idx[3 * t + k] = std::uint32_t(state->triangles[t][k]);
  state->scene.AddTriangles(vertices, indices);

  return [state](const std::vector<Vec3f>& q, std::vector<float>* d) {
    d->assign(q.size(), 0.f);
    if (q.empty()) return;
    o3c::Tensor query = o3c::Tensor::Empty({std::int64_t(q.size()), 3}, o3c::Float32);
    std::memcpy(query.GetDataPtr<float>(), q.data(), q.size() * sizeof(Vec3f));
    auto result = state->scene.ComputeClosestPoints(query);
    const float* points = result.at("points").GetDataPtr<float>();
    const auto* prim = result.at("primitive_ids").GetDataPtr<std::uint32_t>();
    const float* uv = result.at("primitive_uvs").GetDataPtr<float>();
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < std::int64_t(q.size()); ++i) {
      const Vec3f c(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
      const Triangle& t = state->triangles[prim[i]];
      const float u = uv[2 * i], v = uv[2 * i + 1];
      const Vec3f n = (1.f - u - v) * state->normals[t[0]] + u * state->normals[t[1]] + v * state->normals[t[2]];
      const Vec3f offset = q[std::size_t(i)] - c;
      (*d)[std::size_t(i)] = offset.dot(n) < 0.f ? -offset.norm() : offset.norm();
    }
  };
}

}  // namespace scan2lod
