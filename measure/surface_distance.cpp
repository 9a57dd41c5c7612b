#include <scan2lod/measure/surface_distance.h>

#include <scan2lod/core/error.h>
#include <scan2lod/core/point_triangle.h>
#include <scan2lod/core/progress.h>

#include <Eigen/Geometry>
#include <open3d/core/Tensor.h>
#include <open3d/t/geometry/RaycastingScene.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

namespace scan2lod {
namespace {

static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f arrays are copied as flat floats");

// Queries per Embree call: bounds the result tensors (~40 bytes a point).
constexpr std::size_t kChunk = std::size_t(1) << 20;

// Uniform in [0, 1) from the top 53 bits; std::uniform_real_distribution is
// implementation-defined, which would make seeds non-portable.
double unit_uniform(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

// The triangles that carry area; the rest are left out of scenes.
std::vector<Triangle> surface_triangles(const TriangleMesh& mesh) {
  std::vector<Triangle> kept;
  kept.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (!triangle_is_degenerate(mesh, t)) kept.push_back(mesh.triangles[t]);
  return kept;
}

}  // namespace

std::vector<Vec3f> sample_surface(const TriangleMesh& mesh, std::size_t count, std::uint64_t seed) {
  check_triangle_indices(mesh);
  std::vector<double> cdf(mesh.triangles.size());
  double total = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    const Vec3d a = mesh.positions[tri[0]].cast<double>();
    total += 0.5 * (mesh.positions[tri[1]].cast<double>() - a)
                       .cross(mesh.positions[tri[2]].cast<double>() - a)
                       .norm();
    cdf[t] = total;
  }
  if (!(total > 0))
    throw InputError("", "the mesh has no triangle with non-zero area to sample");

  std::mt19937_64 rng(seed);
  std::vector<Vec3f> points(count);
  for (Vec3f& p : points) {
    // upper_bound skips zero-area triangles: their CDF step is empty.
    const double u = unit_uniform(rng) * total;
    std::size_t t = std::size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin());
    t = std::min(t, cdf.size() - 1);
    // sqrt warps the unit square onto the triangle with uniform density.
    const double s = std::sqrt(unit_uniform(rng)), r = unit_uniform(rng);
    const Triangle& tri = mesh.triangles[t];
    const Vec3d a = mesh.positions[tri[0]].cast<double>();
    const Vec3d b = mesh.positions[tri[1]].cast<double>();
    const Vec3d c = mesh.positions[tri[2]].cast<double>();
    p = ((1 - s) * a + s * (1 - r) * b + s * r * c).cast<float>();
  }
  return points;
}

