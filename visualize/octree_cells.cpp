#include <scan2lod/visualize/octree_cells.h>

#include <scan2lod/reconstruct/cube_grid.h>

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkFloatArray.h>
#include <vtkIntArray.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkTypeInt32Array.h>

#include <algorithm>
#include <cassert>

namespace scan2lod {

std::vector<std::int32_t> lod_cut(const McOctree& tree, const LodArray& lod, std::size_t priority) {
  assert(priority <= lod.full());
  std::vector<std::int32_t> cut;
  if (tree.size() == 0) return cut;
  if (priority == 0) return {0};
  std::vector<std::uint8_t> expanded(tree.size(), 0);
  for (std::size_t i = 0; i < priority; ++i) expanded[std::size_t(lod.order[i])] = 1;
  for (std::size_t n = 1; n < tree.size(); ++n)
    if (!expanded[n] && tree.nodes.parents[n] >= 0 && expanded[std::size_t(tree.nodes.parents[n])]) cut.push_back(std::int32_t(n));
  return cut;
}

vtkSmartPointer<vtkPolyData> cell_outlines(const McOctree& tree, const std::vector<std::int32_t>& nodes) {
  static const int kEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                    {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  auto points = vtkSmartPointer<vtkFloatArray>::New();
  points->SetNumberOfComponents(3);
  points->SetNumberOfTuples(vtkIdType(8 * nodes.size()));
  auto offsets = vtkSmartPointer<vtkTypeInt32Array>::New();
  auto connectivity = vtkSmartPointer<vtkTypeInt32Array>::New();
  offsets->SetNumberOfTuples(vtkIdType(12 * nodes.size() + 1));
  connectivity->SetNumberOfTuples(vtkIdType(24 * nodes.size()));
  auto levels = vtkSmartPointer<vtkIntArray>::New();
  levels->SetName("Level");
  levels->SetNumberOfTuples(vtkIdType(12 * nodes.size()));
  float* p = points->GetPointer(0);
  std::int32_t* o = offsets->GetPointer(0);
  std::int32_t* c = connectivity->GetPointer(0);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const std::size_t n = std::size_t(nodes[i]);
    int x, y, z;
    unpack_key(tree.nodes.keys[n], &x, &y, &z);
    const std::int64_t scale = std::int64_t(1) << (tree.depth - tree.nodes.levels[n]);  // leaf cubes per side
    for (int k = 0; k < 8; ++k) {
      const Vec3f q = tree.grid.corner_position((x + (k & 1)) * scale, (y + ((k >> 1) & 1)) * scale,
                                                (z + ((k >> 2) & 1)) * scale);
      p[3 * (8 * i + k) + 0] = q.x();
      p[3 * (8 * i + k) + 1] = q.y();
      p[3 * (8 * i + k) + 2] = q.z();
    }
    for (int e = 0; e < 12; ++e) {
      const std::size_t cell = 12 * i + std::size_t(e);
      o[cell] = std::int32_t(2 * cell);
      c[2 * cell + 0] = std::int32_t(8 * i + kEdges[e][0]);
      c[2 * cell + 1] = std::int32_t(8 * i + kEdges[e][1]);
      levels->SetValue(vtkIdType(cell), tree.nodes.levels[n]);
    }
  }
  o[12 * nodes.size()] = std::int32_t(24 * nodes.size());
  auto pts = vtkSmartPointer<vtkPoints>::New();
  pts->SetData(points);
  auto lines = vtkSmartPointer<vtkCellArray>::New();
  lines->SetData(offsets, connectivity);
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(pts);
  poly->SetLines(lines);
  poly->GetCellData()->SetScalars(levels);
  return poly;
}

std::vector<std::int32_t> lod_cut(const LodModel& model, std::size_t priority) {
  if (!model.octree) return {};
  return lod_cut(model.octree->tree, model.octree->lod, std::min(priority, model.octree->lod.full()));
}

vtkSmartPointer<vtkPolyData> cell_outlines(const LodModel& model, const std::vector<std::int32_t>& nodes) {
  if (!model.octree) return cell_outlines(McOctree{}, {});
  return cell_outlines(model.octree->tree, nodes);
}

OctreeSeries octree_series(const LodModel& model) {
  OctreeSeries s;
  if (!model.octree) return s;
  const McOctree& tree = model.octree->tree;
  const LodArray& lod = model.octree->lod;
  s.metric.reserve(lod.full());
  for (std::size_t i = 0; i < lod.full(); ++i) s.metric.push_back(double(tree.nodes.metrics[std::size_t(lod.order[i])]));
  s.triangles.assign(lod.accumulated.begin(), lod.accumulated.end());
  return s;
}

}  // namespace scan2lod
