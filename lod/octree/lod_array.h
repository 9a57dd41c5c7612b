// Node priority numbering (Lee 2007, §5.2, §5.4.3) and the accumulation table
// (§6.1). Starting from the root, the expandable node with the largest LOD
// metric expands next; a node is expandable once every node beside it on its
// level (the 26 around it) exists in the current cut or has no surface. So
// neighbouring nodes in any prefix differ by at most one level.
//
// The array itself is built by number_nodes (lod/octree/octree_order.h).
#pragma once

#include <scan2lod/lod/octree/mc_octree.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

struct LodArray {
  std::vector<std::int32_t> order;  // nodes in the order they expand; order[0] is the root
  // accumulated[i]: triangles of the mesh after the first i expansions
  // (accumulated[0]: the root's own), order.size() + 1 entries.
  std::vector<std::int64_t> accumulated;
  // No level is offered inside the first `pinned` expansions (what the
  // coarsening could not undo soundly, lod/octree/coarsening.h) ...
  std::size_t pinned = 0;
  // ... nor at these priority numbers (ascending), inside a step of several
  // expansions that the coarsening took together.
  std::vector<std::int32_t> inside_steps;

  std::size_t full() const { return order.size(); }
};

// The accumulation table of lod.order (LodArray::accumulated), counted by
// following the extracted meshes exactly: O(expansions) node emissions.
std::vector<std::int64_t> accumulation_table(const McOctree& tree, const LodArray& lod);

// The priority numbers at which levels are offered: past the pinned prefix
// (older models) and outside the coarsening's steps (`inside_steps`), those
// whose triangle count is at least every earlier one's, up to full detail. A
// single expansion
// can lower the count (a node's children may need fewer triangles than it, and
// its coarser neighbours' transitions change), so offered levels skip those
// dips and the count never decreases from one offered level to the next.
std::vector<std::size_t> monotone_priorities(const LodArray& lod);

// The offered priority number (count of expansions) at or below the first
// `percent` of the LOD array, as in Lee 2007's tables; percent clamped to [0, 100].
// Inside the pinned prefix (only low percentages) it is the prefix's end.
std::size_t priority_for_percent(const LodArray& lod, double percent);

// The largest offered priority number whose mesh has at most `triangles`
// triangles, through the accumulation table. A budget below the smallest
// offered level gets that level (more triangles than asked: callers say so)
// or, in older models with a pinned prefix, the largest level inside it that
// fits, at the price of boundary loops near the rim that the full mesh lacks.
std::size_t priority_for_triangles(const LodArray& lod, std::int64_t triangles);

// The offered level a triangle budget gets (lod/level_budget.h): the one
// priority_for_triangles gives, or, where that falls more than 10 % short of
// the budget, the next offered level when it is at most 10 % over.
std::size_t priority_for_budget(const LodArray& lod, std::int64_t triangles);

// The octree with its priority numbering, as a model (lod/lod_model.h) holds
// it: its vertices live in the model's VertexArray (tree.vertices is left
// empty there).
struct OctreeLod {
  McOctree tree;
  LodArray lod;
};

}  // namespace scan2lod
