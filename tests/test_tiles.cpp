// 3D Tiles 1.1 output (delivery/): `scan2lod export M.mco --format 3dtiles`
// on the bunny, checked by CesiumGS's 3D Tiles Validator (bundled in
// ../shared/tools), every tile by the Khronos glTF-Validator, against the
// model's own cluster hierarchy, and against the same model read page by
// page.
#include <scan2lod/delivery/tile_gaps.h>
#include <scan2lod/delivery/tile_tree.h>
#include <scan2lod/delivery/tileset.h>
#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include "test_support.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <set>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using testing::CliRun;
using testing::run_cli;
using testing::run_shell;
using testing::scratch_folder;

constexpr int kTileTriangles = 1500;  // small, so that the bunny at R = 64 makes a deep tree

bool have_node() { return std::system("node --version >/dev/null 2>&1") == 0; }

json read_json(const fs::path& path) {
  std::ifstream in(path);
  return json::parse(in);
}

// The JSON chunk of a .glb.
json glb_json(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_GE(bytes.size(), 20u) << path;
  std::uint32_t magic, length;
  std::memcpy(&magic, bytes.data(), 4);
  std::memcpy(&length, bytes.data() + 12, 4);
  EXPECT_EQ(magic, 0x46546C67u) << path;
  return json::parse(std::string(bytes.data() + 20, length));
}

std::int64_t glb_triangles(const fs::path& path) {
  const json g = glb_json(path);
  const int indices = g["meshes"][0]["primitives"][0]["indices"].get<int>();
  return g["accessors"][std::size_t(indices)]["count"].get<std::int64_t>() / 3;
}

// Every tile of tileset.json, parents before children, with its parent's index.
struct TileJson {
  json tile;
  int parent;
  int depth;
};
std::vector<TileJson> tiles_of(const json& tileset) {
  std::vector<TileJson> out{{tileset["root"], -1, 0}};
  for (std::size_t i = 0; i < out.size(); ++i)
    if (out[i].tile.contains("children"))
      for (const json& c : out[i].tile["children"]) out.push_back({c, int(i), out[i].depth + 1});
  return out;
}

// The bundled 3D Tiles validator's report on a tileset.
json tiles_validator_report(const fs::path& tileset) {
  const fs::path report = tileset.parent_path().parent_path() / (tileset.parent_path().filename().string() + ".report.json");
  const CliRun r = run_shell("node " + std::string(SCAN2LOD_SHARED_DIR) +
                             "/tools/3d-tiles-validator/validator.cjs --tilesetFile " + tileset.string() +
                             " --reportFile " + report.string() + " 2>&1");
  EXPECT_EQ(r.status, 0) << r.output;
  return read_json(report);
}

const fs::path& bunny_tileset() {
  static const fs::path dir = [] {
    const fs::path d = scratch_folder("tiles") / "bunny";
    const CliRun r = run_cli("export " + testing::bunny_model().string() + " --format 3dtiles --tile-triangles " +
                             std::to_string(kTileTriangles) + " -o " + d.string() + " -q");
    EXPECT_EQ(r.status, 0) << r.output;
    return d;
  }();
  return dir;
}

// The plan, and each tile's content as the planner hands it out (empty for
// tiles without).
TileTree plan_with_contents(const LodModel& model, const TileOptions& options, std::vector<TileContent>* contents) {
  const auto keep = [contents](const TileTree&, std::size_t i, const TileContent& c) {
    if (contents->size() <= i) contents->resize(i + 1);
    (*contents)[i] = c;
  };
  const TileTree tree = plan_tiles(model, options, "", keep);
  contents->resize(tree.tiles.size());
  return tree;
}

// Every file under `dir`, by its path there, with its bytes.
std::map<std::string, std::string> files_under(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    files[fs::relative(e.path(), dir).string()] =
        std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  return files;
}

std::vector<float> group_errors(const LodModel& model) {
  std::vector<float> e;
  for (const GroupBound& g : model.clusters->groups) e.push_back(g.error);
  return e;
}

}  // namespace

