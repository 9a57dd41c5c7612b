// The gaps between tiles of a tree (delivery/tile_tree.h) that a viewer may
// draw side by side: two tiles neither of which is the other's ancestor.
//
// Where a tile's content ends (an edge of one of its triangles that no other
// of its triangles shares, outside its cell: the tile's seam), the neighbour
// whose cell holds that point draws the surface; the gap is how far the
// point is from the neighbour's triangles. Each seam edge is sampled at its
// ends and middle. A gap is "over" when it exceeds the larger geometric error
// of the two tiles plus `tolerance` (a quantization step: less is not seen).
#pragma once

#include <scan2lod/delivery/tile_tree.h>

#include <cstdint>
#include <vector>

namespace scan2lod {

struct TileGapStats {
  std::int64_t points = 0;      // seam points measured
  double max_gap = 0;           // the widest gap, in the model's units
  double max_ratio = 0;         // the largest gap / max(error of the two tiles), where that error is > 0
  std::int64_t over = 0;        // points whose gap exceeds the larger error + tolerance
};

// by_depth_difference[d]: pairs whose depths differ by d (the last entry
// gathers larger differences); all: every pair.
struct TileGaps {
  std::vector<TileGapStats> by_depth_difference;
  TileGapStats all;
};

// contents[i]: tree.tiles[i]'s, as plan_tiles handed it out (empty for a
// tile without content); all held at once, so for models that fit.
TileGaps measure_tile_gaps(const TileTree& tree, const std::vector<TileContent>& contents, double tolerance,
                           int depth_differences = 3);

}  // namespace scan2lod
