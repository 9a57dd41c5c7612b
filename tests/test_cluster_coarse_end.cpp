// The cluster hierarchy's coarse end on a surface of high genus: a ball cut
// from a thickened gyroid, a sheet with dozens of handles that edge collapse
// cannot remove. Every cut of 1 k triangles or more is as sound as the full
// mesh; below, handles may close but no piece is lost; and the coarsest cut
// has at most kCoarsestTriangles.
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/reconstruct/marching_cubes.h>
#include "test_cluster_cuts.h"

#include <gtest/gtest.h>

#include <cmath>

namespace scan2lod {
namespace {

// Inside where negative: a gyroid sheet |G| < thickness, inside a ball.
double gyroid_ball(const Vec3d& p) {
  const double k = 2 * M_PI;  // two periods across the ball's diameter
  const double g = std::sin(k * p.x()) * std::cos(k * p.y()) + std::sin(k * p.y()) * std::cos(k * p.z()) +
                   std::sin(k * p.z()) * std::cos(k * p.x());
  return std::max(std::abs(g) - 0.6, p.norm() - 1.0);
}

// Oriented samples of the zero set: where the field changes sign along the
// edges of an n^3 lattice, normals from its gradient.
OrientedPoints sample_zero_set(double (*f)(const Vec3d&), int n, double half) {
  OrientedPoints out;
  const double step = 2 * half / n, eps = 1e-5;
  auto at = [&](int i, int j, int k) { return Vec3d(-half + i * step, -half + j * step, -half + k * step); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const Vec3d p = at(i, j, k);
        const double fp = f(p);
        for (const Vec3d& q : {at(i + 1, j, k), at(i, j + 1, k), at(i, j, k + 1)}) {
          const double fq = f(q);
          if ((fp < 0) == (fq < 0)) continue;
          const Vec3d x = p + (q - p) * (fp / (fp - fq));
          const Vec3d grad((f(x + Vec3d(eps, 0, 0)) - f(x - Vec3d(eps, 0, 0))),
                           (f(x + Vec3d(0, eps, 0)) - f(x - Vec3d(0, eps, 0))),
                           (f(x + Vec3d(0, 0, eps)) - f(x - Vec3d(0, 0, eps))));
          if (!(grad.norm() > 0)) continue;
          out.positions.push_back(x.cast<float>());
          out.normals.push_back(grad.normalized().cast<float>());
        }
      }
  return out;
}

long genus(const MeshTopology& t) {
  return (2 * long(t.components) - t.euler_characteristic - long(t.boundary_loops)) / 2;
}

TEST(ClusterCoarseEnd, HighGenusGoesDownToAFewHundredTrianglesWithSoundCutsAboveOneThousand) {
  ReconstructOptions options;
  options.resolution = 64;
  TriangleMesh mesh = reconstruct(sample_zero_set(gyroid_ball, 160, 1.1), options).mesh;
  const MeshTopology full = mesh_topology(mesh);
  ASSERT_GE(genus(full), 30) << "the shape must have the handles this test is about";
  LodModel model;
  add_cluster_hierarchy(&model, mesh, false);
  LevelExtractor extractor(model, LodStructure::kClusters);
  EXPECT_LE(extractor.coarsest_triangles(), std::int64_t(kCoarsestTriangles));

  std::size_t sound = 0, coarse = 0;
  for (const LevelRequest& request : testing::every_uniform_cut(*model.clusters)) {
    const LevelCut& cut = extractor.extract(request);
    TriangleMesh level;
    level.positions.assign(model.vertices.positions.begin(), model.vertices.positions.end());
    level.triangles = cut.triangles;
    const MeshTopology t = mesh_topology(level);
    if (cut.triangles.size() >= 1000) {
      EXPECT_EQ(t.non_manifold_edges, 0u) << cut.triangles.size() << " triangles";
      EXPECT_LE(t.boundary_loops, full.boundary_loops) << cut.triangles.size() << " triangles";
      EXPECT_LE(t.components, full.components) << cut.triangles.size() << " triangles";
      ++sound;
    } else {
      EXPECT_EQ(t.components, full.components) << cut.triangles.size() << " triangles: no piece lost";
      ++coarse;
    }
  }
  EXPECT_GT(sound, 5u);
  EXPECT_GE(coarse, 1u);
  // The last steps halve: a budget just under the sound cuts gets a cut
  // near it, not the coarsest.
  const std::size_t under = extractor.extract(LevelRequest::at_most_triangles(999)).triangles.size();
  std::printf("a budget of 999 triangles: %zu\n", under);
  EXPECT_GE(under, 2 * std::size_t(extractor.coarsest_triangles()));

  // The coarsest cut still stands for the shape: within a few percent of
  // the diagonal of the full mesh, both ways.
  const LevelCut& coarsest = extractor.extract(LevelRequest::at_most_triangles(std::int64_t(kCoarsestTriangles)));
  TriangleMesh top;
  top.positions.assign(model.vertices.positions.begin(), model.vertices.positions.end());
  top.triangles = coarsest.triangles;
  const SurfaceComparison c = compare_surfaces(top, mesh, CompareOptions{20000, 1});
  std::printf("full: %zu triangles, genus %ld; coarsest: %zu triangles, genus %ld, mean distance %.4f / %.4f of the diagonal\n",
              mesh.triangles.size(), genus(full), top.triangles.size(), genus(mesh_topology(top)),
              c.a_to_b.mean / c.diagonal, c.b_to_a.mean / c.diagonal);
  EXPECT_LT(c.a_to_b.mean, 0.03 * c.diagonal);
  EXPECT_LT(c.b_to_a.mean, 0.03 * c.diagonal);
}

}  // namespace
}  // namespace scan2lod