TEST(Tiles, TheBunnysTilesetHasNoErrorInEitherValidator) {
  if (!have_node()) GTEST_SKIP() << "node is not installed";
  const fs::path dir = bunny_tileset();
  const json report = tiles_validator_report(dir / "tileset.json");
  EXPECT_EQ(report["numErrors"].get<int>(), 0) << report.dump(1);
  EXPECT_EQ(report["numWarnings"].get<int>(), 0) << report.dump(1);

  // The validators cannot decode EXT_meshopt_compression (they report it as
  // an info and skip the data): the same tiles uncompressed are checked whole.
  const fs::path plain = scratch_folder("tiles") / "bunny_plain";
  const CliRun r = run_cli("export " + testing::bunny_model().string() + " --format 3dtiles --no-meshopt " +
                           "--tile-triangles " + std::to_string(kTileTriangles) + " -o " + plain.string() + " -q");
  ASSERT_EQ(r.status, 0) << r.output;
  const json plain_report = tiles_validator_report(plain / "tileset.json");
  EXPECT_EQ(plain_report["numErrors"].get<int>(), 0) << plain_report.dump(1);
  EXPECT_EQ(plain_report["numInfos"].get<int>(), 0) << plain_report.dump(1);
  const fs::path modules = fs::path(SCAN2LOD_BINARY_DIR) / "npm" / "node_modules";
  ASSERT_TRUE(fs::exists(modules / "gltf-validator")) << "run scripts/build.sh deps";
  std::string files;
  int count = 0;
  for (const fs::path& d : {dir, plain})
    for (const auto& e : fs::directory_iterator(d / "tiles")) files += " " + e.path().string(), ++count;
  ASSERT_GT(count, 8);
  const CliRun v = run_shell("node " + std::string(SCAN2LOD_SOURCE_DIR) + "/tests/gltf/validate.mjs " +
                             modules.string() + files + " 2>&1");
  EXPECT_EQ(v.status, 0) << v.output.substr(0, 3000);
  std::size_t clean = 0;
  for (std::size_t at = 0; (at = v.output.find("\"numErrors\":0,\"numWarnings\":0", at)) != std::string::npos; ++at)
    ++clean;
  EXPECT_EQ(clean, std::size_t(count)) << v.output.substr(0, 3000);
}

// The root holds the coarsest cut; every other tile at most the bound; errors
// are the hierarchy's measured group errors and never grow going down.
TEST(Tiles, RootIsTheCoarsestCutAndErrorsAreMeasuredAndFallDownward) {
  const fs::path dir = bunny_tileset();
  const LodModel model = load_model(testing::bunny_model().string());
  const std::vector<float> errors = group_errors(model);
  const float coarsest = *std::max_element(errors.begin(), errors.end());
  LevelExtractor extractor(model, LodStructure::kClusters);
  const std::int64_t coarsest_triangles = std::int64_t(extractor.extract(LevelRequest::at_error(coarsest)).triangles.size());
  EXPECT_EQ(coarsest_triangles, extractor.coarsest_triangles());

  const std::vector<TileJson> tiles = tiles_of(read_json(dir / "tileset.json"));
  ASSERT_GT(tiles.size(), 8u);
  EXPECT_EQ(tiles[0].tile["refine"], "REPLACE");
  EXPECT_EQ(glb_triangles(dir / tiles[0].tile["content"]["uri"].get<std::string>()), coarsest_triangles);
  EXPECT_FLOAT_EQ(tiles[0].tile["geometricError"].get<float>(), coarsest);
  int deepest = 0;
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const json& t = tiles[i].tile;
    const float e = t["geometricError"].get<float>();
    EXPECT_TRUE(e == 0 || std::find(errors.begin(), errors.end(), e) != errors.end())
        << "tile " << i << ": geometricError " << e << " is no group's measured error";
    if (tiles[i].parent >= 0) {
      EXPECT_LE(e, tiles[std::size_t(tiles[i].parent)].tile["geometricError"].get<float>()) << "tile " << i;
    }
    if (i > 0 && t.contains("content")) {
      EXPECT_LE(glb_triangles(dir / t["content"]["uri"].get<std::string>()), kTileTriangles) << "tile " << i;
    }
    deepest = std::max(deepest, tiles[i].depth);
  }
  EXPECT_GE(deepest, 2);
}

// The leaves hold full detail: their triangles, without the ones two cells
// share, are the full-detail cut, triangle for triangle.
TEST(Tiles, TheLeavesTogetherAreTheFullDetailMesh) {
  const LodModel model = load_model(testing::bunny_model().string());
  TileOptions options;
  options.max_triangles = kTileTriangles;
  std::vector<TileContent> contents;
  const TileTree tree = plan_with_contents(model, options, &contents);
  std::set<Triangle> leaves;
  std::int64_t leaf_triangles = 0;
  for (std::size_t i = 0; i < tree.tiles.size(); ++i) {
    const Tile& t = tree.tiles[i];
    if (!t.leaf()) continue;
    EXPECT_EQ(t.threshold, kFullDetail) << t.name;
    EXPECT_EQ(t.geometric_error, 0.f) << t.name;
    EXPECT_EQ(std::int64_t(contents[i].triangles.size()), t.triangle_count) << t.name;
    const std::vector<std::uint32_t>& model_vertex = contents[i].model_vertices;
    for (const Triangle& tri : contents[i].triangles)
      leaves.insert({std::int32_t(model_vertex[std::size_t(tri[0])]), std::int32_t(model_vertex[std::size_t(tri[1])]),
                     std::int32_t(model_vertex[std::size_t(tri[2])])});
    leaf_triangles += t.triangle_count;
  }
  LevelExtractor extractor(model, LodStructure::kClusters);
  std::vector<Triangle> full = extractor.extract(LevelRequest::at_percent(100)).triangles;
  const std::set<Triangle> full_set(full.begin(), full.end());
  EXPECT_EQ(std::int64_t(leaves.size()), model.clusters->full_triangles);
  EXPECT_EQ(leaves, full_set);
  // Cells share the triangles that cross their faces: a few percent more.
  EXPECT_LT(double(leaf_triangles), 1.5 * double(leaves.size()));
  // The files hold the plan's tiles.
  const std::vector<TileJson> tiles = tiles_of(read_json(bunny_tileset() / "tileset.json"));
  EXPECT_EQ(tiles.size(), tree.tiles.size());
}

