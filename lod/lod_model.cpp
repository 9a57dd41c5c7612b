#include <scan2lod/lod/lod_model.h>

#include <scan2lod/core/compact_mesh.h>
#include <scan2lod/core/error.h>
#include <scan2lod/lod/clusters/paged_model.h>
#include <scan2lod/lod/structure.h>

#include <algorithm>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <stdexcept>

namespace scan2lod {

std::vector<const StructureKind*> structures_in_file_order() {
  std::vector<const StructureKind*> kinds = registered_structures();
  std::stable_sort(kinds.begin(), kinds.end(),
                   [](const StructureKind* a, const StructureKind* b) { return a->first_major < b->first_major; });
  return kinds;
}

const StructureKind& structure_kind(LodStructure id) {
  for (const StructureKind* kind : registered_structures())
    if (kind->id == id) return *kind;
  throw std::logic_error("LOD structure " + std::to_string(int(id)) + " is not registered");
}

const char* structure_name(LodStructure s) { return structure_kind(s).name; }

std::vector<std::string> structure_names() {
  std::vector<std::string> names;
  for (const StructureKind* kind : registered_structures()) names.push_back(kind->name);
  return names;
}

bool LodModel::has(LodStructure s) const { return structure_kind(s).present(*this); }

LodStructure default_structure(const LodModel& model) {
  for (const StructureKind* kind : registered_structures())
    if (kind->present(model)) return kind->id;
  return registered_structures().back()->id;
}

namespace {

// "a, b or c": `items` as a sentence lists them.
std::string spoken_list(const std::vector<const char*>& items, const char* conjunction) {
  std::string text;
  for (std::size_t i = 0; i < items.size(); ++i)
    text += std::string(i == 0 ? "" : i + 1 == items.size() ? conjunction : ", ") + items[i];
  return text;
}

// What the model holds, as a message says it: "both", "only the octree".
std::string held_structures(const LodModel& model) {
  std::vector<const char*> held;
  for (const StructureKind* kind : registered_structures())
    if (kind->present(model)) held.push_back(kind->phrase);
  if (held.empty()) return "none";
  if (held.size() == 1) return std::string("only ") + held[0];
  if (held.size() == registered_structures().size()) return held.size() == 2 ? "both" : "all of them";
  return spoken_list(held, " and ");
}

}  // namespace

LodStructure structure_named(const LodModel& model, const std::string& name, const std::string& source) {
  LodStructure s = default_structure(model);
  if (!name.empty()) {
    std::vector<const char*> names;
    const StructureKind* named = nullptr;
    for (const StructureKind* kind : registered_structures()) {
      names.push_back(kind->name);
      if (name == kind->name) named = kind;
    }
    if (!named) throw InputError("", "--structure must be " + spoken_list(names, " or ") + ", got '" + name + "'");
    s = named->id;
  }
  require_structure(model, s, source);
  return s;
}

void require_structure(const LodModel& model, LodStructure s, const std::string& source) {
  if (!model.has(s))
    throw InputError(source, std::string("the model has no ") + structure_name(s) + " structure (it holds " +
                                 held_structures(model) + "); rebuild it with scan2lod build --structure " +
                                 structure_name(s) + " or both");
}

void StructureInfo::say(const char* format, ...) {
  va_list args, copy;
  va_start(args, format);
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  if (n > 0) {
    const std::size_t at = text.size();
    text.resize(at + std::size_t(n) + 1);
    std::vsnprintf(text.data() + at, std::size_t(n) + 1, format, args);
    text.resize(at + std::size_t(n));
  }
  va_end(args);
}

static LevelRequest request_of(LevelRequest::Kind kind) {
  LevelRequest r;
  r.kind = kind;
  return r;
}
LevelRequest LevelRequest::at_percent(double p) {
  LevelRequest r = request_of(Kind::kPercent);
  r.percent = p;
  return r;
}
LevelRequest LevelRequest::at_triangles(std::int64_t t) {
  LevelRequest r = request_of(Kind::kTriangles);
  r.triangles = t;
  return r;
}
LevelRequest LevelRequest::at_most_triangles(std::int64_t t) {
  LevelRequest r = at_triangles(t);
  r.strict = true;
  return r;
}
LevelRequest LevelRequest::at_error(double e) {
  LevelRequest r = request_of(Kind::kError);
  r.error = e;
  return r;
}
LevelRequest LevelRequest::for_camera(const CameraView& c, double pixel_error) {
  LevelRequest r = request_of(Kind::kCamera);
  r.camera = c;
  r.pixel_error = pixel_error;
  return r;
}
LevelRequest LevelRequest::at_priority(std::size_t p) {
  LevelRequest r = request_of(Kind::kPriority);
  r.priority = p;
  return r;
}

LevelExtractor::LevelExtractor(const LodModel& model, LodStructure structure) : model_(&model), structure_(structure) {
  require_structure(model, structure, "");
  levels_ = structure_kind(structure).make_levels(model);
}

LevelExtractor::LevelExtractor(LevelExtractor&&) noexcept = default;
LevelExtractor& LevelExtractor::operator=(LevelExtractor&&) noexcept = default;
LevelExtractor::~LevelExtractor() = default;

std::int64_t LevelExtractor::full_triangles() const { return levels_->full_triangles(); }

std::int64_t LevelExtractor::coarsest_triangles() const { return levels_->coarsest_triangles(); }

std::pair<std::int64_t, std::int64_t> LevelExtractor::offered_around(std::int64_t triangles) const {
  std::int64_t under = -1, over = -1;
  for (const std::int64_t count : levels_->offered_triangles()) {
    if (count <= triangles) under = std::max(under, count);
    else if (over < 0 || count < over) over = count;
  }
  return {under, over};
}

int LevelExtractor::levels() const { return levels_->levels(); }

std::vector<std::uint8_t> LevelExtractor::triangle_levels() const { return levels_->triangle_levels(cut_); }

const LevelCut& LevelExtractor::extract(const LevelRequest& request) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  cut_.structure = structure_;
  cut_.triangles.clear();
  cut_.clusters = 0;
  cut_.priority = 0;
  cut_.error = 0;
  levels_->select(request, &cut_);
  cut_.select_seconds = std::chrono::duration<double>(clock::now() - start).count();
  levels_->emit(&cut_);
  cut_.extract_seconds = std::chrono::duration<double>(clock::now() - start).count();
  return cut_;
}

