#include <scan2lod/visualize/levels.h>

#include <scan2lod/core/error.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace scan2lod {

LevelSource::LevelSource(const LodModel& model, LodStructure structure)
    : model_(&model), extractor_(model, structure) {}

Level LevelSource::at(const LevelRequest& request) {
  const auto start = std::chrono::steady_clock::now();
  last_from_cursor_ = false;
  const LevelCut& cut = extractor_.extract(request);
  Level level;
  level.structure = cut.structure;
  level.priority = cut.priority;
  level.error = cut.error;
  level.clusters = cut.clusters;
  level.percent = cut.percent;
  level.mesh = compact_level(*model_, cut.triangles);
  level.extract_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return level;
}

Level LevelSource::at_percent(double percent) {
  LevelRequest r = LevelRequest::at_percent(std::clamp(percent, 0.0, 100.0));
  r.refine = false;
  return at(r);
}

Level LevelSource::at_triangles(std::int64_t triangles) {
  LevelRequest r = LevelRequest::at_triangles(triangles);
  r.refine = false;
  return at(r);
}

const LevelCut& LevelSource::cut(const LevelRequest& request) {
  using Kind = LevelRequest::Kind;
  const bool slider = request.kind == Kind::kPercent || request.kind == Kind::kTriangles ||
                      request.kind == Kind::kPriority;
  if (structure() != LodStructure::kOctree || !slider) {
    last_from_cursor_ = false;
    return extractor_.extract(request);
  }
  // The octree's slider: the same priority the extractor would choose, reached
  // by the cursor's incremental moves.
  const auto start = std::chrono::steady_clock::now();
  const OctreeLod& o = *model_->octree;
  const std::size_t p = extractor_.octree_priority(request);
  const auto selected = std::chrono::steady_clock::now();
  if (!cursor_) cursor_.emplace(o.tree, o.lod);
  cursor_->move_to(p);
  cursor_->live_triangles(&cursor_cut_.triangles);  // without the holes, which the counts shown would include
  cursor_cut_.structure = LodStructure::kOctree;
  cursor_cut_.priority = p;
  cursor_cut_.percent = o.lod.full() ? 100.0 * double(p) / double(o.lod.full()) : 100.0;
  cursor_cut_.select_seconds = std::chrono::duration<double>(selected - start).count();
  cursor_cut_.extract_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  last_from_cursor_ = true;
  return cursor_cut_;
}

std::vector<std::uint8_t> LevelSource::triangle_levels() const {
  if (last_from_cursor_) return std::vector<std::uint8_t>(cursor_cut_.triangles.size(), 0);
  return extractor_.triangle_levels();
}

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
