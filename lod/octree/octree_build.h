// The phases of build_mc_octree (lod/octree/mc_octree.h), in the order it runs them:
//
//   1. skeleton          every node, level by level from the root (mc_octree.cpp)
//   2. lattice signs     one sign per lattice point, shared by every node that
//                        has the point as a corner (octree_signs.cpp)
//   3. edge resolution   the vertex on a coarse edge: the leaf vertex at the end
//                        of the halves that change sign (octree_edges.cpp)
//   4. cases, triangles  each node's marching cube, leaves up (octree_cases.cpp)
//   5. transitions       boundary signs and crossings refined to the next level,
//                        and the 26 neighbours (octree_transitions.cpp)
//   6. jump vertices     added vertices where the field's sign flips without a
//                        surface, pulled to the mesh (octree_jumps.cpp)
//   7. added vertices    normals and colours for the vertices phase 3 added
//                        (octree_centres.cpp)
//   8. level vertices    each level's own copies of its crossings, placed by
//                        the mesh's tangent planes (octree_level_vertices.cpp)
//  8b. own triangulations  each coarse polygon cut along the diagonals whose
//                        triangles lie nearest the mesh (octree_triangulations.cpp)
//   9. metric            the LOD metric from sums over the leaf triangles
//                        (octree_metric.cpp)
//  10. patch groups      the leaves' hole patches grouped by hole (octree_patches.cpp)
//  11. centre vertices   one per internal node for its transition fans, fitted
//                        and unfolded (octree_centres.cpp)
//  12. straight faces    the node faces whose crossings include three in line,
//                        which the fans avoid (octree_straight_faces.cpp)
//
// Internal to lod/: the build's files include it, and the model file's
// unpacking (lod/octree/model_pack.cpp), which finds neighbours again as phase 5 does.
#pragma once

#include <scan2lod/core/array_view.h>
#include <scan2lod/core/flat_hash.h>
#include <scan2lod/lod/octree/mc_octree.h>
#include <scan2lod/reconstruct/mesh_field.h>
#include <scan2lod/spatial/point_index.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

namespace scan2lod {
namespace octree_build {

// Node ranges per level: level l's nodes are [level_begin[l], level_begin[l + 1]).
using LevelBegin = std::vector<std::int32_t>;

// One step along each axis of a packed key.
constexpr std::uint64_t kAxisStep[3] = {1ull, 1ull << 20, 1ull << 40};

// Keys, sizes and neighbours (octree_keys.cpp, in the runtime library: a
// model file's unpacking needs them too).

// The edge length of a node's cube.
double node_size(const McOctree& tree, std::size_t node);

// Leaf-lattice key of corner c of the node with `key` on a level whose cubes
// span 2^shift leaf cubes.
std::uint64_t corner_lattice_key(std::uint64_t key, int shift, int c);

// Leaf-lattice key of local lattice point p (0..26, x fastest) of the node
// with `key` on a level whose cubes span 2^shift leaf cubes.
std::uint64_t local_lattice_key(std::uint64_t key, int shift, int p);

// ---- 1. skeleton (mc_octree.cpp) -------------------------------------------

// Fills tree->nodes' keys, levels, parents and children, and sizes the other
// per-node arrays; returns the level ranges.
LevelBegin build_skeleton(const CubeNodes& leaves, McOctree* tree);

// ---- 2. lattice signs (octree_signs.cpp) -----------------------------------

// Leaf corners whose every crossing edge holds a vertex that no kept triangle
// uses (see octree_signs.cpp): 1 for each such corner of `leaves`.
std::vector<std::uint8_t> dropped_corners(const CubeNodes& leaves, const TriangleMesh& mesh);

// Signs on the leaf lattice: the leaves' own where they have them, else
// inferred from the tree (`Inference`), else the field's, each point decided
// once. The octree asks for some ten million signs; they sit as bits in 16^3
// bricks under a dense directory, because a hash map's cache miss per lookup
// was most of the transitions' time. Distances, which only leaf-edge
// interpolation needs, stay in a hash map.
class LatticeSigns {
 public:
  // Infers a point's sign from the tree, given a node that holds the point;
  // false when it cannot.
  using Inference = std::function<bool(std::uint64_t key, std::int32_t node, bool* inside)>;

  // `dropped[i]`: corner i's sign only shaped pieces that clean-up removed; the
  // field decides it instead.
  LatticeSigns(const CubeNodes& leaves, const SignedDistanceField& field, const std::vector<std::uint8_t>& dropped);

  void set_inference(Inference infer) { infer_ = std::move(infer); }

  // Makes sure every key has a sign: inferred where `nodes` (a node holding
  // each key) allow it, the rest in one batched field call.
  void ensure(const std::vector<std::uint64_t>& keys, const std::vector<std::int32_t>* nodes = nullptr);

