// Phase 8 of build_mc_octree: level vertices (lod/octree/octree_build.h).
//
// A coarse edge's crossing is the finest mesh's vertex there, on the surface:
// a coarse node's triangles between such vertices are chords, below every
// convex bump and above every hollow, by the square of the node's size. So
// each level above the leaves gets its own copy of every vertex its edges
// resolve to, placed as quadric clustering places a cluster's vertex
// (Lindstrom, *Out-of-Core Simplification of Large Polygonal Models*, 2000):
// nearest, in least squares, to the tangent planes of the mesh around it.
// The levels' triangles then straddle the surface instead of cutting under it
// (the bunny at R = 256: 15-26 % less distance at 1k, 2k, 5k and 20k triangles).
//
// Indices change, not topology: an edge of a level resolves to one vertex,
// and every node of a cut sees each edge at one level (the neighbour rule), so
// a cut joins the same copies wherever the leaves' shared vertex joined it.
#include <scan2lod/core/mesh_edges.h>
#include <scan2lod/lod/octree/octree_build.h>

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

namespace scan2lod {
namespace octree_build {

namespace {

// The tangent planes within kReach node sizes of a crossing place its copy,
// which stays within kLimit node sizes of it. Tangent planes of a sphere of
// radius r within distance R meet their least-squares point R^2 / (4 r)
// outside it, about a chord's mean sag for chords somewhat shorter than R.
// Measured on the bunny at R = 256 (distance at 1k-20k triangles), a reach of
// 0.5 gained 10 %, 0.85 gained 15-25 %, 1.0 less again.
constexpr float kReach = 0.85f;
constexpr float kLimit = 0.7f;
// Only planes facing the crossing's way count: the far side of a thin part
// (an ear) is another sheet.
constexpr float kSameSheet = 0.5f;
// Moves shorter than this share of a leaf cube are not made: on a flat face
// they only take the copies onto its plane, where three that shared a lattice
// line before fall on one line (a box's faces at R = 256).
constexpr float kLeast = 0.1f;
// At most this many vertices' planes, the nearest along the mesh: only the
// coarsest levels' reach holds more (level 1 of the bunny at R = 256, a
// quarter of the mesh).
constexpr std::size_t kMostPlanes = 8192;
// Pulls the least-squares point towards the crossing, per plane: where the
// planes are nearly parallel (a flat or cylindrical stretch) it would slide
// along them. Stronger pulls (0.05) gave back a third of the gain.
constexpr double kStay = 0.01;

// The mesh's vertices, each with the vertices it shares an edge with.
struct Neighbours {
  std::vector<std::int32_t> first;  // vertices + 1 offsets into `of`
  std::vector<std::int32_t> of;

