// From the cluster DAG to a tree of tiles (3D Tiles 1.1, REPLACE refinement).
//
// The cluster hierarchy (lod/clusters/cluster_hierarchy.h) is a DAG: a group's clusters
// come from several clusters below, which other groups share. 3D Tiles wants a
// tree. The tree here is spatial: an octree over the model's bounds, each cell
// holding one cut of the DAG restricted to the cell, finer going down, as
// Cesium's tilers and Nexus's patches hold one level of detail per cell:
//
// - the root holds the coarsest cut (every group applied), the whole model;
// - a cell below holds the finest uniform cut whose triangles that touch the
//   cell (their bounding box meets the cell's) number at most
//   TileOptions::max_triangles, strictly finer than its parent's cut; a cell
//   whose parent's next finer cut does not fit holds nothing and passes its
//   parent's cut on to its own octants;
// - a cell at full detail (no group applied) is a leaf, so the leaves hold
//   every full-detail triangle.
//
// A triangle that crosses a cell's face is in both cells, so neighbouring
// tiles overlap by a triangle's width instead of leaving a hole where their
// cuts, of different thresholds, end differently: what is left between them
// is the distance between two cuts' surfaces, each within its measured error
// of the full-detail surface (delivery/tile_gaps.h measures it).
//
// A tile's geometric error is measured, not halved by rule: the largest error
// of the groups that made its clusters (0 at full detail), raised to its
// children's where a child's is larger, so that errors never grow going down.
//
// The model may be in memory (load_model) or read page by page
// (open_paged_model): the tiles are the same. Each tile's content is handed
// out as soon as it is decided and not kept, so that planning holds the
// cluster records, the page cache and about one tile, whatever the model's
// size.
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/octree/mc_octree.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace scan2lod {

struct TileOptions {
  // Most triangles a tile holds; the root holds the coarsest cut whatever it
  // holds (at most kCoarsestTriangles, 256, on any mesh of fewer pieces).
  std::int64_t max_triangles = 16384;
  int max_depth = 20;  // cells below this depth hold their cut even when over budget
  // Called with the share of the model's cluster triangles placed so far; may be empty.
  std::function<void(double)> progress;
};

// A threshold of the uniform cut (lod/clusters/cluster_cut.h): a group is applied when
// its error is at most the threshold. kFullDetail applies none.
constexpr float kFullDetail = -1.f;

struct Tile {
  int parent = -1;                   // index in TileTree::tiles, -1 for the root
  std::vector<int> children;
  int depth = 0;
  std::string name;                  // the octant path: "r", "r5", "r57", ...
  Aabb cell;                         // the octree cell
  float threshold = kFullDetail;     // the cut it holds
  std::int64_t triangle_count = 0;   // its content's triangles; 0: no content
  float content_error = 0;           // the largest own-group error of their clusters (0: full detail)
  float geometric_error = 0;         // max of content_error over its subtree
  Aabb content_box;                  // around its triangles' vertices
  Aabb subtree_box;                  // around its and its descendants' content
  bool has_content() const { return triangle_count > 0; }
  bool leaf() const { return children.empty(); }
};

struct TileTree {
  std::vector<Tile> tiles;   // tiles[0] is the root; a parent comes before its children
  Aabb bounds;               // the cluster hierarchy's vertices
  float coarsest_error = 0;  // the coarsest cut's threshold (the largest group error)
  std::int64_t full_triangles = 0;
};

// A tile's content: its triangles over vertices of its own, numbered in the
// order the triangles first use them, one vertex for each of the model's
// (however many clusters or pages name it).
struct TileContent {
  VertexArray vertices;                       // normals and colours when the model has them
  std::vector<Triangle> triangles;            // into `vertices`, cluster by cluster
  std::vector<std::uint32_t> model_vertices;  // each vertex's number in the model
};

// Called once for each tile with content, as soon as that content is
// decided: tree.tiles[index] is the tile, its name, cell, counts and
// content_box final (its children, geometric_error and subtree_box not yet),
// and so is tree.bounds. `content` is reused once the call returns.
using TileContentSink = std::function<void(const TileTree& tree, std::size_t index, const TileContent& content)>;

// Plans the tiles of `model`'s cluster hierarchy, in memory or read page by
// page, handing each tile's content to `content` (may be empty). Throws
// InputError (naming `source`) when the model has no cluster hierarchy, and
// what reading a page throws.
TileTree plan_tiles(const LodModel& model, const TileOptions& options = {}, const std::string& source = "",
                    const TileContentSink& content = {});

}  // namespace scan2lod
