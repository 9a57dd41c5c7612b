// visualize/ by its pixels: the montage and plots of the bundled bunny are
// rendered off-screen (the tests run under xvfb-run), read back from the PNG,
// and measured: how much of a panel the object covers, how dense the
// wireframe's edges are, whether two renders agree to the pixel.
#include <scan2lod/core/error.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/visualize/levels.h>
#include <scan2lod/visualize/montage.h>
#include <scan2lod/visualize/octree_cells.h>
#include <scan2lod/visualize/plots.h>
#include <scan2lod/visualize/scene.h>

#include "test_support.h"

#include <gtest/gtest.h>

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

using scan2lod::testing::CliRun;
using scan2lod::testing::run_cli;

fs::path scratch() { return scan2lod::testing::scratch_folder("visualize"); }

using scan2lod::testing::have_display;

const std::string kScans = scan2lod::testing::bunny_scans();

using scan2lod::testing::bunny_model;

// The bunny with the octree alone (R = 32, quick): what --structure clusters refuses.
const fs::path& octree_only_model() {
  static const fs::path path = [] {
    const fs::path p = scan2lod::testing::scratch_folder("models") / "bunny32_octree.mco";
    const CliRun r = run_cli("build " + kScans + " -o " + p.string() + " -r 32 --structure octree -q");
    EXPECT_EQ(r.status, 0) << r.output;
    return p;
  }();
  return path;
}

// An RGB picture, rows from the top.
struct Picture {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  const std::uint8_t* at(int x, int y) const { return &rgb[3 * (std::size_t(y) * width + x)]; }
};

Picture read_png(const fs::path& path) {
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  Picture p;
  int dims[3];
  image->GetDimensions(dims);
  p.width = dims[0];
  p.height = dims[1];
  const int components = image->GetNumberOfScalarComponents();
  p.rgb.resize(3 * std::size_t(p.width) * p.height);
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x) {
      const auto* src = static_cast<const std::uint8_t*>(image->GetScalarPointer(x, p.height - 1 - y, 0));
      for (int k = 0; k < 3; ++k) p.rgb[3 * (std::size_t(y) * p.width + x) + k] = src[components >= 3 ? k : 0];
    }
  return p;
}

// A rectangle of a picture, without the caption strip at the panel's foot.
struct Region {
  int x, y, width, height;
};

Region body(const scan2lod::MontagePanel& p) { return {p.x, p.y, p.width, p.height * 85 / 100}; }

double fraction(const Picture& pic, const Region& r, bool (*test)(const std::uint8_t*)) {
  std::size_t hits = 0;
  for (int y = r.y; y < r.y + r.height; ++y)
    for (int x = r.x; x < r.x + r.width; ++x) hits += test(pic.at(x, y));
  return double(hits) / (double(r.width) * r.height);
}

bool not_background(const std::uint8_t* c) { return c[0] < 245 || c[1] < 245 || c[2] < 245; }
bool dark(const std::uint8_t* c) { return c[0] < 110 && c[1] < 110 && c[2] < 110; }

std::size_t differing_pixels(const Picture& pic, const Region& a, const Region& b) {
  std::size_t n = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const std::uint8_t *p = pic.at(a.x + x, a.y + y), *q = pic.at(b.x + x, b.y + y);
      n += p[0] != q[0] || p[1] != q[1] || p[2] != q[2];
    }
  return n;
}

}  // namespace

TEST(VisualizeLevels, PercentListsAreParsedStrictly) {
  EXPECT_EQ(scan2lod::parse_percent_list("100,80,60.5", "--percent"), (std::vector<double>{100, 80, 60.5}));
  for (const char* bad : {"", "100,,80", "abc", "101", "-1", "50x"})
    EXPECT_THROW(scan2lod::parse_percent_list(bad, "--percent"), std::runtime_error) << bad;
  int w = 0, h = 0;
  scan2lod::parse_size("320x240", "--size", &w, &h);
  EXPECT_EQ(w, 320);
  EXPECT_EQ(h, 240);
  for (const char* bad : {"320", "0x10", "10x", "x10", "10x10x", "99999x10"})
    EXPECT_THROW(scan2lod::parse_size(bad, "--size", &w, &h), std::runtime_error) << bad;
}

