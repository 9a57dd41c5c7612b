// Claims about measure/: topology counts on shapes with known answers, and
// distances that agree with an independent brute-force computation.
#include <scan2lod/core/error.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>

#include <Eigen/Geometry>
#include <open3d/geometry/TriangleMesh.h>

#include "test_shapes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace scan2lod;
using scan2lod::testing::from_open3d;

namespace {

TriangleMesh sphere(double radius, int resolution) {
  return from_open3d(*open3d::geometry::TriangleMesh::CreateSphere(radius, resolution));
}

// Unit cube, 12 outward-facing triangles.
TriangleMesh cube() {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.positions.emplace_back(float(i & 1), float((i >> 1) & 1), float(i >> 2));
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

TriangleMesh tetrahedron(const Vec3f& offset) {
  TriangleMesh m;
  m.positions = {offset, offset + Vec3f(1, 0, 0), offset + Vec3f(0, 1, 0), offset + Vec3f(0, 0, 1)};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

TriangleMesh concat(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh m = a;
  const auto n = std::int32_t(a.positions.size());
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  for (Triangle t : b.triangles) m.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
  return m;
}

// Unit square in the z = height plane, two triangles.
TriangleMesh square(float height) {
  TriangleMesh m;
  m.positions = {{0, 0, height}, {1, 0, height}, {1, 1, height}, {0, 1, height}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

// Reference distance by a different route than the library's Voronoi-region
// walk: project onto the plane; inside -> plane distance, else nearest edge.
double segment_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

double brute_force_distance(const Vec3f& pf, const TriangleMesh& m) {
  const Vec3d p = pf.cast<double>();
  double best = INFINITY;
  for (const Triangle& t : m.triangles) {
    const Vec3d a = m.positions[t[0]].cast<double>(), b = m.positions[t[1]].cast<double>(),
                c = m.positions[t[2]].cast<double>();
    const Vec3d n = (b - a).cross(c - a);
    if (n.squaredNorm() == 0) continue;
    const Vec3d q = p - n * ((p - a).dot(n) / n.squaredNorm());
    const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                        (a - c).cross(q - c).dot(n) >= 0;
    const double d = inside ? (p - q).norm()
                            : std::min({segment_distance(p, a, b), segment_distance(p, b, c),
                                        segment_distance(p, c, a)});
    best = std::min(best, d);
  }
  return best;
}

// ~1000 queries: spread over the box, and close to vertices and edges where
// the closest feature changes.
std::vector<Vec3f> queries_around(const TriangleMesh& m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  std::normal_distribution<float> jitter(0.f, 1e-3f);
  const Aabb box = bounds(m.positions);
  std::vector<Vec3f> q;
  for (int i = 0; i < 400; ++i) {
    Vec3f u(unit(rng), unit(rng), unit(rng));
    q.push_back(box.min - 0.25f * box.extent() + 1.5f * box.extent().cwiseProduct(u));
  }
  for (int i = 0; i < 300; ++i) {
    const Vec3f& v = m.positions[rng() % m.positions.size()];
    q.push_back(v + Vec3f(jitter(rng), jitter(rng), jitter(rng)));
  }
  for (int i = 0; i < 300; ++i) {
    const Triangle& t = m.triangles[rng() % m.triangles.size()];
    const int k = int(rng() % 3);
    const Vec3f e = m.positions[t[k]] + unit(rng) * (m.positions[t[(k + 1) % 3]] - m.positions[t[k]]);
    q.push_back(e + Vec3f(jitter(rng), jitter(rng), jitter(rng)));
  }
  return q;
}

// Three rounds of ~1000 queries; exact agreement to 1e-6 relative even where
// Embree's float comparison sees ties.
void expect_matches_brute_force(const TriangleMesh& m, std::uint64_t seed) {
  for (std::uint64_t round = 0; round < 3; ++round) {
    const std::vector<Vec3f> q = queries_around(m, seed + 1000 * round);
    const std::vector<float> d = distances_to_surface(q, m);
    ASSERT_EQ(d.size(), q.size());
    for (std::size_t i = 0; i < q.size(); ++i) {
      const double ref = brute_force_distance(q[i], m);
      ASSERT_NEAR(d[i], ref, 1e-6 * ref) << "round " << round << ", query " << i;
    }
  }
}

}  // namespace

// --- topology --------------------------------------------------------------

TEST(MeasureTopology, CubeIsAClosedSphere) {
  const MeshTopology t = mesh_topology(cube());
  EXPECT_EQ(t.vertices, 8u);
  EXPECT_EQ(t.referenced_vertices, 8u);
  EXPECT_EQ(t.triangles, 12u);
  EXPECT_EQ(t.edges, 18u);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.boundary_loops, 0u);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.degenerate_triangles, 0u);
}

TEST(MeasureTopology, CubeWithOneTriangleRemovedHasOneTriangularHole) {
  TriangleMesh m = cube();
  m.triangles.pop_back();
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.boundary_edges, 3u);
  EXPECT_EQ(t.boundary_loops, 1u);
  EXPECT_EQ(t.euler_characteristic, 1);
  EXPECT_EQ(t.components, 1u);
}

TEST(MeasureTopology, OpenTubeHasTwoBoundaryLoops) {
  // Four quads around the z axis; rims at z = 0 and z = 1.
  TriangleMesh m;
  for (int z = 0; z < 2; ++z)
    for (int i = 0; i < 4; ++i) m.positions.emplace_back(float(i == 1 || i == 2), float(i >= 2), float(z));
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    m.triangles.push_back({i, j, j + 4});
    m.triangles.push_back({i, j + 4, i + 4});
  }
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.boundary_edges, 8u);
  EXPECT_EQ(t.boundary_loops, 2u);
  EXPECT_EQ(t.euler_characteristic, 0);
}

