// Reading a model page by page (lod/clusters/paged_model.h): every cut is the whole
// model's cut, byte for byte; the pages held never exceed the budget; a cut
// reads only its own pages; a damaged page is named when it is read; and a
// file without pages is left to load_model.
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/core/error.h>
#include <scan2lod/lod/clusters/page_geometry.h>
#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/clusters/paged_view.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

using namespace scan2lod;
namespace fs = std::filesystem;

namespace {

// The bunny at R = 128, clusters alone: about 250 k triangles stored, 47 pages.
const fs::path& bunny128() {
  static const fs::path path = [] {
    const OrientedPoints points = load_oriented_points({scan2lod::testing::bunny_scans()});
    ReconstructOptions options;
    options.resolution = 128;
    const Reconstruction r = reconstruct(points, options);
    LodModel m;
    add_cluster_hierarchy(&m, r.mesh, false);
    const fs::path p = scan2lod::testing::scratch_folder("paged") / "bunny128.mco";
    save_model(p.string(), m);
    return p;
  }();
  return path;
}

const LodModel& whole() {
  static const LodModel m = load_model(bunny128().string());
  return m;
}

std::vector<LevelRequest> requests() {
  const Aabb box = model_bounds(whole());
  const Vec3f centre = 0.5f * (box.min + box.max);
  std::vector<LevelRequest> r = {LevelRequest::at_percent(100), LevelRequest::at_percent(30),
                                 LevelRequest::at_percent(0), LevelRequest::at_triangles(5000),
                                 LevelRequest::at_error(whole().clusters->groups.back().error / 4)};
  // Orbiting near and far: cuts that mix levels.
  for (int i = 0; i < 8; ++i) {
    CameraView c;
    c.target = centre;
    const float a = 0.8f * float(i), d = box.diagonal() * (i % 2 ? 0.6f : 2.5f);
    c.eye = centre + Vec3f(d * std::cos(a), 0.2f * d, d * std::sin(a));
    r.push_back(LevelRequest::for_camera(c, 1.0));
  }
  return r;
}

void expect_same_mesh(const TriangleMesh& a, const TriangleMesh& b, const std::string& what) {
  EXPECT_EQ(a.triangles, b.triangles) << what;
  EXPECT_EQ(a.positions, b.positions) << what;
  EXPECT_EQ(a.normals, b.normals) << what;
  EXPECT_EQ(a.colors, b.colors) << what;
}

std::vector<char> file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const fs::path& p, const std::vector<char>& b) {
  std::ofstream(p, std::ios::binary).write(b.data(), std::streamsize(b.size()));
}

// Where a section's payload lies, from the directory (lod/model_file.h).
std::pair<std::uint64_t, std::uint64_t> section_of(const std::vector<char>& b, const char (&tag)[5]) {
  std::uint32_t count;
  std::memcpy(&count, b.data() + 16, 4);
  for (std::uint32_t i = 0; i < count; ++i) {
    const char* e = b.data() + 40 + 48 * i;
    if (std::memcmp(e, tag, 4) != 0) continue;
    std::uint64_t offset, length;
    std::memcpy(&offset, e + 24, 8);
    std::memcpy(&length, e + 32, 8);
    return {offset, length};
  }
  ADD_FAILURE() << "no section " << tag;
  return {0, 0};
}

// What opening `path` page by page throws, or "opened" when it opens.
std::string open_error(const fs::path& path) {
  try {
    open_paged_model(path.string(), 1 << 20);
    return "opened";
  } catch (const InputError& e) {
    return e.what();
  }
}

}  // namespace

TEST(PagedModel, EveryCutIsTheWholeModelsCut) {
  std::optional<LodModel> paged = open_paged_model(bunny128().string(), std::uint64_t(1) << 30);
  ASSERT_TRUE(paged.has_value());
  EXPECT_FALSE(paged->octree.has_value());
  EXPECT_TRUE(paged->clusters->triangles.empty());
  EXPECT_EQ(paged->clusters->stored_triangles(), whole().clusters->stored_triangles());
  EXPECT_GT(paged->clusters->pages.size(), 30u);
  // The box from the pages' boxes is the box of the vertices clusters use.
  Aabb used;
  for (const Triangle& t : whole().clusters->triangles)
    for (const std::int32_t v : t) used.extend(whole().vertices.positions[std::size_t(v)]);
  const Aabb a = model_bounds(*paged);
  EXPECT_EQ(a.min, used.min);
  EXPECT_EQ(a.max, used.max);
  LevelExtractor from_pages(*paged, LodStructure::kClusters), from_whole(whole(), LodStructure::kClusters);
  int i = 0;
  for (const LevelRequest& r : requests()) {
    const LevelCut& p = from_pages.extract(r);
    const LevelCut& w = from_whole.extract(r);
    ASSERT_EQ(p.triangles, w.triangles) << "request " << i;
    expect_same_mesh(compact_level(*paged, p.triangles), compact_level(whole(), w.triangles),
                     "request " + std::to_string(i));
    ++i;
  }
}

