// The cluster hierarchy built in blocks (ClusterOptions::block_triangles):
// the full detail is the input mesh, every cut is as sound as in core and as
// close to the surface, the build is the same on any core count, and a
// hierarchy spooled to disk writes the same model as one held in memory.
// The pages (runs of clusters a viewer reads at once) tile the clusters and
// hold every cluster a cut draws, in core and in blocks.
// The bunny's scans at R = 256 (about 280 k triangles) in blocks of 16 k:
// 32 blocks in the first pass.
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/core/error.h>
#include <scan2lod/lod/clusters/triangle_spool.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/pipeline/build_model.h>
#include <scan2lod/reconstruct/marching_cubes.h>
#include "test_cluster_cuts.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <random>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;

constexpr std::int64_t kBlock = 16384;

const TriangleMesh& bunny256() {
  static const TriangleMesh mesh = [] {
    ReconstructOptions options;
    options.resolution = 256;
    return reconstruct(load_oriented_points({testing::bunny_scans()}), options).mesh;
  }();
  return mesh;
}

LodModel hierarchy(std::int64_t block, int threads = 0, std::shared_ptr<TriangleSpool> spool = nullptr) {
  ClusterOptions options;
  options.block_triangles = block;
  options.threads = threads;
  options.spool = std::move(spool);
  LodModel model;
  add_cluster_hierarchy(&model, bunny256(), false, options);
  return model;
}

const LodModel& in_core() {
  static const LodModel m = hierarchy(0);
  return m;
}

const LodModel& in_blocks() {
  static const LodModel m = hierarchy(kBlock);
  return m;
}

std::vector<Triangle> sorted_rotated(std::vector<Triangle> tris) {
  for (Triangle& t : tris) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  std::sort(tris.begin(), tris.end());
  return tris;
}

}  // namespace

TEST(ClusterBlocks, FullDetailIsTheInputMeshAndTheTopIsCoarse) {
  LevelExtractor extractor(in_blocks(), LodStructure::kClusters);
  EXPECT_EQ(sorted_rotated(extractor.extract(LevelRequest::at_error(0)).triangles),
            sorted_rotated(bunny256().triangles));
  // No coarser than in core allows, and about twice the mesh stored.
  const std::int64_t core_top = LevelExtractor(in_core(), LodStructure::kClusters).coarsest_triangles();
  EXPECT_LE(extractor.coarsest_triangles(), std::max<std::int64_t>(2 * core_top, 512));
  EXPECT_LE(double(in_blocks().clusters->triangles.size()), 2.4 * double(bunny256().triangles.size()));
}

TEST(ClusterBlocks, EveryCutIsAsSoundAsTheFullMesh) {
  const TriangleMesh& mesh = bunny256();
  const MeshTopology full = mesh_topology(mesh);
  LevelExtractor extractor(in_blocks(), LodStructure::kClusters);
  const std::vector<LevelRequest> cuts = testing::every_uniform_cut(*in_blocks().clusters);
  int checked = 0;
  for (std::size_t i = 0; i < cuts.size(); i += std::max<std::size_t>(1, cuts.size() / 80)) {
    const LevelCut& cut = extractor.extract(cuts[i]);
    if (cut.triangles.size() < 1000) continue;
    const MeshTopology t = mesh_topology(compact_level(in_blocks(), cut.triangles));
    EXPECT_EQ(t.non_manifold_edges, 0u) << cut.triangles.size() << " triangles";
    EXPECT_LE(t.boundary_loops, full.boundary_loops) << cut.triangles.size() << " triangles";
    EXPECT_LE(t.components, full.components) << cut.triangles.size() << " triangles";
    ++checked;
  }
  EXPECT_GT(checked, 10);
  // Cuts seen from cameras mix levels across the blocks' old borders.
  const Aabb box = model_bounds(in_blocks());
  const Vec3f centre = 0.5f * (box.min + box.max);
  std::mt19937 random(11);
  std::uniform_real_distribution<float> unit(-1.f, 1.f);
  for (int view = 0; view < 12; ++view) {
    CameraView camera;
    const Vec3f direction = Vec3f(unit(random), unit(random), unit(random)).normalized();
    camera.eye = centre + direction * box.diagonal() * (0.6f + unit(random) * 0.4f + 0.4f);
    camera.target = centre;
    camera.height = 720;
    for (double pixels : {1.0, 4.0}) {
      const LevelCut& cut = extractor.extract(LevelRequest::for_camera(camera, pixels));
      const MeshTopology t = mesh_topology(compact_level(in_blocks(), cut.triangles));
      EXPECT_EQ(t.non_manifold_edges, 0u) << "view " << view << " at " << pixels << " px";
      EXPECT_LE(t.boundary_loops, full.boundary_loops) << "view " << view << " at " << pixels << " px";
    }
  }
}

