// Shapes with known answers, shared by the tests: Open3D's primitives as plain
// meshes, and their virtual range scans as oriented points.
#pragma once

#include "acquisition/virtual_scanner.h"
#include "core/types.h"

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

}  // namespace scan2lod::testing