TEST(PagedModel, ACutReadsOnlyItsPages) {
  const std::uint64_t file = fs::file_size(bunny128());
  for (const LevelRequest& r : {LevelRequest::at_percent(2), requests()[6], requests()[7]}) {
    std::optional<LodModel> paged = open_paged_model(bunny128().string(), std::uint64_t(1) << 30);
    ASSERT_TRUE(paged.has_value());
    const PageStats& read = paged->clusters->paged->stats();
    EXPECT_LT(read.head_bytes, file / 50) << "opening reads the hierarchy's records, not its geometry";
    EXPECT_EQ(read.pages_read, 0u);
    LevelExtractor extractor(*paged, LodStructure::kClusters);
    const LevelCut& cut = extractor.extract(r);
    const TriangleMesh mesh = compact_level(*paged, cut.triangles);
    // The cut's own bytes: its triangles and vertices as a mesh.
    const std::uint64_t own = mesh.triangles.size() * 12 + mesh.positions.size() * 24;
    EXPECT_GT(read.pages_read, 0u);
    if (r.kind == LevelRequest::Kind::kPercent) {
      EXPECT_LT(read.head_bytes + read.page_bytes_read, file / 10);  // pages are coarser than a 2 % cut
    } else {
      EXPECT_LE(read.page_bytes_read, 3 * own) << read.pages_read << " pages, " << mesh.triangles.size() << " triangles";
    }
  }
}

TEST(PagedModel, PagesHeldStayWithinTheBudgetAndPinnedPagesStay) {
  std::optional<LodModel> probe = open_paged_model(bunny128().string(), 0);
  ASSERT_TRUE(probe.has_value());
  const ClusterPages& pages = *probe->clusters->paged;
  std::uint64_t largest = 0;
  for (std::size_t p = 0; p < pages.size(); ++p) largest = std::max(largest, pages.page_bytes(p));
  const std::uint64_t budget = 4 * largest;

  std::optional<LodModel> paged = open_paged_model(bunny128().string(), budget);
  ClusterPages& held = *paged->clusters->paged;
  const std::size_t top = held.size() - 1;  // the last page holds the coarsest clusters
  held.pin(top);
  LevelExtractor from_pages(*paged, LodStructure::kClusters), from_whole(whole(), LodStructure::kClusters);
  int i = 0;
  for (const LevelRequest& r : requests()) {
    const LevelCut& p = from_pages.extract(r);
    EXPECT_EQ(p.triangles, from_whole.extract(r).triangles) << "request " << i;
    EXPECT_LE(held.stats().resident_bytes, budget) << "request " << i;
    EXPECT_TRUE(held.resident(top));
    ++i;
  }
  EXPECT_LE(held.stats().peak_resident_bytes, budget);
  // Full detail twice over does not fit: pages were dropped and read again.
  EXPECT_GT(held.stats().pages_read, held.size());
}