// Where tiles of different depths meet, the gap between their surfaces stays
// under the larger of their geometric errors (plus a quantization step).
TEST(Tiles, GapsBetweenNeighbouringTilesStayUnderTheirError) {
  const LodModel model = load_model(testing::bunny_model().string());
  TileOptions options;
  options.max_triangles = kTileTriangles;
  std::vector<TileContent> contents;
  const TileTree tree = plan_with_contents(model, options, &contents);
  const double step = tileset_quantization_step(tree, TileGlbOptions{});
  const TileGaps gaps = measure_tile_gaps(tree, contents, step);
  for (std::size_t d = 0; d < gaps.by_depth_difference.size(); ++d)
    std::printf("depth difference %zu%s: %lld seam points, widest gap %.3g (%.3g of the bounds' diagonal), "
                "largest gap/error %.3g, over the error %lld\n",
                d, d + 1 == gaps.by_depth_difference.size() ? "+" : "",
                (long long)gaps.by_depth_difference[d].points, gaps.by_depth_difference[d].max_gap,
                gaps.by_depth_difference[d].max_gap / tree.bounds.diagonal(), gaps.by_depth_difference[d].max_ratio,
                (long long)gaps.by_depth_difference[d].over);
  EXPECT_GT(gaps.by_depth_difference[1].points, 100);
  EXPECT_EQ(gaps.all.over, 0);
  EXPECT_LT(gaps.all.max_ratio, 1.0);
}

// Read page by page within a budget smaller than a page, so that every page
// is dropped and read again as the planner comes back to it, the model
// gives the same tileset as loaded whole: every .glb and tileset.json, byte
// for byte.
TEST(Tiles, APagedModelGivesTheWholeModelsTilesetByteForByte) {
  const std::string path = testing::bunny_model().string();
  const LodModel whole = load_model(path);
  std::optional<LodModel> paged = open_paged_model(path, 1);
  ASSERT_TRUE(paged) << path << " has no pages";
  ASSERT_EQ(paged->vertices.size(), 0u);
  TilesetOptions options;
  options.tiles.max_triangles = kTileTriangles;
  const fs::path base = scratch_folder("tiles_paged");
  const TilesetReport from_whole = write_tileset(whole, (base / "whole").string(), options);
  const TilesetReport from_pages = write_tileset(*paged, (base / "paged").string(), options);
  EXPECT_EQ(from_pages.tiles, from_whole.tiles);
  EXPECT_EQ(from_pages.bytes, from_whole.bytes);
  EXPECT_GT(paged->clusters->paged->stats().pages_read, paged->clusters->paged->size());

  const std::map<std::string, std::string> a = files_under(base / "whole"), b = files_under(base / "paged");
  EXPECT_EQ(a.size(), from_whole.content_tiles + 1);
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    const auto other = b.find(name);
    ASSERT_NE(other, b.end()) << name << " is missing from the paged model's tileset";
    EXPECT_TRUE(bytes == other->second) << name << " differs (" << bytes.size() << " and " << other->second.size()
                                        << " bytes)";
  }
}

// A model with an origin (georeferenced inputs) gets it as the root's
// transform; the tiles and boxes are the same as without it.
TEST(Tiles, TheModelsOriginIsTheRootTransform) {
  LodModel model = load_model(testing::bunny_model().string());
  const Vec3d origin(501000.25, 5002000.5, 300.125);
  model.origin = origin;
  const fs::path path = scratch_folder("tiles") / "bunny_utm.mco", dir = scratch_folder("tiles") / "bunny_utm";
  save_model(path.string(), model);
  const CliRun r = run_cli("export " + path.string() + " --format 3dtiles --tile-triangles " +
                           std::to_string(kTileTriangles) + " -o " + dir.string() + " -q");
  ASSERT_EQ(r.status, 0) << r.output;
  const json with = read_json(dir / "tileset.json"), without = read_json(bunny_tileset() / "tileset.json");
  const std::vector<double> expected = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, origin.x(), origin.y(), origin.z(), 1};
  EXPECT_EQ(with["root"]["transform"].get<std::vector<double>>(), expected);
  EXPECT_FALSE(without["root"].contains("transform"));
  json stripped = with;
  stripped["root"].erase("transform");
  EXPECT_EQ(stripped["root"], without["root"]);
  if (!have_node()) return;
  const json report = tiles_validator_report(dir / "tileset.json");
  EXPECT_EQ(report["numErrors"].get<int>(), 0) << report.dump(1);
}

