#include <scan2lod/visualize/poly_data.h>

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkFloatArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkTypeInt32Array.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cstring>

namespace scan2lod {
namespace {

static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f arrays are copied as flat floats");
static_assert(sizeof(Triangle) == 3 * sizeof(std::int32_t), "triangles are copied as flat indices");

vtkSmartPointer<vtkFloatArray> float3(const std::vector<Vec3f>& v, const char* name) {
  auto a = vtkSmartPointer<vtkFloatArray>::New();
  a->SetNumberOfComponents(3);
  a->SetNumberOfTuples(vtkIdType(v.size()));
  if (!v.empty()) std::memcpy(a->GetPointer(0), v.data(), v.size() * sizeof(Vec3f));
  if (name) a->SetName(name);
  return a;
}

vtkSmartPointer<vtkPoints> points_of(const std::vector<Vec3f>& v) {
  auto p = vtkSmartPointer<vtkPoints>::New();
  p->SetData(float3(v, nullptr));
  return p;
}

}  // namespace

void set_triangles(vtkPolyData* poly, const std::vector<Triangle>& triangles) {
  auto offsets = vtkSmartPointer<vtkTypeInt32Array>::New();
  offsets->SetNumberOfTuples(vtkIdType(triangles.size() + 1));
  std::int32_t* o = offsets->GetPointer(0);
  for (std::size_t i = 0; i <= triangles.size(); ++i) o[i] = std::int32_t(3 * i);
  auto connectivity = vtkSmartPointer<vtkTypeInt32Array>::New();
  connectivity->SetNumberOfTuples(vtkIdType(3 * triangles.size()));
  if (!triangles.empty()) std::memcpy(connectivity->GetPointer(0), triangles.data(), triangles.size() * sizeof(Triangle));
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  polys->SetData(offsets, connectivity);
  poly->SetPolys(polys);
}

vtkSmartPointer<vtkPolyData> mesh_to_poly_data(const TriangleMesh& mesh) {
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points_of(mesh.positions));
  set_triangles(poly, mesh.triangles);

  if (mesh.normals.size() == mesh.positions.size() && !mesh.normals.empty())
    poly->GetPointData()->SetNormals(float3(mesh.normals, "Normals"));

  auto colors = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colors->SetName("Colors");
  colors->SetNumberOfComponents(3);
  colors->SetNumberOfTuples(vtkIdType(mesh.positions.size()));
  unsigned char* c = colors->GetPointer(0);
  if (mesh.colors.size() == mesh.positions.size()) {
    if (!mesh.colors.empty()) std::memcpy(c, mesh.colors.data(), mesh.colors.size() * sizeof(Rgb));
  } else if (mesh.normals.size() == mesh.positions.size()) {
    for (std::size_t i = 0; i < mesh.normals.size(); ++i)
      for (int k = 0; k < 3; ++k)
        c[3 * i + k] = static_cast<unsigned char>(std::clamp(127.5f + 127.5f * mesh.normals[i][k], 0.f, 255.f));
  } else {
    std::fill(c, c + 3 * mesh.positions.size(), static_cast<unsigned char>(200));
  }
  poly->GetPointData()->AddArray(colors);
  return poly;
}

vtkSmartPointer<vtkPolyData> points_to_poly_data(const OrientedPoints& points, const Rgb& color) {
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points_of(points.positions));
  auto offsets = vtkSmartPointer<vtkTypeInt32Array>::New();
  auto connectivity = vtkSmartPointer<vtkTypeInt32Array>::New();
  offsets->SetNumberOfTuples(vtkIdType(points.size() + 1));
  connectivity->SetNumberOfTuples(vtkIdType(points.size()));
  for (std::size_t i = 0; i <= points.size(); ++i) offsets->SetValue(vtkIdType(i), std::int32_t(i));
  for (std::size_t i = 0; i < points.size(); ++i) connectivity->SetValue(vtkIdType(i), std::int32_t(i));
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  verts->SetData(offsets, connectivity);
  poly->SetVerts(verts);
  auto colors = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colors->SetName("Colors");
  colors->SetNumberOfComponents(3);
  colors->SetNumberOfTuples(vtkIdType(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) colors->SetTypedTuple(vtkIdType(i), color.data());
  poly->GetPointData()->SetScalars(colors);
  return poly;
}

vtkSmartPointer<vtkPolyData> normals_to_poly_data(const OrientedPoints& points, float length, std::size_t stride,
                                                  const Rgb& color) {
  stride = std::max<std::size_t>(stride, 1);
  const std::size_t n = (points.size() + stride - 1) / stride;
  std::vector<Vec3f> ends;
  ends.reserve(2 * n);
  for (std::size_t i = 0; i < points.size(); i += stride) {
    ends.push_back(points.positions[i]);
    ends.push_back(points.positions[i] + length * points.normals[i]);
  }
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points_of(ends));
  auto offsets = vtkSmartPointer<vtkTypeInt32Array>::New();
  auto connectivity = vtkSmartPointer<vtkTypeInt32Array>::New();
  offsets->SetNumberOfTuples(vtkIdType(n + 1));
  connectivity->SetNumberOfTuples(vtkIdType(2 * n));
  for (std::size_t i = 0; i <= n; ++i) offsets->SetValue(vtkIdType(i), std::int32_t(2 * i));
  for (std::size_t i = 0; i < 2 * n; ++i) connectivity->SetValue(vtkIdType(i), std::int32_t(i));
  auto lines = vtkSmartPointer<vtkCellArray>::New();
  lines->SetData(offsets, connectivity);
  poly->SetLines(lines);
  auto colors = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colors->SetName("Colors");
  colors->SetNumberOfComponents(3);
  colors->SetNumberOfTuples(vtkIdType(2 * n));
  for (std::size_t i = 0; i < 2 * n; ++i) colors->SetTypedTuple(vtkIdType(i), color.data());
  poly->GetPointData()->SetScalars(colors);
  return poly;
}

}  // namespace scan2lod
