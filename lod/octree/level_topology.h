// The topology of one level as it is coarsened, and whether a local change keeps
// it sound: no edge of more than two triangles, no more boundary loops, no more
// connected components (through shared vertices, as measure/topology.h counts
// them). The octree's order (lod/octree/coarsening.h) asks it before every collapse.
//
// The level is held as counts only: triangles per vertex, triangles per edge
// (an open-addressing table) and boundary edges per vertex. A change replaces
// `removed` (triangles of the level) by `added`; only their vertices and
// edges are looked at, so a check costs O(change), however large the level.
//
// The checks are sufficient, not necessary (a change they refuse may be sound
// through parts of the level they do not look at):
// - boundary (loops are the boundary edges' connected components): rims of
//   the change that reach the rest of the level's rims and were joined must
//   stay joined, and the loops wholly inside the change must not grow in number;
// - components: vertices the rest of the level uses and one removed piece
//   joined must still be joined by one added piece, and the added triangles
//   must hold as many pieces of their own (touching nothing else) as the
//   removed ones did: a piece may coarsen, not vanish or break off;
// - the Euler characteristic must not fall: a hole or a handle may close, but
//   no tunnel opens between two sheets.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/measure/topology.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace scan2lod {

// Whether a level counted whole (measure/topology.h) is sound against the
// full mesh: no non-manifold edge, no more boundary loops, no more
// components, and no more handles (2 genus = 2 components - loops - χ, for
// orientable surfaces): the rules above, for the whole level.
bool sound_level(const MeshTopology& level, const MeshTopology& full);

class LevelTopology {
 public:
  // An empty level over `vertices` vertex ids, with room for about
  // `edges` edges before the table grows.
  LevelTopology(std::size_t vertices, std::size_t edges);

  // Adds triangles to the level unchecked (the full mesh, at the start).
  void add(const std::vector<Triangle>& triangles);

  // Whether replacing `removed` (all in the level) by `added` keeps the level
  // sound, as above. Leaves the level unchanged.
  bool keeps_topology(const std::vector<Triangle>& removed, const std::vector<Triangle>& added);

  // Applies the replacement keeps_topology last checked; nothing may come
  // between the two.
  void commit();

  // Applies a replacement unchecked.
  void replace(const std::vector<Triangle>& removed, const std::vector<Triangle>& added);

 private:
  struct Slot {
    std::uint64_t key;
    std::int32_t count;  // triangles of the level using the edge
    std::int32_t local;  // its entry in edges_ during a check, else -1
  };
  void reserve(std::size_t more);
  std::size_t slot_of(std::uint64_t key);  // inserts with count 0
  void change_edge(std::size_t slot, int delta);
  // Local ids for the change's vertices and its edges, with how many
  // removed and added triangles use each.
  void gather(const std::vector<Triangle>& removed, const std::vector<Triangle>& added);
  void release();  // clears local ids
  bool boundary_kept();
  bool euler_kept(std::size_t removed, std::size_t added) const;
  bool components_kept(const std::vector<Triangle>& removed, const std::vector<Triangle>& added);

  std::vector<Slot> table_;
  std::size_t used_ = 0;
  std::vector<std::int32_t> uses_;           // triangles per vertex
  std::vector<std::int32_t> boundary_degree_;  // boundary edges per vertex

  // Scratch, reused: local vertex ids (-1 outside a check) and per local vertex data.
  std::vector<std::int32_t> local_;
  std::vector<std::int32_t> vertex_of_;
  struct Local {
    std::int32_t removed_uses, added_uses;
    std::int32_t rims[2];    // boundary edges in the change, before (0) and after (1)
    std::int32_t outside;    // boundary edges outside the change
  };
  std::vector<Local> locals_;
  struct EdgeUse {
    std::size_t slot;
    std::int32_t removed, added;
    std::int32_t before;  // triangles of the level using it now
  };
  std::vector<EdgeUse> edges_;
  std::vector<std::int32_t> partner_[2], parent_[2];
};

}  // namespace scan2lod
