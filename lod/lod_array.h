// Node priority numbering (Lee 2007, §5.2, §5.4.3) and the accumulation table
// (§6.1). Starting from the root, the expandable node with the largest LOD
// metric expands next; a node is expandable once every node beside it on its
// level (the 26 around it) exists in the current cut or has no surface. So
// neighbouring nodes in any prefix differ by at most one level.
//
// Two additions to the seed. The nodes above the full mesh's rim, above the rims
// of hole patches and above crossings the leaves lack (with what the neighbour
// rule makes them wait for) expand first, whatever their metric, so that no
// level opens a boundary the full mesh lacks: on the bunny at R = 256 that is
// 2,129 of 71,343 expansions (18,867 triangles), the `pinned` prefix. Then nodes whose children
// have no more triangles than they do expand as soon as they may.
#pragma once

#include "lod/mc_octree.h"

#include <cstdint>
#include <vector>

namespace scan2lod {

struct LodArray {
  std::vector<std::int32_t> order;  // nodes in the order they expand; order[0] is the root
  // accumulated[i]: triangles of the mesh after the first i expansions
  // (accumulated[0]: the root's own), order.size() + 1 entries.
  std::vector<std::int64_t> accumulated;
  // The first `pinned` expansions are the pinned nodes (see above): no level
  // is offered inside them, where part of the rim would still be coarse.
  std::size_t pinned = 0;

  std::size_t full() const { return order.size(); }
};

// Numbers the nodes of `tree` with a priority queue: O(n log n) for n nodes.
LodArray number_nodes(const McOctree& tree);

// The priority numbers at which levels are offered: 0, then from the end of the
// pinned prefix on, those whose triangle count is at least every earlier one's,
// up to full detail. A single expansion
// can lower the count (a node's children may need fewer triangles than it, and
// its coarser neighbours' transitions change), so offered levels skip those
// dips and the count never decreases from one offered level to the next.
std::vector<std::size_t> monotone_priorities(const LodArray& lod);

// The offered priority number (count of expansions) at or below the first
// `percent` of the LOD array, as in Lee 2007's tables; percent clamped to [0, 100].
// Inside the pinned prefix (only low percentages) it is the prefix's end.
std::size_t priority_for_percent(const LodArray& lod, double percent);

// The largest offered priority number whose mesh has at most `triangles`
// triangles, through the accumulation table (at least 0). A budget below the
// smallest offered level gets the largest level inside the pinned prefix that
// fits: smaller than any offered one, at the price of boundary loops near the
// rim that the full mesh lacks.
std::size_t priority_for_triangles(const LodArray& lod, std::int64_t triangles);

}  // namespace scan2lod
