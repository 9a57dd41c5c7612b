// A 3D Tiles 1.1 tileset of a model's cluster hierarchy (Cesium, *3D Tiles
// Specification 1.1*, 2023): `tileset.json` and one .glb per tile with
// content, in a folder, REPLACE refinement throughout.
//
// - The tree is delivery/tile_tree.h's: octree cells over cuts of the DAG at
//   falling measured errors, the coarsest cut at the root, full detail at
//   the leaves.
// - Each tile's boundingVolume is a box around its own and its descendants'
//   vertices (so that a parent encloses its children), and its content's
//   boundingVolume a box around its own vertices alone; both axis-aligned in
//   the model's frame, widened by one quantization step.
// - The model's origin (LodModel::origin, georeferenced inputs) is the
//   root's transform, a translation in double, so that the tileset lies in
//   the inputs' frame while the tiles' floats stay local.
// - tileset.geometricError is the model's diagonal: the error of drawing
//   nothing.
//
// The folder appears complete or not at all: the tiles are written into a
// hidden folder beside it, which is renamed into place at the end (an old
// tileset there is replaced; any other folder is refused).
//
// Each tile is written as soon as the planner decides its content, so that
// memory holds the cluster records, the page cache of a model read page by
// page (lod/clusters/paged_model.h) and about one tile: a model too large to load
// whole is tiled from its pages, into the same bytes.
#pragma once

#include <scan2lod/delivery/tile_glb.h>
#include <scan2lod/delivery/tile_tree.h>
#include <scan2lod/lod/lod_model.h>

#include <cstdint>
#include <functional>
#include <string>

namespace scan2lod {

struct TilesetOptions {
  TileOptions tiles;
  TileGlbOptions glb;
  // Called with a stage's name ("write": tiles planned and written, as the
  // share of the full-detail triangles placed) and how far it is (0 to 1);
  // may be empty.
  std::function<void(const std::string&, double)> progress;
  // Called with the folder being written (not yet in place) after the tiles
  // and tileset.json, to put more files beside them (the command line adds
  // the viewer page, viewer_page.h); may be empty. What it throws ends the
  // write as a failed one.
  std::function<void(const std::string& folder)> add_files;
};

struct TilesetReport {
  std::size_t tiles = 0, content_tiles = 0, leaves = 0;
  int depth = 0;                      // the deepest tile's depth (root: 0)
  std::uint64_t bytes = 0;            // tileset.json and the tiles
  std::uint64_t largest_tile_bytes = 0;
  std::int64_t largest_tile_triangles = 0;  // the root aside when it holds more
  std::int64_t root_triangles = 0;
  std::int64_t triangles = 0;         // over every tile
  double root_error = 0;
  double plan_seconds = 0;            // reading clusters and choosing cuts
  double write_seconds = 0;           // encoding and writing the files, interleaved with planning
};

// Writes the tileset of `model` (loaded whole, or opened with
// open_paged_model: the same files) into the folder `dir` (created; an
// existing tileset there is replaced). `source` names the model in errors.
// Throws InputError when the model has no cluster hierarchy, when `dir` is a
// folder that holds something other than a tileset, when a page cannot be
// read or a write fails; nothing is left at `dir` then.
TilesetReport write_tileset(const LodModel& model, const std::string& dir, const TilesetOptions& options = {},
                            const std::string& source = "");

// The tileset.json text for `tree`, its tiles named `tiles/NAME.glb`.
std::string tileset_json(const TileTree& tree, const Vec3d& origin, float quantization_step,
                         const std::string& generator);

// The step of the grid the tiles' positions are quantized on (0 unquantized).
float tileset_quantization_step(const TileTree& tree, const TileGlbOptions& options);

}  // namespace scan2lod
