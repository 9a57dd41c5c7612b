// Range data from meshes (Lee 2007, §4.3.1, §4.4, §6.3): mesh vertices as
// oriented points, and virtual orthographic range scans of a known sphere.
#include <scan2lod/acquisition/mesh_points.h>
#include <scan2lod/acquisition/range_grid_ply.h>
#include <scan2lod/acquisition/virtual_scanner.h>
#include <scan2lod/core/error.h>
#include <scan2lod/io/mesh_file.h>

#include "test_support.h"

#include <gtest/gtest.h>
#include <open3d/geometry/TriangleMesh.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

TriangleMesh sphere(double radius, int resolution) {
  auto o3d = open3d::geometry::TriangleMesh::CreateSphere(radius, resolution);
  TriangleMesh m;
  for (const Eigen::Vector3d& v : o3d->vertices_) m.positions.push_back(v.cast<float>());
  for (const Eigen::Vector3i& t : o3d->triangles_) m.triangles.push_back({t[0], t[1], t[2]});
  return m;
}

std::vector<Vec3f> fibonacci(int n) {
  std::vector<Vec3f> d;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n, r = std::sqrt(1.0 - z * z);
    d.emplace_back(float(r * std::cos(golden * i)), float(r * std::sin(golden * i)), float(z));
  }
  return d;
}

Vec3f to_world(const VirtualScan& s, const Vec3f& p) {
  return s.pose.rotation * p + s.pose.translation;
}

fs::path scratch(const std::string& name) {
  const fs::path dir = scan2lod::testing::scratch_folder() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// --- mesh vertices as oriented points (§4.3.1) ------------------------------

TEST(MeshPoints, SphereVertexNormalsAreRadialWithinOneDegree) {
  const TriangleMesh m = sphere(1.0, 40);
  const OrientedPoints p = mesh_to_oriented_points(m);
  ASSERT_EQ(p.size(), m.positions.size());
  ASSERT_EQ(p.spacing.size(), p.size());
  EXPECT_TRUE(p.colors.empty());
  const double cos_1deg = std::cos(kPi / 180.0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_NEAR(p.normals[i].norm(), 1.f, 1e-5f);
    EXPECT_GE(p.normals[i].dot(p.positions[i].normalized()), cos_1deg) << "vertex " << i;
    // Edges of a resolution-40 sphere are at most ~2*pi/80 long.
    EXPECT_GT(p.spacing[i], 0.f);
    EXPECT_LT(p.spacing[i], 0.1f);
  }
}

TEST(MeshPoints, DropsUnusedAndDegenerateVerticesAndKeepsColours) {
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {5, 5, 5}, {7, 7, 7}};
  m.colors = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}, {10, 11, 12}, {13, 14, 15}};
  // Vertex 3 is used by nothing; vertex 4 only by a zero-area triangle.
  m.triangles = {{0, 1, 2}, {4, 4, 0}};
  const OrientedPoints p = mesh_to_oriented_points(m);
  ASSERT_EQ(p.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(p.positions[i], m.positions[i]);
    EXPECT_EQ(p.colors[i], m.colors[i]);
    EXPECT_NEAR(p.normals[i].z(), 1.f, 1e-6f);  // counter-clockwise seen from +z
  }
  // Vertex 1's edges in its only triangle: 2 and sqrt(8).
  EXPECT_NEAR(p.spacing[1], (2.0 + std::sqrt(8.0)) / 2, 1e-5);
}

// --- virtual range scans (§4.4) -------------------------------------------

class VirtualScanner : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    mesh_ = new TriangleMesh(sphere(1.0, 100));
    scans_ = new std::vector<VirtualScan>(virtual_scan(*mesh_, {14, 128, 128}));
  }
  static void TearDownTestSuite() {
    delete scans_;
    delete mesh_;
  }
  static TriangleMesh* mesh_;
  static std::vector<VirtualScan>* scans_;
};
TriangleMesh* VirtualScanner::mesh_ = nullptr;
std::vector<VirtualScan>* VirtualScanner::scans_ = nullptr;