// render --camera: ten numbers, or an error that names the flag and what it expects.
TEST(VisualizeRender, ACameraGivenInFullIsReadOrRefusedByName) {
  const scan2lod::ViewCamera v = scan2lod::parse_view_camera("1,2,3,0,0,0.5,0,1,0,35", "--camera");
  EXPECT_EQ(v.eye, scan2lod::Vec3d(1, 2, 3));
  EXPECT_EQ(v.target, scan2lod::Vec3d(0, 0, 0.5));
  EXPECT_EQ(v.up, scan2lod::Vec3d(0, 1, 0));
  EXPECT_EQ(v.fov_degrees, 35);
  for (const char* bad : {"", "1,2,3,0,0,0,0,1,0", "1,2,3,0,0,0,0,1,0,35,1", "1,2,3,0,0,0,0,1,0,x", "1,2,3,,0,0,0,1,0,35",
                          "1,2,3,1,2,3,0,1,0,35", "0,0,1,0,0,0,0,0,2,35", "1,2,3,0,0,0,0,1,0,180",
                          "1,2,3,0,0,0,0,1,0,nan"}) {
    try {
      scan2lod::parse_view_camera(bad, "--camera");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const scan2lod::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--camera"), std::string::npos) << e.what();
    }
  }
}

TEST(VisualizeLevels, TheCutCoversTheSurfaceOnceAtEveryPriority) {
  // Every leaf lies below exactly one node of the cut, whatever the priority.
  // (octree_cells reads the octree's arrays, so its test does too.)
  const scan2lod::LodModel model = scan2lod::load_model(bunny_model().string());
  ASSERT_TRUE(model.octree);
  const scan2lod::McOctree& t = model.octree->tree;
  const scan2lod::LodArray& lod = model.octree->lod;
  for (std::size_t p : {std::size_t(0), std::size_t(1), lod.full() / 5, lod.full()}) {
    const std::vector<std::int32_t> cut = scan2lod::lod_cut(model, p);
    EXPECT_EQ(cut, scan2lod::lod_cut(t, lod, p));
    std::vector<int> covered(t.size(), 0);
    for (std::int32_t n : cut) covered[std::size_t(n)] = 1;
    std::size_t leaves = 0;
    for (std::size_t n = 0; n < t.size(); ++n) {
      if (!t.is_leaf(n)) continue;
      ++leaves;
      int hits = 0;
      for (std::int64_t a = std::int64_t(n); a >= 0; a = t.nodes.parents[std::size_t(a)]) hits += covered[std::size_t(a)];
      ASSERT_EQ(hits, 1) << "leaf " << n << " at priority " << p;
    }
    if (p == 0) {
      EXPECT_EQ(cut, std::vector<std::int32_t>{0});
    }
    if (p == lod.full()) {
      EXPECT_EQ(cut.size(), leaves);
    }
  }
}

TEST(VisualizeLevels, LevelSourceGivesTheFacesLevelsOfEitherStructure) {
  const scan2lod::LodModel model = scan2lod::load_model(bunny_model().string());
  ASSERT_TRUE(model.octree && model.clusters);
  for (scan2lod::LodStructure s : {scan2lod::LodStructure::kOctree, scan2lod::LodStructure::kClusters}) {
    scan2lod::LevelSource source(model, s);
    scan2lod::LevelExtractor extractor(model, s);
    EXPECT_EQ(source.structure(), s);
    for (double percent : {100.0, 50.0, 20.0, 0.0, 37.5, 100.0}) {
      // The stored levels (for the clusters: not refined to the count).
      scan2lod::LevelRequest stored = scan2lod::LevelRequest::at_percent(percent);
      stored.refine = false;
      const scan2lod::LevelCut& want = extractor.extract(stored);
      const scan2lod::Level level = source.at_percent(percent);
      EXPECT_EQ(level.mesh.triangles.size(), want.triangles.size()) << scan2lod::structure_name(s) << percent;
      EXPECT_EQ(level.mesh.positions.size(), scan2lod::compact_level(model, want.triangles).positions.size());
      EXPECT_EQ(level.priority, want.priority);
      EXPECT_EQ(level.error, want.error);
      // The slider's path (for the octree a LodCursor): the same triangles as a multiset.
      std::vector<scan2lod::Triangle> a = source.cut(stored).triangles;
      std::vector<scan2lod::Triangle> b = want.triangles;
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      EXPECT_EQ(a, b) << scan2lod::structure_name(s) << " " << percent;
      const std::vector<std::uint8_t> levels = source.triangle_levels();
      ASSERT_EQ(levels.size(), a.size());
      if (s == scan2lod::LodStructure::kClusters && percent == 100.0) {
        EXPECT_EQ(*std::max_element(levels.begin(), levels.end()), 0);
      }
      if (s == scan2lod::LodStructure::kClusters && percent == 0.0) {
        EXPECT_GT(*std::max_element(levels.begin(), levels.end()), 0);
      }
    }
  }
  EXPECT_EQ(scan2lod::structure_named(model, "", "m.mco"), scan2lod::LodStructure::kClusters);
  EXPECT_EQ(scan2lod::structure_named(model, "octree", "m.mco"), scan2lod::LodStructure::kOctree);
  EXPECT_THROW(scan2lod::structure_named(model, "tree", "m.mco"), std::runtime_error);
}

