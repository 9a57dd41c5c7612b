// The cluster hierarchy's claims (Cignoni et al., Batched Multi-Triangulation,
// 2005): the finest cut is the input mesh, every uniform cut is as sound as
// the full mesh, every view-dependent cut is watertight where the full mesh
// is, and the generalized quadrics keep colours. Real scans (the bundled
// bunny) and shapes with known answers (a scanned sphere).
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/lod/clusters/cut_refinement.h>
#include <scan2lod/lod/level_budget.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/reconstruct/marching_cubes.h>
#include "test_shapes.h"
#include "test_cluster_cuts.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <open3d/geometry/KDTreeFlann.h>
#include <open3d/geometry/TriangleMesh.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace scan2lod {
namespace {

struct Built {
  TriangleMesh mesh;
  LodModel model;
};

const Built& bunny128() {
  static const Built b = [] {
    ReconstructOptions options;
    options.resolution = 128;
    Built out;
    out.mesh = reconstruct(load_oriented_points({testing::bunny_scans()}), options).mesh;
    add_cluster_hierarchy(&out.model, out.mesh, false);
    return out;
  }();
  return b;
}

TriangleMesh level_mesh(const LodModel& model, const std::vector<Triangle>& tris) {
  TriangleMesh m;
  m.positions.assign(model.vertices.positions.begin(), model.vertices.positions.end());
  m.triangles = tris;
  return m;
}

std::vector<Triangle> sorted_rotated(std::vector<Triangle> tris) {
  for (Triangle& t : tris) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  std::sort(tris.begin(), tris.end());
  return tris;
}

TEST(ClusterHierarchy, FinestCutIsTheInputMesh) {
  const Built& b = bunny128();
  LevelExtractor extractor(b.model, LodStructure::kClusters);
  const LevelCut& cut = extractor.extract(LevelRequest::at_error(0));
  EXPECT_EQ(sorted_rotated(cut.triangles), sorted_rotated(b.mesh.triangles));
  const LevelCut& all = extractor.extract(LevelRequest::at_percent(100));
  EXPECT_EQ(all.triangles.size(), b.mesh.triangles.size());
  // The shared vertices are the mesh's own, unmoved, then those the
  // collapses placed: each used by some coarser cluster, and fewer than the
  // mesh's.
  ASSERT_GE(b.model.vertices.size(), b.mesh.positions.size());
  EXPECT_TRUE(std::equal(b.mesh.positions.begin(), b.mesh.positions.end(), b.model.vertices.positions.begin()));
  const std::size_t added = b.model.vertices.size() - b.mesh.positions.size();
  EXPECT_GT(added, 0u);
  EXPECT_LT(added, b.mesh.positions.size());
  EXPECT_EQ(b.model.cluster_vertex_count, b.model.vertices.size());
  std::vector<std::uint8_t> used(b.model.vertices.size(), 0);
  for (const Triangle& t : b.model.clusters->triangles)
    for (std::int32_t v : t) used[std::size_t(v)] = 1;
  EXPECT_EQ(std::count(used.begin() + std::ptrdiff_t(b.mesh.positions.size()), used.end(), 0), 0);
}

TEST(ClusterHierarchy, GoesDownToAFewHundredTrianglesAndStoresUnderTwoAndAHalfTimesTheMesh) {
  const Built& b = bunny128();
  LevelExtractor extractor(b.model, LodStructure::kClusters);
  EXPECT_LE(extractor.coarsest_triangles(), 256);
  EXPECT_LE(double(b.model.clusters->triangles.size()), 2.4 * double(b.mesh.triangles.size()));
}

TEST(ClusterHierarchy, EveryUniformCutIsAsSoundAsTheFullMesh) {
  const Built& b = bunny128();
  const MeshTopology full = mesh_topology(b.mesh);
  LevelExtractor extractor(b.model, LodStructure::kClusters);
  const ClusterCutTable table = cluster_cut_table(*b.model.clusters);
  for (std::int64_t count : table.triangles) {
    LevelRequest stored = LevelRequest::at_most_triangles(count);
    stored.refine = false;
    ASSERT_EQ(std::int64_t(extractor.extract(stored).triangles.size()), count) << "the table counts what the cut emits";
  }
  int checked = 0;
  for (const LevelRequest& request : testing::every_uniform_cut(*b.model.clusters)) {
    const LevelCut& cut = extractor.extract(request);
    if (cut.triangles.size() < 1000) continue;
    const MeshTopology t = mesh_topology(level_mesh(b.model, cut.triangles));
    EXPECT_EQ(t.non_manifold_edges, 0u) << cut.triangles.size() << " triangles";
    EXPECT_LE(t.boundary_loops, full.boundary_loops) << cut.triangles.size() << " triangles";
    EXPECT_LE(t.components, full.components) << cut.triangles.size() << " triangles";
    ++checked;
  }
  EXPECT_GT(checked, 10);
}

// Each collapse puts its vertex where the summed quadric is least (Garland
// and Heckbert, 1997), not at an end of the edge: closer cuts, for fewer new
// vertices than the mesh has.
TEST(ClusterHierarchy, VerticesAtTheQuadricMinimumMakeCloserCuts) {
  const Built& b = bunny128();
  LodModel ends;
  ClusterOptions half_edge;
  half_edge.optimal_placement = false;
  add_cluster_hierarchy(&ends, b.mesh, false, half_edge);
  EXPECT_EQ(ends.vertices.size(), b.mesh.positions.size()) << "half-edge collapses add no vertex";
  LevelExtractor optimal(b.model, LodStructure::kClusters), endpoint(ends, LodStructure::kClusters);
  for (std::int64_t budget : {2000, 10000, 40000}) {
    auto error = [&](LevelExtractor& e) {
      const TriangleMesh cut = compact_level(e.model(), e.extract(LevelRequest::at_triangles(budget)).triangles);
      const SurfaceComparison c = compare_surfaces(cut, b.mesh, CompareOptions{100000, 1});
      return (c.a_to_b.mean + c.b_to_a.mean) / c.diagonal;
    };
    const double with = error(optimal), without = error(endpoint);
    std::printf("%lld triangles: %.3g at the minimum, %.3g at an end (%.2fx)\n", (long long)budget, with, without,
                with / without);
    EXPECT_LT(with, without) << budget << " triangles";
  }
}

// A strict budget gets the finest cut that fits; a plain one that cut too,
// unless it falls more than 10 % short and the next is at most 10 % over
// (lod/level_budget.h; the octree's side: OctreeSoundness.*).
TEST(ClusterHierarchy, BudgetsGiveTheFinestCutThatFitsOrOneWithinTenPercent) {
  const Built& b = bunny128();
  // Refined to the count or not (lod/clusters/cut_refinement.h), the same rules hold.
  for (const bool refine : {true, false}) {
    const LodStructure structure = LodStructure::kClusters;
    LevelExtractor extractor(b.model, structure);
    std::int64_t last = 0, last_strict = 0, over = 0;
    for (std::int64_t budget : {500, 1000, 2000, 3000, 5000, 7000, 10000, 20000, 50000}) {
      LevelRequest at_most = LevelRequest::at_most_triangles(budget), within = LevelRequest::at_triangles(budget);
      at_most.refine = within.refine = refine;
      const std::int64_t strict = std::int64_t(extractor.extract(at_most).triangles.size());
      const std::int64_t got = std::int64_t(extractor.extract(within).triangles.size());
      EXPECT_LE(strict, std::max<std::int64_t>(budget, extractor.coarsest_triangles())) << budget;
      EXPECT_TRUE(got == strict || (10 * strict < 9 * budget && got > budget && 10 * got <= 11 * budget))
          << structure_name(structure) << ", budget " << budget << ": " << got << " (at most: " << strict << ")";
      EXPECT_GE(strict, last_strict) << "larger budgets never get fewer triangles";
      EXPECT_GE(got, last) << "larger budgets never get fewer triangles";
      last = got, last_strict = strict, over += got > budget;
    }
    std::printf("%s: %lld of 9 budgets took the level just over\n", refine ? "refined" : "stored", (long long)over);
  }
}

TEST(ClusterHierarchy, ViewCutsAreWatertightFromAnyCamera) {
  const Built& b = bunny128();
  const MeshTopology full = mesh_topology(b.mesh);
  const Aabb box = model_bounds(b.model);
  const Vec3f centre = 0.5f * (box.min + box.max);
  const float size = box.diagonal();
  LevelExtractor extractor(b.model, LodStructure::kClusters);
  std::mt19937 random(7);
  std::uniform_real_distribution<float> unit(-1.f, 1.f);
  std::size_t smallest = SIZE_MAX, largest = 0;
  for (int view = 0; view < 50; ++view) {
    CameraView camera;
    // Half outside the box at 0.6 to 3 diagonals, half inside it.
    const Vec3f direction = Vec3f(unit(random), unit(random), unit(random)).normalized();
    const Vec3f inside = Vec3f(unit(random), unit(random), unit(random)).cwiseProduct(box.extent());
    camera.eye = view % 2 ? Vec3f(centre + direction * size * (0.6f + 1.2f * (unit(random) + 1)))
                          : Vec3f(centre + 0.5f * inside);
    camera.target = centre;
    camera.height = 720;
    for (double pixels : {0.5, 1.0, 2.0, 4.0, 8.0}) {
      const LevelCut& cut = extractor.extract(LevelRequest::for_camera(camera, pixels));
      const MeshTopology t = mesh_topology(level_mesh(b.model, cut.triangles));
      ASSERT_EQ(t.non_manifold_edges, 0u) << "view " << view << " at " << pixels << " px";
      ASSERT_LE(t.boundary_loops, full.boundary_loops) << "view " << view << " at " << pixels << " px";
      ASSERT_LE(t.components, full.components) << "view " << view << " at " << pixels << " px";
      smallest = std::min(smallest, cut.triangles.size());
      largest = std::max(largest, cut.triangles.size());
    }
  }
  // The cameras did ask for different cuts.
  EXPECT_LT(double(smallest), 0.5 * double(largest));
}

// A sphere of radius 1 with three colour bands, scanned, reconstructed and
// simplified with and without colours in the quadrics.
// A box's faces are flat: a collapse along one of its edges can leave three
// vertices in line in one triangle, no area in float (box R = 128 had one,
// R = 256 four). No stored triangle of any level may be such a sliver.
TEST(ClusterHierarchy, FlatFacesGiveNoTriangleWithoutArea) {
  ReconstructOptions options;
  options.resolution = 128;
  const TriangleMesh box =
      reconstruct(testing::scan_shape(testing::from_open3d(*open3d::geometry::TriangleMesh::CreateBox(1, 1, 1))),
                  options)
          .mesh;
  LodModel model;
  add_cluster_hierarchy(&model, box, false);
  const TriangleMesh stored = level_mesh(model, model.clusters->triangles);
  std::size_t flat = 0;
  for (std::size_t t = 0; t < stored.triangles.size(); ++t) flat += triangle_is_degenerate(stored, t);
  EXPECT_EQ(flat, 0u) << "of " << stored.triangles.size() << " stored triangles";
  EXPECT_EQ(mesh_topology(box).degenerate_triangles, 0u) << "the full mesh has none to begin with";
  EXPECT_GT(stored.triangles.size(), box.triangles.size());
}

Rgb band_colour(const Vec3f& p) {
  if (p.z() > 0.35f) return {230, 40, 40};
  if (p.z() < -0.35f) return {40, 40, 230};
  return {40, 200, 40};
}

const TriangleMesh& banded_sphere() {
  static const TriangleMesh mesh = [] {
    TriangleMesh sphere = testing::from_open3d(*open3d::geometry::TriangleMesh::CreateSphere(1.0, 120));
    for (const Vec3f& p : sphere.positions) sphere.colors.push_back(band_colour(p));
    ReconstructOptions options;
    options.resolution = 64;
    return reconstruct(testing::scan_shape(sphere), options).mesh;
  }();
  return mesh;
}

// Mean colour distance from each full-mesh vertex to the nearest vertex the cut uses.
double colour_error(const LodModel& model, const std::vector<Triangle>& tris, const TriangleMesh& full) {
  std::vector<std::uint8_t> used(model.vertices.size(), 0);
  std::vector<std::int32_t> ids;
  for (const Triangle& t : tris)
    for (std::int32_t v : t)
      if (!used[std::size_t(v)]) used[std::size_t(v)] = 1, ids.push_back(v);
  Eigen::MatrixXd points(3, Eigen::Index(ids.size()));
  for (std::size_t i = 0; i < ids.size(); ++i)
    points.col(Eigen::Index(i)) = model.vertices.positions[std::size_t(ids[i])].cast<double>();
  open3d::geometry::KDTreeFlann tree(points);
  double sum = 0;
  std::vector<int> nearest(1);
  std::vector<double> d2(1);
  for (std::size_t v = 0; v < full.positions.size(); ++v) {
    tree.SearchKNN(Eigen::Vector3d(full.positions[v].cast<double>()), 1, nearest, d2);
    const Rgb& a = full.colors[v];
    const Rgb& b = model.vertices.colors[std::size_t(ids[std::size_t(nearest[0])])];
    sum += std::sqrt(double((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                            (a[2] - b[2]) * (a[2] - b[2])));
  }
  return sum / double(full.positions.size());
}

TEST(ClusterHierarchy, ColoursInTheQuadricsKeepColourBands) {
  const TriangleMesh& full = banded_sphere();
  ASSERT_EQ(full.colors.size(), full.positions.size());
  LodModel with, without;
  add_cluster_hierarchy(&with, full, false);
  ClusterOptions blind;
  blind.color_weight = 0;
  add_cluster_hierarchy(&without, full, false, blind);
  const std::int64_t budget = 5000;
  ASSERT_GT(full.triangles.size(), 4u * budget);
  LevelExtractor a(with, LodStructure::kClusters), b(without, LodStructure::kClusters);
  const LevelCut cut_with = a.extract(LevelRequest::at_triangles(budget));
  const LevelCut cut_without = b.extract(LevelRequest::at_triangles(budget));
  const double e_with = colour_error(with, cut_with.triangles, full);
  const double e_without = colour_error(without, cut_without.triangles, full);
  EXPECT_LT(e_with, e_without) << cut_with.triangles.size() << " vs " << cut_without.triangles.size() << " triangles";
  RecordProperty("colour_error_with", std::to_string(e_with));
  RecordProperty("colour_error_without", std::to_string(e_without));
  RecordProperty("triangles", std::to_string(cut_with.triangles.size()) + " of " + std::to_string(full.triangles.size()));
  // And the surface is still the unit sphere.
  const TriangleMesh m = compact_level(with, cut_with.triangles);
  double worst = 0;
  for (const Vec3f& p : m.positions) worst = std::max(worst, std::abs(double(p.norm()) - 1.0));
  EXPECT_LT(worst, 0.02);
}

// A count between two stored cuts is served from a finer one refined to it
// by half-edge collapse (lod/clusters/cut_refinement.h): exactly the count,
// as sound as the full mesh, over the model's own vertices.
TEST(CutRefinement, CountsBetweenStoredCutsGetThemExactlyOverTheModelsVertices) {
  const Built& b = bunny128();
  const MeshTopology full = mesh_topology(b.mesh);
  LevelExtractor extractor(b.model, LodStructure::kClusters);
  const ClusterCutTable table = cluster_cut_table(*b.model.clusters);
  int refined = 0;
  for (std::int64_t budget : {1500, 2500, 4000, 7000, 12000, 25000, 45000, 70000}) {
    const float finer = rank_to_refine(table, budget);
    const LevelCut& cut = extractor.extract(LevelRequest::at_triangles(budget));
    if (finer < 0) {
      EXPECT_EQ(cut.refined_from, 0u) << budget;
      continue;
    }
    ++refined;
    const std::int64_t from = std::int64_t(cut.refined_from), got = std::int64_t(cut.triangles.size());
    EXPECT_GT(from, budget);
    EXPECT_LE(got, budget);
    EXPECT_GE(got, budget - 4) << "collapses take two triangles at a time";
    for (const Triangle& t : cut.triangles)
      for (std::int32_t v : t) ASSERT_LT(std::size_t(v), b.model.vertices.size());
    const MeshTopology t = mesh_topology(level_mesh(b.model, cut.triangles));
    EXPECT_EQ(t.non_manifold_edges, 0u) << budget;
    EXPECT_EQ(t.degenerate_triangles, 0u) << budget;
    EXPECT_LE(t.boundary_loops, full.boundary_loops) << budget;
    EXPECT_LE(t.components, full.components) << budget;
    // The levels a view colours follow the triangles that stayed.
    EXPECT_EQ(extractor.triangle_levels().size(), cut.triangles.size());
    // The stored cut, as the budget rules give it, unrefined; from further
    // than the headroom only where that one misses the budget.
    LevelRequest stored = LevelRequest::at_triangles(budget);
    stored.refine = false;
    const LevelCut& plain = extractor.extract(stored);
    EXPECT_EQ(plain.refined_from, 0u);
    if (double(from) > kRefineHeadroom * double(budget))
      EXPECT_FALSE(meets_budget(std::int64_t(plain.triangles.size()), budget)) << budget << " from " << from;
  }
  EXPECT_GE(refined, 5);
}

// The point of refining: a stored cut between two levels mixes them, and
// its error is the mix of theirs; collapsing a finer cut to the count comes
// closer to the full mesh.
TEST(CutRefinement, RefinedCutsAreCloserThanTheStoredCutsTheyReplace) {
  const Built& b = bunny128();
  LevelExtractor extractor(b.model, LodStructure::kClusters);
  auto error = [&](const LevelRequest& r) {
    const TriangleMesh cut = compact_level(b.model, extractor.extract(r).triangles);
    const SurfaceComparison c = compare_surfaces(cut, b.mesh, CompareOptions{100000, 1});
    return (c.a_to_b.mean + c.b_to_a.mean) / c.diagonal;
  };
  double refined_sum = 0, stored_sum = 0;
  for (std::int64_t budget : {4000, 12000, 25000, 45000, 70000}) {
    LevelRequest stored = LevelRequest::at_triangles(budget);
    stored.refine = false;
    const double r = error(LevelRequest::at_triangles(budget)), s = error(stored);
    std::printf("%lld triangles: refined %.3g, stored %.3g (%.2fx)\n", (long long)budget, r, s, r / s);
    EXPECT_LT(r, 1.1 * s) << budget;
    refined_sum += r, stored_sum += s;
  }
  EXPECT_LT(refined_sum, 0.95 * stored_sum);
}

// A sphere stays a sphere: one piece, closed, Euler characteristic 2.
TEST(CutRefinement, ARefinedSphereIsStillASphere) {
  const TriangleMesh& full = banded_sphere();
  LodModel model;
  add_cluster_hierarchy(&model, full, false);
  LevelExtractor extractor(model, LodStructure::kClusters);
  int refined = 0;
  for (std::int64_t budget : {1200, 2000, 3500, 6000, 10000}) {
    const LevelCut& cut = extractor.extract(LevelRequest::at_triangles(budget));
    if (cut.refined_from == 0) continue;
    ++refined;
    const MeshTopology t = mesh_topology(level_mesh(model, cut.triangles));
    EXPECT_EQ(t.components, 1u) << budget;
    EXPECT_EQ(t.boundary_edges, 0u) << budget;
    EXPECT_EQ(t.non_manifold_edges, 0u) << budget;
    EXPECT_EQ(t.euler_characteristic, 2) << budget;
    const TriangleMesh m = compact_level(model, cut.triangles);
    double worst = 0;
    for (const Vec3f& p : m.positions) worst = std::max(worst, std::abs(double(p.norm()) - 1.0));
    EXPECT_LT(worst, 0.02) << budget;
  }
  EXPECT_GE(refined, 2);
}

}  // namespace
}  // namespace scan2lod