std::vector<float> distances_to_surface(const std::vector<Vec3f>& points,
                                        const TriangleMesh& surface) {
  namespace o3c = open3d::core;
  check_triangle_indices(surface);
  const std::vector<Triangle> tris = surface_triangles(surface);
  if (tris.empty())
    throw InputError("", "the surface has no triangle with non-zero area to measure against");

  o3c::Tensor vertices = o3c::Tensor::Empty({std::int64_t(surface.positions.size()), 3}, o3c::Float32);
  std::memcpy(vertices.GetDataPtr<float>(), surface.positions.data(),
              surface.positions.size() * sizeof(Vec3f));
  o3c::Tensor indices = o3c::Tensor::Empty({std::int64_t(tris.size()), 3}, o3c::UInt32);
  auto* idx = indices.GetDataPtr<std::uint32_t>();
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) idx[3 * t + k] = std::uint32_t(tris[t][k]);
  open3d::t::geometry::RaycastingScene scene;
  scene.AddTriangles(vertices, indices);

  // Embree compares distances in float, so where triangles are nearly tied
  // (close to a shared edge or vertex) it may return a neighbour of the
  // nearest one, off by ~1e-7 of the mesh size. Rechecking the one-ring of
  // its pick in double settles those ties; this CSR lists each vertex's triangles.
  std::vector<std::uint32_t> ring_begin(surface.positions.size() + 1, 0), ring;
  for (const Triangle& t : tris)
    for (std::int32_t v : t) ++ring_begin[std::size_t(v) + 1];
  for (std::size_t v = 0; v < surface.positions.size(); ++v) ring_begin[v + 1] += ring_begin[v];
  ring.resize(ring_begin.back());
  {
    std::vector<std::uint32_t> fill(ring_begin.begin(), ring_begin.end() - 1);
    for (std::size_t t = 0; t < tris.size(); ++t)
      for (std::int32_t v : tris[t]) ring[fill[std::size_t(v)]++] = std::uint32_t(t);
  }
  auto distance2 = [&](const Vec3d& p, std::uint32_t t) {
    const Triangle& tri = tris[t];
    return point_triangle_distance2(p, surface.positions[tri[0]].cast<double>(),
                                    surface.positions[tri[1]].cast<double>(),
                                    surface.positions[tri[2]].cast<double>());
  };

  std::vector<float> d(points.size());
  Progress progress("distances", points.size());
  for (std::size_t begin = 0; begin < points.size(); begin += kChunk) {
    const std::size_t n = std::min(kChunk, points.size() - begin);
    o3c::Tensor query = o3c::Tensor::Empty({std::int64_t(n), 3}, o3c::Float32);
    std::memcpy(query.GetDataPtr<float>(), points.data() + begin, n * sizeof(Vec3f));
    auto result = scene.ComputeClosestPoints(query);
    const auto* prim = result.at("primitive_ids").GetDataPtr<std::uint32_t>();
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < std::int64_t(n); ++i) {
      const Vec3d p = points[begin + std::size_t(i)].cast<double>();
      double best = distance2(p, prim[i]);
      for (std::int32_t v : tris[prim[i]])
        for (std::uint32_t k = ring_begin[std::size_t(v)]; k < ring_begin[std::size_t(v) + 1]; ++k)
          best = std::min(best, distance2(p, ring[k]));
      d[begin + std::size_t(i)] = float(std::sqrt(best));
    }
    progress.advance(n);
  }
  return d;
}

DistanceStats distance_stats(std::vector<float> d) {
  DistanceStats s;
  s.samples = d.size();
  if (d.empty()) return s;
  double sum = 0, sum2 = 0, max = 0;
  for (float x : d) {
    sum += x;
    sum2 += double(x) * double(x);
    max = std::max(max, double(x));
  }
  s.mean = sum / double(d.size());
  s.rms = std::sqrt(sum2 / double(d.size()));
  s.max = max;
  // Nearest rank: the smallest value with at least 95% of samples at or below it.
  const auto rank = std::size_t(std::ceil(0.95 * double(d.size())));
  auto nth = d.begin() + std::ptrdiff_t(std::max<std::size_t>(rank, 1) - 1);
  std::nth_element(d.begin(), nth, d.end());
  s.p95 = *nth;
  return s;
}

SurfaceComparison compare_surfaces(const TriangleMesh& a, const TriangleMesh& b,
                                   const CompareOptions& options) {
  if (a.triangles.empty()) throw InputError("", "mesh A has no triangles to compare");
  if (b.triangles.empty()) throw InputError("", "mesh B has no triangles to compare");
  SurfaceComparison out;
  out.a = mesh_topology(a);
  out.b = mesh_topology(b);
  // Over triangle corners only: scan files keep stray unreferenced points.
  Aabb box;
  for (const Triangle& t : b.triangles)
    for (std::int32_t v : t) box.extend(b.positions[v]);
  out.diagonal = box.diagonal();

  auto sample_count = [&](const TriangleMesh& m) {
    return options.samples ? options.samples
                           : std::max<std::size_t>(10 * m.triangles.size(), 100000);
  };
  // B's stream is offset by the golden-ratio constant so that seeds s and s+1
  // do not share samples between directions.
  const std::uint64_t seed_b = options.seed + 0x9E3779B97F4A7C15ull;
  out.a_to_b = distance_stats(distances_to_surface(sample_surface(a, sample_count(a), options.seed), b));
  out.b_to_a = distance_stats(distances_to_surface(sample_surface(b, sample_count(b), seed_b), a));
  return out;
}

}  // namespace scan2lod
