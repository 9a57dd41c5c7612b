// The registration of the LOD structures, with registered_structures.cpp:
// each structure's id, and its member of every model (LodModel derives from
// RegisteredStructures, so callers that need a structure's own arrays read
// model.octree or model.clusters). A new structure is its own room (which
// implements lod/structure.h) plus a line or two here and in the .cpp.
#pragma once

#include <scan2lod/lod/clusters/cluster_hierarchy.h>
#include <scan2lod/lod/octree/lod_array.h>

#include <optional>

namespace scan2lod {

enum class LodStructure { kOctree, kClusters };

// What a model holds of each structure: nothing, or the whole structure.
struct RegisteredStructures {
  std::optional<OctreeLod> octree;         // lod/octree/
  std::optional<ClusterHierarchy> clusters;  // lod/clusters/
};

}  // namespace scan2lod
