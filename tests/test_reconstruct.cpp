// Claims of Lee 2007, §4.2 on shapes with known answers.
#include <scan2lod/measure/topology.h>
#include <scan2lod/reconstruct/cube_table.h>
#include <scan2lod/reconstruct/hole_filling.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <tuple>

using namespace scan2lod;

namespace {

// Oriented points on a sphere (golden spiral), normals radial.
OrientedPoints sphere_points(float radius, int count) {
  OrientedPoints p;
  const float golden = float(M_PI) * (3.f - std::sqrt(5.f));
  for (int i = 0; i < count; ++i) {
    float z = 1.f - 2.f * (i + 0.5f) / count;
    float r = std::sqrt(1.f - z * z);
    Vec3f n(r * std::cos(golden * i), r * std::sin(golden * i), z);
    p.positions.push_back(radius * n);
    p.normals.push_back(n);
  }
  return p;
}

double signed_volume(const TriangleMesh& m) {
  double v = 0;
  for (const auto& t : m.triangles)
    v += m.positions[t[0]].cast<double>().dot(
             m.positions[t[1]].cast<double>().cross(m.positions[t[2]].cast<double>())) / 6.0;
  return v;
}

}  // namespace

TEST(CubeTable, EveryCaseClosesItsLoops) {
  const auto& table = cube_cases();
  EXPECT_EQ(table[0].triangle_count, 0);
  EXPECT_EQ(table[255].triangle_count, 0);
  for (int mask = 1; mask < 255; ++mask) {
    // Each crossed edge lies on exactly two face segments, so a case's triangles
    // use each boundary (crossing-to-crossing on a face) edge once.
    int crossings = 0;
    for (int e = 0; e < 12; ++e)
      crossings += ((mask >> edge_corner(e, 0)) & 1) != ((mask >> edge_corner(e, 1)) & 1);
    EXPECT_EQ(__builtin_popcount(table[mask].edge_mask), crossings) << "case " << mask;
    EXPECT_GT(table[mask].triangle_count, 0) << "case " << mask;
  }
}

TEST(CubeTable, RandomSignFieldsGiveClosedManifolds) {
  // The classic 15-case table joins an ambiguous face differently in a case and
  // its complement, which opens holes. Random signs hit every ambiguous pairing;
  // the only boundary allowed is where the surface leaves the block of cubes.
  const auto& table = cube_cases();
  const int n = 7;  // corners per side
  std::mt19937 rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<int> inside(n * n * n);
    for (int& s : inside) s = int(rng() & 1);
    auto corner = [&](int x, int y, int z) { return inside[(z * n + y) * n + x]; };
    std::map<std::tuple<int, int, int, int>, int> edge_vertex;
    TriangleMesh mesh;
    for (int z = 0; z + 1 < n; ++z)
      for (int y = 0; y + 1 < n; ++y)
        for (int x = 0; x + 1 < n; ++x) {
          int mask = 0;
          for (int c = 0; c < 8; ++c)
            mask |= corner(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1)) << c;
          const CubeCase& cc = table[mask];
          int ids[12];
          for (int e = 0; e < 12; ++e) {
            if (!(cc.edge_mask >> e & 1)) continue;
            int c0 = edge_corner(e, 0);
            auto key = std::make_tuple(x + (c0 & 1), y + ((c0 >> 1) & 1), z + ((c0 >> 2) & 1), e / 4);
            auto it = edge_vertex.emplace(key, int(mesh.positions.size())).first;
            if (it->second == int(mesh.positions.size())) {
              Vec3f p(float(std::get<0>(key)), float(std::get<1>(key)), float(std::get<2>(key)));
              p[e / 4] += 0.5f;
              mesh.positions.push_back(p);
            }
            ids[e] = it->second;
          }
          for (int t = 0; t < cc.triangle_count; ++t)
            mesh.triangles.push_back({ids[cc.triangles[t][0]], ids[cc.triangles[t][1]], ids[cc.triangles[t][2]]});
        }
    MeshTopology topo = mesh_topology(mesh);
    EXPECT_EQ(topo.non_manifold_edges, 0u) << "trial " << trial;
    // Boundary edges may only lie on the block's outer faces.
    std::map<std::pair<int, int>, int> uses;
    for (const auto& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) {
        int a = t[k], b = t[(k + 1) % 3];
        uses[{std::min(a, b), std::max(a, b)}]++;
      }
    for (const auto& [edge, count] : uses) {
      if (count != 1) continue;
      const Vec3f& pa = mesh.positions[edge.first];
      const Vec3f& pb = mesh.positions[edge.second];
      bool on_outer_face = false;
      for (int a = 0; a < 3; ++a)
        for (float side : {0.f, float(n - 1)})
          on_outer_face |= pa[a] == side && pb[a] == side;
      ASSERT_TRUE(on_outer_face) << "hole inside the block, trial " << trial;
    }
  }
}

