#include <scan2lod/core/types.h>

#include <gtest/gtest.h>

TEST(Types, BoundsOfTwoPoints) {
  std::vector<scan2lod::Vec3f> p = {{0, 0, 0}, {1, 2, 2}};
  EXPECT_FLOAT_EQ(scan2lod::bounds(p).diagonal(), 3.0f);
}
