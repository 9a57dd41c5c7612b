// Crack patching's transition triangulation (lod/octree/transition.h) on hand-made
// configurations whose answer is known.
#include <scan2lod/lod/octree/transition.h>
#include <scan2lod/reconstruct/cube_table.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

using namespace scan2lod;

namespace {

int lattice(int i, int j, int k) { return i + 3 * j + 9 * k; }

struct Vertices {
  std::vector<std::int32_t> edges = std::vector<std::int32_t>(12);
  std::vector<std::int32_t> sub_edges = std::vector<std::int32_t>(kSubEdges);
  Vertices() {
    std::iota(edges.begin(), edges.end(), 100);
    std::iota(sub_edges.begin(), sub_edges.end(), 200);
  }
};

constexpr std::int32_t kCentre = 999;

// Groups of triangles joined through shared vertices.
std::vector<std::vector<Triangle>> pieces(const std::vector<Triangle>& triangles) {
  std::vector<std::size_t> group(triangles.size());
  std::iota(group.begin(), group.end(), 0);
  auto find = [&](std::size_t x) {
    while (group[x] != x) x = group[x] = group[group[x]];
    return x;
  };
  std::map<std::int32_t, std::size_t> first_with;
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (const std::int32_t v : triangles[t]) {
      const auto [at, added] = first_with.insert({v, t});
      if (!added) group[find(t)] = find(at->second);
    }
  std::map<std::size_t, std::vector<Triangle>> by_root;
  for (std::size_t t = 0; t < triangles.size(); ++t) by_root[find(t)].push_back(triangles[t]);
  std::vector<std::vector<Triangle>> out;
  for (auto& [root, members] : by_root) out.push_back(members);
  return out;
}

// V - E + F of a set of triangles.
long euler(const std::vector<Triangle>& triangles) {
  std::set<std::int32_t> vertices;
  std::set<std::pair<std::int32_t, std::int32_t>> edges;
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k) {
      vertices.insert(t[k]);
      edges.insert(std::minmax(t[k], t[(k + 1) % 3]));
    }
  return long(vertices.size()) - long(edges.size()) + long(triangles.size());
}

}  // namespace

TEST(Transition, TwoSheetsThroughOneNodeDoNotMeetAtTheCentre) {
  // Two opposite corners, each with its three edge midpoints, inside; every
  // face finer: two separate sheets cut the node, each a loop of crossings.
  std::uint32_t inside = 0;
  for (const int p : {lattice(0, 0, 0), lattice(1, 0, 0), lattice(0, 1, 0), lattice(0, 0, 1), lattice(2, 2, 2),
                      lattice(1, 2, 2), lattice(2, 1, 2), lattice(2, 2, 1)})
    inside |= 1u << p;
  const Vertices v;
  const TransitionInput in{inside, v.edges.data(), v.sub_edges.data(), kCentre, 0x3f, 0xfff};
  std::vector<Triangle> triangles;
  triangulate_transition(in, &triangles);
  EXPECT_EQ(int(triangles.size()), transition_triangle_count(in));

  const auto sheets = pieces(triangles);
  ASSERT_EQ(sheets.size(), 2u);  // one vertex shared would make them one piece
  int centred = 0;
  for (const auto& sheet : sheets) {
    EXPECT_EQ(euler(sheet), 1) << "each sheet a disc";
    centred += std::any_of(sheet.begin(), sheet.end(), [](const Triangle& t) {
      return std::find(t.begin(), t.end(), kCentre) != t.end();
    });
  }
  EXPECT_EQ(centred, 1);
  // Symmetric sheets: the centred one has two triangles more (n against n - 2).
  EXPECT_EQ(std::max(sheets[0].size(), sheets[1].size()) - std::min(sheets[0].size(), sheets[1].size()), 2u);
}

