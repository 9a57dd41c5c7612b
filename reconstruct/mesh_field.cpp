#include <scan2lod/reconstruct/mesh_field.h>

#include <scan2lod/core/error.h>
#include <scan2lod/core/mesh_edges.h>

#include <algorithm>
#include <array>
#include <cmath>

#include <open3d/core/Tensor.h>
#include <open3d/t/geometry/RaycastingScene.h>

#include <cstring>
#include <exception>
#include <memory>
#include <thread>

namespace scan2lod {

MeshField mesh_field(const TriangleMesh& mesh) {
  namespace o3c = open3d::core;
  struct State {
    open3d::t::geometry::RaycastingScene scene;
    std::vector<Triangle> triangles;
    // Angle-weighted pseudo-normals (Baerentzen & Aanaes 2005): the closest
    // point's face, edge or vertex one signs the offset correctly wherever the
    // surface is closed, which the scans' interpolated normals do not.
    std::vector<Vec3f> face_normals, vertex_normals, edge_normals;
    std::vector<std::array<std::int32_t, 3>> triangle_edges;  // edge k joins corners k and k+1
  };
  auto state = std::make_shared<State>();
  // Debian's Open3D asserts on zero-area triangles (ENVIRONMENT.md).
  for (const Triangle& t : mesh.triangles) {
    const Vec3f& a = mesh.positions[t[0]];
    if ((mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).squaredNorm() > 0.f) state->triangles.push_back(t);
  }
  if (state->triangles.empty()) throw InputError("", "the mesh has no triangle with area to measure a distance to");
  const std::size_t nt = state->triangles.size();
  state->face_normals.resize(nt);
  state->vertex_normals.assign(mesh.positions.size(), Vec3f::Zero());
  MeshEdges edges = mesh_edges(state->triangles, mesh.positions.size());
  state->edge_normals.assign(edges.size(), Vec3f::Zero());
  for (std::size_t t = 0; t < nt; ++t) {
    const Triangle& tri = state->triangles[t];
    const Vec3f n = (mesh.positions[tri[1]] - mesh.positions[tri[0]])
                        .cross(mesh.positions[tri[2]] - mesh.positions[tri[0]]).normalized();
    state->face_normals[t] = n;
    for (int k = 0; k < 3; ++k) {
      const Vec3f a = (mesh.positions[tri[(k + 1) % 3]] - mesh.positions[tri[k]]).normalized();
      const Vec3f b = (mesh.positions[tri[(k + 2) % 3]] - mesh.positions[tri[k]]).normalized();
      state->vertex_normals[tri[k]] += std::acos(std::clamp(a.dot(b), -1.f, 1.f)) * n;
      state->edge_normals[std::size_t(edges.of_triangle[t][k])] += n;
    }
  }
  state->triangle_edges = std::move(edges.of_triangle);
  o3c::Tensor vertices = o3c::Tensor::Empty({std::int64_t(mesh.positions.size()), 3}, o3c::Float32);
  std::memcpy(vertices.GetDataPtr<float>(), mesh.positions.data(), mesh.positions.size() * sizeof(Vec3f));
  o3c::Tensor indices = o3c::Tensor::Empty({std::int64_t(state->triangles.size()), 3}, o3c::UInt32);
  auto* idx = indices.GetDataPtr<std::uint32_t>();
  for (std::size_t t = 0; t < state->triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) idx[3 * t + k] = std::uint32_t(state->triangles[t][k]);
  state->scene.AddTriangles(vertices, indices);

  // Open3D's closest points (and their triangles) of q[begin, end).
  auto closest_of = [state](const std::vector<Vec3f>& q, std::size_t begin, std::size_t end) {
    const std::int64_t count = std::int64_t(end - begin);
    o3c::Tensor points_in = o3c::Tensor::Empty({count, 3}, o3c::Float32);
    std::memcpy(points_in.GetDataPtr<float>(), q.data() + begin, std::size_t(count) * sizeof(Vec3f));
    return state->scene.ComputeClosestPoints(points_in);
  };
  // Distances of q[begin, end) into d[begin, end).
  auto query = [state, closest_of](const std::vector<Vec3f>& q, std::size_t begin, std::size_t end,
                                   std::vector<float>* d) {
    const std::int64_t count = std::int64_t(end - begin);
    auto result = closest_of(q, begin, end);
    const float* points = result.at("points").GetDataPtr<float>();
    const auto* prim = result.at("primitive_ids").GetDataPtr<std::uint32_t>();
    const float* uv = result.at("primitive_uvs").GetDataPtr<float>();
    // One thread: Open3D ran the query on TBB's workers, and an OpenMP team
    // here kept both cores spinning against them, 5-8 ms per call whatever
    // its size (the octree makes dozens of small calls).
    for (std::int64_t i = 0; i < count; ++i) {
      const Vec3f c(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
      const std::uint32_t t = prim[i];
      const Triangle& tri = state->triangles[t];
      // Barycentric weights of the corners; a (near) zero one puts the closest
      // point on the opposite edge, two put it on a corner.
      const float w[3] = {1.f - uv[2 * i] - uv[2 * i + 1], uv[2 * i], uv[2 * i + 1]};
      constexpr float kOnFeature = 1e-4f;
      const int zeros = int(w[0] < kOnFeature) + int(w[1] < kOnFeature) + int(w[2] < kOnFeature);
      Vec3f n = state->face_normals[t];
      if (zeros >= 2) {
        const int k = w[0] >= w[1] && w[0] >= w[2] ? 0 : w[1] >= w[2] ? 1 : 2;
        n = state->vertex_normals[tri[k]];
      } else if (zeros == 1) {
        const int opposite = w[0] < kOnFeature ? 0 : w[1] < kOnFeature ? 1 : 2;
        n = state->edge_normals[state->triangle_edges[t][(opposite + 1) % 3]];
      }
      const Vec3f offset = q[begin + std::size_t(i)] - c;
      (*d)[begin + std::size_t(i)] = offset.dot(n) < 0.f ? -offset.norm() : offset.norm();
    }
  };
  // Open3D commits the scene (builds its BVH) on the first query, unguarded:
  // done here, before any caller can query from two threads.
  {
    std::vector<float> d(1);
    query({mesh.positions[state->triangles.front()[0]]}, 0, 1, &d);
  }
  MeshField field;
  field.closest = [closest_of](const std::vector<Vec3f>& q, std::vector<Vec3f>* closest) {
    closest->resize(q.size());
    if (q.empty()) return;
    const auto result = closest_of(q, 0, q.size());
    const float* c = result.at("points").GetDataPtr<float>();
    for (std::size_t i = 0; i < q.size(); ++i) (*closest)[i] = Vec3f(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
  };
  field.distance = [query](const std::vector<Vec3f>& q, std::vector<float>* d) {
    d->assign(q.size(), 0.f);
    if (q.empty()) return;
    // Open3D splits a query into TBB tasks of 1024 points, so a smaller one
    // runs on one core; points far from the mesh take tens of microseconds
    // each (the octree's coarse corners), so such calls go out in two halves.
    constexpr std::size_t kTask = 1024, kWorthSplitting = 32;
    if (q.size() < kWorthSplitting || q.size() > kTask) return query(q, 0, q.size(), d);
    const std::size_t half = q.size() / 2;
    std::exception_ptr failed;
    std::thread first([&] {
      try {
        query(q, 0, half, d);
      } catch (...) {
        failed = std::current_exception();
      }
    });
    query(q, half, q.size(), d);
    first.join();
    if (failed) std::rethrow_exception(failed);
  };
  return field;
}

}  // namespace scan2lod
