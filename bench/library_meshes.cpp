#include <scan2lod/bench/library_meshes.h>

#include <vtkCellArray.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPoints.h>

#include <stdexcept>
#include <string>

namespace scan2lod::bench {

vtkSmartPointer<vtkPolyData> to_vtk(const TriangleMesh& m) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToFloat();
  points->SetNumberOfPoints(vtkIdType(m.positions.size()));
  for (std::size_t i = 0; i < m.positions.size(); ++i) points->SetPoint(vtkIdType(i), m.positions[i].data());
  vtkNew<vtkCellArray> polys;
  polys->AllocateExact(vtkIdType(m.triangles.size()), vtkIdType(3 * m.triangles.size()));
  for (const Triangle& t : m.triangles) {
    const vtkIdType ids[3] = {t[0], t[1], t[2]};
    polys->InsertNextCell(3, ids);
  }
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetPolys(polys);
  return poly;
}

TriangleMesh from_vtk(vtkPolyData* poly) {
  TriangleMesh out;
  out.positions.resize(std::size_t(poly->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i) {
    double p[3];
    poly->GetPoint(i, p);
    out.positions[std::size_t(i)] = Vec3d(p[0], p[1], p[2]).cast<float>();
  }
  vtkCellArray* polys = poly->GetPolys();
  out.triangles.reserve(std::size_t(polys->GetNumberOfCells()));
  vtkNew<vtkIdList> cell;
  for (polys->InitTraversal(); polys->GetNextCell(cell);) {
    if (cell->GetNumberOfIds() != 3)
      throw std::runtime_error("VTK returned a polygon with " + std::to_string(cell->GetNumberOfIds()) +
                               " corners, not a triangle");
    out.triangles.push_back({std::int32_t(cell->GetId(0)), std::int32_t(cell->GetId(1)), std::int32_t(cell->GetId(2))});
  }
  return out;
}

open3d::geometry::TriangleMesh to_open3d(const TriangleMesh& m) {
  open3d::geometry::TriangleMesh out;
  out.vertices_.reserve(m.positions.size());
  for (const Vec3f& p : m.positions) out.vertices_.push_back(p.cast<double>());
  out.triangles_.reserve(m.triangles.size());
  for (const Triangle& t : m.triangles) out.triangles_.emplace_back(t[0], t[1], t[2]);
  return out;
}

TriangleMesh from_open3d(const open3d::geometry::TriangleMesh& m) {
  TriangleMesh out;
  out.positions.reserve(m.vertices_.size());
  for (const Eigen::Vector3d& v : m.vertices_) out.positions.push_back(v.cast<float>());
  out.triangles.reserve(m.triangles_.size());
  for (const Eigen::Vector3i& t : m.triangles_) out.triangles.push_back({t[0], t[1], t[2]});
  return out;
}

}  // namespace scan2lod::bench
