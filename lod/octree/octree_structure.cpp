// The prioritized marching-cube octree (Lee 2007) behind the LOD face: its
// levels by priority number, percent or triangle budget (lod/octree/extract.h),
// its record among the registered structures (lod/structure.h), what `info`
// says of it, and a model made from a built octree.
#include <scan2lod/core/error.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/octree_sections.h>
#include <scan2lod/lod/structure.h>

#include <string>

namespace scan2lod {

LodModel model_from_octree(McOctree tree, LodArray lod) {
  LodModel model;
  model.vertices = std::move(tree.vertices);
  tree.vertices = {};
  model.octree = OctreeLod{std::move(tree), std::move(lod)};
  return model;
}

namespace {

// The priority number extract() chooses for `request`.
std::size_t priority_for_request(const LodArray& lod, const LevelRequest& request) {
  using Kind = LevelRequest::Kind;
  switch (request.kind) {
    case Kind::kPercent: return priority_for_percent(lod, request.percent);
    case Kind::kTriangles:
      return request.strict ? priority_for_triangles(lod, request.triangles)
                            : priority_for_budget(lod, request.triangles);
    case Kind::kPriority:
      if (request.priority > lod.full())
        throw InputError("", "priority " + std::to_string(request.priority) + " is past the octree's " +
                                 std::to_string(lod.full()) + " expansions");
      return request.priority;
    case Kind::kError:
    case Kind::kCamera: break;
  }
  throw InputError("", "the octree offers levels by percent, triangles or priority, not by error or camera; "
                       "use --structure clusters");
}

class OctreeLevels final : public StructureLevels {
 public:
  explicit OctreeLevels(const OctreeLod& octree) : octree_(octree) {}

  void select(const LevelRequest& request, LevelCut* cut) override {
    cut->priority = priority_for_request(octree_.lod, request);
  }
  void emit(LevelCut* cut) override {
    const LodArray& lod = octree_.lod;
    extract_lod(octree_.tree, lod, cut->priority, &expanded_, &cut->triangles);
    cut->percent = lod.full() ? 100.0 * double(cut->priority) / double(lod.full()) : 100.0;
  }
  std::int64_t full_triangles() const override { return octree_.lod.accumulated.back(); }
  std::int64_t coarsest_triangles() const override {
    return octree_.lod.accumulated[priority_for_percent(octree_.lod, 0)];
  }
  std::vector<std::int64_t> offered_triangles() const override {
    std::vector<std::int64_t> counts;
    for (const std::size_t p : monotone_priorities(octree_.lod)) counts.push_back(octree_.lod.accumulated[p]);
    return counts;
  }
  int levels() const override { return octree_.tree.depth + 1; }
  // Extraction does not say which level a triangle came from.
  std::vector<std::uint8_t> triangle_levels(const LevelCut& cut) const override {
    return std::vector<std::uint8_t>(cut.triangles.size(), 0);
  }

 private:
  const OctreeLod& octree_;
  std::vector<std::uint8_t> expanded_;  // scratch
};

StructureInfo octree_info(const LodModel& model, const std::vector<double>& percents) {
  const OctreeSummary o = describe_octree(model);
  const auto lods = summarize_levels(model, LodStructure::kOctree, percents);
  StructureInfo info;
  nlohmann::ordered_json levels = nlohmann::ordered_json::array();
  for (const LevelSummary& l : lods)
    levels.push_back({{"percent", l.percent}, {"priority", l.priority}, {"triangles", l.triangles},
                      {"vertices", l.vertices}});
  info.json = {{"resolution", o.resolution},   {"depth", o.depth},   {"nodes", o.nodes},
               {"nodes_per_level", o.nodes_per_level}, {"leaves", o.leaves}, {"expansions", o.expansions},
               {"pinned", o.pinned},           {"offered_levels", o.offered_levels},
               {"coarsest_offered_triangles", o.coarsest_triangles}, {"levels_of_detail", levels}};
  // Kept at the top level too, as before the cluster hierarchy.
  info.top_level_keys = {"resolution", "depth", "nodes", "nodes_per_level", "leaves", "expansions", "pinned",
                         "levels_of_detail"};
  info.say("\noctree: resolution %d (depth %d), cube size %.6g, origin (%.6g, %.6g, %.6g)\n", o.resolution, o.depth,
           o.cube_size, o.origin.x(), o.origin.y(), o.origin.z());
  info.say("%zu nodes, %zu leaves, %zu expansions; nodes per level:", o.nodes, o.leaves, o.expansions);
  for (std::size_t c : o.nodes_per_level) info.say(" %zu", c);
  if (o.pinned)
    info.say("\nthe first %zu expansions (%lld triangles) keep the rim at full detail: no level is offered "
             "inside them",
             o.pinned, static_cast<long long>(o.pinned_triangles));
  info.say("\n%zu levels offered, from %lld triangles to %lld", o.offered_levels,
           static_cast<long long>(o.coarsest_triangles), static_cast<long long>(o.full_triangles));
  info.say("\n\n%6s %10s %10s %10s\n", "LOD %", "priority", "triangles", "vertices");
  for (const LevelSummary& l : lods)
    info.say("%6g %10zu %10zu %10zu\n", l.percent, l.priority, l.triangles, l.vertices);
  return info;
}

}  // namespace

std::size_t LevelExtractor::octree_priority(const LevelRequest& request) const {
  require_structure(*model_, LodStructure::kOctree, "");
  return priority_for_request(model_->octree->lod, request);
}

OctreeSummary describe_octree(const LodModel& model) {
  require_structure(model, LodStructure::kOctree, "");
  const McOctree& t = model.octree->tree;
  const LodArray& lod = model.octree->lod;
  OctreeSummary s;
  s.resolution = t.grid.resolution;
  s.depth = t.depth;
  s.cube_size = t.grid.cube_size;
  s.origin = t.grid.origin;
  s.nodes = t.size();
  s.nodes_per_level.assign(std::size_t(t.depth) + 1, 0);
  for (std::size_t n = 0; n < t.size(); ++n) {
    ++s.nodes_per_level[t.nodes.levels[n]];
    s.leaves += t.is_leaf(n);
  }
  s.expansions = lod.full();
  s.pinned = lod.pinned;
  s.pinned_triangles = lod.accumulated[lod.pinned];
  s.full_triangles = lod.accumulated.back();
  const std::vector<std::size_t> offered = monotone_priorities(lod);
  s.offered_levels = offered.size();
  s.coarsest_triangles = lod.accumulated[offered.front()];
  return s;
}

const StructureKind& octree_structure() {
  static const StructureKind kind{
      LodStructure::kOctree,
      "octree",
      "the octree",
      "octree",
      1,
      [](const LodModel& model) { return model.octree.has_value(); },
      [](const LodModel& model) -> std::unique_ptr<StructureLevels> {
        return std::make_unique<OctreeLevels>(*model.octree);
      },
      octree_sections,
      octree_info,
  };
  return kind;
}

}  // namespace scan2lod
