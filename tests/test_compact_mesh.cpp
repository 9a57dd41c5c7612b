// Compacting an index buffer over a shared vertex array: once (compact_mesh)
// or many times over one table (renumber_used).
#include <scan2lod/core/compact_mesh.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

using namespace scan2lod;

TEST(CompactMesh, RenumberUsedNumbersAsCompactMeshDoesAndTouchesOnlyWhatIsUsed) {
  std::vector<Vec3f> positions;
  for (int i = 0; i < 10; ++i) positions.push_back(Vec3f(float(i), 0.f, 0.f));
  const std::vector<Triangle> first = {{7, 2, 5}, {5, 2, 9}}, second = {{9, 1, 7}};

  std::vector<Triangle> a = first, b = second;
  const TriangleMesh once = compact_mesh(positions, {}, {}, {&a, &b});

  std::vector<std::int32_t> remap(positions.size(), -1), used;
  std::vector<Triangle> c = first, d = second;
  renumber_used(&c, &remap, &used);
  EXPECT_EQ(used, (std::vector<std::int32_t>{7, 2, 5, 9}));
  renumber_used(&d, &remap, &used);  // numbering goes on across lists
  EXPECT_EQ(c, a);
  EXPECT_EQ(d, b);
  EXPECT_EQ(used, (std::vector<std::int32_t>{7, 2, 5, 9, 1}));
  ASSERT_EQ(once.positions.size(), used.size());
  for (std::size_t r = 0; r < used.size(); ++r) EXPECT_EQ(once.positions[r], positions[std::size_t(used[r])]);
  // Only the used entries were written: resetting them restores the table.
  for (std::size_t v = 0; v < remap.size(); ++v) {
    const bool is_used = std::find(used.begin(), used.end(), std::int32_t(v)) != used.end();
    EXPECT_EQ(remap[v] >= 0, is_used) << v;
  }
}
