// Claims of Lee 2007 chapters 5-6 about the prioritized marching-cube octree.
#include <scan2lod/acquisition/lattice_normals.h>
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/acquisition/virtual_scanner.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/mc_octree.h>
#include <scan2lod/lod/octree/octree_order.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include "test_shapes.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <open3d/geometry/TriangleMesh.h>

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

using namespace scan2lod;
using scan2lod::testing::from_open3d;
using scan2lod::testing::scan_shape;

namespace {

struct Model {
  OrientedPoints points;
  Reconstruction reconstruction;
  McOctree tree;
  LodArray lod;
};

Model build_model(OrientedPoints points, int resolution) {
  Model m;
  m.points = std::move(points);
  ReconstructOptions options;
  options.resolution = resolution;
  m.reconstruction = reconstruct(m.points, options);
  m.tree = build_mc_octree(m.reconstruction);
  m.lod = number_nodes(m.tree);
  return m;
}

const Model& bunny64() {
  static const Model m =
      build_model(load_oriented_points({scan2lod::testing::bunny_scans()}), 64);
  return m;
}

std::vector<Triangle> sorted_rotated(std::vector<Triangle> t) {
  // Same triangle, whatever corner it starts at.
  for (Triangle& x : t) std::rotate(x.begin(), std::min_element(x.begin(), x.end()), x.end());
  std::sort(t.begin(), t.end());
  return t;
}

}  // namespace

TEST(McOctree, FullDetailIsTheMarchingCubesMesh) {
  const Model& m = bunny64();
  std::vector<std::uint8_t> scratch;
  std::vector<Triangle> full;
  extract_lod(m.tree, m.lod, m.lod.full(), &scratch, &full);
  EXPECT_EQ(sorted_rotated(full), sorted_rotated(m.reconstruction.mesh.triangles));
  // Same vertex positions: the octree's vertex array starts with the mesh's.
  ASSERT_EQ(m.tree.mesh_vertices, m.reconstruction.mesh.positions.size());
  for (std::size_t v = 0; v < m.tree.mesh_vertices; ++v)
    ASSERT_EQ(m.tree.vertices.positions[v], m.reconstruction.mesh.positions[v]);
}

TEST(LodArray, EveryNodeExpandsOnceParentsFirst) {
  const Model& m = bunny64();
  std::vector<int> seen(m.tree.size(), 0);
  std::size_t internal = 0;
  for (std::size_t n = 0; n < m.tree.size(); ++n) internal += !m.tree.is_leaf(n);
  ASSERT_EQ(m.lod.order.size(), internal);
  EXPECT_EQ(m.lod.order.front(), 0);
  std::vector<std::uint8_t> expanded(m.tree.size(), 0);
  expanded[0] = 1;
  for (std::size_t i = 1; i < m.lod.order.size(); ++i) {
    const std::int32_t n = m.lod.order[i];
    ASSERT_EQ(seen[n]++, 0);
    ASSERT_TRUE(expanded[m.tree.nodes.parents[n]]) << "node expanded before its parent";
    expanded[n] = 1;
  }
}