TEST_F(VirtualScanner, EverySampleLiesOnTheSphere) {
  ASSERT_EQ(scans_->size(), 14u);
  std::size_t valid = 0;
  for (const VirtualScan& s : *scans_) {
    ASSERT_EQ(s.image.cols, 128);
    ASSERT_EQ(s.image.rows, 128);
    ASSERT_EQ(s.image.points.size(), 128u * 128u);
    for (const Vec3f& p : s.image.points) {
      if (std::isnan(p.x())) continue;
      ++valid;
      EXPECT_NEAR(to_world(s, p).norm(), 1.0, 1e-3);
    }
  }
  EXPECT_GT(valid, 14u * 10000u);
}

TEST_F(VirtualScanner, TheViewsTogetherCoverTheWholeSphere) {
  std::vector<Vec3f> samples;
  for (const VirtualScan& s : *scans_)
    for (const Vec3f& p : s.image.points)
      if (!std::isnan(p.x())) samples.push_back(to_world(s, p));
  for (const Vec3f& d : fibonacci(1000)) {
    float nearest = 1e9f;
    for (const Vec3f& q : samples) nearest = std::min(nearest, (q - d).squaredNorm());
    EXPECT_LT(std::sqrt(nearest), 0.1f) << "direction " << d.transpose() << " unseen";
  }
}

TEST_F(VirtualScanner, EachViewSeesTheSpheresDisc) {
  // The window spans the diameter plus a 2% margin on its shorter side, so the
  // disc fills pi/4 / 1.02^2 of it.
  const double expected = kPi / 4 / (1.02 * 1.02);
  for (const VirtualScan& s : *scans_) {
    std::size_t valid = 0;
    for (const Vec3f& p : s.image.points) valid += !std::isnan(p.x());
    EXPECT_NEAR(double(valid) / double(s.image.points.size()), expected, 0.02);
  }
}

TEST_F(VirtualScanner, TheScannerSitsOnThePlusZSide) {
  for (const VirtualScan& s : *scans_) {
    for (std::size_t i = 0; i < s.image.points.size(); ++i) {
      const Vec3f& p = s.image.points[i];
      if (std::isnan(p.x())) continue;
      // The sphere's outward normal, expressed in the scan frame.
      const Vec3f n = s.pose.rotation.transpose() * to_world(s, p).normalized();
      if (s.image.confidence[i] > 0.05f) {
        EXPECT_GT(n.z(), 0.f);
      } else {
        EXPECT_GT(n.z(), -0.05f);  // silhouette: faceting tilts it a little
      }
      EXPECT_NEAR(s.image.confidence[i], n.z(), 0.03f);
    }
  }
}

TEST_F(VirtualScanner, PosesAreRigidAndRowZeroIsTheTop) {
  for (const VirtualScan& s : *scans_) {
    const Eigen::Matrix3f& r = s.pose.rotation;
    EXPECT_LT((r.transpose() * r - Eigen::Matrix3f::Identity()).norm(), 1e-5f);
    EXPECT_NEAR(r.determinant(), 1.f, 1e-5f);
    const int W = s.image.cols;
    for (int row = 1; row < s.image.rows; ++row)
      for (int col = 1; col < W; ++col) {
        const Vec3f& p = s.image.points[std::size_t(row * W + col)];
        const Vec3f& up = s.image.points[std::size_t((row - 1) * W + col)];
        const Vec3f& left = s.image.points[std::size_t(row * W + col - 1)];
        if (!std::isnan(p.x()) && !std::isnan(up.x())) {
          EXPECT_GT(up.y(), p.y());
        }
        if (!std::isnan(p.x()) && !std::isnan(left.x())) {
          EXPECT_LT(left.x(), p.x());
        }
      }
  }
}

