// QueryNeighbourhood keeps every point within its radius of a query (what a
// search from the queries may use) and little beyond: random points and
// queries, distances checked one by one.
#include <scan2lod/spatial/points_near.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using scan2lod::QueryNeighbourhood;
using scan2lod::Vec3f;

TEST(PointsNear, EveryPointWithinTheRadiusIsNearAndFarOnesAreNot) {
  std::mt19937 random(7);
  std::uniform_real_distribution<float> coordinate(-1.f, 1.f);
  std::vector<Vec3f> queries(200), points(20000);
  for (Vec3f& q : queries) q = Vec3f(coordinate(random), coordinate(random), coordinate(random)) * 0.5f;
  for (Vec3f& p : points) p = Vec3f(coordinate(random), coordinate(random), coordinate(random));
  for (const double radius : {0.01, 0.05, 0.2}) {
    const QueryNeighbourhood around(queries, radius);
    std::size_t within = 0, near = 0;
    for (const Vec3f& p : points) {
      float closest = 1e9f;
      for (const Vec3f& q : queries) closest = std::min(closest, (p - q).norm());
      const bool is_near = around.near(p);
      if (closest <= radius) {
        ++within;
        EXPECT_TRUE(is_near) << radius;
      }
      // A marked cell is the query's or a neighbour: at most 2 cells' diagonal away.
      if (closest > 2 * std::sqrt(3.0) * radius + 1e-6) {
        EXPECT_FALSE(is_near) << radius;
      }
      near += is_near;
    }
    EXPECT_GT(within, 0u);
    EXPECT_LT(near, points.size());
  }
  // No queries: nothing is near.
  EXPECT_FALSE(QueryNeighbourhood({}, 1.0).near(Vec3f::Zero()));
}

}  // namespace