TEST(Transition, ACornerBesideFinerFacesIsCutOffOnHalfEdges) {
  // Corner 0 alone inside and its three faces finer: one loop, all fanned.
  const std::uint32_t inside = 1u << lattice(0, 0, 0);
  const Vertices v;
  // Faces x = 0, y = 0 and z = 0 (axis * 2 + side 0) and the three edges at
  // corner 0 (x-, y- and z-edges number 0, 4 and 8 in cube_table.h).
  const TransitionInput in{inside, v.edges.data(), v.sub_edges.data(), kCentre, 0x15, 0x111};
  std::vector<Triangle> triangles;
  triangulate_transition(in, &triangles);
  // The corner is cut off on its three half-edges: a three-crossing loop, one
  // triangle, no centre needed.
  ASSERT_EQ(triangles.size(), 1u);
  EXPECT_EQ(std::count(triangles[0].begin(), triangles[0].end(), kCentre), 0);
  for (const std::int32_t c : triangles[0]) EXPECT_GE(c, 200) << "crossings on half-edges, not whole ones";
}

TEST(Transition, StraightFacesAreThoseWithThreeCrossingsInLine) {
  // The node spans [0, 2]^3 in local lattice units; every crossing starts at
  // a random point of its (sub-)edge.
  std::vector<Vec3f> positions;
  Vertices v;
  std::srand(1);
  auto point = [](int p) { return Vec3f(float(p % 3), float(p / 3 % 3), float(p / 9)); };
  auto along = [&](int a, int b) {
    const float t = 0.2f + 0.6f * float(std::rand()) / float(RAND_MAX);
    positions.push_back(point(a) + t * (point(b) - point(a)));
    return std::int32_t(positions.size() - 1);
  };
  const auto& sub = transition_sub_edges();
  for (int k = 0; k < kSubEdges; ++k) v.sub_edges[std::size_t(k)] = along(sub[std::size_t(k)].a, sub[std::size_t(k)].b);
  for (int e = 0; e < 12; ++e)
    v.edges[std::size_t(e)] = along(lattice_of_corner(edge_corner(e, 0)), lattice_of_corner(edge_corner(e, 1)));
  auto straight = [&] { return int(straight_faces(v.edges.data(), v.sub_edges.data(), positions.data())); };
  EXPECT_EQ(straight(), 0) << "no three in line";

  // The line z = 0.5 on face x = 2 (bit 1) meets the lower halves of the
  // z-edges at y = 0 and y = 2 and the half-line inside the face at y = 1.
  auto sub_edge = [&](int a, int b) -> std::int32_t& {
    for (int k = 0; k < kSubEdges; ++k)
      if (sub[std::size_t(k)].a == std::min(a, b) && sub[std::size_t(k)].b == std::max(a, b))
        return v.sub_edges[std::size_t(k)];
    throw std::logic_error("no such sub-edge");
  };
  auto whole_edge = [&](int a, int b) -> std::int32_t& {
    for (int e = 0; e < 12; ++e)
      if (std::minmax(lattice_of_corner(edge_corner(e, 0)), lattice_of_corner(edge_corner(e, 1))) == std::minmax(a, b))
        return v.edges[std::size_t(e)];
    throw std::logic_error("no such edge");
  };
  const Vec3f on_line[3] = {Vec3f(2, 0, 0.5f), Vec3f(2, 1, 0.5f), Vec3f(2, 2, 0.5f)};
  positions[std::size_t(sub_edge(lattice(2, 0, 0), lattice(2, 0, 1)))] = on_line[0];
  positions[std::size_t(sub_edge(lattice(2, 1, 0), lattice(2, 1, 1)))] = on_line[1];
  positions[std::size_t(sub_edge(lattice(2, 2, 0), lattice(2, 2, 1)))] = on_line[2];
  EXPECT_EQ(straight(), 2) << "three sub-edge crossings in line on face x = 2";
  positions[std::size_t(sub_edge(lattice(2, 2, 0), lattice(2, 2, 1)))] = Vec3f(2, 2, 0.55f);
  EXPECT_EQ(straight(), 0) << "a twentieth of a cell off the line";

  // Whole edges' crossings on the line instead of their halves': never in
  // one triangulation with a crossing inside the face.
  positions[std::size_t(sub_edge(lattice(2, 0, 0), lattice(2, 0, 1)))] = Vec3f(2, 0, 0.3f);
  positions[std::size_t(whole_edge(lattice(2, 0, 0), lattice(2, 0, 2)))] = on_line[0];
  positions[std::size_t(whole_edge(lattice(2, 2, 0), lattice(2, 2, 2)))] = on_line[2];
  EXPECT_EQ(straight(), 0) << "a whole edge's crossing beside one inside its face";
}
