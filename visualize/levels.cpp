#include "visualize/levels.h"

#include "core/error.h"
#include "lod/extract.h"
#include "lod/lod_array.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace scan2lod {

Level LevelSource::at_priority(std::size_t priority) {
  const LodModel& m = *model_;
  assert(priority <= m.lod.full());
  Level level;
  level.priority = priority;
  level.percent = m.lod.full() ? 100.0 * double(priority) / double(m.lod.full()) : 100.0;
  const auto start = std::chrono::steady_clock::now();
  extract_lod(m.tree, m.lod, priority, &scratch_, &triangles_);
  level.mesh = compact_lod(m.tree, triangles_);
  level.extract_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return level;
}

const std::vector<Triangle>& LevelSource::triangles_at(std::size_t priority, double* seconds) {
  assert(priority <= model_->lod.full());
  const auto start = std::chrono::steady_clock::now();
  if (!cursor_) cursor_.emplace(model_->tree, model_->lod);
  cursor_->move_to(priority);
  cursor_->live_triangles(&triangles_);  // without the holes, which the counts shown would include
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return triangles_;
}

Level LevelSource::at_percent(double percent) {
  return at_priority(priority_for_percent(model_->lod, std::clamp(percent, 0.0, 100.0)));
}

Level LevelSource::at_triangles(std::int64_t triangles) {
  return at_priority(priority_for_triangles(model_->lod, triangles));
}

std::int64_t LevelSource::max_triangles() const {
  const auto& a = model_->lod.accumulated;
  return a.empty() ? 0 : *std::max_element(a.begin(), a.end());
}

Aabb model_bounds(const LodModel& model) { return bounds(model.tree.positions); }

std::vector<double> parse_percent_list(const std::string& text, const std::string& flag) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const char* begin = item.c_str();
    char* end = nullptr;
    const double v = std::strtod(begin, &end);
    while (end && *end == ' ') ++end;
    if (item.empty() || end == begin || *end != '\0' || !std::isfinite(v))
      throw InputError("", flag + " expects percentages separated by commas (e.g. 100,80,60,40,20), got '" + item + "'");
    if (v < 0 || v > 100)
      throw InputError("", flag + " values must lie between 0 and 100, got " + item);
    out.push_back(v);
  }
  if (out.empty()) throw InputError("", flag + " needs at least one percentage, got '" + text + "'");
  return out;
}

}  // namespace scan2lod
