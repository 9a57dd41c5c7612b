// Incremental extraction (lod/octree/lod_cursor.h, the idea of Ramos's LODStrips, 2008, on
// Lee 2007's octree): moving between levels gives extract_lod's mesh and costs in
// proportion to the expansions in between, not to the mesh.
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/lod_cursor.h>
#include <scan2lod/lod/octree/mc_octree.h>
#include <scan2lod/lod/octree/octree_order.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include "test_shapes.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <open3d/geometry/TriangleMesh.h>

#include <algorithm>
#include <cstdlib>
#include <random>
#include <vector>

using namespace scan2lod;

namespace {

// A node's change re-emits its children (expansion) or itself (collapse), and
// the cut nodes among its 18 same-level neighbours across a face or an edge; a
// move rebuilds the cut instead when that re-emits fewer than 32 per change.
constexpr std::size_t kMostPerExpansion = 8 + 18, kMostPerChange = 32;

// Neighbours across a face or an edge: one or two offsets nonzero.
bool splits(int cell) {
  const int offsets = (cell % 3 != 1) + (cell / 3 % 3 != 1) + (cell / 9 != 1);
  return offsets == 1 || offsets == 2;
}

// The octree of a model (the cursor's structure): its tree and LOD array;
// the vertices its index buffers name are the model's (model.vertices).
const OctreeLod& octree_of(const LodModel& m) {
  if (!m.octree) {
    ADD_FAILURE() << "the model has no octree";
    std::abort();
  }
  return *m.octree;
}

const LodModel& bunny_lod_model() {
  static const LodModel m = load_model(scan2lod::testing::bunny_model().string());
  return m;
}
const OctreeLod& bunny() { return octree_of(bunny_lod_model()); }

const OctreeLod& torus() {
  static const LodModel m = [] {
    ReconstructOptions options;
    options.resolution = 32;
    const auto shape = open3d::geometry::TriangleMesh::CreateTorus(1.0, 0.4, 200, 80);
    const Reconstruction r =
        reconstruct(scan2lod::testing::scan_shape(scan2lod::testing::from_open3d(*shape)), options);
    McOctree tree = build_mc_octree(r);
    LodArray lod = number_nodes(tree);
    return model_from_octree(std::move(tree), std::move(lod));
  }();
  return octree_of(m);
}

std::vector<Triangle> sorted(std::vector<Triangle> t) {
  std::sort(t.begin(), t.end());
  return t;
}

std::size_t degenerate(const std::vector<Triangle>& t) {
  return std::size_t(std::count_if(t.begin(), t.end(), [](const Triangle& x) { return x[0] == x[1] && x[1] == x[2]; }));
}

// The most nodes a move between priorities a and b may re-emit: per expansion
// its children and neighbours, per collapse itself and its neighbours.
std::size_t emission_bound(const McOctree& tree, const LodArray& lod, std::size_t a, std::size_t b) {
  std::size_t bound = 0;
  for (std::size_t i = std::min(a, b); i < std::max(a, b); ++i) {
    const std::int32_t node = lod.order[i];
    bound += b > a ? tree.nodes.child_counts[std::size_t(node)] : 1;
    for (int c = 0; c < 27; ++c) bound += splits(c) && tree.transitions.neighbours[std::size_t(node)][std::size_t(c)] >= 0;
  }
  return bound;
}

// Nodes of the cut at `priority`: not expanded, under an expanded parent.
std::size_t cut_size(const McOctree& tree, const LodArray& lod, std::size_t priority) {
  if (priority == 0) return 1;
  std::vector<std::uint8_t> expanded(tree.size(), 0);
  for (std::size_t i = 0; i < priority; ++i) expanded[std::size_t(lod.order[i])] = 1;
  std::size_t n = 0;
  for (std::size_t node = 1; node < tree.size(); ++node)
    n += !expanded[node] && expanded[std::size_t(tree.nodes.parents[node])];
  return n;
}

// What a move from `from` to the cursor's priority may have re-emitted: its
// changes' children or selves and neighbours, or, rebuilt, the cut alone.
void expect_cost(const OctreeLod& m, const LodCursor& cursor, std::size_t from, std::size_t to) {
  const std::size_t changes = from > to ? from - to : to - from, emitted = cursor.emitted_nodes_last_move();
  EXPECT_LE(emitted, kMostPerChange * changes) << from << " -> " << to;
  if (cursor.rebuilt_last_move())
    EXPECT_EQ(emitted, cut_size(m.tree, m.lod, to)) << from << " -> " << to;
  else
    EXPECT_LE(emitted, emission_bound(m.tree, m.lod, from, to)) << from << " -> " << to;
}

// Moves a cursor to each target in turn and compares it with extract_lod.
void expect_moves_match_extraction(const OctreeLod& m, const std::vector<std::size_t>& targets) {
  LodCursor cursor(m.tree, m.lod);
  std::vector<std::uint8_t> scratch;
  std::vector<Triangle> expected, live;
  std::size_t rebuilt = 0;
  for (const std::size_t target : targets) {
    const std::size_t from = cursor.priority();
    cursor.move_to(target);
    rebuilt += cursor.rebuilt_last_move();
    ASSERT_EQ(cursor.priority(), target);
    extract_lod(m.tree, m.lod, target, &scratch, &expected);
    cursor.live_triangles(&live);
    ASSERT_EQ(sorted(live), sorted(expected)) << from << " -> " << target;
    EXPECT_EQ(cursor.triangles(), m.lod.accumulated[target]) << target;
    // Fillers are exactly the holes, and holes stay within a quarter of the buffer.
    const std::size_t holes = degenerate(cursor.buffer());
    EXPECT_EQ(cursor.buffer().size() - holes, std::size_t(cursor.triangles())) << target;
    EXPECT_LE(4 * holes, cursor.buffer().size()) << target;
    expect_cost(m, cursor, from, target);
  }
  // Both ways of moving were taken: changes applied, and the cut rebuilt.
  EXPECT_GT(rebuilt, 0u);
  EXPECT_LT(rebuilt, targets.size() / 2) << rebuilt;
}

// Slider-like moves with a fixed seed: both ends, large jumps, small steps both ways.
std::vector<std::size_t> random_targets(std::size_t full, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::vector<std::size_t> targets = {0, full, 0, full / 2, full / 2 + 1, full / 2, full};
  std::size_t at = full;
  const long most = std::max(2L, long(full) / 200);  // a small step: up to 0.5 % of the array
  for (int i = 0; i < 150; ++i) {
    if (i % 3 == 0) {
      at = std::uniform_int_distribution<std::size_t>(0, full)(random);
    } else {
      const long step = std::uniform_int_distribution<long>(-most, most)(random);
      at = std::size_t(std::clamp(long(at) + step, 0L, long(full)));
    }
    targets.push_back(at);
    if (i % 50 == 0) targets.push_back(i % 100 ? full : 0);
  }
  return targets;
}

}  // namespace

