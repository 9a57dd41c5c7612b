// The cluster hierarchy: continuous LOD from edge collapses, drawn cluster by
// cluster. Cignoni et al., *Batched Multi-Triangulation* (2005); Karis,
// *Nanite: A Deep Dive* (2021).
//
// The full mesh is cut into clusters of about 128 triangles. Then, round after
// round, neighbouring clusters are partitioned into groups (METIS, by shared
// border), each group is simplified to about half by quadric edge collapse
// with only the vertices it shares with other groups locked, and the result is
// cut into new clusters that join the next round. Every border is thus
// simplified one round up, and the scan's real open boundaries simplify along
// themselves from the start.
//
// Each cluster carries two group errors: its own (of the group that made it;
// 0 at full detail) and its parent's (of the group it was simplified in next;
// none at the top). Errors never shrink going up and group bounds enclose the
// bounds below, so the rule "draw c when own(c) <= t < parent(c)" decides each
// cluster alone and the union is watertight, for one t everywhere or for a t
// that is the error projected to the screen.
#pragma once

#include <scan2lod/core/array_view.h>
#include <scan2lod/core/types.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace scan2lod {

class TriangleSpool;
class ClusterPages;
class WorkSharing;

// A bounding sphere and the object-space error of the simplification that
// made a group (Hausdorff-like: the largest distance of a vertex it removed
// or moved from the surface that replaced it, plus the largest error below,
// so never less than the groups below it).
struct GroupBound {
  float center[3];
  float radius;
  float error;
};

struct Cluster {
  std::uint32_t first_triangle;  // into ClusterHierarchy::triangles
  std::uint16_t triangle_count;
  std::uint8_t level;            // DAG round: 0 at full detail
  std::uint8_t reserved = 0;
  std::int32_t own_group;        // the group that made it, -1 at full detail (error 0)
  std::int32_t parent_group;     // the group it is simplified in next, -1 at the top
};

// A run of clusters whose triangles are one run of the model file's 'CTRI'
// section: the unit a viewer reads from disk. A cut at error t draws a
// cluster of the page only if min_error <= t < max_error; the sphere holds
// every cluster of the page (from the groups' spheres: radius infinite when
// the hierarchy has no group).
struct ClusterPage {
  std::uint32_t first_cluster;
  std::uint32_t cluster_count;
  float center[3];
  float radius;
  float min_error;  // the least own error of its clusters (0 at full detail)
  float max_error;  // the largest parent error of its clusters (infinite at the top)
};

struct ClusterHierarchy {
  std::vector<Cluster> clusters;      // as finished: level by level in core, block by block in blocks
  std::vector<Triangle> triangles;    // every cluster's, into the model's shared vertices
  std::vector<GroupBound> groups;     // errors and bounds of the simplified groups
  // Per group, what cuts by triangle count rank groups by: its mean
  // deviation (of the vertices it removed or moved) plus the largest rank
  // below, so that it never falls going up either. The largest deviation
  // (GroupBound::error) bounds what a cut at an error, or on screen, may
  // show; ranked by it, groups with one stray vertex came late in every cut
  // by count (the pair's scans at R = 256 cut at 50 k and 100 k of 196 k
  // triangles: 1.16x and 1.65x VTK QuadricDecimation's error, 1.12x and
  // 1.53x ranked by the mean, normals at 0.0005). Empty (a model from
  // before 4.7): the errors.
  std::vector<float> group_ranks;
  std::int64_t full_triangles = 0;    // triangles of the full-detail cut
  // Set by a build in blocks with a spool: `triangles` is empty and the
  // clusters index the spool's triangles instead, on disk until the model
  // is written (lod/clusters/triangle_spool.h). load_spooled() brings them in.
  std::shared_ptr<TriangleSpool> spool;
  // Set by open_paged_model: `triangles` is empty, and cuts read their
  // triangles and vertices page by page from the file (lod/clusters/paged_model.h).
  std::shared_ptr<ClusterPages> paged;
  // Left by the build: the vertices its collapses placed, indexed from the
  // count of positions it was given. add_cluster_hierarchy moves them into
  // the model's vertices; a model file does not hold them apart.
  std::vector<Vec3f> added_positions, added_normals;  // normals: when the mesh has them
  std::vector<Rgb> added_colors;                      // when the mesh has them

  std::size_t size() const { return clusters.size(); }
  int levels() const;                 // DAG rounds, 1 for a hierarchy of one level
  // Clusters in consecutive runs of about kPageTriangles triangles (a run
  // ends early where triangles are not contiguous); made by the build and
  // kept in the model file.
  std::vector<ClusterPage> pages;
  std::uint64_t stored_triangles() const;  // in memory or spooled
  void load_spooled();                // the spool's triangles into `triangles`
};

// Blocks of a large mesh's hierarchy, the same whatever the memory: a
// build within a budget (in bricks) and one without make the same
// hierarchy, since the blocks, and the order inside each, follow from the
// triangles' positions alone. 2^17 triangles take about 50 MiB of working
// memory, which a 400 MiB budget holds beside a 4 M-triangle mesh.
constexpr std::int64_t kBlockTriangles = std::int64_t(1) << 17;
// Up to this many triangles the hierarchy is built whole: faster on two
// cores, where blocks run one after another.
constexpr std::int64_t kWholeMeshTriangles = std::int64_t(1) << 20;
constexpr std::int64_t kAutomaticBlocks = -1;

// The blocks `options_block` (ClusterOptions::block_triangles) gives a mesh
// of `triangles`: 0 when it is built whole.
std::int64_t block_triangles_for(std::int64_t options_block, std::size_t triangles);