  explicit Neighbours(const TriangleMesh& mesh) : first(mesh.positions.size() + 1, 0) {
    const MeshEdges edges = mesh_edges(mesh.triangles, mesh.positions.size());
    for (const auto& e : edges.ends) ++first[std::size_t(e[0]) + 1], ++first[std::size_t(e[1]) + 1];
    for (std::size_t v = 0; v + 1 < first.size(); ++v) first[v + 1] += first[v];
    of.resize(std::size_t(first.back()));
    std::vector<std::int32_t> at(first.begin(), first.end() - 1);
    for (const auto& e : edges.ends) {
      of[std::size_t(at[std::size_t(e[0])]++)] = e[1];
      of[std::size_t(at[std::size_t(e[1])]++)] = e[0];
    }
  }
};

// A thread's scratch for the walks: a mark per vertex (the walk's number, so
// nothing is cleared between walks) and the queue.
struct Walk {
  std::vector<std::uint32_t> mark;
  std::uint32_t number = 0;
  std::vector<std::int32_t> queue;
};

// Where the copy of mesh vertex `at` goes for a level whose cubes are `size`.
// The planes are those of the mesh vertices within reach that the mesh joins
// to `at` inside the ball: a walk along its edges touches only them, and the
// far side of a thin part, which only its rim joins, stays out.
Vec3f placed(const TriangleMesh& mesh, const std::vector<Vec3f>& normals, const Neighbours& neighbours,
             std::int32_t at, float size, float cube, Walk* walk) {
  const Vec3f p = mesh.positions[std::size_t(at)];
  const Vec3f n0 = normals[std::size_t(at)];
  const float reach2 = (kReach * size) * (kReach * size);
  Eigen::Matrix3d planes = Eigen::Matrix3d::Zero();
  Eigen::Vector3d offsets = Eigen::Vector3d::Zero();
  double along = 0.0, across = 0.0;  // the same along n0 alone
  int count = 0;
  const std::uint32_t number = ++walk->number;
  walk->queue.assign(1, at);
  walk->mark[std::size_t(at)] = number;
  for (std::size_t head = 0; head < walk->queue.size(); ++head) {
    const std::int32_t i = walk->queue[head];
    for (std::int32_t k = neighbours.first[std::size_t(i)]; k < neighbours.first[std::size_t(i) + 1]; ++k) {
      const std::int32_t j = neighbours.of[std::size_t(k)];
      if (walk->mark[std::size_t(j)] == number || walk->queue.size() == kMostPlanes ||
          (mesh.positions[std::size_t(j)] - p).squaredNorm() > reach2)
        continue;
      walk->mark[std::size_t(j)] = number;
      walk->queue.push_back(j);
    }
    const Vec3f& n = normals[std::size_t(i)];
    const float facing = n.dot(n0);
    if (facing < kSameSheet) continue;
    const double offset = n.dot(mesh.positions[std::size_t(i)] - p);
    const Eigen::Vector3d nd = n.cast<double>();
    planes += nd * nd.transpose();
    offsets += nd * offset;
    along += facing * offset;
    across += double(facing) * facing;
    ++count;
  }
  if (count == 0) return p;  // a vertex no triangle uses has no normal
  const float limit = kLimit * size;
  planes.diagonal().array() += kStay * count;
  const Eigen::Vector3f move = planes.ldlt().solve(offsets).cast<float>();
  if (move.norm() < kLeast * cube) return p;
  if (move.norm() <= limit) return p + move;
  // Beyond the limit the planes disagree (a crease, a corner): move along the
  // normal alone, as far as the limit allows.
  const float step = std::clamp(float(along / across), -limit, limit);
  return std::fabs(step) < kLeast * cube ? p : p + step * n0;
}

// Where a node's own triangle would lose its area or turn over with its copies
// placed (on a box, copies near an edge or a corner meet its planes in one
// line or point), its copies go back to the vertices they copy, where the
// triangle was whole. Until no triangle turns: a copy sent back can turn
// another of its triangles only towards how it was.
void keep_triangles_turned(const LevelBegin& level_begin, std::size_t first_copy,
                           const std::vector<std::int32_t>& sources, McOctree* tree) {
  auto& positions = tree->vertices.positions;
  auto was = [&](std::int32_t v) {
    return positions[std::size_t(v) >= first_copy ? std::size_t(sources[std::size_t(v) - first_copy]) : std::size_t(v)];
  };
  // The coarse nodes' own triangles follow the leaves' (laid out from the leaves' level up).
  const auto first = std::size_t(tree->nodes.first_triangle[std::size_t(level_begin[tree->depth - 1])]);
  for (bool moved = true; moved;) {
    moved = false;
    for (std::size_t t = first; t < tree->triangles.size(); ++t) {
      const Triangle& tri = tree->triangles[t];
      const Vec3f now = (positions[std::size_t(tri[1])] - positions[std::size_t(tri[0])])
                            .cross(positions[std::size_t(tri[2])] - positions[std::size_t(tri[0])]);
      const Vec3f before = (was(tri[1]) - was(tri[0])).cross(was(tri[2]) - was(tri[0]));
      if (now.dot(before) > 0.f && (now.x() != 0.f || now.y() != 0.f || now.z() != 0.f)) continue;
      for (std::int32_t v : tri)
        if (std::size_t(v) >= first_copy && positions[std::size_t(v)] != was(v)) {
          positions[std::size_t(v)] = was(v);
          moved = true;
        }
    }
  }
}

}  // namespace

void level_vertices(const TriangleMesh& mesh, const LevelBegin& level_begin, McOctree* tree) {
  const int depth = tree->depth;
  VertexArray& vertices = tree->vertices;
  const std::size_t before = vertices.size();
  tree->level_vertices_first = before;
  if (depth == 0) return;
  OctreeNodes& nodes = tree->nodes;
  // One copy per (level, vertex), found through a table over the vertices
  // that each level clears after itself.
  std::vector<std::int32_t> copy_of(tree->mesh_vertices, -1), used;
  std::vector<std::int32_t> sources;  // per copy, the vertex it copies
  std::vector<std::uint8_t> copy_levels;
  // Only the mesh's vertices are copied: the octree's added ones are off them
  // already, where no leaf crosses, and stay shared.
  const auto mesh_vertices = std::int32_t(tree->mesh_vertices);
  auto copy = [&](std::int32_t& v, int level) {
    if (v < 0 || v >= mesh_vertices) return;
    std::int32_t& c = copy_of[std::size_t(v)];
    if (c < 0) {
      c = std::int32_t(before + sources.size());
      sources.push_back(v);
      copy_levels.push_back(std::uint8_t(level));
      used.push_back(v);
    }
    v = c;
  };
  for (int level = 0; level < depth; ++level) {
    // The level's edges: its nodes' own, and the sub-edges of the level above.
    for (std::int32_t n = level_begin[level]; n < level_begin[level + 1]; ++n) {
      for (std::int32_t& v : nodes.edge_vertices[std::size_t(n)]) copy(v, level);
      const auto first = tree->triangles.begin() + nodes.first_triangle[std::size_t(n)];
      for (auto t = first; t != first + nodes.triangle_counts[std::size_t(n)]; ++t)
        for (std::int32_t& v : *t)
          if (v < mesh_vertices) v = copy_of[std::size_t(v)];
    }
    if (level > 0)
      for (std::int32_t n = level_begin[level - 1]; n < level_begin[level]; ++n)
        for (std::int32_t& v : tree->transitions.sub_edge_vertices[std::size_t(n)]) copy(v, level);
    for (std::int32_t v : used) copy_of[std::size_t(v)] = -1;
    used.clear();
  }

  const std::size_t copies = sources.size();
  vertices.positions.resize(before + copies);
  const std::vector<Vec3f> normals = vertex_normals(mesh);
  const Neighbours neighbours(mesh);
  const float cube = float(tree->grid.cube_size);
#pragma omp parallel
  {
    Walk walk;
    walk.mark.assign(mesh.positions.size(), 0);
#pragma omp for schedule(dynamic, 256)
    for (std::size_t i = 0; i < copies; ++i) {
      const float size = std::ldexp(cube, depth - copy_levels[i]);
      vertices.positions[before + i] = placed(mesh, normals, neighbours, sources[i], size, cube, &walk);
    }
  }
  keep_triangles_turned(level_begin, before, sources, tree);
  // Normals and colours are the copied vertex's.
  if (!vertices.normals.empty()) {
    vertices.normals.resize(before + copies);
    for (std::size_t i = 0; i < copies; ++i) vertices.normals[before + i] = vertices.normals[std::size_t(sources[i])];
  }
  if (!vertices.colors.empty()) {
    vertices.colors.resize(before + copies);
    for (std::size_t i = 0; i < copies; ++i) vertices.colors[before + i] = vertices.colors[std::size_t(sources[i])];
  }
}

}  // namespace octree_build
}  // namespace scan2lod
