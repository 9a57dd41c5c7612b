// Issue 13: the octree's coarse levels against vertex clustering, the crudest
// peer, on the same full mesh at the same triangle count: Open3D's
// SimplifyVertexClustering, its voxel size searched for the count. Error:
// the two-sided mean surface distance (measure/surface_distance.h), as
// bench/lod reports it.
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/lod_cursor.h>
#include <scan2lod/measure/surface_distance.h>

#include "test_shapes.h"

#include <gtest/gtest.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/utility/Logging.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

using namespace scan2lod;

namespace {

double two_sided_mean(const TriangleMesh& level, const TriangleMesh& full) {
  const SurfaceComparison c = compare_surfaces(level, full);
  return (c.a_to_b.mean + c.b_to_a.mean) / 2 / c.diagonal;
}

// Vertex clustering of `full` with the voxel whose output is closest to
// `target` triangles: bisection on log(size), the count falling as voxels grow.
TriangleMesh vertex_clustering(const TriangleMesh& full, std::int64_t target) {
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  open3d::geometry::TriangleMesh input;
  for (const Vec3f& p : full.positions) input.vertices_.push_back(p.cast<double>());
  for (const Triangle& t : full.triangles) input.triangles_.emplace_back(t[0], t[1], t[2]);
  const double diagonal = (input.GetMaxBound() - input.GetMinBound()).norm();
  double lo = diagonal / 8192, hi = diagonal / 4, best = lo;
  std::int64_t best_miss = target;
  for (int i = 0; i < 40 && best_miss > target / 500; ++i) {
    const double mid = std::sqrt(lo * hi);
    const auto c = std::int64_t(input.SimplifyVertexClustering(mid)->triangles_.size());
    if (std::llabs(c - target) < best_miss) best_miss = std::llabs(c - target), best = mid;
    (c > target ? lo : hi) = mid;
  }
  return scan2lod::testing::from_open3d(*input.SimplifyVertexClustering(best));
}

}  // namespace

// The bunny's reference surface, sampled and rebuilt at R = 128 (about 100 k
// triangles at full detail). At 2 k, 5 k and 20 k triangles the octree's
// level is closer to the full mesh than vertex clustering's result. Measured
// when written: 2.39 / 1.03 / 0.291 against 2.56 / 1.30 / 0.302 (1e-3 of the
// diagonal). Before nodes held by the neighbour rule collapsed at their own
// rank (lod/octree/coarsening.cpp), the 2 k level was at 2.76, above it.
TEST(OctreeFidelity, CloserThanVertexClusteringAtTheCoarseEnd) {
  const std::string surface = std::string(SCAN2LOD_SHARED_DIR) + "/data/bunny/reconstruction/bun_zipper.ply";
  const auto b = scan2lod::testing::build_octree_model(load_oriented_points({surface}), 128);
  LodCursor cursor(b.tree, b.lod);
  std::vector<Triangle> triangles;
  cursor.move_to(b.lod.full());
  cursor.live_triangles(&triangles);
  const TriangleMesh full = compact_lod(b.tree, triangles);
  for (const std::int64_t budget : {2000, 5000, 20000}) {
    cursor.move_to(priority_for_triangles(b.lod, budget));
    cursor.live_triangles(&triangles);
    const TriangleMesh level = compact_lod(b.tree, triangles);
    const TriangleMesh clustered = vertex_clustering(full, std::int64_t(level.triangles.size()));
    const double octree = two_sided_mean(level, full), peer = two_sided_mean(clustered, full);
    std::printf("budget %lld: octree %zu triangles, error %.4f; vertex clustering %zu triangles, error %.4f (1e-3 diag)\n",
                static_cast<long long>(budget), level.triangles.size(), 1e3 * octree, clustered.triangles.size(),
                1e3 * peer);
    EXPECT_GE(level.triangles.size(), std::size_t(budget * 9 / 10)) << "budget " << budget;
    // Within 2 % of the count, so that neither side wins by size.
    EXPECT_LE(std::llabs(std::int64_t(clustered.triangles.size()) - std::int64_t(level.triangles.size())),
              std::int64_t(level.triangles.size()) / 50)
        << "budget " << budget;
    EXPECT_LT(octree, peer) << "budget " << budget;
  }
}
