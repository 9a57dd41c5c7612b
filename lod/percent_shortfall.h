// What a caller is told about a level that misses the percent asked of it:
// the command line prints it as a warning, the Python package raises it as a
// UserWarning.
#pragma once

#include <scan2lod/lod/lod_model.h>

#include <string>

namespace scan2lod {

// Where `cut` answered a percentage P (`asker` P: "--percent", "--levels")
// with a level more than 10 % away from P % (lod/level_budget.h, the tolerance
// a --triangles budget is met within; budget_shortfall says that case): a
// sentence naming the percent asked and the one got; empty otherwise. For the
// clusters P % is of the full triangle count, for the octree of the LOD array.
std::string percent_shortfall(const LodModel& model, LodStructure structure, const std::string& asker, double percent,
                              const LevelCut& cut);

}  // namespace scan2lod
