// Point clouds in: vertex-only PLY, unorganized PCD and .xyz/.pts text, with
// their normals or with normals estimated and oriented; range scans refused
// without the .conf that registers them; and the resolution guard.
#include <scan2lod/acquisition/cloud_normals.h>
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/acquisition/organized_pcd.h>
#include <scan2lod/acquisition/point_cloud_files.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/reconstruct/marching_cubes.h>
#include <scan2lod/reconstruct/resolution_guard.h>

#include "test_support.h"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

using namespace scan2lod;
namespace fs = std::filesystem;

namespace {

const std::string kData = std::string(SCAN2LOD_SOURCE_DIR) + "/data/bunny";
const std::string kReference = std::string(SCAN2LOD_SHARED_DIR) + "/data/bunny/reconstruction/bun_zipper.ply";

fs::path scratch(const std::string& name) { return scan2lod::testing::scratch_folder("point_clouds") / name; }

void spit(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

template <class F>
std::string input_error(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Points on a sphere of radius r about c, spread by the golden angle.
PointCloud sphere_cloud(std::size_t n, float r, const Vec3f& c, bool normals) {
  PointCloud cloud;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (std::size_t i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (double(i) + 0.5) / double(n);
    const double s = std::sqrt(1.0 - z * z);
    const Vec3f u(float(s * std::cos(golden * double(i))), float(s * std::sin(golden * double(i))), float(z));
    cloud.positions.push_back(c + r * u);
    if (normals) cloud.normals.push_back(u);
  }
  return cloud;
}

// The bunny's ten registered scans merged into one unorganized cloud.
PointCloud merged_bunny(bool normals) {
  const OrientedPoints scans = load_oriented_points({kData + "/bun.conf"});
  PointCloud cloud;
  cloud.positions = scans.positions;
  if (normals) cloud.normals = scans.normals;
  return cloud;
}

struct CloudRun {
  std::size_t points = 0;
  SurfaceComparison c;
};

CloudRun reconstruct_cloud_file(const std::string& path) {
  CloudRun run;
  AcquisitionReport report;
  const OrientedPoints points = load_oriented_points({path}, {}, &report);
  EXPECT_EQ(report.clouds, 1u);
  run.points = points.size();
  ReconstructOptions options;
  options.resolution = 256;
  const Reconstruction r = reconstruct(points, options);
  CompareOptions compare;
  compare.samples = 400000;
  run.c = compare_surfaces(r.mesh, read_mesh(kReference), compare);
  return run;
}

}  // namespace

TEST(PointCloudFiles, PlyWithNormalsRoundTripsThroughTheWriter) {
  PointCloud cloud = sphere_cloud(100, 2.f, Vec3f(1, 2, 3), true);
  cloud.colors.assign(100, Rgb{10, 20, 30});
  const fs::path p = scratch("sphere.ply");
  write_point_cloud_ply(p.string(), cloud);
  const PointCloud back = read_point_cloud_ply(p.string());
  ASSERT_EQ(back.size(), 100u);
  ASSERT_EQ(back.normals.size(), 100u);
  ASSERT_EQ(back.colors.size(), 100u);
  EXPECT_EQ(back.positions[17], cloud.positions[17]);
  EXPECT_EQ(back.normals[42], cloud.normals[42]);
  EXPECT_EQ(back.colors[5], (Rgb{10, 20, 30}));
}

TEST(PointCloudFiles, AsciiPlyWithDoublesAndOtherPropertiesIsRead) {
  const fs::path p = scratch("ascii.ply");
  spit(p,
       "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 2\nproperty double x\nproperty double y\n"
       "property double z\nproperty float intensity\nproperty float normal_x\nproperty float normal_y\n"
       "property float normal_z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
       "1 2 3 0.5 0 0 1\n4 5 6 0.7 0 1 0\n");
  const PointCloud c = read_point_cloud_ply(p.string());
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], Vec3f(4, 5, 6));
  ASSERT_EQ(c.normals.size(), 2u);
  EXPECT_EQ(c.normals[1], Vec3f(0, 1, 0));
}