TEST(PagedModel, DamagedPagesAreNamedWhenRead) {
  const fs::path dir = scan2lod::testing::scratch_folder("paged");
  const std::vector<char> good = file_bytes(bunny128());
  // A flipped byte in the last page: opening reads no page, a cut that
  // draws it says which page of which file is damaged.
  std::vector<char> bad = good;
  const auto [pages_at, pages_length] = section_of(good, "PGEO");
  bad[pages_at + pages_length - 20] ^= 0x40;
  const fs::path damaged = dir / "damaged_page.mco";
  write_bytes(damaged, bad);
  std::optional<LodModel> paged = open_paged_model(damaged.string(), std::uint64_t(1) << 30);
  ASSERT_TRUE(paged.has_value());
  LevelExtractor extractor(*paged, LodStructure::kClusters);
  try {
    extractor.extract(LevelRequest::at_percent(0));
    FAIL() << "a damaged page was drawn";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("damaged_page.mco"), std::string::npos) << what;
    EXPECT_NE(what.find("section 'PGEO'"), std::string::npos) << what;
    EXPECT_NE(what.find("checksum mismatch"), std::string::npos) << what;
  }
  // The whole file's checksums catch it too.
  EXPECT_THROW(load_model(damaged.string()), InputError);

  // A damaged index is caught on opening.
  bad = good;
  const auto [index_at, index_length] = section_of(good, "PGIX");
  ASSERT_GT(index_length, 0u);
  bad[index_at + 3] ^= 0x01;
  const fs::path damaged_index = dir / "damaged_index.mco";
  write_bytes(damaged_index, bad);
  EXPECT_NE(open_error(damaged_index).find("checksum mismatch in section 'PGIX'"), std::string::npos)
      << open_error(damaged_index);

  // A truncated file says where.
  bad.assign(good.begin(), good.begin() + std::ptrdiff_t(pages_at + 100));
  const fs::path truncated = dir / "truncated.mco";
  write_bytes(truncated, bad);
  EXPECT_NE(open_error(truncated).find("truncated in section 'PGEO'"), std::string::npos) << open_error(truncated);
}

TEST(PagedModel, FilesWithoutPagesAreLeftToLoadModel) {
  const fs::path dir = scan2lod::testing::scratch_folder("paged");
  // Format 3 has no pages; an octree alone has no hierarchy to page.
  const std::vector<std::uint8_t> old = encode_model(whole(), 3);
  const fs::path old_path = dir / "format3.mco";
  std::ofstream(old_path, std::ios::binary).write(reinterpret_cast<const char*>(old.data()), std::streamsize(old.size()));
  EXPECT_FALSE(open_paged_model(old_path.string(), 1 << 20).has_value());
  EXPECT_FALSE(open_paged_model(scan2lod::testing::bunny_model().string(), 1 << 20).value().octree.has_value());
  EXPECT_THROW(open_paged_model((dir / "missing.mco").string(), 1 << 20), InputError);
}

TEST(PagedModel, PageGeometryRoundTripsWithColoursAndLongIndices) {
  // 70 000 vertices in one page: 32-bit local indices.
  VertexArray v;
  const int n = 70000;
  for (int i = 0; i < n; ++i) {
    v.positions.push_back(Vec3f(float(i), float(i % 7), -float(i)));
    v.normals.push_back(Vec3f(0, 0, 1));
    v.colors.push_back(Rgb{std::uint8_t(i), std::uint8_t(i >> 8), 7});
  }
  std::vector<Triangle> triangles;
  for (int i = 0; i + 2 < n; i += 3) triangles.push_back({i + 2, i, i + 1});
  PageEncoder encoder;
  std::vector<std::uint8_t> blob;
  Aabb box;
  ASSERT_TRUE(encoder.encode(triangles.data(), triangles.size(), v, &blob, &box));
  EXPECT_EQ(blob.size() % 8, 0u);
  EXPECT_EQ(box.max, Vec3f(float(n - 2), 6, 0));
  PageGeometry page;
  ASSERT_EQ(decode_page(blob.data(), blob.size(), triangles.size(), true, true, 0, std::uint64_t(n), &page), "");
  ASSERT_EQ(page.triangles.size(), triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t local = page.triangles[t][k];
      const std::uint32_t model = page.model_vertices[std::size_t(local)];
      ASSERT_EQ(model, std::uint32_t(triangles[t][k]));
      ASSERT_EQ(page.positions[std::size_t(local)], v.positions[model]);
      ASSERT_EQ(page.colors[std::size_t(local)], v.colors[model]);
    }
  // What does not fit is said, not read.
  EXPECT_NE(decode_page(blob.data(), blob.size() - 8, triangles.size(), true, true, 0, std::uint64_t(n), &page), "");
  EXPECT_NE(decode_page(blob.data(), blob.size(), triangles.size() + 1, true, true, 0, std::uint64_t(n), &page), "");
  EXPECT_NE(decode_page(blob.data(), blob.size(), triangles.size(), false, true, 0, std::uint64_t(n), &page), "");
  EXPECT_NE(decode_page(blob.data(), blob.size(), triangles.size(), true, true, 10, std::uint64_t(n), &page)
                .find("outside"),
            std::string::npos);
}

