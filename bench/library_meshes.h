// Meshes between scan2lod's TriangleMesh and the peers' own types (VTK,
// Open3D), for both benchmarks. Only positions and triangles are copied:
// nothing else enters a measure.
#pragma once

#include <scan2lod/core/types.h>

#include <open3d/geometry/TriangleMesh.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

namespace scan2lod::bench {

// A float-point vtkPolyData with one triangle cell per triangle.
vtkSmartPointer<vtkPolyData> to_vtk(const TriangleMesh& mesh);

// The polys of `poly`. Throws std::runtime_error on a cell that is not a triangle.
TriangleMesh from_vtk(vtkPolyData* poly);

open3d::geometry::TriangleMesh to_open3d(const TriangleMesh& mesh);
TriangleMesh from_open3d(const open3d::geometry::TriangleMesh& mesh);

}  // namespace scan2lod::bench