TEST(PointCloudFiles, BadPlyNamesTheVertexOrHeaderLine) {
  const fs::path p = scratch("bad.ply");
  spit(p, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
          "end_header\n1 2 3\n4 five 6\n");
  EXPECT_NE(input_error([&] { read_point_cloud_ply(p.string()); }).find("vertex 1 needs 3 numbers"),
            std::string::npos);
  spit(p, "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\n"
          "property float z\nend_header\n0123456789");
  EXPECT_NE(input_error([&] { read_point_cloud_ply(p.string()); }).find("truncated"), std::string::npos);
  spit(p, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n");
  EXPECT_NE(input_error([&] { read_point_cloud_ply(p.string()); }).find("lacks a float x, y or z"),
            std::string::npos);
}

TEST(PointCloudFiles, XyzAndPtsTextAreRead) {
  const fs::path xyzn = scratch("n.xyz");
  spit(xyzn, "# x y z nx ny nz\n0 0 0 0 0 1\n1 0 0 0 0 1\n\n0 1 0 0 0 1\n");
  PointCloud c = read_point_cloud_text(xyzn.string());
  ASSERT_EQ(c.size(), 3u);
  ASSERT_EQ(c.normals.size(), 3u);
  EXPECT_TRUE(c.colors.empty());
  const fs::path pts = scratch("scan.pts");
  spit(pts, "2\n0 0 0 -120 255 0 0\n1 1 1 -100 0 255 0\n");
  c = read_point_cloud_text(pts.string());
  ASSERT_EQ(c.size(), 2u);
  EXPECT_TRUE(c.normals.empty());
  ASSERT_EQ(c.colors.size(), 2u);
  EXPECT_EQ(c.colors[1], (Rgb{0, 255, 0}));
  // Count lines alone before the first point (one per scan section) are
  // skipped, as earlier releases skipped them.
  spit(pts, "2\n2\n0 0 0 -120 255 0 0\n1 1 1 -100 0 255 0\n");
  c = read_point_cloud_text(pts.string());
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.colors[1], (Rgb{0, 255, 0}));
  const fs::path rgb = scratch("rgb.xyz");
  spit(rgb, "0 0 0 200 10 10\n");
  c = read_point_cloud_text(rgb.string());
  EXPECT_TRUE(c.normals.empty());
  EXPECT_EQ(c.colors.size(), 1u);
  spit(rgb, "0 0 0\n1 1\n");
  EXPECT_NE(input_error([&] { read_point_cloud_text(rgb.string()); }).find("line 2"), std::string::npos);
  spit(rgb, "0 0 zero\n");
  EXPECT_NE(input_error([&] { read_point_cloud_text(rgb.string()); }).find("expected numbers"), std::string::npos);
}

TEST(PointCloudFiles, UnorganizedPcdIsACloudWithItsNormals) {
  pcl::PointCloud<pcl::PointNormal> pc;
  const PointCloud sphere = sphere_cloud(500, 1.f, Vec3f::Zero(), true);
  for (std::size_t i = 0; i < sphere.size(); ++i) {
    pcl::PointNormal p;
    p.getVector3fMap() = sphere.positions[i];
    p.getNormalVector3fMap() = sphere.normals[i];
    pc.push_back(p);
  }
  const fs::path p = scratch("sphere.pcd");
  pcl::io::savePCDFileBinary(p.string(), pc);
  EXPECT_FALSE(pcd_is_organized(p.string()));
  const PointCloud c = read_unorganized_pcd(p.string());
  ASSERT_EQ(c.size(), 500u);
  ASSERT_EQ(c.normals.size(), 500u);
  EXPECT_FALSE(c.viewpoint.has_value());
  AcquisitionReport report;
  const OrientedPoints points = load_oriented_points({p.string()}, {}, &report);
  EXPECT_EQ(report.clouds, 1u);
  EXPECT_EQ(report.clouds_estimated, 0u);
  EXPECT_EQ(points.size(), 500u);
}

