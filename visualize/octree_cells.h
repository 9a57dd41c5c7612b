// The octree cells behind a level of detail (Lee 2007, §5.1, Fig. 5.4): the cut
// through the marching-cube octree that `priority` expansions leave, each cell
// drawn as a cube outline coloured by its level, so a user sees where the
// detail goes. The one place in visualize/ that reads the octree's arrays
// (model.octree, when the model has one); the plots' octree series live here
// for that reason.
#pragma once

#include <scan2lod/lod/lod_model.h>

#include <vtkSmartPointer.h>

#include <cstdint>
#include <vector>

class vtkPolyData;

namespace scan2lod {

// The nodes of the cut after the first `priority` entries of the LOD array
// have expanded: the root when priority is 0, else every child of an expanded
// node that has not expanded itself. Ascending node order.
std::vector<std::int32_t> lod_cut(const McOctree& tree, const LodArray& lod, std::size_t priority);

// Cube outlines (12 line cells per node) with an int cell array "Level" (the
// node's octree level, 0 = root) as the cell scalars.
vtkSmartPointer<vtkPolyData> cell_outlines(const McOctree& tree, const std::vector<std::int32_t>& nodes);

// The same on a model's octree; an empty cut / no outlines without one.
std::vector<std::int32_t> lod_cut(const LodModel& model, std::size_t priority);
vtkSmartPointer<vtkPolyData> cell_outlines(const LodModel& model, const std::vector<std::int32_t>& nodes);

// The octree's priority series (Lee 2007, Figs. 6.6-6.8), empty without one:
// the LOD metric of the node each priority number expands, and the triangles
// after each number of expansions (lod.accumulated, full() + 1 entries).
struct OctreeSeries {
  std::vector<double> metric;
  std::vector<double> triangles;
};
OctreeSeries octree_series(const LodModel& model);

}  // namespace scan2lod