TEST(MeasureTopology, TwoDisjointTetrahedraAreTwoComponents) {
  const TriangleMesh m = concat(tetrahedron({0, 0, 0}), tetrahedron({5, 0, 0}));
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(t.largest_component_triangles, 4u);
  EXPECT_EQ(t.euler_characteristic, 4);
  EXPECT_EQ(t.boundary_edges, 0u);
  int count = 0;
  EXPECT_EQ(triangle_components(m, &count), (std::vector<int>{0, 0, 0, 0, 1, 1, 1, 1}));
  EXPECT_EQ(count, 2);
}

TEST(MeasureTopology, ThreeTrianglesOnOneEdgeAreNonManifold) {
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, -1, 0}, {0.5f, 0, 1}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.non_manifold_edges, 1u);
  EXPECT_EQ(t.boundary_edges, 6u);
  EXPECT_EQ(t.boundary_loops, 1u);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.euler_characteristic, 5 - 7 + 3);
}

TEST(MeasureTopology, TrianglesMeetingAtAVertexShareOneLoopAndComponent) {
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  m.triangles = {{0, 1, 2}, {0, 3, 4}};
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.boundary_edges, 6u);
  EXPECT_EQ(t.boundary_loops, 1u);
  EXPECT_EQ(t.components, 1u);
}

TEST(MeasureTopology, DegenerateTrianglesAreCounted) {
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {7, 7, 7}};
  m.triangles = {{0, 1, 2},   // fine
                 {0, 1, 3},   // collinear: zero area, still an edge-connected triangle
                 {4, 4, 0}};  // repeated index: no surface at all
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.degenerate_triangles, 2u);
  EXPECT_EQ(t.referenced_vertices, 4u);  // vertex 4 is only used by the collapsed triangle
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(triangle_components(m)[2], -1);
}

TEST(MeasureTopology, OpenThreeDSphereIsClosedAndManifold) {
  const TriangleMesh m = sphere(1.0, 20);
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.largest_component_triangles, m.triangles.size());
}