TEST(VirtualScannerColours, AreInterpolatedFromTheVertices) {
  TriangleMesh m = sphere(1.0, 60);
  auto red_of = [](const Vec3f& p) { return 127.5f * (p.x() + 1.f); };
  for (const Vec3f& p : m.positions)
    m.colors.push_back({std::uint8_t(std::lround(red_of(p))), 0, 200});
  const auto scans = virtual_scan(m, {6, 64, 64});
  for (const VirtualScan& s : scans) {
    ASSERT_EQ(s.image.colors.size(), s.image.points.size());
    for (std::size_t i = 0; i < s.image.points.size(); ++i) {
      if (std::isnan(s.image.points[i].x())) continue;
      EXPECT_NEAR(s.image.colors[i][0], red_of(to_world(s, s.image.points[i])), 1.5f);
      EXPECT_EQ(s.image.colors[i][2], 200);
    }
  }
}

TEST(VirtualScannerInput, ZeroAreaTrianglesAndBadOptionsAreHandled) {
  TriangleMesh m = sphere(1.0, 20);
  const std::int32_t n = std::int32_t(m.positions.size());
  m.positions.push_back({0.5f, 0.5f, 0.5f});
  m.positions.push_back({0.25f, 0.25f, 0.25f});
  m.positions.push_back({0.75f, 0.75f, 0.75f});
  m.triangles.push_back({0, 0, 1});          // repeated corner
  m.triangles.push_back({n, n + 1, n + 2});  // collinear corners
  m.triangles.push_back({n, n, n});
  EXPECT_EQ(virtual_scan(m, {2, 16, 16}).size(), 2u);
  EXPECT_THROW(virtual_scan(m, {0, 16, 16}), std::invalid_argument);
  TriangleMesh flat;
  flat.positions = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
  flat.triangles = {{0, 1, 2}};
  EXPECT_THROW(virtual_scan(flat, {}), InputError);
}

TEST(VirtualScannerFiles, ScanSetReadsBackAsRangeGridsAndConf) {
  const fs::path dir = scratch("scanset") / "out";  // write_scan_set creates it
  const auto scans = virtual_scan(sphere(1.0, 40), {3, 32, 24});
  write_scan_set(dir.string(), scans);
  ASSERT_TRUE(fs::exists(dir / "scan_000.ply"));
  const std::vector<ConfEntry> conf = read_conf((dir / "scans.conf").string());
  ASSERT_EQ(conf.size(), scans.size());
  for (std::size_t v = 0; v < scans.size(); ++v) {
    EXPECT_EQ(fs::path(conf[v].file).filename(), "scan_00" + std::to_string(v) + ".ply");
    EXPECT_LT((conf[v].pose.rotation - scans[v].pose.rotation).norm(), 1e-5f);
    EXPECT_LT((conf[v].pose.translation - scans[v].pose.translation).norm(), 1e-6f);
    const RangeImage back = read_range_grid_ply(conf[v].file);
    ASSERT_EQ(back.cols, 32);
    ASSERT_EQ(back.rows, 24);
    ASSERT_EQ(back.points.size(), scans[v].image.points.size());
    for (std::size_t i = 0; i < back.points.size(); ++i) {
      const Vec3f& a = scans[v].image.points[i];
      const Vec3f& b = back.points[i];
      ASSERT_EQ(std::isnan(a.x()), std::isnan(b.x())) << "sample " << i;
      if (!std::isnan(a.x())) {
        EXPECT_LT((a - b).norm(), 1e-6f);
      }
    }
  }
}

TEST(VirtualScannerCli, ScanCommandWritesAScanSet) {
  const fs::path dir = scratch("cli");
  write_mesh((dir / "ball.ply").string(), sphere(1.0, 30));
  const std::string cli = SCAN2LOD_CLI;
  const std::string ok = cli + " -q scan " + (dir / "ball.ply").string() + " -o " +
                         (dir / "scans").string() + " --views 4 --size 40x30 > " +
                         (dir / "out.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(ok.c_str()), 0);
  EXPECT_EQ(read_conf((dir / "scans" / "scans.conf").string()).size(), 4u);
  EXPECT_EQ(read_range_grid_ply((dir / "scans" / "scan_003.ply").string()).cols, 40);
  const std::string bad = cli + " scan " + (dir / "ball.ply").string() + " -o " +
                          (dir / "bad").string() + " --size 40by30 > /dev/null 2>&1";
  EXPECT_NE(std::system(bad.c_str()), 0);
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

}  // namespace
}  // namespace scan2lod