TEST(LodArray, NeighboursDifferByAtMostOneLevelInEveryPrefix) {
  // Walk all prefixes; after each expansion, every new child's same-level
  // neighbourhood must be covered by cut nodes no coarser than its parent.
  const Model& m = bunny64();
  const McOctree& t = m.tree;
  std::map<std::pair<int, std::uint64_t>, std::int32_t> node_at;
  for (std::size_t n = 0; n < t.size(); ++n) node_at[{t.nodes.levels[n], t.nodes.keys[n]}] = std::int32_t(n);
  std::vector<std::uint8_t> in_cut(t.size(), 0), expanded(t.size(), 0);
  in_cut[0] = 1;
  auto covering_level = [&](int level, int x, int y, int z) {
    // The cut node that covers lattice cell (x, y, z) of `level`, or -1 if none.
    for (int l = level; l >= 0; --l) {
      const int s = level - l;
      auto it = node_at.find({l, pack_key(std::uint64_t(x) >> s, std::uint64_t(y) >> s, std::uint64_t(z) >> s)});
      if (it == node_at.end()) continue;
      if (in_cut[it->second]) return l;
      if (expanded[it->second]) return -1;  // covered by finer nodes, or by none
    }
    return -1;
  };
  for (std::size_t i = 0; i < m.lod.order.size(); ++i) {
    const std::int32_t n = m.lod.order[i];
    in_cut[n] = 0;
    expanded[n] = 1;
    for (int c = 0; c < t.nodes.child_counts[n]; ++c) in_cut[t.nodes.first_child[n] + c] = 1;
    for (int c = 0; c < t.nodes.child_counts[n]; ++c) {
      const std::int32_t child = t.nodes.first_child[n] + c;
      int x, y, z;
      unpack_key(t.nodes.keys[child], &x, &y, &z);
      const int side = 1 << t.nodes.levels[child];
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            if (x + dx < 0 || y + dy < 0 || z + dz < 0 || x + dx >= side || y + dy >= side || z + dz >= side) continue;
            const int level = covering_level(t.nodes.levels[child], x + dx, y + dy, z + dz);
            ASSERT_TRUE(level < 0 || level >= t.nodes.levels[child] - 1)
                << "prefix " << i + 1 << ": a level-" << int(t.nodes.levels[child]) << " node beside a level-" << level << " node";
          }
    }
  }
}

TEST(LodArray, OfferedLevelsNeverLoseTriangles) {
  const Model& m = bunny64();
  const std::vector<std::size_t> levels = monotone_priorities(m.lod);
  ASSERT_GE(levels.size(), 2u);
  // From a few triangles (no pinned prefix) to full detail.
  EXPECT_EQ(m.lod.pinned, 0u);
  EXPECT_LE(m.lod.accumulated[levels.front()], m.lod.accumulated.back() / 100);
  EXPECT_EQ(levels.back(), m.lod.full());
  for (std::size_t i = 1; i < levels.size(); ++i) {
    ASSERT_GT(levels[i], levels[i - 1]);
    ASSERT_GE(m.lod.accumulated[levels[i]], m.lod.accumulated[levels[i - 1]]);
  }
  // Dense enough to be continuous: most priority numbers are offered.
  EXPECT_GT(double(levels.size()), 0.5 * double(m.lod.full()));
  for (double percent = 0; percent <= 100; percent += 0.5) {
    const std::size_t p = priority_for_percent(m.lod, percent);
    EXPECT_TRUE(std::binary_search(levels.begin(), levels.end(), p));
  }
  std::int64_t previous = -1;
  for (double percent = 0; percent <= 100; percent += 1) {
    const std::int64_t count = m.lod.accumulated[priority_for_percent(m.lod, percent)];
    ASSERT_GE(count, previous) << percent << "%";
    previous = count;
  }
}

TEST(LodArray, AccumulationTableCountsTheExtractedTriangles) {
  const Model& m = bunny64();
  std::vector<std::uint8_t> scratch;
  std::vector<Triangle> tris;
  for (double percent : {0.0, 1.0, 5.0, 10.0, 20.0, 40.0, 60.0, 80.0, 100.0}) {
    const std::size_t p = priority_for_percent(m.lod, percent);
    extract_lod(m.tree, m.lod, p, &scratch, &tris);
    EXPECT_EQ(std::int64_t(tris.size()), m.lod.accumulated[p]) << percent << "%";
    EXPECT_LE(m.lod.accumulated[priority_for_triangles(m.lod, std::int64_t(tris.size()))], std::int64_t(tris.size()));
  }
  EXPECT_TRUE(std::all_of(scratch.begin(), scratch.end(), [](std::uint8_t f) { return f == 0; }));
}