TEST(ClusterBlocks, CutsAreAsCloseToTheSurfaceAsInCore) {
  const TriangleMesh& mesh = bunny256();
  CompareOptions compare;
  compare.samples = 100000;
  auto error = [&](const LodModel& model, std::int64_t triangles) {
    LevelExtractor cuts(model, LodStructure::kClusters);
    const SurfaceComparison c =
        compare_surfaces(compact_level(model, cuts.extract(LevelRequest::at_triangles(triangles)).triangles), mesh,
                         compare);
    return (c.a_to_b.mean + c.b_to_a.mean) / 2;
  };
  for (std::int64_t triangles : {2000, 8000, 30000}) {
    const double core = error(in_core(), triangles), blocks = error(in_blocks(), triangles);
    std::printf("%lld triangles: in core %.4g, in blocks %.4g (%.3fx)\n", (long long)triangles, core, blocks,
                blocks / core);
    EXPECT_LE(blocks, 1.1 * core) << triangles << " triangles";
  }
}

TEST(ClusterBlocks, TheSameOnAnyCoreCountAndSpooledOrNot) {
  const std::vector<std::uint8_t> two = encode_model(in_blocks());
  EXPECT_EQ(encode_model(hierarchy(kBlock, 1)), two);
  const fs::path dir = testing::scratch_folder("cluster_blocks");
  const std::string path = (dir / "spool").string();
  {
    LodModel spooled = hierarchy(kBlock, 0, std::make_shared<TriangleSpool>(path));
    ASSERT_TRUE(spooled.clusters->spool);
    EXPECT_TRUE(spooled.clusters->triangles.empty());
    EXPECT_EQ(spooled.clusters->stored_triangles(), in_blocks().clusters->triangles.size());
    // Written from the spool, the model is byte for byte the one from memory,
    // and loads back.
    EXPECT_EQ(encode_model(spooled), two);
    save_model((dir / "spooled.mco").string(), spooled);
    const LodModel loaded = load_model((dir / "spooled.mco").string());
    EXPECT_EQ(loaded.clusters->triangles, in_blocks().clusters->triangles);
    // Cuts need the triangles in memory: refused until they are loaded.
    EXPECT_THROW(LevelExtractor(spooled, LodStructure::kClusters).extract(LevelRequest::at_percent(50)),
                 std::logic_error);
    spooled.clusters->load_spooled();
    EXPECT_EQ(spooled.clusters->triangles, in_blocks().clusters->triangles);
  }
  EXPECT_FALSE(fs::exists(path)) << "the spool is removed with its object";
}

