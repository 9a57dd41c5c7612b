// Where the points within a radius of a few queries lie: what a k-nearest search from
// those queries can find within that radius, without reading or indexing
// the rest. Hole closing asks a brick for the signed distances of a few
// thousand corners; gathering and indexing the brick's million points was
// most of the cost (the pair's 10^7 points at R = 2048: 4.8 of the 6.0 s
// that pieces and holes took).
#pragma once

#include <scan2lod/core/flat_hash.h>
#include <scan2lod/core/types.h>

#include <vector>

namespace scan2lod {

class QueryNeighbourhood {
 public:
  QueryNeighbourhood(const std::vector<Vec3f>& queries, double radius);
  // True for every point within the radius of a query (and some a little
  // farther: cells of the radius are marked around each query).
  bool near(const Vec3f& p) const;

 private:
  bool cell_of(const Vec3d& p, std::int64_t out[3]) const;
  double cell_ = 1;
  Vec3d low_ = Vec3d::Zero(), high_ = Vec3d::Zero();
  bool empty_ = true, every_cell_ = false;  // every_cell_: too many cells to key; the box alone decides
  FlatHashMap marked_{16};
};

}  // namespace scan2lod