// Each tile's box holds its own vertices as the glb stores them (turned to
// glTF's y-up, quantized), and a parent's box holds its children's.
TEST(Tiles, BoxesHoldTheTilesVertices) {
  const fs::path dir = bunny_tileset();
  const std::vector<TileJson> tiles = tiles_of(read_json(dir / "tileset.json"));
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const json& t = tiles[i].tile;
    if (!t.contains("content")) continue;
    const std::vector<double> box = t["content"]["boundingVolume"]["box"].get<std::vector<double>>();
    const json g = glb_json(dir / t["content"]["uri"].get<std::string>());
    const json& position = g["accessors"][0];
    const std::vector<double> lo = position["min"], hi = position["max"];
    const std::vector<double> translation = g["nodes"][0]["translation"], scale = g["nodes"][0]["scale"];
    // glTF (x, y, z) is the tileset's (x, -z, y).
    for (int k = 0; k < 3; ++k) {
      const int gk = k == 0 ? 0 : k == 1 ? 2 : 1;
      const double sign = k == 1 ? -1 : 1;
      double a = sign * (translation[std::size_t(gk)] + scale[0] * lo[std::size_t(gk)] / 32767);
      double b = sign * (translation[std::size_t(gk)] + scale[0] * hi[std::size_t(gk)] / 32767);
      if (a > b) std::swap(a, b);
      const double centre = box[std::size_t(k)], half = box[std::size_t(3 + 4 * k)];
      EXPECT_GE(a, centre - half - 1e-6) << "tile " << i << " axis " << k;
      EXPECT_LE(b, centre + half + 1e-6) << "tile " << i << " axis " << k;
      // Tight: within two quantization steps of the vertices.
      EXPECT_LE(std::max(a - (centre - half), (centre + half) - b), 2.5 * scale[0] / 32767) << "tile " << i;
    }
  }
}

// A failed export leaves no folder; a folder of other files, or one holding
// the model, is not replaced.
TEST(Tiles, AFailedExportLeavesNothingAndOtherFoldersAreKept) {
  const fs::path base = scratch_folder("tiles_refusals");
  const CliRun missing = run_cli("export " + testing::bunny_model().string() + " --format 3dtiles -o " +
                                 (base / "no" / "such" / "out").string() + " -q");
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.output.find("does not exist"), std::string::npos) << missing.output;
  EXPECT_FALSE(fs::exists(base / "no"));

  fs::create_directories(base / "photos");
  std::ofstream(base / "photos" / "keep.jpg") << "x";
  const CliRun other = run_cli("export " + testing::bunny_model().string() + " --format 3dtiles -o " +
                               (base / "photos").string() + " -q");
  EXPECT_NE(other.status, 0);
  EXPECT_NE(other.output.find("no tileset.json"), std::string::npos) << other.output;
  EXPECT_TRUE(fs::exists(base / "photos" / "keep.jpg"));

  const CliRun not_model = run_cli("export " + (base / "photos" / "keep.jpg").string() + " --format 3dtiles -o " +
                                   (base / "out").string() + " -q");
  EXPECT_NE(not_model.status, 0);
  EXPECT_NE(not_model.output.find("keep.jpg"), std::string::npos) << not_model.output;
  EXPECT_FALSE(fs::exists(base / "out"));
  for (const auto& e : fs::directory_iterator(base))
    EXPECT_EQ(e.path().filename().string().find(".partial"), std::string::npos) << e.path();

  // An old tileset is replaced whole.
  const fs::path dir = base / "again";
  for (int run = 0; run < 2; ++run) {
    const CliRun r = run_cli("export " + testing::bunny_model().string() + " --format 3dtiles -o " + dir.string() +
                             " --tile-triangles " + std::to_string(run == 0 ? 500 : 100000) + " -q");
    ASSERT_EQ(r.status, 0) << r.output;
  }
  std::size_t files = 0, content = 0;
  for (const auto& e : fs::directory_iterator(dir / "tiles")) files += e.is_regular_file();
  for (const TileJson& t : tiles_of(read_json(dir / "tileset.json"))) content += t.tile.contains("content");
  EXPECT_EQ(files, content);
}

}  // namespace scan2lod