TEST(Reconstruct, SphereIsClosedOutwardAndOnTheSurface) {
  const float radius = 1.0f;
  OrientedPoints points = sphere_points(radius, 60000);
  ReconstructOptions options;
  options.resolution = 64;
  Reconstruction r = reconstruct(points, options);
  MeshTopology topo = mesh_topology(r.mesh);
  EXPECT_EQ(topo.boundary_edges, 0u);
  EXPECT_EQ(topo.non_manifold_edges, 0u);
  EXPECT_EQ(topo.components, 1u);
  EXPECT_EQ(topo.euler_characteristic, 2);
  // Outward: positive enclosed volume close to the ball's.
  const double volume = signed_volume(r.mesh);
  EXPECT_NEAR(volume, 4.0 / 3.0 * M_PI, 0.01 * 4.0 / 3.0 * M_PI);
  // Every vertex within 5% of a cube of the sphere.
  const double h = r.leaves.grid.cube_size;
  double worst = 0, mean = 0;
  for (const Vec3f& p : r.mesh.positions) {
    double e = std::abs(p.norm() - radius);
    worst = std::max(worst, e);
    mean += e;
  }
  mean /= r.mesh.positions.size();
  EXPECT_LT(mean, 0.05 * h);
  EXPECT_LT(worst, 0.25 * h);
  // Normals point outward.
  for (std::size_t v = 0; v < r.mesh.positions.size(); ++v)
    ASSERT_GT(r.mesh.normals[v].dot(r.mesh.positions[v].normalized()), 0.9f);
}

TEST(Reconstruct, VerticesSitAtTheDistanceRatioNotTheMidpoint) {
  // A tilted plane z = 0.3 x: its tangent-plane distance is linear, so ratio
  // placement puts every vertex exactly on it; midpoints would be up to h/2 off.
  OrientedPoints points;
  const Vec3f n = Vec3f(-0.3f, 0.f, 1.f).normalized();
  for (int i = 0; i <= 100; ++i)
    for (int j = 0; j <= 100; ++j) {
      float x = i * 0.01f, y = j * 0.01f;
      points.positions.push_back(Vec3f(x, y, 0.3f * x));
      points.normals.push_back(n);
    }
  ReconstructOptions options;
  options.resolution = 64;
  options.distance.method = DistanceMethod::hoppe;
  Reconstruction r = reconstruct(points, options);
  ASSERT_GT(r.mesh.triangles.size(), 1000u);
  const double h = r.leaves.grid.cube_size;
  double worst = 0;
  std::size_t on_plane = 0;
  for (const Vec3f& p : r.mesh.positions) {
    const double off = std::abs(p.z() - 0.3f * p.x());
    worst = std::max(worst, off);
    on_plane += off < 1e-4 * h;
  }
  // Crossings are kept kCrossingMargin of an edge off the corners: only the
  // vertices near a corner on the plane move, and by at most that.
  EXPECT_LE(worst, 1.001 * kCrossingMargin * h);
  EXPECT_GT(double(on_plane), 0.75 * r.mesh.positions.size());  // 83 % here
  // Outward everywhere; exact but for slivers at the patch's rim.
  std::size_t exact = 0;
  for (const Vec3f& v : r.mesh.normals) {
    ASSERT_GT(v.dot(n), 0.f);
    exact += v.dot(n) > 0.999f;
  }
  EXPECT_GT(double(exact), 0.95 * r.mesh.normals.size());
}