TEST(MeasureTopology, IndexOutOfRangeIsAnInputError) {
  TriangleMesh m = square(0);
  m.triangles.push_back({0, 2, 4});
  EXPECT_THROW(mesh_topology(m), InputError);
}

TEST(MeasureTopology, DropSmallComponentsKeepsTheBigPiece) {
  const TriangleMesh big = sphere(1.0, 10);
  const TriangleMesh m = concat(concat(tetrahedron({5, 0, 0}), big), tetrahedron({-5, 0, 0}));
  const TriangleMesh kept = drop_small_components(m, 0.1);
  EXPECT_EQ(kept.triangles.size(), big.triangles.size());
  EXPECT_EQ(kept.positions.size(), big.positions.size());
  EXPECT_EQ(mesh_topology(kept).components, 1u);
  EXPECT_EQ(drop_small_components(m, 0).triangles.size(), m.triangles.size());
}

// --- distances -------------------------------------------------------------

TEST(MeasureDistance, AgreesWithBruteForceOnAJitteredSphere) {
  TriangleMesh m = sphere(1.0, 8);  // 112 triangles
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> jitter(-0.05f, 0.05f);
  for (Vec3f& p : m.positions) p += Vec3f(jitter(rng), jitter(rng), jitter(rng));
  expect_matches_brute_force(m, 11);
}

TEST(MeasureDistance, AgreesWithBruteForceOnATriangleSoup) {
  TriangleMesh m;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  for (int t = 0; t < 80; ++t) {
    for (int k = 0; k < 3; ++k) m.positions.emplace_back(unit(rng), unit(rng), unit(rng));
    m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
  }
  expect_matches_brute_force(m, 12);
}

TEST(MeasureDistance, AgreesWithBruteForceOnANoisyHeightField) {
  TriangleMesh m;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> height(-0.2f, 0.2f);
  const int n = 9;  // 8 x 8 cells, 128 triangles
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) m.positions.emplace_back(x * 0.125f, y * 0.125f, height(rng));
  for (int y = 0; y + 1 < n; ++y)
    for (int x = 0; x + 1 < n; ++x) {
      const int v = y * n + x;
      m.triangles.push_back({v, v + 1, v + n + 1});
      m.triangles.push_back({v, v + n + 1, v + n});
    }
  expect_matches_brute_force(m, 13);
}

TEST(MeasureDistance, DegenerateTrianglesAreSkippedNotFatal) {
  // Open3D aborts on a repeated-index triangle; the measure must not.
  TriangleMesh m = square(0);
  m.positions.emplace_back(2, 0, 0);
  m.triangles.push_back({0, 0, 2});
  m.triangles.push_back({0, 1, 4});  // collinear sliver along the x axis
  const std::vector<float> d = distances_to_surface({{0.5f, 0.5f, 1.f}, {0.5f, 0.25f, -0.5f}}, m);
  EXPECT_NEAR(d[0], 1.0, 1e-7);
  EXPECT_NEAR(d[1], 0.5, 1e-7);
}

TEST(MeasureDistance, ParallelSquaresAreTheirOffsetApartBothWays) {
  CompareOptions options;
  options.samples = 5000;
  const SurfaceComparison c = compare_surfaces(square(0.f), square(0.01f), options);
  EXPECT_NEAR(c.a_to_b.mean, 0.01, 1e-6);
  EXPECT_NEAR(c.b_to_a.mean, 0.01, 1e-6);
  EXPECT_NEAR(c.a_to_b.max, 0.01, 1e-6);
  EXPECT_NEAR(c.b_to_a.p95, 0.01, 1e-6);
  EXPECT_EQ(c.a_to_b.samples, 5000u);
  EXPECT_NEAR(c.diagonal, std::sqrt(2.0), 1e-6);
}