  // The distance at key (the field's where the sign was inferred).
  float exact(std::uint64_t key);

  // The distance at key when the leaves or the field gave one.
  bool value(std::uint64_t key, float* v) const {
    const std::int32_t at = value_index_.find(key);
    if (at < 0) return false;
    *v = values_[std::size_t(at)];
    return true;
  }

  bool known(std::uint64_t key) const { return bit(key, 0); }
  bool inside(std::uint64_t key) const { return bit(key, kWordsPerBitset); }

 private:
  static constexpr int kBrickShift = 4;  // 16^3 points a brick
  static constexpr std::size_t kWordsPerBitset = std::size_t(1) << (3 * kBrickShift - 6);

  // Where a key's bits are: its brick's slot in the directory, and the word
  // (within the brick's known bits; its inside bits follow them) and bit.
  struct Spot {
    std::size_t brick, word;
    std::uint64_t mask;
  };
  Spot spot(std::uint64_t key) const;
  bool bit(std::uint64_t key, std::size_t offset) const {
    const Spot s = spot(key);
    const std::int32_t b = directory_[s.brick];
    return b >= 0 && (bits_[std::size_t(b) * 2 * kWordsPerBitset + s.word + offset] & s.mask);
  }
  void set(std::uint64_t key, bool in);
  void store(std::uint64_t key, float d);
  void query(const std::vector<std::uint64_t>& fresh);

  const CubeGrid& grid_;
  const SignedDistanceField& field_;
  int side_;                             // bricks along each axis
  std::vector<std::int32_t> directory_;  // brick -> its index in bits_, or -1
  std::vector<std::uint64_t> bits_;
  FlatHashMap value_index_;
  std::vector<float> values_;
  Inference infer_;
};

// Where the mesh field's sign may turn without a surface: along the mesh's rim
// (its boundary edges) and over hole patches; as points, searched with FLANN.
class SignHazards {
 public:
  SignHazards(const TriangleMesh& mesh, const std::vector<Triangle>& patches);
  ~SignHazards();
  // Whether every hazard is farther than `distance` from p.
  bool farther_than(const Vec3f& p, double distance) const;

 private:
  void add_segment(const Vec3f& a, const Vec3f& b);

  OrientedPoints points_;
  std::vector<Eigen::AlignedBox3f> boxes_;
  double gap_ = 0.0;
  std::unique_ptr<PointIndex> index_;
};

// A point in a child cube the tree lacks has no leaf around it: no surface
// crosses that cube, so the point takes the sign of the cube's corner at the
// parent's centre, which the parent's children already hold (Lee 2007, Fig.
// 5.2, gives parents their children's signs the same way). Near the mesh's
// rim or a hole patch the mesh field's sign can turn inside such a cube
// without a surface (beyond a rim, or across a patch no leaf holds): there
// the field is asked. A LatticeSigns::Inference.
class TreeSignInference {
 public:
  TreeSignInference(const McOctree& tree, const LatticeSigns& signs, const SignHazards& hazards)
      : tree_(tree), signs_(signs), hazards_(hazards), centre_usable_(tree.size(), 0) {}
  bool operator()(std::uint64_t key, std::int32_t node, bool* inside);

 private:
  std::int32_t deepest_holding(std::uint64_t key, std::int32_t node) const;

  const McOctree& tree_;
  const LatticeSigns& signs_;
  const SignHazards& hazards_;
  std::vector<std::int8_t> centre_usable_;  // per node: 1 yes, -1 no, 0 not yet known
};

// ---- 3. edge resolution (octree_edges.cpp) ---------------------------------

// The vertex on a coarse edge whose ends' signs differ: the half that changes
// sign, recursively, down to a leaf edge, whose leaf vertex it shares (Lee
// 2007, §5.1). Only where no leaf has a vertex on that leaf edge is one
// added to tree->vertices, interpolated. Remembers every edge it resolved.
class EdgeResolver {
 public:
  EdgeResolver(const CubeNodes& leaves, const FlatHashMap& leaf_index, LatticeSigns* signs, McOctree* tree)
      : leaves_(leaves), leaf_index_(leaf_index), signs_(*signs), tree_(*tree), added_on_edge_(1024),
        memo_(std::size_t(tree->depth) + 1) {}

  // The vertex on each given level-`level` edge (lower lattice corner << 2 |
  // axis). slots[i].first: the node whose edge or sub-edge edges[i] is, which
  // holds the points its walk asks signs of.
  void resolve(int level, const std::vector<std::uint64_t>& edges,
               const std::vector<std::pair<std::int32_t, int>>& slots, std::vector<std::int32_t>* out);

  // The added vertices whose leaf edge the field jumps across instead of
  // passing through zero (phase 6).
  const std::vector<std::int32_t>& jumps() const { return jumps_; }