TEST(Reconstruct, RejectsBadPoints) {
  OrientedPoints empty;
  EXPECT_THROW(reconstruct(empty), std::runtime_error);
  OrientedPoints nan_point = sphere_points(1.f, 100);
  nan_point.positions[7].x() = std::nanf("");
  try {
    reconstruct(nan_point);
    FAIL() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("point 7"), std::string::npos) << e.what();
  }
  OrientedPoints same_point;
  same_point.positions.assign(10, Vec3f(1, 2, 3));
  same_point.normals.assign(10, Vec3f::UnitZ());
  EXPECT_THROW(reconstruct(same_point), std::runtime_error);  // zero-size grid
  ReconstructOptions bad;
  bad.resolution = 100;
  EXPECT_THROW(reconstruct(sphere_points(1.f, 100), bad), std::runtime_error);
}

TEST(HoleFilling, NoFlatTriangleWhereTheRimRunsStraight) {
  // A flat 4 x 4 grid of unit squares without its middle 2 x 2: the hole's
  // rim has 8 vertices, three on each side of it, as a marching-cubes rim
  // along lattice lines has. Every triangulation of it has the same area, and
  // some take three vertices of one side (no area): those must not be chosen.
  TriangleMesh mesh;
  for (int y = 0; y <= 4; ++y)
    for (int x = 0; x <= 4; ++x) mesh.positions.push_back(Vec3f(float(x), float(y), 0.f));
  auto id = [](int x, int y) { return std::int32_t(y * 5 + x); };
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      if (x >= 1 && x <= 2 && y >= 1 && y <= 2) continue;
      mesh.triangles.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      mesh.triangles.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  ASSERT_EQ(mesh_topology(mesh).boundary_loops, 2u);
  const std::vector<Triangle> patch = fill_small_holes(mesh, 8);  // the outer rim has 16 edges
  ASSERT_EQ(patch.size(), 6u);
  double area = 0.0;
  for (const Triangle& t : patch) {
    const Vec3f& a = mesh.positions[t[0]];
    const Vec3f n = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);
    EXPECT_GT(n.z(), 0.f) << "a patch triangle of no area or facing down";
    area += 0.5 * double(n.norm());
  }
  EXPECT_NEAR(area, 4.0, 1e-6);
  mesh.triangles.insert(mesh.triangles.end(), patch.begin(), patch.end());
  const MeshTopology after = mesh_topology(mesh);
  EXPECT_EQ(after.boundary_loops, 1u);
  EXPECT_EQ(after.non_manifold_edges, 0u);
  EXPECT_EQ(after.degenerate_triangles, 0u);
}

TEST(HoleFilling, ClosesSmallHolesKeepsLargeOnesAndOrientsPatches) {
  // A marching-cubes sphere with two holes cut out: a small cap and a big band.
  ReconstructOptions options;
  options.resolution = 32;
  Reconstruction r = reconstruct(sphere_points(1.f, 60000), options);
  TriangleMesh mesh;
  mesh.positions = r.mesh.positions;
  for (const Triangle& t : r.mesh.triangles) {
    const Vec3f c = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.f;
    if (c.z() > 0.93f) continue;               // small cap: ~20 rim edges
    if (std::abs(c.z()) < 0.08f) continue;     // the equator band: two long rims
    mesh.triangles.push_back(t);
  }
  const MeshTopology before = mesh_topology(mesh);
  ASSERT_EQ(before.boundary_loops, 3u);
  const std::vector<Triangle> patch = fill_small_holes(mesh, 60);
  ASSERT_FALSE(patch.empty());
  mesh.triangles.insert(mesh.triangles.end(), patch.begin(), patch.end());
  const MeshTopology after = mesh_topology(mesh);
  EXPECT_EQ(after.boundary_loops, 2u);  // the band's rims are longer than 60 edges
  EXPECT_EQ(after.non_manifold_edges, 0u);
  EXPECT_EQ(after.degenerate_triangles, 0u);
  // Consistent orientation: no directed edge is used twice.
  std::map<std::pair<int, int>, int> directed;
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ASSERT_EQ((directed[std::make_pair(t[k], t[(k + 1) % 3])]++), 0);
  // The patch lies over the cap, facing outward.
  for (const Triangle& t : patch) {
    const Vec3f& a = mesh.positions[t[0]];
    const Vec3f n = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);
    EXPECT_GT(n.z(), 0.f);
  }
}
