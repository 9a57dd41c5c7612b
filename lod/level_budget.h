// How a triangle budget picks one of a structure's levels, the same way for
// the octree and the cluster hierarchy.
//
// A structure offers levels at discrete counts, and at the coarse end they can
// lie far apart: on the bunny at R = 256 the octree has a level of 265
// triangles, before the ears show, and the next sound one at 533, with both.
// Read as a strict cap, a budget of 500 got the earless 265, half of it. So a
// budget is met within kBudgetTolerance: the finest level with at most the
// budget, unless that falls more than 10 % short and a level no more than
// 10 % over exists, which is then taken instead. A caller that must never
// exceed the budget (a memory cap) asks for it strictly.
#pragma once

#include <cstdint>

namespace scan2lod {

constexpr double kBudgetTolerance = 0.10;

// Whether to take the coarsest level above `budget` (`over` triangles) rather
// than the finest within it (`under`); -1 where no such level exists.
inline bool take_level_over(std::int64_t under, std::int64_t over, std::int64_t budget) {
  if (over < 0) return false;
  if (under < 0) return true;
  const double b = double(budget);
  return double(under) < (1.0 - kBudgetTolerance) * b && double(over) <= (1.0 + kBudgetTolerance) * b;
}

// Whether a level of `count` triangles meets `budget`: within kBudgetTolerance
// of it, either way.
inline bool meets_budget(std::int64_t count, std::int64_t budget) {
  const double b = double(budget), c = double(count);
  return c >= (1.0 - kBudgetTolerance) * b && c <= (1.0 + kBudgetTolerance) * b;
}

// The largest count a level picked for `budget` may have (strict: the budget).
inline std::int64_t budget_ceiling(std::int64_t budget, bool strict) {
  return strict ? budget : std::int64_t(double(budget) * (1.0 + kBudgetTolerance));
}

}  // namespace scan2lod
