// The marching-cube octree (Lee, *Efficient LOD Model Generation of 3D Objects
// using Prioritized Marching Cube Octree*, 2007, §5.1): the leaf cube nodes of a
// reconstruction, and above them every coarser cube that holds one, each a
// marching cube of its own with corner signs, a vertex on each crossed edge and
// its triangles.
//
// Corner signs. A corner shared by leaf cubes keeps the leaves' signed
// distance; any other lattice point gets the same signed-distance field,
// evaluated once per point. So every node that shares a corner sees the same
// sign, which is what keeps neighbouring nodes' faces in agreement (Lee
// derives parents' signs from their children, which neighbours can see
// differently).
//
// Edge vertices. A coarse edge whose end signs differ takes the half that holds
// the change, recursively, down to a leaf edge, and uses that leaf's vertex
// (§5.1: "extending the child edge that holds the crossing"). Each level then
// gets its own copy of it, moved off the surface by the mesh's tangent planes
// around it, so that a coarse node's triangles straddle the surface rather
// than cut under it as chords. Only where no leaf has a vertex on that edge is
// one added, interpolated on the leaf edge, and shared by the levels. Where the
// field only jumps there (its sign flips beyond an open rim, where no surface
// is), the added vertex is pulled to the mesh: coarse nodes over a rim then
// end at the rim instead of reaching out to their cube's faces.
//
// The build runs as named phases, one file each; lod/octree/octree_build.h lists them.
#pragma once

#include <scan2lod/core/large_array.h>
#include <scan2lod/core/types.h>
#include <scan2lod/lod/octree/transition.h>
#include <scan2lod/reconstruct/marching_cubes.h>
#include <scan2lod/reconstruct/signed_distance.h>

#include <array>
#include <cstdint>
#include <vector>

namespace scan2lod {

struct MeshField;  // reconstruct/mesh_field.h

// The nodes, level by level from the root (level 0); a node's children are
// contiguous and on the next level. Every array has one entry per node.
struct OctreeNodes {
  LargeArray<std::uint64_t> keys;  // packed (x, y, z) on its level's lattice
  LargeArray<std::uint8_t> levels;
  LargeArray<std::int32_t> parents;       // -1 for the root
  LargeArray<std::int32_t> first_child;   // -1 for leaves
  LargeArray<std::uint8_t> child_counts;
  LargeArray<std::uint8_t> cases;         // mask of inside corners
  LargeArray<std::array<std::int32_t, 12>> edge_vertices;  // vertex per crossed edge, else -1
  LargeArray<std::int32_t> first_triangle;  // the node's own triangles: [first, first + count)
  LargeArray<std::uint8_t> triangle_counts;
  LargeArray<float> metrics;  // LOD metric (OctreeOptions::metric): larger expands first; 0 for leaves

  std::size_t size() const { return keys.size(); }
};

// Crack patching (lod/octree/transition.h), for the nodes above the leaves, which
// come first: indexed by node in [0, internal nodes).
struct OctreeTransitions {
  LargeArray<std::uint32_t> boundary_inside;  // bit p: local lattice point p is inside
  LargeArray<std::array<std::int32_t, kSubEdges>> sub_edge_vertices;
  LargeArray<std::int32_t> centre_vertices;  // -1 where nothing crosses the node's boundary
  LargeArray<std::array<std::int32_t, 27>> neighbours;  // node in each cell around (13: itself), or -1
  // Bit axis*2+side: the node's crossings on that face include three in line
  // (lod/octree/transition.h's straight_faces), found once their positions are final.
  LargeArray<std::uint8_t> straight_faces;

  std::size_t size() const { return centre_vertices.size(); }
};

// The leaves' hole patches (CubeNodes::patch_triangles), grouped by hole: a
// group shows once every node whose children hold its rim has expanded.
struct OctreePatches {
  std::vector<Triangle> triangles;
  std::vector<std::int32_t> group_first;  // groups + 1 offsets into triangles
  std::vector<std::int32_t> needs_first;  // groups + 1 offsets into needs
  std::vector<std::int32_t> needs;        // nodes that must be expanded