TEST(LodCursor, RandomMovesGiveExtractLodsTrianglesOnTheBunny) {
  const OctreeLod& m = bunny();
  ASSERT_GT(m.tree.patch_groups(), 0u);  // hole patches show and hide on the way
  expect_moves_match_extraction(m, random_targets(m.lod.full(), 1));
  // In a model the tree keeps no vertices: the buffer indexes the model's.
  EXPECT_TRUE(m.tree.vertices.positions.empty());
  const std::size_t vertices = bunny_lod_model().vertices.size();
  LodCursor cursor(m.tree, m.lod);
  for (const std::size_t p : {m.lod.full(), m.lod.full() / 2, std::size_t(0)}) {
    cursor.move_to(p);
    for (const Triangle& t : cursor.buffer())
      for (const std::int32_t v : t) ASSERT_TRUE(v >= 0 && std::size_t(v) < vertices) << v << " at " << p;
  }
}

TEST(LodCursor, RandomMovesGiveExtractLodsTrianglesOnATorus) {
  const OctreeLod& m = torus();
  expect_moves_match_extraction(m, random_targets(m.lod.full(), 2));
}

TEST(LodCursor, EveryStepUpAndDownFollowsTheAccumulationTable) {
  // One expansion at a time through the whole LOD array and back: each step's
  // count is the table's, and re-emits at most its children (or itself) and neighbours.
  const OctreeLod& m = bunny();
  const std::size_t full = m.lod.full();
  LodCursor cursor(m.tree, m.lod);
  std::vector<std::uint8_t> scratch;
  std::vector<Triangle> expected, live;
  const auto step = [&](std::size_t p) {
    const std::size_t from = cursor.priority();
    cursor.move_to(p);
    EXPECT_EQ(cursor.triangles(), m.lod.accumulated[p]) << p;
    expect_cost(m, cursor, from, p);
    if (p % (full / 16 + 1) == 0 || p == full) {
      extract_lod(m.tree, m.lod, p, &scratch, &expected);
      cursor.live_triangles(&live);
      EXPECT_EQ(sorted(live), sorted(expected)) << p;
      EXPECT_EQ(cursor.buffer().size() - degenerate(cursor.buffer()), std::size_t(cursor.triangles())) << p;
    }
  };
  for (std::size_t p = 1; p <= full; ++p) step(p);
  for (std::size_t p = full; p-- > 0;) step(p);
}

