// Run-time LOD mesh generation (Lee 2007, §6.1-6.2): the first N entries of the
// LOD array are expanded, and the cut below them is emitted by reference into
// the octree's precomputed vertices and triangles. No floating-point work.
#pragma once

#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/mc_octree.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

// The flag bit that marks a node expanded, in the flags emit_node and
// mark_cut read.
constexpr std::uint8_t kExpanded = 1;

// Triangles (indices into tree.vertices.positions) of the mesh after `priority`
// expansions (0: the root's, lod.full(): the full marching-cubes mesh).
// `expanded` is scratch space of tree.size() flags, left all-zero on return.
void extract_lod(const McOctree& tree, const LodArray& lod, std::size_t priority,
                 std::vector<std::uint8_t>* expanded, std::vector<Triangle>* triangles);

// The full mesh's triangles: every leaf's own, then the hole patches (the
// level at full detail, as a multiset).
std::vector<Triangle> full_triangles(const McOctree& tree);

// Marks the level after `priority` expansions in `flags` (tree.size(), all
// zero on entry): 1 for the expanded nodes, 2 for the nodes of the cut below
// them (the root alone at priority 0).
void mark_cut(const McOctree& tree, const LodArray& lod, std::size_t priority, std::uint8_t* flags);

// A node of the cut and how many triangles it emitted.
struct CutBlock {
  std::int32_t node;
  std::int32_t count;
};

// Appends the triangles of the nodes flagged 2 in `flags` (mark_cut's cut),
// in node order, as extract_lod does on one thread, and to `blocks` each of
// those nodes with its count (LodCursor's blocks).
void emit_cut(const McOctree& tree, const std::vector<std::uint8_t>& flags, std::vector<Triangle>* triangles,
              std::vector<CutBlock>* blocks);

// Appends the triangles of one node of the cut, given which nodes are expanded
// (bit 0 of their flag):
// its own, or, beside expanded cells, its transition triangulation.
void emit_node(const McOctree& tree, std::int32_t node, const std::vector<std::uint8_t>& expanded,
               std::vector<Triangle>* triangles);

// How many triangles emit_node appends for each of nodes[0, size), into
// counts: the nodes' data are asked for all at once, so that their cache
// misses overlap.
void node_triangle_counts(const McOctree& tree, const std::int32_t* nodes, int size,
                          const std::vector<std::uint8_t>& expanded, std::int32_t* counts);

// Starts loading what emit_node reads of `node`, its flags aside: for a
// caller that knows a few nodes ahead which ones it will emit.
void prefetch_node(const McOctree& tree, std::int32_t node);

// A self-contained mesh of those triangles: only the vertices they use, with
// normals and colours.
TriangleMesh compact_lod(const McOctree& tree, const std::vector<Triangle>& triangles);

}  // namespace scan2lod
