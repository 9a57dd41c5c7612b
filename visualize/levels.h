// One level of detail of a loaded model, taken through the LOD face
// (lod/lod_model.h: LevelExtractor + compact_level, what `scan2lod extract`
// writes), with the numbers every view shows beside it. The viewer, the montage
// and the plots share this, so they show exactly what the command line writes,
// for either structure of the model (the octree or the cluster hierarchy).
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/octree/lod_cursor.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace scan2lod {

struct Level {
  LodStructure structure = LodStructure::kOctree;
  std::size_t priority = 0;   // octree: expansions applied
  double error = 0;           // clusters: the uniform error threshold
  std::size_t clusters = 0;   // clusters: drawn
  double percent = 100;       // octree: of the LOD array; clusters: of the full-detail triangles
  TriangleMesh mesh;          // compact: only the vertices its triangles use
  double extract_seconds = 0; // extraction + compact_level
};

// Takes levels out of one structure of one model, keeping the extractor's
// scratch space and tables between calls (the slider and a moving camera
// re-extract on every change).
class LevelSource {
 public:
  // Throws InputError if the model lacks `structure`.
  LevelSource(const LodModel& model, LodStructure structure);
  // The model's default structure (default_structure).
  explicit LevelSource(const LodModel& model) : LevelSource(model, default_structure(model)) {}

  // A compact level (LevelExtractor::extract, then compact_level).
  Level at(const LevelRequest& request);
  // The stored level (for the clusters, not refined to the count: what the
  // viewer's slider shows).
  Level at_percent(double percent);  // percent clamped to [0, 100]
  Level at_triangles(std::int64_t triangles);

  // Only the level's triangles: indices into the model's shared vertices
  // (valid until the next call). The viewer draws them against the whole
  // vertex array, uploaded once, so a change sends only indices. For the
  // octree, percent, triangle and priority requests move a LodCursor from the
  // last call's level (a slider move costs in proportion to the expansions it
  // crosses; the triangles are extract_lod's in another order, without holes);
  // everything else goes through the LevelExtractor.
  const LevelCut& cut(const LevelRequest& request);
  // Per triangle of the last cut(), its cluster's DAG level (clusters; 0 =
  // full detail), or zeros for the octree.
  std::vector<std::uint8_t> triangle_levels() const;
  // Levels a view may colour: the octree's depth + 1 or the DAG's rounds.
  int levels() const { return extractor_.levels(); }

  const LodModel& model() const { return *model_; }
  LodStructure structure() const { return extractor_.structure(); }
  // Triangles at full detail and at the coarsest level: the slider's range.
  std::int64_t max_triangles() const { return extractor_.full_triangles(); }
  std::int64_t min_triangles() const { return extractor_.coarsest_triangles(); }

 private:
  const LodModel* model_;
  LevelExtractor extractor_;
  std::optional<LodCursor> cursor_;  // octree: cut()'s level, made on first use
  LevelCut cursor_cut_;
  bool last_from_cursor_ = false;
};

// Parses "100,80,60" into percentages. Throws InputError (naming `flag`) for
// an empty list, a non-number, or a value outside [0, 100].
std::vector<double> parse_percent_list(const std::string& text, const std::string& flag);


}  // namespace scan2lod