TriangleMesh compact_level(const LodModel& model, const std::vector<Triangle>& triangles) {
  if (model.clusters && model.clusters->paged) return model.clusters->paged->compact(triangles);
  std::vector<Triangle> out = triangles;
  const VertexArray& v = model.vertices;
  TriangleMesh mesh = compact_mesh(v.positions, v.normals, v.colors, {&out});
  mesh.triangles = std::move(out);
  return mesh;
}

Aabb model_bounds(const LodModel& model) {
  if (model.clusters && model.clusters->paged) return model.clusters->paged->bounds();
  return bounds(model.vertices.positions);
}

std::vector<LevelSummary> summarize_levels(const LodModel& model, LodStructure structure,
                                           const std::vector<double>& percents) {
  LevelExtractor extractor(model, structure);
  std::vector<LevelSummary> out;
  std::vector<std::uint8_t> used(model.vertices.size(), 0);
  for (double percent : percents) {
    LevelRequest request = LevelRequest::at_percent(percent);
    request.refine = false;  // what the structure stores, at no cost
    const LevelCut& cut = extractor.extract(request);
    LevelSummary s;
    s.percent = percent;
    s.priority = cut.priority;
    s.error = cut.error;
    s.clusters = cut.clusters;
    s.triangles = cut.triangles.size();
    for (const Triangle& t : cut.triangles)
      for (std::int32_t v : t)
        if (!used[std::size_t(v)]) used[std::size_t(v)] = 1, ++s.vertices;
    for (const Triangle& t : cut.triangles)
      for (std::int32_t v : t) used[std::size_t(v)] = 0;
    out.push_back(s);
  }
  return out;
}

}  // namespace scan2lod