TEST(VisualizeRender, MontagePanelsShowTheBunnyAndItsLevels) {
  if (!have_display()) GTEST_SKIP() << "no X display; scripts/build.sh test runs the tests under xvfb-run";
  const fs::path out = scratch() / "montage.png";
  const CliRun r = run_cli("render " + bunny_model().string() + " --percent 100,20,60,60 --size 200x200 --mode both -o " +
                       out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const Picture pic = read_png(out);
  ASSERT_EQ(pic.width, 400);
  ASSERT_EQ(pic.height, 800);
  auto panel = [](int row, int column) {
    scan2lod::MontagePanel p;
    p.x = column * 200, p.y = row * 200, p.width = 200, p.height = 200;
    return body(p);
  };
  // Column 0 wireframe, column 1 shaded; rows 100, 20, 60, 60 %.
  for (int row = 0; row < 4; ++row) {
    const double covered = fraction(pic, panel(row, 1), not_background);
    EXPECT_GT(covered, 0.15) << "row " << row;
    EXPECT_LT(covered, 0.80) << "row " << row;
    // Wireframe and shaded differ in most of the object's pixels.
    EXPECT_GT(double(differing_pixels(pic, panel(row, 0), panel(row, 1))), 0.5 * covered * 200 * 170) << "row " << row;
  }
  // Edges: dark pixels per object pixel, 20 % against 100 %.
  const double full = fraction(pic, panel(0, 0), dark) / fraction(pic, panel(0, 1), not_background);
  const double fifth = fraction(pic, panel(1, 0), dark) / fraction(pic, panel(1, 1), not_background);
  EXPECT_GT(full, 0.25);
  EXPECT_LT(fifth, 0.8 * full) << "edge density 20 %: " << fifth << ", 100 %: " << full;
  // The same level twice in one picture: the same pixels, caption included,
  // but for a handful on shaded silhouettes (Mesa's rasteriser is not exactly
  // translation-invariant between viewports; two runs agree exactly, below).
  for (int column = 0; column < 2; ++column)
    EXPECT_LE(differing_pixels(pic, {column * 200, 400, 200, 200}, {column * 200, 600, 200, 200}), 20u)
        << "column " << column;
  // The printed table: 4 levels with their triangle counts, 20 % well below 100 %.
  EXPECT_NE(r.output.find("8 panels, 400x800 pixels"), std::string::npos) << r.output;
}

TEST(VisualizeRender, TwoRunsGiveTheSamePicture) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const fs::path a = scratch() / "same_a.png", b = scratch() / "same_b.png";
  for (const fs::path& out : {a, b}) {
    const CliRun r =
        run_cli("render " + bunny_model().string() + " --percent 40 --size 160x120 --mode shaded -o " + out.string());
    ASSERT_EQ(r.status, 0) << r.output;
  }
  const Picture pa = read_png(a), pb = read_png(b);
  ASSERT_EQ(pa.width, 160);
  ASSERT_EQ(pa.height, 120);
  EXPECT_EQ(pa.rgb, pb.rgb);
  EXPECT_GT(fraction(pa, {0, 0, 160, 100}, not_background), 0.1);
}