// Text bodies are cut into 1 MB line blocks parsed on all cores
// (acquisition/text_records.h): a file of many blocks reads every point in
// file order, and the line named for a bad value is the file's own.
TEST(PointCloudFiles, LargeTextFilesReadInOrderAndNameTheirBadLine) {
  const std::size_t n = 200000;  // about 9 MB of text: several blocks
  std::string text = "# x y z nx ny nz, a comment and a blank line first\n\n";
  std::vector<std::size_t> line_of(n);
  std::size_t lines = 2;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 1000 == 999) text += "\n", ++lines;  // blank lines inside, skipped
    text += std::to_string(i) + " " + std::to_string(0.5 * double(i % 7)) + " -" + std::to_string(i % 13) +
            " 0 0 1\n";
    line_of[i] = ++lines;
  }
  const fs::path path = scratch("large.xyz");
  spit(path, text);
  const PointCloud c = read_point_cloud_text(path.string());
  ASSERT_EQ(c.size(), n);
  ASSERT_EQ(c.normals.size(), n);
  for (std::size_t i = 0; i < n; ++i)
    ASSERT_EQ(c.positions[i], Vec3f(float(i), float(0.5 * double(i % 7)), -float(i % 13))) << i;
  // Two bad lines in different blocks: the first is named, with its line number.
  std::string bad = text;
  for (const std::size_t i : {std::size_t(150000), std::size_t(123456)}) {
    const std::size_t at = bad.find("\n" + std::to_string(i) + " ") + 1;
    bad.replace(at, std::to_string(i).size(), "x" + std::to_string(i));
  }
  spit(path, bad);
  EXPECT_NE(input_error([&] { read_point_cloud_text(path.string()); })
                .find("line " + std::to_string(line_of[123456]) + " ('x123456"),
            std::string::npos);
  // The same points as an ASCII PCD (PCL's writer) read as the binary one does, to PCL's 8 digits.
  pcl::PointCloud<pcl::PointNormal> pc;
  for (std::size_t i = 0; i < n; i += 7) {
    pcl::PointNormal q;
    q.getVector3fMap() = c.positions[i] * 1.0001f;
    q.getNormalVector3fMap() = Vec3f(0.6f, 0.f, 0.8f);
    pc.push_back(q);
  }
  const fs::path ascii = scratch("large_ascii.pcd"), binary = scratch("large_binary.pcd");
  pcl::io::savePCDFileASCII(ascii.string(), pc);
  pcl::io::savePCDFileBinary(binary.string(), pc);
  const PointCloud a = read_unorganized_pcd(ascii.string()), b = read_unorganized_pcd(binary.string());
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.normals.size(), b.normals.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_LE((a.positions[i] - b.positions[i]).norm(), 1e-7f * (1.f + b.positions[i].norm())) << i;
    ASSERT_LE((a.normals[i] - b.normals[i]).norm(), 1e-7f) << i;
  }
}

TEST(CloudNormals, EstimatedNormalsOfASpherePointOutward) {
  const PointCloud cloud = sphere_cloud(4000, 1.f, Vec3f(5, 0, 0), false);
  const OrientedPoints points = cloud_to_oriented_points(cloud);
  ASSERT_EQ(points.size(), 4000u);
  std::size_t outward = 0;
  double worst = 1.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3f radial = (points.positions[i] - Vec3f(5, 0, 0)).normalized();
    const double cosine = points.normals[i].dot(radial);
    outward += cosine > 0;
    worst = std::min(worst, std::fabs(cosine));
  }
  EXPECT_EQ(outward, points.size());
  EXPECT_GT(worst, 0.99);  // the tangent plane of 20 neighbours on a unit sphere
  // 4000 points over 4 pi: about 0.056 apart.
  ASSERT_EQ(points.spacing.size(), points.size());
  EXPECT_NEAR(points.spacing[0], 0.056, 0.015);
}

TEST(CloudNormals, TowardTheSensorWhenTheFileNamesOne) {
  // A plane seen from above, with the sensor below it: normals point down.
  PointCloud cloud;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) cloud.positions.emplace_back(0.1f * i, 0.1f * j, 0.f);
  cloud.viewpoint = Vec3f(1.5f, 1.5f, -10.f);
  const OrientedPoints points = cloud_to_oriented_points(cloud);
  ASSERT_EQ(points.size(), 900u);
  for (const Vec3f& n : points.normals) ASSERT_LT(n.z(), -0.99f);
}

TEST(CloudNormals, TooFewUsablePointsIsAnError) {
  PointCloud cloud;
  cloud.source = "two.xyz";
  cloud.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0)};
  EXPECT_NE(input_error([&] { cloud_to_oriented_points(cloud); }).find("two.xyz"), std::string::npos);
}

// The acceptance of issue 14: the scans merged into one cloud reconstruct as
// well as the scans do, with the normals they had and with normals estimated.
// Writes the merged scans (with or without their normals), reconstructs the
// file and checks it against the reference as the scans themselves pass.
void expect_like_the_scans(bool normals, const std::string& name) {
  const fs::path p = scratch(name);
  write_point_cloud_ply(p.string(), merged_bunny(normals));
  const CloudRun run = reconstruct_cloud_file(p.string());
  EXPECT_GT(run.points, 350000u);
  const double two_sided = 0.5 * (run.c.a_to_b.mean + run.c.b_to_a.mean);
  EXPECT_LE(two_sided, 0.0003 * run.c.diagonal);
  EXPECT_EQ(run.c.a.components, 1u);
  EXPECT_LE(run.c.a.boundary_loops, 10u);
}

TEST(BunnyCloud, MergedScansWithNormalsReconstructLikeTheScans) {
  if (!fs::exists(kReference)) GTEST_SKIP() << "needs ../shared";
  expect_like_the_scans(true, "bunny_normals.ply");
}