TEST(MeasureDistance, SameMeshIsZeroApart) {
  const TriangleMesh m = sphere(1.0, 30);
  CompareOptions options;
  options.samples = 20000;
  const SurfaceComparison c = compare_surfaces(m, m, options);
  EXPECT_LT(c.a_to_b.max, 1e-6);
  EXPECT_LT(c.b_to_a.max, 1e-6);
}

TEST(MeasureDistance, SeedsChangeTheSamplesNotTheAnswer) {
  // A coarse sphere lies inside a fine one by about the coarse chord sagitta.
  const TriangleMesh coarse = sphere(1.0, 10), fine = sphere(1.0, 60);
  CompareOptions one, two;
  two.seed = 2;
  const SurfaceComparison c1 = compare_surfaces(coarse, fine, one);
  const SurfaceComparison c2 = compare_surfaces(coarse, fine, two);
  EXPECT_EQ(c1.a_to_b.samples, 100000u);  // max(10 * 180 triangles, 100000)
  EXPECT_GT(c1.a_to_b.mean, 1e-3);
  EXPECT_NEAR(c2.a_to_b.mean, c1.a_to_b.mean, 0.02 * c1.a_to_b.mean);
  EXPECT_NEAR(c2.b_to_a.mean, c1.b_to_a.mean, 0.02 * c1.b_to_a.mean);
  EXPECT_NEAR(c2.a_to_b.rms, c1.a_to_b.rms, 0.02 * c1.a_to_b.rms);
  // The max sits on the coarse mesh's face centres, which both seeds get close to.
  EXPECT_NEAR(c2.a_to_b.max, c1.a_to_b.max, 0.05 * c1.a_to_b.max);
}

TEST(MeasureDistance, MeshWithoutTrianglesIsAnInputError) {
  TriangleMesh empty;
  empty.positions = {{0, 0, 0}};
  EXPECT_THROW(compare_surfaces(empty, square(0), {}), InputError);
  EXPECT_THROW(compare_surfaces(square(0), empty, {}), InputError);
}

TEST(MeasureDistance, StatsOfOneToHundred) {
  std::vector<float> d;
  for (int i = 1; i <= 100; ++i) d.push_back(float(i));
  const DistanceStats s = distance_stats(d);
  EXPECT_DOUBLE_EQ(s.mean, 50.5);
  EXPECT_DOUBLE_EQ(s.rms, std::sqrt(338350.0 / 100));
  EXPECT_DOUBLE_EQ(s.p95, 95);
  EXPECT_DOUBLE_EQ(s.max, 100);
  EXPECT_EQ(s.samples, 100u);
  EXPECT_EQ(distance_stats({}).samples, 0u);
}

TEST(MeasureSampling, UniformByAreaAndRepeatableForASeed) {
  // Triangles of area 0.5 (z = 0) and 1.5 (z = 1): a quarter of the samples on the first.
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {3, 0, 1}, {0, 1, 1}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  const std::vector<Vec3f> p = sample_surface(m, 100000, 9);
  EXPECT_EQ(p, sample_surface(m, 100000, 9));
  EXPECT_NE(p, sample_surface(m, 100000, 10));
  const auto low = std::count_if(p.begin(), p.end(), [](const Vec3f& x) { return x.z() == 0.f; });
  EXPECT_NEAR(double(low) / double(p.size()), 0.25, 0.005);
  // Uniform within a triangle too: x + 3y <= 1 cuts a similar triangle with a
  // third of the sides, so a ninth of the area, off the corner at (0, 0, 1).
  const auto corner = std::count_if(p.begin(), p.end(), [](const Vec3f& x) {
    return x.z() == 1.f && x.x() + 3 * x.y() <= 1;
  });
  EXPECT_NEAR(double(corner) / double(p.size() - std::size_t(low)), 1.0 / 9, 0.005);
  for (float dist : distances_to_surface(p, m)) ASSERT_LT(dist, 1e-6f);
}
