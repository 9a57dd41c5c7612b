// The octree cells behind a level of detail (seed 003 §5.1, Fig. 5.4): the cut
// through the marching-cube octree that `priority` expansions leave, each cell
// drawn as a cube outline coloured by its level, so a user sees where the
// detail goes.
#pragma once

#include "lod/model_file.h"

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

}  // namespace scan2lod
