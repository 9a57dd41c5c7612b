// The edge where plain meshes become VTK poly data: the viewer, the montage and
// the plots draw through these, the pipeline never sees a VTK type.
#pragma once

#include <scan2lod/core/types.h>

#include <vtkSmartPointer.h>

class vtkPolyData;

namespace scan2lod {

// Triangles of `mesh` as poly data: float points, 32-bit connectivity (a
// straight copy, no per-cell inserts), "Normals" when the mesh has them and
// "Colors" (unsigned char RGB) always: the mesh's own vertex colours, or,
// when it has none, its normals mapped to RGB (0.5 + 0.5 n) so that the
// colour mode still shows something. Cost is linear in the mesh and small
// next to extraction (the slider benchmark, bench/viewer_bench.cpp).
vtkSmartPointer<vtkPolyData> mesh_to_poly_data(const TriangleMesh& mesh);

// Replaces the triangles of `poly` (whose points stay) by `triangles`, a
// straight copy of the indices. The OpenGL mapper then re-sends only the
// index buffer: the points, normals and colours are uploaded once.
void set_triangles(vtkPolyData* poly, const std::vector<Triangle>& triangles);

// Oriented points as poly data: one vertex cell per point, all in `color`.
vtkSmartPointer<vtkPolyData> points_to_poly_data(const OrientedPoints& points, const Rgb& color);

// Normals as short line segments from each `stride`-th point p to p + length n,
// all in `color` (the viewer's normal glyphs for scan sets).
vtkSmartPointer<vtkPolyData> normals_to_poly_data(const OrientedPoints& points, float length, std::size_t stride,
                                                  const Rgb& color);

}  // namespace scan2lod
