// Incremental extraction (the idea of Ramos's LODStrips, 2008 on Lee 2007's octree): a
// level held as an index buffer and moved to another priority by applying the
// expansions or collapses in between, instead of rebuilding the cut.
//
// Cost: a node's change alters only itself, its children and the cut nodes
// beside it across a face or an edge (their transitions read its flag), so a
// move re-emits at most 8 + 18 nodes per expansion and 1 + 18 per collapse.
// A move with under 32 cut nodes per change rebuilds the cut in node order
// instead (as extract_lod does, a scan of the tree's flags), then the cheaper.
// Holes are compacted once they pass a quarter of the buffer: amortised O(change).
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/mc_octree.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace scan2lod {

class LodCursor {
 public:
  // The mesh after 0 expansions (the root's). `tree` and `lod` must outlive the
  // cursor and stay unchanged. Memory: O(tree.size() + patch needs) in flat
  // arrays, plus the buffer and a node id per buffer slot.
  LodCursor(const McOctree& tree, const LodArray& lod);

  // Moves to the mesh after `priority` expansions (clamped to lod.full()):
  // expands lod.order[priority() .. priority) or collapses
  // lod.order[priority .. priority()) last first.
  void move_to(std::size_t priority);

  std::size_t priority() const { return priority_; }

  // Index buffer into tree.vertices.positions, for a renderer as it is: the level's
  // triangles, in blocks per cut node and patch group, and holes of
  // degenerate triangles (all three indices equal) where blocks were removed.
  // Holes are at most a quarter of it after every move.
  const std::vector<Triangle>& buffer() const { return buffer_; }

  // Live (non-hole) triangles in buffer(): lod.accumulated[priority()].
  std::int64_t triangles() const { return std::int64_t(buffer_.size() - holes_); }

  // The live triangles alone, for export and tests: extract_lod's at the same
  // priority, as a multiset (the order differs).
  void live_triangles(std::vector<Triangle>* triangles) const;

  // Nodes whose triangles the last move_to emitted (emit_node calls).
  std::size_t emitted_nodes_last_move() const { return emitted_last_move_; }
  // Whether the last move_to rebuilt the whole cut rather than apply changes.
  bool rebuilt_last_move() const { return rebuilt_last_move_; }

 private:
  // Block ids: nodes [0, tree.size()), then patch group g as tree.size() + g.
  void rebuild(std::size_t priority);
  void expand(std::int32_t node);
  void collapse(std::int32_t node);
  void prefetch(std::int32_t node) const;  // what emit or remove will read
  void mark(std::int32_t node);
  void mark_around(std::int32_t node);
  bool in_cut(std::int32_t node) const;
  void emit(std::int32_t id);
  void place(std::int32_t id, std::size_t first);  // the block is buffer_[first, end)
  void remove(std::int32_t id);
  void append_group(std::size_t group);
  void compact();

  const McOctree* tree_;
  const LodArray* lod_;
  std::size_t priority_ = 0;
  std::size_t cut_nodes_ = 0;

  // Per node: bit 0 expanded (what emit_node reads), bit 1 waiting to re-emit.
  std::vector<std::uint8_t> flags_;
  std::vector<std::int32_t> dirty_;  // nodes with bit 1, this move

  // Per block id: where its triangles sit in buffer_ and how many (0: none).
  std::vector<std::size_t> block_first_;
  std::vector<std::int32_t> block_count_;
  std::vector<Triangle> buffer_;
  // Per buffer slot: the block id at a block's first slot, kInside in the rest
  // of a block, kHole in a hole (lod_cursor.cpp).
  std::vector<std::int32_t> slot_owner_;
  std::vector<Triangle> emitted_;  // one node's new triangles, before they go in
  std::vector<CutBlock> cut_;      // rebuild's nodes and counts
  std::size_t holes_ = 0;

  // Patch groups: needs not yet expanded (a group shows at 0), and per node
  // the groups that need it ([first[n], first[n + 1]) of need_groups_).
  std::vector<std::int32_t> needs_left_;
  std::vector<std::int32_t> need_groups_first_;
  std::vector<std::int32_t> need_groups_;

  std::size_t emitted_last_move_ = 0;
  bool rebuilt_last_move_ = false;
};

}  // namespace scan2lod
