// Builds the octree's LOD array (lod/octree/lod_array.h): which node expands when.
//
// Nodes are ranked by metric as Lee 2007 numbers them (§5.4.3): the
// expandable node with the largest metric next, a node being expandable once
// the nodes beside it on its level exist, so that neighbours in any prefix
// differ by at most one level. Nodes whose children have no more triangles
// than they do rank as soon as they may.
//
// That ranking is then replayed backwards from the full mesh
// (lod/octree/coarsening.h): nodes collapse latest-ranked first, each collapse
// checked to keep the level sound (no new boundary loop, piece or non-manifold
// edge), a refused node collapsing later with its parent or with the
// neighbours the rule ties it to. The array is that sequence reversed, so the
// coarse levels keep the full mesh's topology down to a few triangles.
#pragma once

#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/mc_octree.h>

namespace scan2lod {

// O(n log n) for n nodes, plus O(change) checks per collapse; part of the
// build (scan2lod_core), not of the runtime library.
LodArray number_nodes(const McOctree& tree);

}  // namespace scan2lod
