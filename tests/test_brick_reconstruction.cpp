// Reconstruction brick by brick gives the in-core surface: the same triangles
// at the same positions, on the bunny's real scans and on a scanned torus,
// whatever the brick size; its cluster cuts are as close; it resumes from the
// bricks a build left, also after SIGKILL; and a budget below one brick is
// refused with the minimum.
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/core/error.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/pipeline/build_model.h>
#include <scan2lod/reconstruct/brick_reconstruction.h>
#include <scan2lod/reconstruct/resolution_guard.h>

#include "test_shapes.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <open3d/geometry/TriangleMesh.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>

using namespace scan2lod;
namespace fs = std::filesystem;

namespace {

// Each triangle as its three corners, rotated so the smallest comes first
// (orientation kept), sorted: meshes equal as surfaces compare equal whatever
// their numbering.
using Corners = std::array<std::array<float, 3>, 3>;
std::vector<Corners> canonical(const TriangleMesh& mesh) {
  std::vector<Corners> out;
  for (const Triangle& t : mesh.triangles) {
    Corners c;
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) c[k][a] = mesh.positions[t[k]][a];
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    out.push_back(c);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The largest corner distance between two surfaces of equal triangles, or
// infinity when their triangle counts differ.
double largest_move(const TriangleMesh& a, const TriangleMesh& b) {
  const std::vector<Corners> ca = canonical(a), cb = canonical(b);
  if (ca.size() != cb.size()) return std::numeric_limits<double>::infinity();
  double worst = 0;
  for (std::size_t i = 0; i < ca.size(); ++i)
    for (int k = 0; k < 3; ++k)
      for (int x = 0; x < 3; ++x) worst = std::max(worst, double(std::fabs(ca[i][k][x] - cb[i][k][x])));
  return worst;
}

const OrientedPoints& bunny_points() {
  static const OrientedPoints points = load_oriented_points({std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf"});
  return points;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = scan2lod::testing::scratch_folder("bricks") / name;
  fs::remove_all(dir);
  return dir;
}

}  // namespace

TEST(BrickReconstruction, BunnyInBricksIsTheInCoreSurface) {
  // Pieces and holes are decided on the welded whole as in core: with and
  // without hole closing, the same triangles at the same positions.
  for (double max_hole : {0.4, 0.0}) {
    ReconstructOptions options;
    options.resolution = 128;
    options.max_hole = max_hole;
    const Reconstruction whole = reconstruct(bunny_points(), options);
    const double diagonal = bounds(whole.mesh.positions).diagonal();
    for (int cubes : {32, 64}) {
      BrickOptions bricks;
      bricks.work_dir = fresh_dir("bunny" + std::to_string(cubes)).string();
      bricks.brick_cubes = cubes;
      BrickStats stats;
      const Reconstruction parts = reconstruct_in_bricks(bunny_points(), options, bricks, &stats);
      SCOPED_TRACE("bricks of " + std::to_string(cubes) + ", max_hole " + std::to_string(max_hole));
      EXPECT_GE(stats.bricks, 8u);
      EXPECT_EQ(parts.stats.patch_triangles, whole.stats.patch_triangles);
      EXPECT_EQ(parts.mesh.triangles.size(), whole.mesh.triangles.size());
      EXPECT_LE(largest_move(parts.mesh, whole.mesh), 1e-6 * diagonal);
      const MeshTopology a = mesh_topology(whole.mesh), b = mesh_topology(parts.mesh);
      EXPECT_EQ(b.boundary_loops, a.boundary_loops);
      EXPECT_EQ(b.non_manifold_edges, 0u);
    }
  }
}

TEST(BrickReconstruction, PointsSpooledToDiskGiveTheInCoreSurface) {
  // Scan by scan to a spool on disk, binned by brick there: no more than two
  // scans' points are in memory at once, and the surface is the in-core one.
  ReconstructOptions options;
  options.resolution = 128;
  const Reconstruction whole = reconstruct(bunny_points(), options);
  BuildOptions build;
  build.reconstruct = options;
  build.octree = false;
  build.strategy = BuildStrategy::kBricks;
  build.brick_cubes = 32;
  build.work_dir = (fresh_dir("spooled") / "work").string();
  AcquisitionReport acquisition;
  InputPoints points = load_within_budget({std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf"}, build,
                                          &acquisition);
  ASSERT_TRUE(points.spool);
  EXPECT_EQ(points.points.size(), 0u);
  EXPECT_EQ(points.size(), bunny_points().size());
  EXPECT_EQ(acquisition.range_images, 10u);
  const PointCensus census = points.spool->census();
  EXPECT_EQ(census.hash, census_of(bunny_points()).hash);  // the records of the merged points, byte for byte
  EXPECT_TRUE(census.spacing && census.confidence);
  const std::string spool_path = points.spool->path();
  EXPECT_TRUE(fs::exists(spool_path));
  BuildReport report;
  const Reconstruction parts = reconstruct_within_budget(&points, build, &report);
  EXPECT_FALSE(points.spool);  // freed once binned
  EXPECT_FALSE(fs::exists(spool_path));
  EXPECT_TRUE(report.in_bricks);
  EXPECT_GE(report.bricks.bricks, 8u);
  EXPECT_EQ(parts.mesh.triangles.size(), whole.mesh.triangles.size());
  EXPECT_LE(largest_move(parts.mesh, whole.mesh), 1e-6 * bounds(whole.mesh.positions).diagonal());
  EXPECT_EQ(mesh_topology(parts.mesh).boundary_loops, mesh_topology(whole.mesh).boundary_loops);
}

TEST(BrickReconstruction, ScannedTorusInBricksIsTheInCoreSurfaceWithWideSpacings) {
  // Stray points of wide spacing (as a scan's grazing rim leaves) reach far:
  // the bricks near them widen their halo until every value is the whole
  // set's.
  auto torus = open3d::geometry::TriangleMesh::CreateTorus(1.0, 0.35, 120, 60);
  OrientedPoints points = scan2lod::testing::scan_shape(scan2lod::testing::from_open3d(*torus), 14, 200);
  ASSERT_EQ(points.spacing.size(), points.size());
  for (const Vec3f& stray : {Vec3f(0.0f, 0.0f, 1.4f), Vec3f(2.4f, 0.0f, 0.2f), Vec3f(-0.3f, 2.2f, -0.9f)}) {
    points.positions.push_back(stray);
    points.normals.push_back(Vec3f::UnitZ());
    points.confidence.push_back(1.f);
    points.spacing.push_back(0.4f);
  }
  ReconstructOptions options;
  options.resolution = 64;
  const Reconstruction whole = reconstruct(points, options);
  BrickOptions bricks;
  bricks.work_dir = fresh_dir("torus").string();
  bricks.brick_cubes = 16;
  BrickStats stats;
  const Reconstruction parts = reconstruct_in_bricks(points, options, bricks, &stats);
  const BrickPlan plan = plan_bricks(points, options, bricks);
  EXPECT_GT(stats.widest_halo, 1.2 * plan.halo);
  EXPECT_EQ(parts.mesh.triangles.size(), whole.mesh.triangles.size());
  EXPECT_LE(largest_move(parts.mesh, whole.mesh), 1e-6 * bounds(whole.mesh.positions).diagonal());
  EXPECT_EQ(mesh_topology(parts.mesh).euler_characteristic, mesh_topology(whole.mesh).euler_characteristic);
}

TEST(BrickReconstruction, ResumesFromFinishedBricksWithTheSameSurface) {
  ReconstructOptions options;
  options.resolution = 64;
  BrickOptions bricks;
  bricks.work_dir = fresh_dir("resume").string();
  bricks.brick_cubes = 16;
  BrickStats first;
  const Reconstruction a = reconstruct_in_bricks(bunny_points(), options, bricks, &first);
  // As a killed build leaves it: some bricks never written, one cut short;
  // and one changed on disk.
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(fs::path(bricks.work_dir) / "bricks")) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_GT(files.size(), 8u);
  for (std::size_t i = 0; i < files.size(); i += 3) fs::remove(files[i]);
  fs::resize_file(files[1], fs::file_size(files[1]) / 2);
  {
    // One flipped byte in the middle of another: run again, not trusted.
    std::fstream f(files[2], std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(std::streamoff(fs::file_size(files[2]) / 2));
    const char byte = char(f.peek() ^ 0x5a);
    f.seekp(std::streamoff(fs::file_size(files[2]) / 2));
    f.put(byte);
  }
  BrickStats second;
  const Reconstruction b = reconstruct_in_bricks(bunny_points(), options, bricks, &second);
  EXPECT_GT(second.bricks_resumed, 0u);
  EXPECT_LT(second.bricks_resumed, first.bricks);
  ASSERT_EQ(a.mesh.triangles.size(), b.mesh.triangles.size());
  EXPECT_TRUE(a.mesh.triangles == b.mesh.triangles);
  EXPECT_EQ(0, std::memcmp(a.mesh.positions.data(), b.mesh.positions.data(), a.mesh.positions.size() * sizeof(Vec3f)));
  // Another resolution is another plan: nothing is taken from these bricks.
  options.resolution = 32;
  BrickStats other;
  reconstruct_in_bricks(bunny_points(), options, bricks, &other);
  EXPECT_EQ(other.bricks_resumed, 0u);
}

TEST(BrickReconstruction, ABudgetBelowOneBrickIsRefusedWithTheMinimum) {
  ReconstructOptions options;
  options.resolution = 256;
  BrickOptions bricks;
  bricks.memory_bytes = 1 << 20;
  try {
    plan_bricks(bunny_points(), options, bricks);
    FAIL() << "a 1 MiB budget was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("below what one brick needs"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("at least"), std::string::npos) << e.what();
  }
  bricks.memory_bytes = 150.0 * (1 << 20);
  const BrickPlan plan = plan_bricks(bunny_points(), options, bricks);
  EXPECT_LE(plan.brick_bytes, bricks.memory_bytes);
  EXPECT_LT(plan.brick_cubes, 256);
}

TEST(BrickReconstruction, AKilledBuildRunAgainGivesTheSameModel) {
  using scan2lod::testing::run_cli;
  const fs::path dir = fresh_dir("killed");
  fs::create_directories(dir);
  const std::string conf = std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf";
  const std::string common = " --structure clusters -r 128 --brick-cubes 32 --quiet --work-dir ";
  ASSERT_EQ(run_cli("build " + conf + " -o " + (dir / "whole.mco").string() + common + (dir / "w1").string()).status, 0);
  // Killed at some moment (SIGKILL: nothing of it runs on), then run again.
  const std::string again = "build " + conf + " -o " + (dir / "again.mco").string() + common + (dir / "w2").string();
  std::system(("timeout -s KILL 0.6 " + std::string(SCAN2LOD_CLI) + " " + again + " >/dev/null 2>&1").c_str());
  EXPECT_FALSE(fs::exists(dir / "again.mco"));
  ASSERT_EQ(run_cli(again).status, 0);
  std::ifstream a(dir / "whole.mco", std::ios::binary), b(dir / "again.mco", std::ios::binary);
  const std::string bytes_a((std::istreambuf_iterator<char>(a)), {}), bytes_b((std::istreambuf_iterator<char>(b)), {});
  EXPECT_GT(bytes_a.size(), 0u);
  EXPECT_TRUE(bytes_a == bytes_b);
}

TEST(BrickReconstruction, TheCommandLineRefusesABudgetBelowOneBrick) {
  using scan2lod::testing::run_cli;
  const fs::path dir = fresh_dir("refused");
  fs::create_directories(dir);
  const scan2lod::testing::CliRun r = run_cli("build " + std::string(SCAN2LOD_SOURCE_DIR) +
                                              "/data/bunny/bun.conf --structure clusters --memory 1M -o " +
                                              (dir / "m.mco").string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("below what one brick needs"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("at least"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_empty(dir));
  // The octree needs every leaf cube at once: in bricks it is refused, naming why.
  const scan2lod::testing::CliRun o = run_cli("build " + std::string(SCAN2LOD_SOURCE_DIR) +
                                              "/data/bunny/bun.conf --brick-cubes 64 -o " + (dir / "o.mco").string());
  EXPECT_NE(o.status, 0);
  EXPECT_NE(o.output.find("--structure clusters"), std::string::npos) << o.output;
}

TEST(BrickReconstruction, ASurfaceTheMachineCannotWeldIsRefusedBeforeItsBricks) {
  // The weld still holds the whole surface: at a resolution whose surface
  // this machine cannot hold, the build stops before the work folder is made,
  // naming the machine's memory and a resolution that fits.
  using scan2lod::testing::run_cli;
  ReconstructOptions options;
  BrickOptions bricks;
  bricks.memory_bytes = 1024.0 * (1 << 20);
  int R = 2048;
  for (options.resolution = R; plan_bricks(bunny_points(), options, bricks).weld_bytes <= machine_memory_bytes();)
    options.resolution = R *= 2;
  const fs::path dir = fresh_dir("machine");
  fs::create_directories(dir);
  const scan2lod::testing::CliRun r =
      run_cli("build " + std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf --structure clusters -r " +
              std::to_string(R) + " --memory 1G --work-dir " + (dir / "work").string() + " -o " +
              (dir / "m.mco").string());
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("more than this machine's " + binary_size(machine_memory_bytes())), std::string::npos)
      << r.output;
  const std::size_t at = r.output.find("--resolution ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const int fits = std::atoi(r.output.c_str() + at + 13);
  EXPECT_TRUE(fits > 0 && fits < R) << r.output;
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(BrickReconstruction, ClusterHierarchyOfABrickBuildIsTheInCoreOne) {
  // The welded mesh numbers its vertices and triangles otherwise than the
  // in-core one; in the same blocks (as any build of a mesh of more than
  // kWholeMeshTriangles gets, at any budget that holds them) the hierarchy
  // is the same, cut for cut.
  BuildOptions options;
  options.reconstruct.resolution = 128;
  options.octree = false;
  options.cluster_block = 8192;
  options.strategy = BuildStrategy::kInCore;
  const LodModel core = build_model(bunny_points(), nullptr, options);
  options.strategy = BuildStrategy::kBricks;
  options.brick_cubes = 32;
  options.work_dir = fresh_dir("cuts").string();
  BuildReport report;
  LodModel bricks = build_model(bunny_points(), nullptr, options, &report);
  ASSERT_TRUE(report.in_bricks);
  ASSERT_GE(report.bricks.bricks, 8u);
  bricks.clusters->load_spooled();
  ASSERT_GT(core.clusters->full_triangles, 3 * options.cluster_block);
  EXPECT_EQ(bricks.clusters->size(), core.clusters->size());
  EXPECT_EQ(bricks.clusters->groups.size(), core.clusters->groups.size());
  EXPECT_EQ(bricks.clusters->stored_triangles(), core.clusters->stored_triangles());
  LevelExtractor full(core, LodStructure::kClusters);
  const TriangleMesh reference = compact_level(core, full.extract(LevelRequest::at_percent(100)).triangles);
  CompareOptions compare;
  compare.samples = 100000;
  auto cut = [&](const LodModel& model, std::int64_t triangles) {
    LevelExtractor cuts(model, LodStructure::kClusters);
    return compact_level(model, cuts.extract(LevelRequest::at_triangles(triangles)).triangles);
  };
  for (std::int64_t triangles : {1000, 4000, 16000}) {
    const TriangleMesh a = cut(core, triangles), b = cut(bricks, triangles);
    EXPECT_EQ(b.triangles.size(), a.triangles.size()) << triangles << " triangles";
    const SurfaceComparison in_core = compare_surfaces(a, reference, compare);
    const SurfaceComparison in_bricks = compare_surfaces(b, reference, compare);
    EXPECT_DOUBLE_EQ(in_bricks.a_to_b.mean, in_core.a_to_b.mean) << triangles << " triangles";
    EXPECT_DOUBLE_EQ(in_bricks.b_to_a.max, in_core.b_to_a.max) << triangles << " triangles";
  }
}

TEST(BrickReconstruction, TheBuildReportsItsMemoryEstimatedAndMeasured) {
  using scan2lod::testing::run_cli;
  const fs::path dir = fresh_dir("memory");
  fs::create_directories(dir);
  const scan2lod::testing::CliRun r =
      run_cli("build " + std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf --structure clusters -r 128 " +
                  "--brick-cubes 32 --memory 300M --json -o " + (dir / "m.mco").string(),
              /*merge_stderr=*/false);
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  const nlohmann::json& m = j.at("memory_mib");
  EXPECT_DOUBLE_EQ(m.at("budget").get<double>(), 300.0);
  EXPECT_GT(m.at("estimated").at("brick").get<double>(), 0.0);
  EXPECT_LE(m.at("estimated").at("brick").get<double>(), 300.0);
  EXPECT_GT(m.at("estimated").at("weld").get<double>(), 0.0);
  EXPECT_GT(m.at("estimated").at("clusters").get<double>(), 0.0);
  EXPECT_GT(m.at("peak_after").at("reconstruct").get<double>(), 10.0);
  EXPECT_GE(m.at("peak_after").at("clusters").get<double>(), m.at("peak_after").at("reconstruct").get<double>());
  EXPECT_GE(j.at("bricks").at("bricks").get<int>(), 8);
}

// The bunny in eight bricks under a budget that the weld and the hierarchy
// can hold too: no stage goes past it (10 % for what RSS sampling misses),
// and each stage's estimate is not far under what it took.
TEST(BrickReconstruction, ABunnyInEightBricksKeepsItsBudgetAtEveryStage) {
  using scan2lod::testing::run_cli;
  const fs::path dir = fresh_dir("budget");
  fs::create_directories(dir);
  const double budget = 160.0;
  const scan2lod::testing::CliRun r =
      run_cli("build " + std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun.conf --structure clusters -r 256 " +
                  "--memory 160M --json --work-dir " + (dir / "work").string() + " -o " + (dir / "m.mco").string(),
              /*merge_stderr=*/false);
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  ASSERT_GE(j.at("bricks").at("bricks").get<int>(), 8);
  const nlohmann::json& m = j.at("memory_mib");
  const double reconstruct = m.at("peak_after").at("reconstruct").get<double>();
  const double clusters = m.at("peak_after").at("clusters").get<double>();
  EXPECT_LE(reconstruct, 1.1 * budget);
  EXPECT_LE(clusters, 1.1 * budget);
  EXPECT_GE(m.at("estimated").at("weld").get<double>(), 0.9 * reconstruct);
  EXPECT_GE(m.at("estimated").at("clusters").get<double>(), 0.9 * clusters);
  EXPECT_LE(m.at("estimated").at("clusters").get<double>(), budget);
}