TEST(PagedModel, ExtractReadsPagesAndWritesTheWholeModelsMesh) {
  const fs::path dir = scan2lod::testing::scratch_folder("paged");
  const std::string model = bunny128().string();
  const fs::path paged = dir / "paged.ply", small = dir / "small_cache.ply";
  const std::string camera = " --camera 0.05,0.15,0.2,-0.02,0.1,0,0,1,0 ";
  const auto r = scan2lod::testing::run_cli("extract " + model + camera + "-o " + paged.string() + " --json", false);
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  ASSERT_TRUE(j.contains("read")) << r.output;
  EXPECT_LT(j["read"]["bytes"].get<double>(), j["read"]["file_bytes"].get<double>());
  EXPECT_GT(j["read"]["pages"].get<int>(), 0);
  // A cache of one byte still writes the cut, a page at a time.
  ASSERT_EQ(scan2lod::testing::run_cli("extract " + model + camera + "-o " + small.string() + " --cache 1 -q").status, 0);
  EXPECT_EQ(file_bytes(paged), file_bytes(small));
  // The whole model's cut, written the same way, is the same file.
  CameraView c;
  c.eye = Vec3f(0.05f, 0.15f, 0.2f);
  c.target = Vec3f(-0.02f, 0.1f, 0);
  LevelExtractor extractor(whole(), LodStructure::kClusters);
  const TriangleMesh mesh = compact_level(whole(), extractor.extract(LevelRequest::for_camera(c, 1.0)).triangles);
  EXPECT_EQ(std::size_t(j["triangles"].get<int>()), mesh.triangles.size());
  EXPECT_EQ(std::size_t(j["vertices"].get<int>()), mesh.positions.size());
  EXPECT_NE(scan2lod::testing::run_cli("extract " + model + camera + "-o " + small.string() + " --cache lots").status, 0);
}

TEST(PagedModel, AViewerOrbitingStaysWithinItsBudget) {
  // A budget of 40 % of every page: far views fit at 1 px, near ones not.
  std::optional<LodModel> probe = open_paged_model(bunny128().string(), 0);
  std::uint64_t all = 0, largest = 0;
  for (std::size_t p = 0; p < probe->clusters->paged->size(); ++p) {
    all += probe->clusters->paged->page_bytes(p);
    largest = std::max(largest, probe->clusters->paged->page_bytes(p));
  }
  const std::uint64_t budget = all * 4 / 10;
  std::optional<LodModel> paged = open_paged_model(bunny128().string(), budget);
  PagedView view(*paged);
  const ClusterPages& pages = view.pages();
  EXPECT_GT(pages.pinned_bytes(), 0u);
  EXPECT_LE(pages.pinned_bytes(), budget / 4 + largest);
  LevelExtractor from_whole(whole(), LodStructure::kClusters);
  const Aabb box = model_bounds(whole());
  const Vec3f centre = 0.5f * (box.min + box.max);
  int coarsened = 0, at_asked = 0;
  std::size_t prefetched = 0;
  auto camera_at = [&](int i) {
    CameraView c;
    c.target = centre;
    const float a = 0.3f * float(i), d = box.diagonal() * (i % 4 < 2 ? 0.7f : 10.0f);
    c.eye = centre + Vec3f(d * std::cos(a), 0.1f * d, d * std::sin(a));
    return c;
  };
  for (int i = 0; i < 24; ++i) {
    const CameraView c = camera_at(i);
    const LevelCut& cut = view.view(c);
    ASSERT_FALSE(cut.triangles.empty());
    EXPECT_LE(pages.stats().resident_bytes, budget) << "view " << i;
    EXPECT_GE(view.pixel_error(), 1.0);
    (view.pixel_error() > 1.0 ? coarsened : at_asked)++;
    // The cut is the whole model's at the error it was cut at: watertight as any.
    EXPECT_EQ(cut.triangles, from_whole.extract(LevelRequest::for_camera(c, view.pixel_error())).triangles) << i;
    prefetched += view.prefetch(camera_at(i + 1));
    EXPECT_LE(pages.stats().resident_bytes, budget) << "prefetch " << i;
  }
  EXPECT_LE(pages.stats().peak_resident_bytes, budget);
  EXPECT_GT(coarsened, 0) << "near views need more than the budget";
  EXPECT_GT(at_asked, 0) << "far views fit at 1 px";
  EXPECT_GT(prefetched, 0u);
}