TEST(BunnyCloud, MergedScansWithoutNormalsReconstructLikeTheScans) {
  if (!fs::exists(kReference)) GTEST_SKIP() << "needs ../shared";
  expect_like_the_scans(false, "bunny_positions.ply");
}

TEST(Registration, RangeScansWithoutTheirConfAreRefusedNamingIt) {
  const std::vector<std::string> scans = {kData + "/bun000.ply", kData + "/bun045.ply"};
  const std::string error = input_error([&] { load_oriented_points(scans); });
  EXPECT_NE(error.find("without the .conf"), std::string::npos) << error;
  EXPECT_NE(error.find("bun.conf"), std::string::npos) << error;
  EXPECT_NE(error.find("--unregistered"), std::string::npos) << error;
  // A scan beside a .conf is not placed by it either.
  EXPECT_FALSE(input_error([&] { load_oriented_points({kData + "/bun.conf", scans[0]}); }).empty());
  // Said to share one frame, they are merged; one scan alone needs no pose.
  AcquisitionOptions unregistered;
  unregistered.unregistered = true;
  AcquisitionReport report;
  EXPECT_GT(load_oriented_points(scans, unregistered, &report).size(), 0u);
  EXPECT_EQ(report.range_images, 2u);
  EXPECT_GT(load_oriented_points({scans[0]}).size(), 0u);
}

TEST(Registration, TheCommandLineRefusesAndAcceptsWithUnregistered) {
  const std::string scans = kData + "/bun000.ply " + kData + "/bun045.ply";
  const fs::path out = scratch("unregistered.ply");
  scan2lod::testing::CliRun r = scan2lod::testing::run_cli("reconstruct " + scans + " -o " + out.string() + " -r 32");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("bun.conf"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  r = scan2lod::testing::run_cli("reconstruct " + scans + " -o " + out.string() + " -r 32 --unregistered");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(out));
}

TEST(ResolutionGuard, EstimateFollowsTheSurface) {
  const OrientedPoints points = load_oriented_points({kData + "/bun.conf"});
  // reconstruct() touches 226 518 cubes at R = 256 and 934 676 at 512 (bench/REPORT.md).
  const ReconstructionEstimate e256 = estimate_reconstruction(points, 256);
  EXPECT_GT(e256.cubes, 226518 / 1.5);
  EXPECT_LT(e256.cubes, 226518 * 1.5);
  const ReconstructionEstimate e512 = estimate_reconstruction(points, 512);
  EXPECT_NEAR(e512.cubes / e256.cubes, 4.0, 0.2);
  EXPECT_GT(e512.bytes, e256.bytes);
}

TEST(ResolutionGuard, TooFineAGridIsRefusedWithTheEstimateAndWhatFits) {
  const OrientedPoints points = load_oriented_points({kData + "/bun000.ply"});
  // 1 GB: R = 8192 needs far more; nothing is allocated for the grid.
  const std::string error = input_error([&] { check_resolution_fits(points, 8192, 2, 1e9); });
  EXPECT_NE(error.find("resolution 8192 would need about"), std::string::npos) << error;
  EXPECT_NE(error.find("GB"), std::string::npos) << error;
  EXPECT_NE(error.find("largest resolution that fits is"), std::string::npos) << error;
  EXPECT_TRUE(input_error([&] { check_resolution_fits(points, 256, 2, 1e9); }).empty());
  // reconstruct() checks before it builds anything.
  ReconstructOptions options;
  options.resolution = 8192;
  options.memory_limit = 1e9;
  EXPECT_NE(input_error([&] { reconstruct(points, options); }).find("would need about"), std::string::npos);
  // The machine's own memory refuses R = 2^18 on the command line.
  const scan2lod::testing::CliRun r = scan2lod::testing::run_cli(
      "reconstruct " + kData + "/bun000.ply -o " + scratch("huge.ply").string() + " -r 262144");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("would need about"), std::string::npos) << r.output;
}

TEST(ResolutionGuard, AMeshFarCoarserThanTheGridGetsAdvice) {
  // 12 vertices a unit apart at R = 256: cubes of 1/248 of the extent.
  OrientedPoints points;
  for (int i = 0; i < 12; ++i) {
    points.positions.emplace_back(float(i % 3), float(i / 3 % 2), float(i / 6));
    points.normals.emplace_back(0.f, 0.f, 1.f);
    points.spacing.push_back(1.f);
  }
  const std::string advice = coarse_input_advice(points, 256);
  EXPECT_NE(advice.find("--resolution"), std::string::npos) << advice;
  EXPECT_TRUE(coarse_input_advice(points, 16).empty());
}