 private:
  std::int32_t leaf_edge_vertex(std::uint64_t edge) const;
  std::int32_t interpolated_vertex(std::uint64_t edge);

  const CubeNodes& leaves_;
  const FlatHashMap& leaf_index_;
  LatticeSigns& signs_;
  McOctree& tree_;
  FlatHashMap added_on_edge_;       // leaf edge -> vertex added on it
  std::vector<FlatHashMap> memo_;   // per level: edge -> its vertex
  std::vector<std::int32_t> jumps_;
};

// ---- 4. cases and triangles (octree_cases.cpp) -----------------------------

// Every node's case, edge vertices and own triangles, level by level from the
// leaves up. Returns, per node, whether its case bits are the lattice's signs
// at its corners: all but leaves with a corner the field decided (a dropped one).
std::vector<std::uint8_t> cases_and_triangles(const CubeNodes& leaves, const FlatHashMap& leaf_index,
                                              const LevelBegin& level_begin, const std::vector<std::uint8_t>& dropped,
                                              LatticeSigns* signs, EdgeResolver* edges, McOctree* tree);

// ---- 5. transitions (octree_transitions.cpp) -------------------------------

// Transition data for the nodes above the leaves: signs and crossings on the
// boundary refined to the next level, and the neighbouring nodes.
void transition_data(const LevelBegin& level_begin, const std::vector<std::uint8_t>& cases_are_signs,
                     LatticeSigns* signs, EdgeResolver* edges, McOctree* tree);

// A node's neighbours in the 27 cells around it (13: itself), from its
// parent's, which must be found first: nodes in index order fill them
// (octree_keys.cpp).
void find_neighbours(std::int32_t node, McOctree* tree);

// ---- 6. jump vertices (octree_jumps.cpp) -----------------------------------

// Moves each vertex of `jumps` (EdgeResolver::jumps) to within half a leaf
// cube of its closest point on the mesh.
void pull_jump_vertices(const std::vector<std::int32_t>& jumps, const ClosestPoints& closest, McOctree* tree);

// ---- 7. added vertices (octree_centres.cpp) --------------------------------

// Normals and colours of the vertices from `first_added` on: normals from the
// triangles around them, colours from their neighbours.
void added_vertex_attributes(std::size_t first_added, McOctree* tree);

// ---- 8. level vertices (octree_level_vertices.cpp) -------------------------

// Gives each level above the leaves its own copy of every mesh vertex its
// edges resolve to, placed by the mesh's tangent planes around it, and points
// the level's edges, sub-edges (of the level above) and own triangles at the
// copies. Their normals and colours are the copied vertex's.
void level_vertices(const TriangleMesh& mesh, const LevelBegin& level_begin, McOctree* tree);

// ---- 8b. own triangulations (octree_triangulations.cpp) --------------------

// Cuts each coarse node's polygons where its triangles lie nearest the mesh
// (`field`'s distance), in place: the same count of triangles per node.
void own_triangulations(const MeshField& field, const LevelBegin& level_begin, McOctree* tree);

// ---- 9. metric (octree_metric.cpp) -----------------------------------------

// Sums over the leaf triangles under each node, bottom-up.
struct LeafSums {
  double area = 0.0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();   // exact area moments
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d planes = Eigen::Matrix3d::Zero();  // their planes' quadric: sum of a n n^T
  Eigen::Vector3d offsets = Eigen::Vector3d::Zero();  // and of a n (n . p)

  LeafSums& operator+=(const LeafSums& o) {
    area += o.area;
    first += o.first;
    second += o.second;
    planes += o.planes;
    offsets += o.offsets;
    return *this;
  }
};

// The sums of the nodes above the leaves (the first `internal` nodes).
std::vector<LeafSums> leaf_sums(const McOctree& tree, std::size_t internal);

// The LOD metric of every node above the leaves (0 for leaves).
void compute_metrics(LodMetric metric, const std::vector<LeafSums>& sums, McOctree* tree);

// ---- 10. patch groups (octree_patches.cpp) ---------------------------------

// Groups the hole patches by hole (triangles joined by shared edges) and gives
// each group the parents of the leaves along its rim.
void group_patches(const std::vector<Triangle>& patches, McOctree* tree);

// ---- 11. centre vertices (octree_centres.cpp) ------------------------------

// One centre vertex per node above the leaves, for its transition fans: the
// mean of its own crossings (of its boundary's where it has none), fitted to
// the leaves' planes below and moved where its fans would fold.
void centre_vertices(const std::vector<LeafSums>& sums, McOctree* tree);

// ---- 12. straight faces (octree_straight_faces.cpp) ------------------------

// Every internal node's straight faces (OctreeTransitions::straight_faces),
// from the vertices' final positions.
void find_straight_faces(ArrayView<Vec3f> positions, McOctree* tree);

}  // namespace octree_build
}  // namespace scan2lod