TEST(LodCursor, OneStepAtHalfReEmitsFarFewerNodesThanTheCut) {
  const OctreeLod& m = bunny();
  const std::size_t half = m.lod.full() / 2;
  LodCursor cursor(m.tree, m.lod);
  cursor.move_to(half);
  const std::size_t cut = cut_size(m.tree, m.lod, half);
  EXPECT_GT(cut, 1000u);
  cursor.move_to(half + 1);
  EXPECT_FALSE(cursor.rebuilt_last_move());
  EXPECT_GE(cursor.emitted_nodes_last_move(), 1u);
  EXPECT_LE(cursor.emitted_nodes_last_move(), kMostPerExpansion);
  EXPECT_LT(100 * cursor.emitted_nodes_last_move(), cut) << cut;
  cursor.move_to(half);
  EXPECT_GE(cursor.emitted_nodes_last_move(), 1u);
  EXPECT_LE(cursor.emitted_nodes_last_move(), 1 + 18u);
  // Ten steps: a few hundred nodes at most, a tenth of the whole cut at R = 64.
  cursor.move_to(half + 10);
  EXPECT_FALSE(cursor.rebuilt_last_move());
  EXPECT_LE(cursor.emitted_nodes_last_move(), 10 * kMostPerExpansion);
  EXPECT_LT(10 * cursor.emitted_nodes_last_move(), cut) << cut;
}

TEST(LodCursor, AJumpAcrossTheArrayRebuildsTheCutOnce) {
  // From the root to full detail: every leaf once, not every change's neighbours.
  const OctreeLod& m = bunny();
  LodCursor cursor(m.tree, m.lod);
  EXPECT_EQ(cursor.priority(), 0u);
  EXPECT_EQ(cursor.triangles(), m.lod.accumulated[0]);
  cursor.move_to(m.lod.full() + 100);  // clamped
  EXPECT_EQ(cursor.priority(), m.lod.full());
  EXPECT_EQ(cursor.triangles(), m.lod.accumulated[m.lod.full()]);
  EXPECT_TRUE(cursor.rebuilt_last_move());
  std::size_t leaves = 0;
  for (std::size_t n = 0; n < m.tree.size(); ++n) leaves += m.tree.is_leaf(n);
  EXPECT_EQ(cursor.emitted_nodes_last_move(), leaves);
  EXPECT_EQ(degenerate(cursor.buffer()), 0u);
}