TEST(ClusterBlocks, PagesHoldEveryClusterACutDrawsAndSurviveTheFile) {
  for (const LodModel* model : {&in_core(), &in_blocks()}) {
    const ClusterHierarchy& h = *model->clusters;
    ASSERT_FALSE(h.pages.empty());
    std::size_t next = 0;
    std::vector<std::size_t> page_of(h.clusters.size());
    for (std::size_t i = 0; i < h.pages.size(); ++i) {
      const ClusterPage& p = h.pages[i];
      ASSERT_EQ(p.first_cluster, next) << "pages tile the clusters in order";
      std::size_t triangles = 0;
      const Vec3f centre(p.center[0], p.center[1], p.center[2]);
      for (std::size_t c = p.first_cluster; c < p.first_cluster + p.cluster_count; ++c) {
        page_of[c] = i;
        const Cluster& cl = h.clusters[c];
        if (c > p.first_cluster) {
          EXPECT_EQ(h.clusters[c - 1].first_triangle + h.clusters[c - 1].triangle_count, cl.first_triangle);
        }
        triangles += cl.triangle_count;
        // The sphere holds the page's geometry.
        for (std::uint32_t t = cl.first_triangle; t < cl.first_triangle + cl.triangle_count; ++t)
          for (std::int32_t v : h.triangles[t])
            EXPECT_LE((model->vertices.positions[std::size_t(v)] - centre).norm(), p.radius * 1.0001f);
      }
      EXPECT_TRUE(triangles <= kPageTriangles || p.cluster_count == 1) << "page " << i << ": " << triangles;
      next += p.cluster_count;
    }
    EXPECT_EQ(next, h.clusters.size());
    // Every cluster a uniform cut draws lies in a page whose interval holds the threshold.
    std::vector<float> errors;
    for (const GroupBound& g : h.groups) errors.push_back(g.error);
    std::sort(errors.begin(), errors.end());
    for (std::size_t k = 0; k < errors.size(); k += std::max<std::size_t>(1, errors.size() / 25)) {
      const float t = errors[k];
      for (std::size_t c = 0; c < h.clusters.size(); ++c) {
        const Cluster& cl = h.clusters[c];
        const float own = cl.own_group < 0 ? 0.f : h.groups[std::size_t(cl.own_group)].error;
        const bool parent_applied = cl.parent_group >= 0 && h.groups[std::size_t(cl.parent_group)].error <= t;
        if (own > t || parent_applied) continue;
        const ClusterPage& p = h.pages[page_of[c]];
        EXPECT_TRUE(p.min_error <= t && t < p.max_error) << "cluster " << c << " at " << t;
      }
    }
  }
  // Saved and loaded, the pages are the same; a file without them (a hand-made
  // hierarchy) gets the same derived; a page that skips a cluster is refused.
  const fs::path dir = testing::scratch_folder("cluster_blocks");
  save_model((dir / "pages.mco").string(), in_blocks());
  const LodModel loaded = load_model((dir / "pages.mco").string());
  ASSERT_EQ(loaded.clusters->pages.size(), in_blocks().clusters->pages.size());
  EXPECT_EQ(std::memcmp(loaded.clusters->pages.data(), in_blocks().clusters->pages.data(),
                        sizeof(ClusterPage) * loaded.clusters->pages.size()), 0);
  LodModel bare = loaded;
  bare.clusters->pages.clear();
  const std::vector<std::uint8_t> without = encode_model(bare);
  EXPECT_EQ(encode_model(decode_model(without.data(), without.size(), "bare.mco")), encode_model(loaded));
  LodModel gap = loaded;
  gap.clusters->pages[1].first_cluster += 1;
  const std::vector<std::uint8_t> bad = encode_model(gap);
  try {
    decode_model(bad.data(), bad.size(), "gap.mco");
    ADD_FAILURE() << "a page that skips a cluster was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("section 'PAGE': page 1"), std::string::npos) << e.what();
  }
}

TEST(ClusterBlocks, TheCommandLineBuildsInBlocksThroughASpool) {
  using testing::run_cli;
  const fs::path dir = testing::scratch_folder("cluster_blocks");
  const testing::CliRun r = run_cli("build " + testing::bunny_scans() + " --structure clusters -r 256 --json " +
                                        "--cluster-block 16384 -o " + (dir / "budget.mco").string(),
                                    /*merge_stderr=*/false);
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j.value("cluster_block", 0), 16384) << r.output;
  EXPECT_FALSE(fs::exists(dir / "budget.mco.work")) << "the work folder is removed after success";
  const LodModel m = load_model((dir / "budget.mco").string());
  EXPECT_EQ(m.clusters->full_triangles, std::int64_t(bunny256().triangles.size()));
}

}  // namespace scan2lod