TEST(VisualizeRender, SingleModePutsLevelsSideBySide) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const fs::path out = scratch() / "row.png";
  const CliRun r = run_cli("render " + bunny_model().string() +
                       " --percent 100,20 --size 150x150 --mode wireframe -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const Picture pic = read_png(out);
  EXPECT_EQ(pic.width, 300);
  EXPECT_EQ(pic.height, 150);
  // Both levels show the object; the sparser one's edges are black
  // ink (the full level's are drawn lit at this size: see the test below).
  const double full = fraction(pic, {0, 0, 150, 127}, not_background);
  const double fifth = fraction(pic, {150, 0, 150, 127}, not_background);
  EXPECT_GT(full, 0.15);
  EXPECT_GT(fifth, 0.4 * full);  // less: white shows between its lines
  EXPECT_GT(fraction(pic, {150, 0, 150, 127}, dark), 0.1);
}

TEST(VisualizeRender, EitherStructureRendersAndItsTableSaysWhich) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const scan2lod::LodModel model = scan2lod::load_model(bunny_model().string());
  for (const char* structure : {"octree", "clusters"}) {
    const fs::path out = scratch() / (std::string("structure_") + structure + ".png");
    const CliRun r = run_cli("render " + bunny_model().string() + " --structure " + structure +
                                 " --percent 100,20 --size 150x150 --mode shaded -o " + out.string(),
                             false);
    ASSERT_EQ(r.status, 0) << r.output;
    const bool octree = std::string(structure) == "octree";
    EXPECT_NE(r.output.find(octree ? "priority" : "clusters"), std::string::npos) << r.output;
    scan2lod::LevelSource levels(model, octree ? scan2lod::LodStructure::kOctree : scan2lod::LodStructure::kClusters);
    EXPECT_NE(r.output.find(" " + std::to_string(levels.at_percent(20).mesh.triangles.size()) + " "),
              std::string::npos)
        << r.output;
    const Picture pic = read_png(out);
    ASSERT_EQ(pic.width, 300);
    EXPECT_GT(fraction(pic, {0, 0, 150, 127}, not_background), 0.1) << structure;
    EXPECT_GT(fraction(pic, {150, 0, 150, 127}, not_background), 0.1) << structure;
  }
}

