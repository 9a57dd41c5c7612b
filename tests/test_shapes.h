// Shapes with known answers, shared by the tests: Open3D's primitives as plain
// meshes, their virtual range scans as oriented points, and the octree LOD
// model of those points.
#pragma once

#include <scan2lod/acquisition/virtual_scanner.h>
#include <scan2lod/core/types.h>
#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/mc_octree.h>
#include <scan2lod/lod/octree/octree_order.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include <open3d/geometry/TriangleMesh.h>

namespace scan2lod::testing {

inline TriangleMesh from_open3d(const open3d::geometry::TriangleMesh& m) {
  TriangleMesh out;
  for (const auto& v : m.vertices_) out.positions.push_back(v.cast<float>());
  for (const auto& t : m.triangles_) out.triangles.push_back({t[0], t[1], t[2]});
  return out;
}

// The mesh scanned from `views` directions at size x size, as oriented points.
inline OrientedPoints scan_shape(const TriangleMesh& mesh, int views = 14, int size = 256) {
  return virtual_scan_points(mesh, {views, size, size});
}

struct OctreeModel {
  McOctree tree;
  LodArray lod;
};

// Reconstructed at `resolution`, then built and numbered as `scan2lod build` does.
inline OctreeModel build_octree_model(const OrientedPoints& points, int resolution) {
  ReconstructOptions options;
  options.resolution = resolution;
  OctreeModel m;
  m.tree = build_mc_octree(reconstruct(points, options));
  m.lod = number_nodes(m.tree);
  return m;
}

}  // namespace scan2lod::testing
