// The octree's arrays as format 4 of the `.mco` stores them (lod/model_file.h):
// only what cannot be derived cheaply, packed.
//
//   - the tree as one child mask per node (bit o: the child in octant
//     o = x + 2y + 4z exists), in breadth-first order with children by octant:
//     keys, levels, parents and children follow;
//   - edge vertices as a 12-bit mask per node and the vertices on the edges it
//     names, node by node (a node has 3-4 crossed edges of 12 on average);
//   - own triangles as a mask over the node's case's triangles (a leaf keeps
//     those the reconstruction's clean-up kept, a coarse node all), laid out
//     from the leaves' level up as the build lays them;
//   - sub-edge vertices as a 48-bit mask per internal node and the vertices it
//     names;
//   - neighbours not at all: they are found again from the tree.
//
// On the bunny at R = 256 that is 10 of the 51 MB format 3 spent on the octree.
#pragma once

#include <scan2lod/lod/octree/mc_octree.h>

#include <cstdint>
#include <string>
#include <vector>

namespace scan2lod {

struct PackedOctree {
  std::vector<std::uint8_t> child_masks;      // per node
  std::vector<std::uint16_t> edge_masks;      // per node
  std::vector<std::int32_t> edge_vertices;    // one per mask bit, node by node
  std::vector<std::uint8_t> triangle_masks;   // per node, over its case's triangles
  std::vector<std::uint64_t> sub_edge_masks;  // per internal node
  std::vector<std::int32_t> sub_edge_vertices;
  // Per triangle of the internal nodes, node by node: edges e0 | e1 << 4 | e2 << 8.
  // Empty in older files: their triangles are the case table's.
  std::vector<std::uint16_t> own_cuts;
};

// Resizes a vector the decoder is about to fill to `count` elements, without
// growing it in steps.
template <class Vector>
void resize_for_load(Vector* v, std::size_t count) {
  v->clear();
  v->reserve(count);
  v->resize(count);
}

// Packs tree's nodes, edge vertices, triangles and sub-edge vertices. Throws
// std::logic_error when the tree is not laid out as build_mc_octree lays it
// (breadth-first, children by octant, a leaf's triangles from its case, an
// internal node's as many as its case has, between its edge vertices), which
// every built or loaded tree is.
PackedOctree pack_octree(const McOctree& tree);

// Rebuilds tree->nodes (all but cases and metrics, which must be set),
// tree->triangles, and tree->transitions' sub-edge vertices and neighbours,
// from `packed` (the internal nodes' triangles from `own_cuts` where it is not
// empty, else from their cases). Throws InputError naming `source` when the packed arrays do
// not agree with each other (counts, masks past their case or past the
// depth); what they name is checked afterwards by the decoder as in format 3.
void unpack_octree(const PackedOctree& packed, const std::string& source, McOctree* tree);

}  // namespace scan2lod