// What a build in blocks did, for reports.
struct ClusterBuildStats {
  std::size_t blocks = 0;       // made in the passes in blocks (the rounds to the top not counted)
  std::size_t blocks_here = 0;  // of them, made by this process (all of them without ClusterOptions::sharing)
  double bytes_exchanged = 0;   // sent to and received from the other ranks: the mesh, then blocks
};

// Every field that shapes the hierarchy also travels to the other ranks of a
// job (HierarchyStart, lod/clusters/cluster_hierarchy.cpp): a new one must
// join it there, or the ranks build different blocks.
struct ClusterOptions {
  int cluster_triangles = 128;   // most triangles per cluster
  int group_clusters = 32;       // clusters per group, about (8 and 16 stall on the bunny: bench/lod)
  double reduction = 0.5;        // a group is simplified to this share of its triangles
  // The same in the first round: lighter, so that cuts near full detail,
  // which mix full-detail groups with first-round ones, mix less. At 0.5,
  // bun_zipper.ply's own triangles cut at 49 k of 69 k were 1.17x the error
  // of meshopt_simplify, at 58 k 1.33x; at 0.65 0.93x and 1.06x, for 2.3x
  // the full mesh's triangles stored, not 2.0x.
  double first_reduction = 0.65;
  double stall = 0.85;           // a group that keeps more than this share did not simplify
  // Weights of the attributes in the generalized quadrics (Garland and
  // Heckbert, *Simplifying Surfaces with Color and Texture using Quadric Error
  // Metrics*, 1998), against positions scaled to a unit diagonal: a unit
  // normal turned by 90 degrees or a colour channel running its whole range
  // costs what a move of `weight` diagonals does. 0 ignores the attribute.
  // Normals at 0.002 chose the collapses at fine levels (the bunny at R = 128
  // was 1.47x meshopt_simplify's error at 50k, 1.08x at 0.0005); at 0.0005
  // still, where deviations are millionths of the diagonal (with groups
  // ranked by their mean deviation, the pair's scans at R = 256 cut at 100 k
  // of 196 k triangles were 1.53x VTK QuadricDecimation's error; 1.40x at
  // 0.0001, 1.39x without normals, whose cuts on screen at 1 px held 24 %
  // more triangles than at 0.0001). Colours at 0.0005 no longer kept a
  // scanned sphere's colour bands (tests/test_clusters).
  float normal_weight = 0.0001f;
  float color_weight = 0.002f;
  // Each collapse places its vertex at the quadric's minimum, adding a
  // vertex; false keeps an end of the edge and adds none.
  bool optimal_placement = true;
  int threads = 0;               // 0: every core
  // Above 0, a mesh of more triangles is built in blocks of about this many,
  // so that the build's working memory is a block's, not the mesh's: each
  // block simplified with the vertices it shares with other blocks locked,
  // then what is left regrouped across those borders, pass after pass.
  // 0: the whole mesh at once. kAutomaticBlocks: the whole mesh up to
  // kWholeMeshTriangles, blocks of kBlockTriangles above.
  std::int64_t block_triangles = kAutomaticBlocks;
  // In blocks: how many blocks of a pass run side by side, each on a thread
  // of its own, holding a block's working memory each (0: one a thread).
  // The model is the same at any number.
  int lanes = 0;
  // With block_triangles: finished clusters' triangles go here as each block
  // ends, not to memory (ClusterHierarchy::spool).
  std::shared_ptr<TriangleSpool> spool;
  // In blocks, on rank 0 of a job of several ranks: the blocks of each pass
  // are made on every rank, the other ranks serving in
  // serve_cluster_hierarchy() (lod/clusters/hierarchy_ranks.h). The model is
  // the same at any number of ranks. Null: this process alone.
  WorkSharing* sharing = nullptr;
  // Filled when not null.
  ClusterBuildStats* stats = nullptr;
  // Called with the share of the triangles simplified so far (0 to 1); may be empty.
  std::function<void(double)> progress;
};

// Triangles the coarsest cut holds at most, on any mesh with fewer pieces
// than this: where edge collapse stalls above it, the last step clusters
// what is left (lod/clusters/group_clustering.h).
constexpr std::size_t kCoarsestTriangles = 256;
// Cuts of at least this many triangles keep the full mesh's soundness (no
// non-manifold edge, no more boundary loops or pieces); smaller ones may
// close handles, but keep every piece.
constexpr std::size_t kSoundCutTriangles = 1000;

// Triangles a page holds at most, unless one cluster holds more (64 KiB at
// 12 bytes a triangle: one read from a disk or over HTTP).
constexpr std::uint32_t kPageTriangles = 5461;

// The pages of `h`'s clusters as they lie (h.pages is not read).
std::vector<ClusterPage> cluster_pages(const ClusterHierarchy& h);

// Builds the hierarchy over `triangles`, which index `positions` (and
// `normals`, `colors` when those are not empty, one per position). The
// triangles are taken as they are: they are the finest cut, in cluster order.
// Vertices with equal positions are treated as one for adjacency and locking.
// With optimal_placement the collapses add vertices (ClusterHierarchy::
// added_positions). Throws InputError when there are no triangles.
ClusterHierarchy build_cluster_hierarchy(ArrayView<Vec3f> positions, ArrayView<Vec3f> normals,
                                         ArrayView<Rgb> colors, std::vector<Triangle> triangles,
                                         const ClusterOptions& options = {});

}  // namespace scan2lod
