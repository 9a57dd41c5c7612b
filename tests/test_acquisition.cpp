// Range images in (Lee 2007, §4.2-4.3): Stanford range grids, .conf poses,
// organized clouds, lattice normals, and clear errors for bad input.
#include <scan2lod/acquisition/lattice_normals.h>
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/acquisition/organized_pcd.h>
#include <scan2lod/acquisition/range_grid_ply.h>
#include <scan2lod/acquisition/scan_set.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/measure/surface_distance.h>

#include "test_support.h"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace scan2lod;
namespace fs = std::filesystem;

namespace {

const std::string kData = std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny";
const std::string kShared = std::string(SCAN2LOD_SHARED_DIR) + "/data/bunny";

fs::path scratch(const std::string& name) {
  const fs::path dir = scan2lod::testing::scratch_folder() / "acquisition";
  fs::create_directories(dir);
  return dir / name;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void spit(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// The error message of f(), or "" when it does not throw InputError.
template <class F>
std::string input_error(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A small ASCII range grid: 3 x 2 cells, one empty.
const char* kTinyGrid =
    "ply\nformat ascii 1.0\nobj_info num_cols 3\nobj_info num_rows 2\n"
    "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
    "element range_grid 6\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n2 0 0\n0 1 0\n1 1 0.5\n"
    "1 0\n1 1\n1 2\n1 3\n1 4\n0\n";

// A bad range-grid file: its name, its text and what its error must say.
struct GridCase {
  std::string name, text, expect;
};

// Each file gives an InputError naming the file and the expected text.
void expect_range_grid_errors(const std::vector<GridCase>& cases) {
  for (const GridCase& c : cases) {
    fs::path p = scratch(c.name + ".ply");
    spit(p, c.text);
    std::string message = input_error([&] { read_range_grid_ply(p.string()); });
    EXPECT_NE(message.find(p.string()), std::string::npos) << c.name << ": " << message;
    EXPECT_NE(message.find(c.expect), std::string::npos) << c.name << ": " << message;
  }
}

}  // namespace

TEST(RangeGrid, ReadsTheLatticeWithHoles) {
  fs::path p = scratch("tiny.ply");
  spit(p, kTinyGrid);
  RangeImage image = read_range_grid_ply(p.string());
  EXPECT_EQ(image.cols, 3);
  EXPECT_EQ(image.rows, 2);
  ASSERT_EQ(image.points.size(), 6u);
  EXPECT_FLOAT_EQ(image.points[4].z(), 0.5f);
  EXPECT_TRUE(std::isnan(image.points[5].x()));
}

// Numbers beyond float's range were read by PCL and narrowed (0 or a
// denormal; infinity makes a hole), not refused; a confidence of another
// type than float was read too.
TEST(RangeGrid, AsciiNumbersBeyondFloatAreNarrowedNotRefused) {
  fs::path p = scratch("tiny_range.ply");
  spit(p, "ply\nformat ascii 1.0\nobj_info num_cols 2\nobj_info num_rows 1\n"
          "element vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty uchar confidence\n"
          "element range_grid 2\nproperty list uchar int vertex_indices\nend_header\n"
          "1e-50 0 +1 7\n1e39 0 1 9\n1 0\n1 1\n");
  const RangeImage image = read_range_grid_ply(p.string());
  ASSERT_EQ(image.points.size(), 2u);
  EXPECT_EQ(image.points[0], Vec3f(0, 0, 1));
  EXPECT_TRUE(std::isnan(image.points[1].x())) << "x = 1e39 is infinite in float: a hole";
  ASSERT_EQ(image.confidence.size(), 2u);
  EXPECT_EQ(image.confidence[0], 7.f);
}

TEST(RangeGrid, BinaryRoundTripIsExact) {
  fs::path p = scratch("tiny.ply");
  spit(p, kTinyGrid);
  RangeImage image = read_range_grid_ply(p.string());
  fs::path q = scratch("tiny_binary.ply");
  write_range_grid_ply(q.string(), image);
  EXPECT_NE(slurp(q.string()).find("binary_little_endian"), std::string::npos);
  RangeImage back = read_range_grid_ply(q.string());
  ASSERT_EQ(back.points.size(), image.points.size());
  for (std::size_t i = 0; i < image.points.size(); ++i) {
    if (std::isnan(image.points[i].x())) {
      EXPECT_TRUE(std::isnan(back.points[i].x()));
    } else {
      EXPECT_EQ(back.points[i], image.points[i]);
    }
  }
}

TEST(RangeGrid, BadFilesNameTheFileAndTheElement) {
  const std::string good = kTinyGrid;
  std::vector<GridCase> cases = {
      {"magic", "plx\n" + good.substr(4), "first line"},
      {"no_end", good.substr(0, good.find("end_header")), "end_header"},
      {"no_cols", [&] { std::string s = good; s.erase(s.find("obj_info num_cols 3\n"), 20); return s; }(),
       "num_cols"},
      {"cells", [&] { std::string s = good; s.replace(s.find("range_grid 6"), 12, "range_grid 7"); return s; }(),
       "range_grid"},
      {"garbled_vertex", [&] { std::string s = good; s.replace(s.find("1 0 0\n"), 5, "1 x 0"); return s; }(),
       "vertex 1"},
      {"truncated", good.substr(0, good.size() - 8), "truncated"},
      {"bad_index", [&] { std::string s = good; s.replace(s.rfind("1 4\n"), 3, "1 9"); return s; }(),
       "vertex index"},
      // PCL asserted (aborted) on it; found by tests/fuzz/inputs_fuzzer.
      {"indented_obj_info", [&] { std::string s = good; s.insert(s.find("obj_info num_rows"), " "); return s; }(),
       "starts with blanks"},
  };
  expect_range_grid_errors(cases);
}

// Stanford's happy_stand scans carry 'bye' lines among their obj_info lines;
// PCL's reader, which earlier releases used, skips such lines, so they are
// skipped with a warning naming the line, in ASCII and binary headers alike.
// Malformed definitions are still refused (BadFilesNameTheFileAndTheElement).
TEST(RangeGrid, HeaderLinesOfNoKeywordAreSkippedWithAWarning) {
  auto with_bye = [](std::string text) {
    text.insert(text.find("obj_info num_rows"), "bye\n");
    text.insert(text.find("element vertex"), "bye\n");
    return text;
  };
  fs::path plain = scratch("tiny.ply"), odd = scratch("tiny_bye.ply");
  spit(plain, kTinyGrid);
  spit(odd, with_bye(kTinyGrid));
  const RangeImage a = read_range_grid_ply(plain.string()), b = read_range_grid_ply(odd.string());
  EXPECT_TRUE(a.warnings.empty());
  ASSERT_EQ(b.warnings.size(), 1u);
  EXPECT_NE(b.warnings[0].find(odd.string()), std::string::npos) << b.warnings[0];
  EXPECT_NE(b.warnings[0].find("('bye') and 1 more"), std::string::npos) << b.warnings[0];
  ASSERT_EQ(a.points.size(), b.points.size());
  for (std::size_t i = 0; i < a.points.size(); ++i)
    if (!std::isnan(a.points[i].x())) {
      EXPECT_EQ(a.points[i], b.points[i]);
    }
  // A binary scan as bundled: the same points, and the warning reaches the report.
  const std::string bundled = slurp(std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun000.ply");
  fs::path binary = scratch("bun000_bye.ply");
  spit(binary, with_bye(bundled));
  AcquisitionReport report;
  const OrientedPoints points = load_oriented_points({binary.string()}, {}, &report);
  EXPECT_EQ(points.size(), load_oriented_points({std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/bun000.ply"}).size());
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("header line"), std::string::npos) << report.warnings[0];
}

// Stanford's original bunny scans are ASCII; the bundled copies are the same
// scans in binary. Read either way, every sample is the same float.
TEST(RangeGrid, AsciiOriginalsReadAsTheirBinaryCopies) {
  const std::string originals = std::string(SCAN2LOD_SHARED_DIR) + "/data/bunny/data/";
  int compared = 0;
  for (const char* name : {"bun000", "bun045", "bun090", "bun180", "bun270", "bun315", "chin", "ear_back", "top2",
                           "top3"}) {
    const std::string ascii = originals + name + ".ply", binary = std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny/" + name + ".ply";
    if (!fs::exists(ascii) || !fs::exists(binary)) continue;
    const RangeImage a = read_range_grid_ply(ascii), b = read_range_grid_ply(binary);
    ASSERT_EQ(a.cols, b.cols) << name;
    ASSERT_EQ(a.rows, b.rows) << name;
    ASSERT_EQ(a.points.size(), b.points.size()) << name;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.points.size(); ++i)
      differ += !(a.points[i] == b.points[i] || (std::isnan(a.points[i].x()) && std::isnan(b.points[i].x())));
    EXPECT_EQ(differ, 0u) << name;
    EXPECT_EQ(a.confidence, b.confidence) << name;
    ++compared;
  }
  EXPECT_GE(compared, 9);
}

TEST(RangeGrid, TruncatedBinaryFilesAreErrorsAtEveryLength) {
  const std::string bunny = kData + "/bun000.ply";
  ASSERT_TRUE(fs::exists(bunny));
  const std::string whole = slurp(bunny);
  for (double f : {0.001, 0.05, 0.3, 0.6, 0.9, 0.999}) {
    fs::path p = scratch("cut.ply");
    spit(p, whole.substr(0, std::size_t(f * whole.size())));
    EXPECT_FALSE(input_error([&] { read_range_grid_ply(p.string()); }).empty()) << "cut at " << f;
  }
}

// The tiny grid in binary little-endian: `vertices` in the header, `rows`
// vertex records written, and cell 4 naming vertex `index`.
std::string binary_grid(const std::string& vertices, int rows, std::int32_t index) {
  std::string s = "ply\nformat binary_little_endian 1.0\nobj_info num_cols 3\nobj_info num_rows 2\n"
                  "element vertex " + vertices + "\nproperty float x\nproperty float y\nproperty float z\n"
                  "element range_grid 6\nproperty list uchar int vertex_indices\nend_header\n";
  for (int v = 0; v < rows; ++v) {
    const float p[3] = {float(v % 3), float(v / 3), 0.f};
    s.append(reinterpret_cast<const char*>(p), sizeof p);
  }
  for (std::int32_t c = 0; c < 6; ++c) {
    if (c == 5) {
      s += '\0';  // a hole
      continue;
    }
    const std::int32_t i = c == 4 ? index : c;
    s += '\1';
    s.append(reinterpret_cast<const char*>(&i), 4);
  }
  return s;
}

TEST(RangeGrid, BinaryIndicesAndVertexCountsAreChecked) {
  // Found by tests/fuzz/inputs_fuzzer and its review: PCL 1.13 reads before
  // its buffer for a negative cell index, hands back an unread (0,0,0) for the
  // index one past the last vertex, and asserts (aborts) when there are more
  // vertices than cells, e.g. 2^62 of them, whose byte count wraps to 0.
  {
    fs::path p = scratch("binary_ok.ply");
    spit(p, binary_grid("5", 5, 4));
    RangeImage image = read_range_grid_ply(p.string());
    EXPECT_EQ(image.points[4], Vec3f(1.f, 1.f, 0.f));
    EXPECT_TRUE(std::isnan(image.points[5].x()));
  }
  // The tiny grid with a sixth vertex and the given cell lines.
  auto full_grid = [](const std::string& cells) {
    std::string s = kTinyGrid;
    s.replace(s.find("vertex 5"), 8, "vertex 6");
    s.replace(s.find("1 0\n1 1\n"), std::string::npos, "2 1 0\n" + cells);
    return s;
  };
  {
    fs::path p = scratch("full_grid.ply");
    spit(p, full_grid("1 0\n1 1\n1 2\n1 3\n1 4\n1 5\n"));
    RangeImage image = read_range_grid_ply(p.string());
    EXPECT_EQ(image.points[5], Vec3f(2.f, 1.f, 0.f));
  }
  std::string more_ascii = kTinyGrid;
  more_ascii.replace(more_ascii.find("vertex 5"), 8, "vertex 7");
  more_ascii.insert(more_ascii.find("1 0\n1 1\n"), "2 1 0\n3 3 3\n");
  const std::vector<GridCase> cases = {
      {"negative_index", binary_grid("5", 5, -1), "cell 4 has a vertex index outside [0, 5)"},
      {"index_past_end", binary_grid("5", 5, 5), "cell 4 has a vertex index outside [0, 5)"},
      {"more_vertices", binary_grid("7", 7, 4), "more than the 6 range_grid cells"},
      {"more_vertices_ascii", more_ascii, "more than the 6 range_grid cells"},
      {"wrapping_count", binary_grid("4611686018427387904", 5, 4), "range_grid cells"},
      {"truncated_cell", binary_grid("5", 5, 4).substr(0, binary_grid("5", 5, 4).size() - 3),
       "truncated"},
      // With as many vertices as cells PCL ignores the grid and returns the
      // vertices in file order; found while reading PCL for the cases above.
      {"full_grid_out_of_order", full_grid("1 5\n1 4\n1 3\n1 2\n1 1\n1 0\n"), "does not name vertex 0"},
  };
  expect_range_grid_errors(cases);
}

TEST(Conf, MissingScanIsNamedWithItsLine) {
  fs::path p = scratch("bad.conf");
  spit(p, "camera 0 0 0 0 0 0 1\nbmesh missing_scan.ply 0 0 0 0 0 0 1\n");
  std::string message = input_error([&] { read_conf(p.string()); });
  EXPECT_NE(message.find("line 2"), std::string::npos) << message;
  EXPECT_NE(message.find("missing_scan.ply"), std::string::npos) << message;
  spit(p, "bmesh x.ply 0 0 zero 0 0 0 1\n");
  EXPECT_NE(input_error([&] { read_conf(p.string()); }).find("bmesh FILE"), std::string::npos);
  spit(p, "# nothing here\n");
  EXPECT_NE(input_error([&] { read_conf(p.string()); }).find("no 'bmesh'"), std::string::npos);
  // A name too long for the file system made std::filesystem::exists throw
  // filesystem_error instead of InputError (found by inputs_fuzzer's review).
  const std::string long_name(300, 'a');
  spit(p, "bmesh " + long_name + ".ply 0 0 0 0 0 0 1\n");
  EXPECT_NE(input_error([&] { read_conf(p.string()); }).find("does not exist"), std::string::npos);
  EXPECT_NE(input_error([&] { load_oriented_points({(scratch("") / (long_name + ".pcd")).string()}); })
                .find("does not exist"),
            std::string::npos);
  EXPECT_NE(input_error([&] { read_organized_pcd((scratch("") / (long_name + ".pcd")).string(), nullptr); })
                .find("does not exist"),
            std::string::npos);
}

TEST(Conf, ConjugateQuaternionPutsTheBunnyOnTheReference) {
  // The convention p' = R(q)^T p + t is checked against the data: the merged
  // scans must lie on the zippered reference surface.
  const std::string reference = kShared + "/reconstruction/bun_zipper.ply";
  if (!fs::exists(reference)) GTEST_SKIP() << "needs ../shared";
  OrientedPoints points = load_oriented_points({kData + "/bun.conf"});
  EXPECT_GT(points.size(), 350000u);
  TriangleMesh ref = read_mesh(reference);
  std::vector<float> d = distances_to_surface(points.positions, ref);
  DistanceStats stats = distance_stats(d);
  const double diagonal = bounds(ref.positions).diagonal();
  EXPECT_LT(stats.mean, 0.0005 * diagonal);  // measured 0.039%; R(q) p + t misses by ~16%
  EXPECT_GT(stats.mean, 0.0001 * diagonal);  // overlapping scans do disagree slightly
}

TEST(LatticeNormals, PlaneFacesTheScannerAndDropsDiscontinuities) {
  // A tilted plane with a step: normals are the plane's, turned to +z; samples
  // across the step do not form triangles, and isolated samples are dropped.
  RangeImage image;
  image.cols = 20;
  image.rows = 10;
  for (int r = 0; r < image.rows; ++r)
    for (int c = 0; c < image.cols; ++c) {
      float z = 0.2f * c + (c >= 10 ? 5.0f : 0.0f);
      image.points.push_back(Vec3f(float(c), float(-r), z));
    }
  image.points[5 * 20 + 3] = Vec3f::Constant(std::nanf(""));
  // One isolated sample surrounded by holes.
  for (int c : {15, 17}) image.points[2 * 20 + c] = Vec3f::Constant(std::nanf(""));
  for (int r : {1, 3}) image.points[r * 20 + 16] = Vec3f::Constant(std::nanf(""));
  OrientedPoints points = range_image_to_points(image, ScanPose{});
  // Dropped: 5 holes, the isolated sample, and (0,16) on the top row, whose
  // only neighbours (left, right) span no triangle.
  EXPECT_EQ(points.size(), 200u - 5u - 2u);
  const Vec3f expected = Vec3f(-0.2f, 0.f, 1.f).normalized();
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_GT(points.normals[i].dot(expected), 0.9999f) << "at " << points.positions[i].transpose();
    EXPECT_NEAR(points.spacing[i], std::sqrt(1.04f) * 0.5f + 0.5f, 0.06f);
  }
}

TEST(OrganizedPcd, ReadsWidthByHeightAndRejectsUnorganized) {
  fs::path p = scratch("cloud.pcd");
  spit(p,
       "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 2\n"
       "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 6\nDATA ascii\n"
       "0 0 1\n1 0 1\n2 0 1\n0 1 1\n1 1 1\nnan nan nan\n");
  ScanPose pose;
  RangeImage image = read_organized_pcd(p.string(), &pose);
  EXPECT_EQ(image.cols, 3);
  EXPECT_EQ(image.rows, 2);
  EXPECT_TRUE(std::isnan(image.points[5].x()));
  // The sensor is at the origin looking along +z: normals face it (-z).
  OrientedPoints points = range_image_to_points(image, pose);
  ASSERT_EQ(points.size(), 4u);  // (2,0) has only its left neighbour: no triangle
  for (const Vec3f& n : points.normals) EXPECT_NEAR(n.z(), -1.f, 1e-6f);

  spit(p, "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
          "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n0 0 1\n1 0 1\n");
  EXPECT_NE(input_error([&] { read_organized_pcd(p.string(), nullptr); }).find("not organized"),
            std::string::npos);
  spit(p, "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 2\n"
          "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\nnan nan nan\nnan nan nan\nnan nan nan\nnan nan nan\n");
  EXPECT_NE(input_error([&] { read_organized_pcd(p.string(), nullptr); }).find("no finite points"),
            std::string::npos);
}

TEST(OrganizedPcd, ReadsWhatPclWritesInEveryDataFormat) {
  pcl::PointCloud<pcl::PointXYZ> cloud(3, 2);
  for (std::size_t i = 0; i < cloud.size(); ++i) cloud[i] = pcl::PointXYZ(float(i % 3), float(i / 3), 1.f + 0.25f * float(i));
  cloud[4].x = cloud[4].y = cloud[4].z = std::nanf("");
  cloud.is_dense = false;
  pcl::PCDWriter writer;
  for (int format = 0; format < 3; ++format) {
    fs::path p = scratch("written" + std::to_string(format) + ".pcd");
    if (format == 0) writer.writeASCII(p.string(), cloud);
    if (format == 1) writer.writeBinary(p.string(), cloud);
    if (format == 2) writer.writeBinaryCompressed(p.string(), cloud);
    RangeImage image = read_organized_pcd(p.string(), nullptr);
    ASSERT_EQ(image.points.size(), 6u) << format;
    for (std::size_t i = 0; i < 6; ++i) {
      if (i == 4) {
        EXPECT_TRUE(std::isnan(image.points[i].x())) << format;
      } else {
        EXPECT_EQ(image.points[i], Vec3f(cloud[i].x, cloud[i].y, cloud[i].z)) << format << " at " << i;
      }
    }
  }
}

TEST(OrganizedPcd, BadFilesNameTheFileAndTheElement) {
  // Found by tests/fuzz/inputs_fuzzer: PCL 1.13's reader dereferences null on
  // a header without fields (the empty file, an unknown first line, COUNT 0),
  // allocates POINTS x point size up front, overflows its buffer when the
  // compressed block's size word is wrong, and turns short ASCII lines into
  // points at the origin. The header and body are now checked before PCL reads.
  const std::string head = "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  const std::string size = "WIDTH 2\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\n";
  const std::string good = head + size + "DATA ascii\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n";
  auto replace = [&](std::string from, std::string to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  std::string compressed = head + size + "DATA binary_compressed\n";
  const std::uint32_t words[2] = {5, 4};  // uncompressed should be 4 points x 12 bytes
  compressed.append(reinterpret_cast<const char*>(words), 8);
  compressed += std::string("\x03" "abcd", 5);
  struct Case {
    std::string name, text, expect;
  };
  const std::vector<Case> cases = {
      {"empty", "", "DATA line"},
      {"garbage_first_line", "SVRO IEN .7\n" + good, "unknown keyword 'SVRO'"},
      {"count_zero", replace("COUNT 1 1 1", "COUNT 0 0 0"), "count '0'"},
      {"bad_size", replace("SIZE 4 4 4", "SIZE 4 x 4"), "size 'x'"},
      {"no_data", head + size, "DATA line"},
      {"points_mismatch", replace("POINTS 4", "POINTS 5"), "POINTS 5"},
      {"huge_points", head + "WIDTH 20000\nHEIGHT 20000\nPOINTS 400000000\nDATA binary\n0000", "truncated"},
      {"too_many_points", replace("POINTS 4", "POINTS 4000000000"), "below 2^31"},
      {"compressed_size", compressed, "uncompressed"},
      {"short_line", replace("1 0 1\n", "1 0\n"), "point 1 needs 3 numbers"},
      {"blank_line", replace("1 0 1\n", " \n"), "point 1 needs 3 numbers"},
      {"truncated", good.substr(0, good.size() - 6), "file ends at point 3"},
      {"keyword_after_data", replace("DATA ascii\n", "DATA ascii\nPOINTS 9\n"), "header keyword"},
      {"zero_viewpoint", replace("0 0 0 1 0 0 0", "0 0 0 0 0 0 0"), "quaternion is zero"},
  };
  for (const Case& c : cases) {
    fs::path p = scratch("bad_" + c.name + ".pcd");
    spit(p, c.text);
    std::string message = input_error([&] { read_organized_pcd(p.string(), nullptr); });
    EXPECT_NE(message.find(p.string()), std::string::npos) << c.name << ": " << message;
    EXPECT_NE(message.find(c.expect), std::string::npos) << c.name << ": " << message;
  }
  // A one-byte rgba field was read as four bytes, past the end of the cloud.
  fs::path p = scratch("narrow_rgba.pcd");
  spit(p, "FIELDS x y z rgba\nSIZE 4 4 4 1\nTYPE F F F U\nWIDTH 2\nHEIGHT 2\nPOINTS 4\nDATA ascii\n"
          "0 0 1 5\n1 0 1 5\n0 1 1 5\n1 1 1 5\n");
  RangeImage image = read_organized_pcd(p.string(), nullptr);
  EXPECT_EQ(image.points.size(), 4u);
  EXPECT_TRUE(image.colors.empty());
}

TEST(LoadInputs, EmptyAndUnknownInputsAreClearErrors) {
  EXPECT_FALSE(input_error([] { load_oriented_points({}); }).empty());
  EXPECT_NE(input_error([] { load_oriented_points({"/nonexistent/scan.ply"}); }).find("does not exist"),
            std::string::npos);
  fs::path p = scratch("notes.txt");
  spit(p, "hello");
  EXPECT_NE(input_error([&] { load_oriented_points({p.string()}); }).find("unknown input type"),
            std::string::npos);
  // A range grid with no two neighbouring samples gives no oriented points.
  fs::path q = scratch("sparse.ply");
  spit(q,
       "ply\nformat ascii 1.0\nobj_info num_cols 3\nobj_info num_rows 1\n"
       "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
       "element range_grid 3\nproperty list uchar int vertex_indices\nend_header\n"
       "0 0 0\n2 0 0\n1 0\n0\n1 1\n");
  EXPECT_NE(input_error([&] { load_oriented_points({q.string()}); }).find("no usable points"),
            std::string::npos);
}

TEST(ScanSet, ConvertKeepsEverySampleAndPose) {
  std::vector<PlacedScan> scans = read_scan_set({kData + "/bun.conf"});
  ASSERT_EQ(scans.size(), 10u);
  fs::path dir = scratch("converted");
  write_scan_set(dir.string(), scans, "bun.conf");
  std::vector<PlacedScan> back = read_scan_set({(dir / "bun.conf").string()});
  ASSERT_EQ(back.size(), scans.size());
  for (std::size_t s = 0; s < scans.size(); ++s) {
    EXPECT_EQ(fs::path(back[s].image.source).filename(), fs::path(scans[s].image.source).filename());
    EXPECT_TRUE(back[s].pose.rotation.isApprox(scans[s].pose.rotation, 1e-6f));
    EXPECT_TRUE(back[s].pose.translation.isApprox(scans[s].pose.translation, 1e-6f));
    ASSERT_EQ(back[s].image.points.size(), scans[s].image.points.size());
    for (std::size_t i = 0; i < scans[s].image.points.size(); ++i)
      if (!std::isnan(scans[s].image.points[i].x())) {
        ASSERT_EQ(back[s].image.points[i], scans[s].image.points[i]);
      }
  }
}
