// Closed shapes stay closed (Lee 2007, §4.4: range images generated from
// meshes): a sphere and a torus, virtually scanned from 14 views, come back as
// closed 2-manifolds with the right Euler characteristic, on the surface.
#include <scan2lod/acquisition/lattice_normals.h>
#include <scan2lod/acquisition/virtual_scanner.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include "test_shapes.h"

#include <gtest/gtest.h>
#include <open3d/geometry/TriangleMesh.h>

#include <cmath>

using namespace scan2lod;
using scan2lod::testing::from_open3d;
using scan2lod::testing::scan_shape;

namespace {

struct ShapeResult {
  MeshTopology topology;
  double mean_error = 0, max_error = 0, cube = 0;
};

template <class Distance>
ShapeResult reconstruct_shape(const TriangleMesh& shape, int resolution, Distance analytic) {
  OrientedPoints points = scan_shape(shape, 14, 256);
  ReconstructOptions options;
  options.resolution = resolution;
  Reconstruction r = reconstruct(points, options);
  ShapeResult out;
  out.topology = mesh_topology(r.mesh);
  out.cube = r.leaves.grid.cube_size;
  for (const Vec3f& p : r.mesh.positions) {
    const double e = std::abs(analytic(p.cast<double>()));
    out.mean_error += e;
    out.max_error = std::max(out.max_error, e);
  }
  out.mean_error /= double(r.mesh.positions.size());
  return out;
}

}  // namespace

TEST(ClosedShapes, ScannedSphereIsAClosedSphere) {
  // Fine tessellation: its facets sit within 1e-4 of the analytic sphere.
  auto sphere = open3d::geometry::TriangleMesh::CreateSphere(1.0, 200);
  for (int resolution : {32, 64}) {
    ShapeResult r = reconstruct_shape(from_open3d(*sphere), resolution,
                                      [](const Vec3d& p) { return p.norm() - 1.0; });
    EXPECT_EQ(r.topology.boundary_edges, 0u) << "R=" << resolution;
    EXPECT_EQ(r.topology.non_manifold_edges, 0u) << "R=" << resolution;
    EXPECT_EQ(r.topology.components, 1u) << "R=" << resolution;
    EXPECT_EQ(r.topology.euler_characteristic, 2) << "R=" << resolution;
    EXPECT_LT(r.mean_error, 0.05 * r.cube) << "R=" << resolution;
  }
}

TEST(ClosedShapes, ScannedTorusIsAClosedTorus) {
  const double R = 1.0, tube = 0.4;
  auto torus = open3d::geometry::TriangleMesh::CreateTorus(R, tube, 300, 120);
  for (int resolution : {32, 64}) {
    ShapeResult r = reconstruct_shape(from_open3d(*torus), resolution, [&](const Vec3d& p) {
      const double ring = std::hypot(p.x(), p.y()) - R;
      return std::hypot(ring, p.z()) - tube;
    });
    EXPECT_EQ(r.topology.boundary_edges, 0u) << "R=" << resolution;
    EXPECT_EQ(r.topology.non_manifold_edges, 0u) << "R=" << resolution;
    EXPECT_EQ(r.topology.components, 1u) << "R=" << resolution;
    EXPECT_EQ(r.topology.euler_characteristic, 0) << "R=" << resolution;
    EXPECT_LT(r.mean_error, 0.05 * r.cube) << "R=" << resolution;
  }
}

TEST(ClosedShapes, ScanColoursReachTheMeshVertices) {
  // Red northern and blue southern hemisphere, carried from the mesh through the
  // virtual range images and the oriented points onto the reconstruction.
  auto sphere = open3d::geometry::TriangleMesh::CreateSphere(1.0, 100);
  TriangleMesh mesh = from_open3d(*sphere);
  for (const Vec3f& p : mesh.positions)
    mesh.colors.push_back(p.z() > 0.f ? Rgb{230, 20, 20} : Rgb{20, 20, 230});
  OrientedPoints points = scan_shape(mesh, 14, 128);
  ASSERT_EQ(points.colors.size(), points.size());
  ReconstructOptions options;
  options.resolution = 32;
  Reconstruction r = reconstruct(points, options);
  ASSERT_EQ(r.mesh.colors.size(), r.mesh.positions.size());
  ASSERT_EQ(r.leaves.corner_colors.size(), r.leaves.corner_keys.size());
  std::size_t checked = 0;
  for (std::size_t v = 0; v < r.mesh.positions.size(); ++v) {
    const float z = r.mesh.positions[v].z();
    if (std::abs(z) < 0.2f) continue;  // the seam blends
    const Rgb& c = r.mesh.colors[v];
    if (z > 0.f) {
      EXPECT_GT(c[0], 200);
      EXPECT_LT(c[2], 50);
    } else {
      EXPECT_LT(c[0], 50);
      EXPECT_GT(c[2], 200);
    }
    ++checked;
  }
  EXPECT_GT(checked, r.mesh.positions.size() / 2);
}
