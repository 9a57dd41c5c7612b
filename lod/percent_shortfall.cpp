#include <scan2lod/lod/percent_shortfall.h>

#include <scan2lod/lod/level_budget.h>

#include <cmath>
#include <cstdio>

namespace scan2lod {
namespace {

std::string number(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

}  // namespace

std::string percent_shortfall(const LodModel& model, LodStructure structure, const std::string& asker, double percent,
                              const LevelCut& cut) {
  if (!(percent > 0)) return "";
  const std::string asked = asker + " " + number("%g", percent) + " asks for " + number("%g", percent) + " % ";
  const std::string got = number("%.1f", cut.percent) + " %";
  if (structure == LodStructure::kClusters) {
    const std::int64_t full = model.clusters->full_triangles;
    const auto want = std::int64_t(std::floor(percent / 100.0 * double(full)));
    const auto have = std::int64_t(cut.triangles.size());
    if (want <= 0 || meets_budget(have, want)) return "";
    std::string text = asked + "of the cluster hierarchy's " + std::to_string(full) + " triangles (" +
                       std::to_string(want) + "); no cut is within 10 % of it: got " + std::to_string(have) +
                       " triangles (" + got + ")";
    const std::int64_t over = LevelExtractor(model, structure).offered_around(want).second;
    if (over >= 0 && over != have)
      text += ", the next cut has " + std::to_string(over) + " (" +
              number("%.1f", 100.0 * double(over) / double(full)) + " %)" +
              (meets_budget(over, want) ? ", which --triangles " + std::to_string(want) + " takes" : "");
    return text;
  }
  // What a percent means is each structure's own; one not named here is not
  // checked.
  if (structure != LodStructure::kOctree) return "";
  const std::int64_t expansions = std::int64_t(model.octree->lod.full());
  const auto want = std::int64_t(std::llround(percent / 100.0 * double(expansions)));
  if (want <= 0 || meets_budget(std::int64_t(cut.priority), want)) return "";
  return asked + "of the octree's LOD array (priority " + std::to_string(want) + " of " + std::to_string(expansions) +
         "); no offered level is within 10 % of it: got priority " + std::to_string(cut.priority) + " (" + got +
         ", " + std::to_string(cut.triangles.size()) + " triangles)";
}

}  // namespace scan2lod
