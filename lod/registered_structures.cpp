// The registration (with registered_structures.h): every LOD structure the
// face offers (lod/structure.h).
// A new structure implements StructureKind in its own room and is listed
// here once.
#include <scan2lod/lod/structure.h>

namespace scan2lod {

const StructureKind& cluster_structure();  // lod/clusters/cluster_structure.cpp
const StructureKind& octree_structure();   // lod/octree/octree_structure.cpp

// In the order a model's default is chosen: the cluster hierarchy, the more
// faithful, before the octree.
const std::vector<const StructureKind*>& registered_structures() {
  static const std::vector<const StructureKind*> kinds = {&cluster_structure(), &octree_structure()};
  return kinds;
}

}  // namespace scan2lod
