// One level of detail of a loaded model, taken the way `scan2lod extract` takes
// it (extract_lod + compact_lod, seed 003 §6.1-6.2), with the numbers every
// view shows beside it. The viewer, the montage and the plots share this, so
// they show exactly what the command line writes.
#pragma once

#include "core/types.h"
#include "lod/lod_cursor.h"
#include "lod/model_file.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace scan2lod {

struct Level {
  std::size_t priority = 0;   // expansions applied
  double percent = 100;       // priority as a share of the LOD array
  TriangleMesh mesh;          // compact: only the vertices its triangles use
  double extract_seconds = 0; // extract_lod + compact_lod
};

// Takes levels out of one model, keeping the scratch space between calls (the
// slider re-extracts on every move).
class LevelSource {
 public:
  explicit LevelSource(const LodModel& model) : model_(&model) {}
  // The level after `priority` expansions; priority must be <= lod.full().
  Level at_priority(std::size_t priority);
  // Only the triangles of that level, extract_lod's in another order: indices
  // into the model's tree.positions (valid until the next call). They come
  // from a LodCursor moved from the last call's level, so a slider move costs
  // in proportion to the expansions it crosses; `seconds` gets that move and
  // the copy of its live triangles. The viewer draws these against the model's
  // whole vertex array, uploaded once, so a slider move sends only indices.
  const std::vector<Triangle>& triangles_at(std::size_t priority, double* seconds);
  // priority_for_percent (percent clamped to [0, 100]), then at_priority.
  Level at_percent(double percent);
  // priority_for_triangles, then at_priority.
  Level at_triangles(std::int64_t triangles);
  const LodModel& model() const { return *model_; }
  // Triangles at full detail: the largest count the slider can ask for.
  std::int64_t max_triangles() const;

 private:
  const LodModel* model_;
  std::vector<std::uint8_t> scratch_;
  std::vector<Triangle> triangles_;
  std::optional<LodCursor> cursor_;  // triangles_at's level, made on first use
};

// The box around every vertex any level can use (all of tree.positions): a
// camera framed on it keeps every level in view.
Aabb model_bounds(const LodModel& model);

// Parses "100,80,60" into percentages. Throws InputError (naming `flag`) for
// an empty list, a non-number, or a value outside [0, 100].
std::vector<double> parse_percent_list(const std::string& text, const std::string& flag);

}  // namespace scan2lod
