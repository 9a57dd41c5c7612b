// The octree's expansion order, found backwards: from the full mesh, nodes
// collapse one by one, the latest in a given ranking first, and a collapse
// that would make the level unsound (lod/octree/level_topology.h) waits. The LOD
// array is that sequence reversed, so every level it offers was checked.
//
// A node whose collapse is refused stays expanded, and its parent may then
// collapse the two together, in one step: a rim then coarsens with a node
// large enough to carry it, and a thin part (an ear) goes only with a node
// that holds all of it, never leaving a piece behind. Inside such a step,
// replayed forwards, only the prefixes the checks pass are offered: a node, or
// a set of its nodes with all they need (one ear of two). The nodes no
// collapse could take off are replayed the same way from the root's level.
// Collapses also keep the neighbour rule (neighbours differ by at most one
// level) at every step.
//
// Internal to lod/ (octree_order.cpp).
#pragma once

#include <scan2lod/lod/octree/mc_octree.h>
#include <scan2lod/measure/topology.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

struct CoarseningOrder {
  std::vector<std::int32_t> order;  // expansions, parents before children
  // The first `coarsest` expansions lead to the coarsest level that could be
  // reached soundly.
  std::size_t coarsest = 0;
  // Priority numbers before `coarsest` and inside a step of several
  // expansions, ascending: no level is offered there.
  std::vector<std::int32_t> inside_steps;
};

// @param rank  per node, where it would expand by metric alone: nodes
//              collapse from the largest rank down, as the checks allow.
// @param full  the full mesh's topology (full_triangles), which small levels
//              counted whole are held to.
CoarseningOrder coarsen(const McOctree& tree, const std::vector<std::int32_t>& rank, const MeshTopology& full);

}  // namespace scan2lod
