#include <scan2lod/lod/level_chain.h>

#include <scan2lod/core/compact_mesh.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/mesh_edges.h>
#include <scan2lod/lod/level_budget.h>
#include <scan2lod/lod/structure.h>

#include <algorithm>
#include <cmath>

namespace scan2lod {
namespace {

std::string describe(const LevelRequest& r) {
  switch (r.kind) {
    case LevelRequest::Kind::kPercent: return "the level at " + std::to_string(r.percent) + " %";
    case LevelRequest::Kind::kTriangles: return "the level at " + std::to_string(r.triangles) + " triangles";
    case LevelRequest::Kind::kError: return "the level at error " + std::to_string(r.error);
    case LevelRequest::Kind::kCamera: return "the camera's level";
    case LevelRequest::Kind::kPriority: return "the level at priority " + std::to_string(r.priority);
  }
  return "a level";
}

}  // namespace

const LevelCut& extract_level_to_deliver(LevelExtractor* extractor, const LevelRequest& request,
                                         const std::string& source) {
  const LevelCut* cut;
  try {
    cut = &extractor->extract(request);
  } catch (const InputError& e) {
    throw InputError(source, e.what());
  }
  const bool over = request.kind == LevelRequest::Kind::kTriangles &&
                    std::int64_t(cut->triangles.size()) > budget_ceiling(request.triangles, request.strict);
  if (cut->triangles.empty() || over)
    throw InputError(source, over ? "no level has at most " + std::to_string(request.triangles) + " triangles" +
                                        (request.strict ? "" : ", nor up to 10 % more") +
                                        "; the coarsest level offered has " +
                                        std::to_string(extractor->coarsest_triangles())
                                  : describe(request) + " has no triangles; ask for a finer one");
  return *cut;
}

std::string budget_shortfall(const LevelExtractor& extractor, const LevelRequest& request, const LevelCut& cut) {
  if (request.kind != LevelRequest::Kind::kTriangles || request.triangles <= 0) return "";
  if (meets_budget(std::int64_t(cut.triangles.size()), request.triangles)) return "";
  const auto [under, over] = extractor.offered_around(request.triangles);
  const bool octree = extractor.structure() == LodStructure::kOctree;
  std::string text = std::string("no ") + structure_kind(extractor.structure()).level_noun +
                     " level is within 10 % of " +
                     std::to_string(request.triangles) + " triangles: ";
  if (under >= 0 && over >= 0)
    text += "the offered levels step from " + std::to_string(under) + " to " + std::to_string(over) + " there";
  else if (under >= 0)
    text += "the finest offered level has " + std::to_string(under);
  else
    text += "the coarsest offered level has " + std::to_string(over);
  text += "; took the one with " + std::to_string(cut.triangles.size());
  // Point to the other structure only where it does meet the budget.
  if (octree && extractor.model().has(LodStructure::kClusters)) {
    const auto [cut_under, cut_over] =
        LevelExtractor(extractor.model(), LodStructure::kClusters).offered_around(request.triangles);
    for (const std::int64_t count : {cut_under, cut_over})
      if (count >= 0 && meets_budget(count, request.triangles)) {
        text += " (the cluster hierarchy has a cut of " + std::to_string(count) + ": --structure clusters)";
        break;
      }
  }
  return text;
}

LevelChain extract_chain(const LodModel& model, LodStructure structure, const std::vector<LevelRequest>& requests,
                         const std::string& source, const ChainOptions& options) {
  LevelExtractor extractor(model, structure);
  LevelChain chain;
  chain.structure = structure;
  for (const LevelRequest& request : requests) {
    ChainLevel level;
    level.cut = extract_level_to_deliver(&extractor, request, source);
    level.shortfall = budget_shortfall(extractor, request, level.cut);
    level.error = structure == LodStructure::kClusters ? level.cut.error
                                                        : 0.25 * mean_edge_length(model.vertices.positions,
                                                                                  level.cut.triangles);
    chain.levels.push_back(std::move(level));
  }
  std::stable_sort(chain.levels.begin(), chain.levels.end(), [](const ChainLevel& a, const ChainLevel& b) {
    return a.cut.triangles.size() > b.cut.triangles.size();
  });
  // Errors must not shrink down the chain for the coverages to make sense.
  for (std::size_t i = 1; i < chain.levels.size(); ++i)
    chain.levels[i].error = std::max(chain.levels[i].error, chain.levels[i - 1].error);

  const double diagonal = model_bounds(model).diagonal();
  const std::size_t n = chain.levels.size();
  for (std::size_t i = 0; i < n; ++i) {
    ChainLevel& level = chain.levels[i];
    level.name = "LOD" + std::to_string(i);
    if (i + 1 == n) break;  // the coarsest is drawn however small
    // Level i gives way to level i + 1 where i + 1 becomes good enough.
    const double next = chain.levels[i + 1].error;
    const double across = next > 0 ? options.pixel_error * diagonal / next / options.screen_height : 1e9;
    level.screen_coverage = std::min(1.0, across * across);
  }
  std::vector<std::vector<Triangle>*> lists;
  for (ChainLevel& level : chain.levels) lists.push_back(&level.cut.triangles);
  const VertexArray& v = model.vertices;
  chain.vertices = compact_mesh(v.positions, v.normals, v.colors, lists);
  return chain;
}

TriangleMesh level_mesh(const LevelChain& chain, std::size_t i) {
  std::vector<Triangle> triangles = chain.levels.at(i).cut.triangles;
  const TriangleMesh& v = chain.vertices;
  TriangleMesh mesh = compact_mesh(v.positions, v.normals, v.colors, {&triangles});
  mesh.triangles = std::move(triangles);
  return mesh;
}

}  // namespace scan2lod