  std::size_t groups() const { return group_first.empty() ? 0 : group_first.size() - 1; }
};

// Positions, normals and colours every level of every LOD structure indexes
// (lod/lod_model.h). The octree's: the full mesh's vertices first, then the
// ones it adds (on edges no leaf crosses, each level's own copies of the mesh
// vertices its edges resolve to, and the centres).
struct VertexArray {
  LargeArray<Vec3f> positions;
  LargeArray<Vec3f> normals;  // empty or one per position
  LargeArray<Rgb> colors;     // empty or one per position
  std::size_t size() const { return positions.size(); }
};

struct McOctree {
  CubeGrid grid;   // the leaves' grid
  int depth = 0;   // leaves sit at level depth; resolution == 2^depth

  OctreeNodes nodes;
  OctreeTransitions transitions;
  LargeArray<Triangle> triangles;  // every node's own triangles (OctreeNodes::first_triangle)
  OctreePatches patches;
  // Built with the tree; LodModel keeps them in its shared VertexArray and
  // leaves these empty (model_from_octree).
  VertexArray vertices;
  std::size_t mesh_vertices = 0;  // the full mesh's vertices: the first of the shared array
  // Where the levels' own copies of mesh vertices begin (build_mc_octree; the
  // vertices added on edges lie between mesh_vertices and here, the centres
  // after the copies). Only the build sets it: a model file does not keep it.
  std::size_t level_vertices_first = 0;

  std::size_t size() const { return nodes.size(); }
  bool is_leaf(std::size_t n) const { return nodes.first_child[n] < 0; }
  // The own triangles of node n's children: what the cut holds where n expanded
  // (transitions aside).
  int children_triangles(std::size_t n) const {
    int sum = 0;
    for (int c = 0; c < nodes.child_counts[n]; ++c) sum += nodes.triangle_counts[std::size_t(nodes.first_child[n] + c)];
    return sum;
  }
  std::size_t internal_nodes() const { return transitions.size(); }
  std::size_t patch_groups() const { return patches.groups(); }
};

// What orders the expansions (number_nodes, lod/octree/octree_order.h, ranks nodes by it, largest first).
enum class LodMetric {
  // Seed §5.2: the area of the children's triangles minus the node's own.
  // Blind to where the area goes: a curved coarse node whose children add
  // little area stays coarse with its surface millimetres off (bench/lod).
  kAreaDifference,
  // The node's deviation from the leaves' surface under it, per triangle its
  // expansion adds: area x RMS distance of those leaf triangles from the
  // plane of the node's own, plus a quarter of the node's size per unit of
  // area it adds or misses. Flat regions stay coarse, curved and thin ones refine.
  kDeviation,
};

struct OctreeOptions {
  LodMetric metric = LodMetric::kDeviation;
};

// Builds the octree over a reconstruction's leaf cube nodes and mesh.
// @param[in] leaves  CubeNodes from reconstruct(); resolution a power of two
// @param[in] mesh    the reconstruction's mesh (its vertices are the leaves')
// @param[in] field   signed distance for lattice points the leaves lack, and
//                    closest points of the surface
// Throws InputError when there are no leaves.
McOctree build_mc_octree(const CubeNodes& leaves, const TriangleMesh& mesh, const MeshField& field,
                         const OctreeOptions& options = {});

// The octree of a reconstruction, the field being the signed distance to its
// finished mesh (reconstruct/mesh_field.h): coarse levels then approximate the
// mesh as delivered, without the pieces and holes that clean-up removed at the
// leaves. (The scan points' own field re-grows them at coarse corners: the
// bunny's coarse levels had 18-48 boundary loops with it, 3-13 with this.)
McOctree build_mc_octree(const Reconstruction& reconstruction, const OctreeOptions& options = {});

}  // namespace scan2lod