namespace {

// The topology of the levels issue 3's acceptance names: 1, 5, 10, 20, ..., 100 %.
std::vector<std::pair<double, MeshTopology>> topology_at_levels(const Model& m) {
  std::vector<std::pair<double, MeshTopology>> levels;
  std::vector<std::uint8_t> scratch;
  std::vector<Triangle> tris;
  for (double percent : {1.0, 5.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0}) {
    extract_lod(m.tree, m.lod, priority_for_percent(m.lod, percent), &scratch, &tris);
    levels.push_back({percent, mesh_topology(compact_lod(m.tree, tris))});
  }
  return levels;
}

void expect_closed_at_every_level(const Model& m, long euler) {
  for (const auto& [percent, t] : topology_at_levels(m)) {
    EXPECT_EQ(t.boundary_edges, 0u) << percent << "%";
    EXPECT_EQ(t.non_manifold_edges, 0u) << percent << "%";
    EXPECT_EQ(t.components, 1u) << percent << "%";
    EXPECT_EQ(t.euler_characteristic, euler) << percent << "%";
  }
}

}  // namespace

TEST(CrackPatching, ScannedSphereIsClosedAtEveryLevel) {
  const Model m = build_model(scan_shape(from_open3d(*open3d::geometry::TriangleMesh::CreateSphere(1.0, 120))), 64);
  expect_closed_at_every_level(m, 2);
}

TEST(CrackPatching, ScannedTorusIsClosedAtEveryLevel) {
  const Model m = build_model(scan_shape(from_open3d(*open3d::geometry::TriangleMesh::CreateTorus(1.0, 0.4, 200, 80))), 64);
  expect_closed_at_every_level(m, 0);
}

TEST(CrackPatching, BunnyHasNoNonManifoldEdgeAtAnyLevel) {
  for (const auto& [percent, t] : topology_at_levels(bunny64())) {
    EXPECT_EQ(t.non_manifold_edges, 0u) << percent << "%";
    EXPECT_EQ(t.degenerate_triangles, 0u) << percent << "%";
  }
}

TEST(LodMetric, DeviationStaysCloserToTheFullMeshThanAreaDifference) {
  // Lee's area difference leaves curved coarse nodes unexpanded; the
  // deviation metric spends the same triangles where the surface bends.
  // Measured: 0.50 and 0.37 of its error at 60 % and 30 % (below half at
  // both before the coarse polygons were cut along their own diagonals,
  // which helps the area difference's coarser nodes more).
  const Model& m = bunny64();
  OctreeOptions seed;
  seed.metric = LodMetric::kAreaDifference;
  const McOctree area_tree = build_mc_octree(m.reconstruction, seed);
  const LodArray area_lod = number_nodes(area_tree);
  const TriangleMesh& full = m.reconstruction.mesh;
  std::vector<std::uint8_t> scratch;
  std::vector<Triangle> tris;
  auto error_at = [&](const McOctree& tree, const LodArray& lod, std::int64_t budget) {
    extract_lod(tree, lod, priority_for_triangles(lod, budget), &scratch, &tris);
    const SurfaceComparison c = compare_surfaces(compact_lod(tree, tris), full);
    return (c.a_to_b.mean + c.b_to_a.mean) / 2 / c.diagonal;
  };
  for (double share : {0.6, 0.3}) {
    const auto budget = std::int64_t(share * double(full.triangles.size()));
    const double deviation = error_at(m.tree, m.lod, budget), area = error_at(area_tree, area_lod, budget);
    std::printf("%.0f %% of the triangles: mean error %.3g (deviation) vs %.3g (area difference) of the diagonal\n",
                100 * share, deviation, area);
    EXPECT_LT(deviation, 0.6 * area) << share;
  }
}

namespace {

// Acceptance 3 of issue 3: no level opens a boundary the full mesh lacks.
void expect_no_new_boundary_loops(const Model& m) {
  const auto levels = topology_at_levels(m);
  ASSERT_EQ(levels.back().first, 100.0);
  const std::size_t full_loops = levels.back().second.boundary_loops;
  for (const auto& [percent, t] : levels) {
    EXPECT_LE(t.boundary_loops, full_loops) << percent << "%";
    EXPECT_EQ(t.non_manifold_edges, 0u) << percent << "%";
  }
}

}  // namespace

TEST(CrackPatching, BunnyLevelsOpenNoBoundaryTheFullMeshLacks) {
  expect_no_new_boundary_loops(bunny64());
  expect_no_new_boundary_loops(
      build_model(load_oriented_points({scan2lod::testing::bunny_scans()}), 128));
}
