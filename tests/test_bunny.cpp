// The bunny's 10 real range scans at R = 256 against the zippered reference
// surface bun_zipper.ply (issue 2's acceptance figures).
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

using namespace scan2lod;

namespace {

const std::string kScans = std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf";
const std::string kReference =
    std::string(SCAN2LOD_SHARED_DIR) + "/data/bunny/reconstruction/bun_zipper.ply";

struct BunnyRun {
  Reconstruction r;
  SurfaceComparison c;
};

const BunnyRun& bunny_run() {
  static const BunnyRun run = [] {
    BunnyRun out;
    OrientedPoints points = load_oriented_points({kScans});
    ReconstructOptions options;
    options.resolution = 256;
    out.r = reconstruct(points, options);
    CompareOptions compare;
    compare.samples = 400000;
    out.c = compare_surfaces(out.r.mesh, read_mesh(kReference), compare);
    return out;
  }();
  return run;
}

}  // namespace

TEST(Bunny, MeanSurfaceDistanceIsUnderThreeHundredthsOfAPercent) {
  if (!std::filesystem::exists(kReference)) GTEST_SKIP() << "needs ../shared";
  const SurfaceComparison& c = bunny_run().c;
  const double two_sided = 0.5 * (c.a_to_b.mean + c.b_to_a.mean);
  // Issue 14's "no loss": 0.0249 % and 0.0707 % when the clean-up was made incremental.
  EXPECT_LE(two_sided, 0.00026 * c.diagonal);
  EXPECT_LE(c.a_to_b.p95, 0.00075 * c.diagonal);
}

TEST(Bunny, OnePieceAndNoHolesButTheDatasOwn) {
  if (!std::filesystem::exists(kReference)) GTEST_SKIP() << "needs ../shared";
  const MeshTopology& t = bunny_run().c.a;
  EXPECT_EQ(t.components, 1u);
  // The reference has the scans' own holes under the base (5 loops).
  EXPECT_LE(t.boundary_loops, bunny_run().c.b.boundary_loops + 5);
  EXPECT_LE(t.boundary_loops, 5u);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.degenerate_triangles, 0u);
  // Marching cubes at R = 256 over the bunny's ~0.057 m^2.
  EXPECT_GT(t.triangles, 350000u);
  EXPECT_LT(t.triangles, 500000u);
}

TEST(Bunny, TrianglesAreConsistentlyOriented) {
  if (!std::filesystem::exists(kReference)) GTEST_SKIP() << "needs ../shared";
  // No directed edge twice: neighbours agree on orientation, patches included.
  const TriangleMesh& m = bunny_run().r.mesh;
  std::vector<std::uint64_t> directed;
  for (const Triangle& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      directed.push_back(std::uint64_t(std::uint32_t(t[k])) << 32 | std::uint32_t(t[(k + 1) % 3]));
  std::sort(directed.begin(), directed.end());
  EXPECT_EQ(std::adjacent_find(directed.begin(), directed.end()), directed.end());
  EXPECT_GT(bunny_run().r.stats.patch_triangles, 0u);
}

TEST(Bunny, LeafCubeNodesDescribeTheMesh) {
  if (!std::filesystem::exists(kReference)) GTEST_SKIP() << "needs ../shared";
  const Reconstruction& r = bunny_run().r;
  const CubeNodes& leaves = r.leaves;
  ASSERT_EQ(leaves.size(), r.stats.cubes_emitting);
  std::size_t edges = 0;
  for (std::size_t l = 0; l < leaves.size(); ++l) {
    for (int e = 0; e < 12; ++e) {
      const std::int32_t v = leaves.edge_vertices[l][e];
      if (v < 0) continue;
      ++edges;
      ASSERT_LT(std::size_t(v), r.mesh.positions.size());
      const float t = leaves.edge_ratios[l][e];
      ASSERT_GT(t, 0.f);
      ASSERT_LT(t, 1.f);
    }
    for (int k = 0; k < 8; ++k)
      ASSERT_EQ(leaves.corner_distances[leaves.corners[l][k]] < 0.f, bool(leaves.cases[l] >> k & 1));
  }
  // Every vertex sits on a crossed grid edge shared by up to 4 cubes.
  EXPECT_GE(edges, r.mesh.positions.size());
  EXPECT_LE(edges, 4 * r.mesh.positions.size());
}

TEST(Bunny, CompareGivesTheSameMeanForTwoSampleSeeds) {
  if (!std::filesystem::exists(kReference)) GTEST_SKIP() << "needs ../shared";
  const TriangleMesh reference = read_mesh(kReference);
  CompareOptions a, b;
  a.seed = 1;
  b.seed = 2;
  a.samples = b.samples = 300000;
  const SurfaceComparison ca = compare_surfaces(bunny_run().r.mesh, reference, a);
  const SurfaceComparison cb = compare_surfaces(bunny_run().r.mesh, reference, b);
  EXPECT_NEAR(ca.a_to_b.mean, cb.a_to_b.mean, 0.05 * ca.a_to_b.mean);
  EXPECT_NEAR(ca.b_to_a.mean, cb.b_to_a.mean, 0.05 * ca.b_to_a.mean);
  EXPECT_NE(ca.a_to_b.mean, cb.a_to_b.mean);  // different samples were drawn
}