TEST(VisualizeRender, BadInputEndsInAClearErrorAndNoFile) {
  const fs::path out = scratch() / "bad.png";
  struct Case {
    std::string args, expected;
  };
  const std::string model = bunny_model().string();
  const std::vector<Case> cases = {
      {"render " + (scratch() / "missing.mco").string() + " -o " + out.string(), "missing.mco"},
      {"render " + kScans + " -o " + out.string(), "bun.conf"},
      {"render " + model + " -o " + (scratch() / "bad.jpg").string(), ".png"},
      {"render " + model + " -o " + (scratch() / "no_such_folder" / "x.png").string(), "does not exist"},
      {"render " + model + " --percent 120 -o " + out.string(), "between 0 and 100"},
      {"render " + model + " --size 0x100 -o " + out.string(), "WIDTHxHEIGHT"},
      {"render " + model + " --mode flat -o " + out.string(), "shaded, wireframe or both"},
      {"render " + (scratch() / "missing.mco").string() + " --structure octree -o " + out.string(), "missing.mco"},
      {"render " + octree_only_model().string() + " --structure clusters -o " + out.string(),
       "has no clusters structure"},
  };
  for (const Case& c : cases) {
    const CliRun r = run_cli(c.args);
    EXPECT_NE(r.status, 0) << c.args;
    EXPECT_NE(r.output.find("error"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << " -> " << r.output;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
}

namespace {

bool near(const std::uint8_t* c, const std::uint8_t* want) {
  return std::abs(int(c[0]) - want[0]) < 40 && std::abs(int(c[1]) - want[1]) < 40 && std::abs(int(c[2]) - want[2]) < 40;
}

// A curve in `colour` inside a chart: how many pixels, and over how many
// columns and rows of the chart they spread.
struct Curve {
  std::size_t pixels = 0, columns = 0, rows = 0;
};

Curve curve_in(const Picture& pic, const Region& r, const std::uint8_t* colour) {
  Curve c;
  std::vector<char> cols(std::size_t(r.width), 0), rows(std::size_t(r.height), 0);
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x)
      if (near(pic.at(r.x + x, r.y + y), colour)) ++c.pixels, cols[std::size_t(x)] = 1, rows[std::size_t(y)] = 1;
  for (char v : cols) c.columns += std::size_t(v);
  for (char v : rows) c.rows += std::size_t(v);
  return c;
}

}  // namespace

TEST(VisualizePlot, TheThreeLodGraphsHoldCurves) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const fs::path out = scratch() / "plots.png";
  const CliRun r = run_cli("plot " + bunny_model().string() + " --structure octree --size 400x300 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("3 charts (octree"), std::string::npos) << r.output;
  const Picture pic = read_png(out);
  ASSERT_EQ(pic.width, 1200);
  ASSERT_EQ(pic.height, 300);
  for (int chart = 0; chart < 3; ++chart) {
    const Curve c = curve_in(pic, {chart * 400, 0, 400, 300}, scan2lod::kPlotBlue);
    // A curve across most of the plot area (about 300 of the 400 columns),
    // not a flat line: the metric falls, the accumulation rises.
    EXPECT_GT(c.columns, 200u) << "chart " << chart;
    EXPECT_GT(c.rows, 25u) << "chart " << chart;
    EXPECT_GT(c.pixels, 300u) << "chart " << chart;
  }
  // The accumulation's curve climbs: its leftmost blue pixels sit lower in the
  // picture than its rightmost ones.
  const Region acc{800, 0, 400, 300};
  int left_y = -1, right_y = -1;
  for (int x = 0; x < acc.width && left_y < 0; ++x)
    for (int y = acc.height - 1; y >= 0; --y)
      if (near(pic.at(acc.x + x, y), scan2lod::kPlotBlue)) { left_y = y; break; }
  for (int x = acc.width - 1; x >= 0 && right_y < 0; --x)
    for (int y = 0; y < acc.height; ++y)
      if (near(pic.at(acc.x + x, y), scan2lod::kPlotBlue)) { right_y = y; break; }
  ASSERT_GE(left_y, 0);
  ASSERT_GE(right_y, 0);
  EXPECT_GT(left_y - right_y, 100);
}

TEST(VisualizePlot, TheClusterGraphsHoldCurves) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const fs::path out = scratch() / "plots_clusters.png";
  const CliRun r = run_cli("plot " + bunny_model().string() + " --size 400x300 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("3 charts (clusters"), std::string::npos) << r.output;  // the default structure
  const Picture pic = read_png(out);
  ASSERT_EQ(pic.width, 1200);
  ASSERT_EQ(pic.height, 300);
  for (int chart = 0; chart < 3; ++chart) {
    const Curve c = curve_in(pic, {chart * 400, 0, 400, 300}, scan2lod::kPlotBlue);
    EXPECT_GT(c.columns, 150u) << "chart " << chart;
    EXPECT_GT(c.rows, 25u) << "chart " << chart;
  }
  // Clusters and vertices rise with the triangles: their curves climb left to right.
  for (int chart = 1; chart < 3; ++chart) {
    const Region g{chart * 400, 0, 400, 300};
    int left_y = -1, right_y = -1;
    for (int x = 0; x < g.width && left_y < 0; ++x)
      for (int y = g.height - 1; y >= 0; --y)
        if (near(pic.at(g.x + x, y), scan2lod::kPlotBlue)) { left_y = y; break; }
    for (int x = g.width - 1; x >= 0 && right_y < 0; --x)
      for (int y = 0; y < g.height; ++y)
        if (near(pic.at(g.x + x, y), scan2lod::kPlotBlue)) { right_y = y; break; }
    EXPECT_GT(left_y - right_y, 100) << "chart " << chart;
  }
}

TEST(VisualizePlot, ErrorAgainstTrianglesFallsToZeroAtFullDetail) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  // The reference is the model's own full-detail mesh: its error is zero at
  // 100 % and positive below.
  const fs::path reference = scratch() / "full_reference.ply";
  ASSERT_EQ(run_cli("extract " + bunny_model().string() + " --percent 100 -o " + reference.string()).status, 0);
  const fs::path out = scratch() / "plots_error.png";
  const CliRun r = run_cli("plot " + bunny_model().string() + " --reference " + reference.string() +
                           " --percent 2,10,40,100 --samples 4000 --size 300x250 -o " + out.string(),
                       false);
  ASSERT_EQ(r.status, 0) << r.output;
  std::istringstream lines(r.output);
  std::string header, line;
  std::getline(lines, header);
  std::vector<double> to_ref;
  for (int i = 0; i < 4 && std::getline(lines, line); ++i) {
    std::istringstream row(line);
    double percent, priority, triangles, a, b;
    ASSERT_TRUE(bool(row >> percent >> priority >> triangles >> a >> b)) << line;
    to_ref.push_back(a + b);
  }
  ASSERT_EQ(to_ref.size(), 4u) << r.output;
  EXPECT_GT(to_ref[0], to_ref[2]);
  EXPECT_GT(to_ref[2], 0.0);
  EXPECT_LT(to_ref[3], 1e-3);
  const Picture pic = read_png(out);
  ASSERT_EQ(pic.width, 600);
  ASSERT_EQ(pic.height, 500);
  const Region error_chart{300, 250, 300, 250};
  // The two directions' errors are close, so the red curve, drawn last,
  // hides much of the blue one: both must show, the red one across the chart.
  EXPECT_GT(curve_in(pic, error_chart, scan2lod::kPlotBlue).columns, 20u);
  EXPECT_GT(curve_in(pic, error_chart, scan2lod::kPlotRed).columns, 100u);
}

TEST(VisualizePlot, BadInputEndsInAClearErrorAndNoFile) {
  const fs::path out = scratch() / "bad_plot.png";
  const std::string model = bunny_model().string();
  struct Case {
    std::string args, expected;
  };
  const std::vector<Case> cases = {
      {"plot " + (scratch() / "missing.mco").string() + " -o " + out.string(), "missing.mco"},
      {"plot " + model + " -o " + (scratch() / "plot.svg").string(), ".png"},
      {"plot " + model + " --reference " + (scratch() / "nope.ply").string() + " -o " + out.string(), "nope.ply"},
      {"plot " + model + " --size 10 -o " + out.string(), "WIDTHxHEIGHT"},
      {"plot " + octree_only_model().string() + " --structure clusters -o " + out.string(),
       "has no clusters structure"},
  };
  for (const Case& c : cases) {
    const CliRun r = run_cli(c.args);
    EXPECT_NE(r.status, 0) << c.args;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << " -> " << r.output;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
}

// Wireframes stay readable however dense: at 1 px per edge and less, the
// lines are lit grey, so the object shows shading, not a black blot.
TEST(VisualizeRender, DenseWireframesShowShadingNotABlot) {
  if (!have_display()) GTEST_SKIP() << "no X display";
  const fs::path out = scratch() / "dense_wire.png";
  const CliRun r = run_cli("render " + bunny_model().string() +
                           " --percent 100 --size 90x90 --mode wireframe -o " + out.string() + " -q");
  ASSERT_EQ(r.status, 0) << r.output;
  const Picture pic = read_png(out);
  const scan2lod::MontagePanel panel = [] {
    scan2lod::MontagePanel p;
    p.x = 0, p.y = 0, p.width = 90, p.height = 90;
    return p;
  }();
  const double covered = fraction(pic, body(panel), not_background);
  ASSERT_GT(covered, 0.15);
  EXPECT_LT(fraction(pic, body(panel), dark) / covered, 0.3);
  // Shading: the object's grey levels spread (a flat fill would not).
  double sum = 0, sum2 = 0, n = 0;
  for (int y = 0; y < 75; ++y)
    for (int x = 0; x < 90; ++x)
      if (not_background(pic.at(x, y))) {
        const double v = pic.at(x, y)[0];
        sum += v, sum2 += v * v, n += 1;
      }
  const double mean = sum / n;
  EXPECT_GT(std::sqrt(sum2 / n - mean * mean), 12.0) << "grey levels of the object: mean " << mean;
}
