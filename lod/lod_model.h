// The LOD face: one model, one shared vertex array, one or more LOD
// structures, and levels asked for by percent, triangle budget, object-space
// error or camera. Every caller (the command line, the viewer, the benchmarks)
// goes through this header; none reads a structure's arrays.
//
// Structures:
// - the prioritized marching-cube octree (Lee, *Efficient LOD Model
//   Generation of 3D Objects using Prioritized Marching Cube Octree*, 2007):
//   lod/octree/mc_octree.h, lod/octree/lod_array.h, lod/octree/extract.h;
// - the cluster hierarchy (Cignoni et al., *Batched Multi-Triangulation*,
//   2005): lod/clusters/cluster_hierarchy.h, lod/clusters/cluster_cut.h.
// A level of either is an index buffer into the model's vertices. Each
// structure implements lod/structure.h in its own room, and the registration
// (lod/registered_structures.h and .cpp) names it and lists it: what is
// generic walks that list (lod/structure.h says what).
#pragma once

#include <scan2lod/core/types.h>
#include <scan2lod/lod/clusters/cluster_cut.h>
#include <scan2lod/lod/registered_structures.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace scan2lod {

// "octree" or "clusters", as the command line spells them.
const char* structure_name(LodStructure s);
// Every registered structure's name, in the order the command line offers
// them: what its --structure options accept.
std::vector<std::string> structure_names();

// The structures' members (octree, clusters) come from the registration.
struct LodModel : RegisteredStructures {
  VertexArray vertices;
  // The point of the inputs' own frame that the vertices are relative to:
  // input frame = origin + position, added in double (AcquisitionReport::
  // origin). Zero but for georeferenced inputs (LAS), whose coordinates a
  // float cannot hold; writers given it (MeshWriteOptions::origin) put levels
  // back in the inputs' frame. Not the octree's grid origin (McOctree::grid).
  Vec3d origin = Vec3d::Zero();
  // What the cluster hierarchy indexes: vertices [first, first + count).
  std::size_t cluster_vertex_first = 0, cluster_vertex_count = 0;

  bool has(LodStructure s) const;
};

// The structure used when none is named: the first registered one the model
// has (the cluster hierarchy, the more faithful, before the octree).
LodStructure default_structure(const LodModel& model);

// The structure `name` (one of structure_names(), or empty for the default) of
// `model`. Throws InputError for another name or a structure the model lacks.
LodStructure structure_named(const LodModel& model, const std::string& name, const std::string& source);

// Throws InputError (naming `source`) unless the model holds `s`.
void require_structure(const LodModel& model, LodStructure s, const std::string& source);

// Takes ownership of an octree built by build_mc_octree and number_nodes; its
// vertex arrays become the model's shared vertices.
LodModel model_from_octree(McOctree tree, LodArray lod);

// Adds a cluster hierarchy built over `mesh`'s triangles. When `mesh` indexes
// the model's vertices already (`shares_vertices`: a reconstruction whose mesh
// is the octree's first vertices), nothing is copied; otherwise its vertices
// are appended. Without vertices yet, the mesh's become the model's.
void add_cluster_hierarchy(LodModel* model, const TriangleMesh& mesh, bool shares_vertices,
                           const ClusterOptions& options = {});
// The same, taking the mesh's arrays instead of copying them.
void add_cluster_hierarchy(LodModel* model, TriangleMesh&& mesh, bool shares_vertices,
                           const ClusterOptions& options = {});

// What a level is asked for by. Exactly one of them.
struct LevelRequest {
  enum class Kind { kPercent, kTriangles, kError, kCamera, kPriority };
  Kind kind = Kind::kPercent;
  double percent = 100;          // octree: of the LOD array; clusters: of the full triangle count
  // Within 10 % of this many (lod/level_budget.h); with `strict`, the finest
  // level with at most this many.
  std::int64_t triangles = 0;
  bool strict = false;
  // Cluster hierarchy, by percent or triangles: a finer stored cut refined to
  // the count by edge collapse where one is near (lod/clusters/cut_refinement.h);
  // false gives the stored cut as it is.
  bool refine = true;
  double error = 0;              // object-space error, in the model's units (clusters only)
  CameraView camera;             // with pixel_error (clusters only)
  double pixel_error = 1;
  std::size_t priority = 0;      // expansions of the LOD array (octree only)

  static LevelRequest at_percent(double p);
  static LevelRequest at_triangles(std::int64_t t);
  static LevelRequest at_most_triangles(std::int64_t t);  // strict
  static LevelRequest at_error(double e);
  static LevelRequest for_camera(const CameraView& c, double pixel_error);
  static LevelRequest at_priority(std::size_t p);
};

class StructureLevels;  // lod/structure.h

// One level: an index buffer into the model's vertices, and how it was chosen.
struct LevelCut {
  LodStructure structure = LodStructure::kClusters;
  std::vector<Triangle> triangles;
  std::size_t clusters = 0;      // clusters drawn (cluster hierarchy)
  std::size_t priority = 0;      // expansions (octree)
  double error = 0;              // the uniform threshold (cluster hierarchy; camera: 0)
  double percent = 100;          // of the structure's full detail (triangles for clusters)
  std::size_t refined_from = 0;  // the stored cut's triangles, when refined to the count; else 0
  double select_seconds = 0;     // choosing the cut
  double extract_seconds = 0;    // choosing and writing the index buffer
};

// Takes levels from one structure of one model, keeping scratch space and the
// cut tables between calls (a slider or a moving camera asks many times).
class LevelExtractor {
 public:
  // Throws InputError if the model lacks `structure`.
  LevelExtractor(const LodModel& model, LodStructure structure);
  LevelExtractor(LevelExtractor&&) noexcept;
  LevelExtractor& operator=(LevelExtractor&&) noexcept;
  ~LevelExtractor();
  // Throws InputError for a request the structure does not offer (an error or
  // camera for the octree, a priority for the clusters, a priority past the
  // LOD array's end).
  const LevelCut& extract(const LevelRequest& request);
  const LodModel& model() const { return *model_; }
  LodStructure structure() const { return structure_; }
  // The octree's priority number for a percent, budget or priority request,
  // as extract() chooses it (octree only). Throws InputError otherwise.
  std::size_t octree_priority(const LevelRequest& request) const;
  // Triangles at full detail.
  std::int64_t full_triangles() const;
  // Triangles of the coarsest level offered.
  std::int64_t coarsest_triangles() const;
  // The offered levels nearest a triangle count: the most triangles at or
  // under `triangles` and the fewest over it (-1 where there is none). Where
  // both are more than kBudgetTolerance away, no level meets that budget.
  std::pair<std::int64_t, std::int64_t> offered_around(std::int64_t triangles) const;
  // Per triangle of the last cut, its cluster's DAG level (clusters; 0 at full
  // detail), or 0 for the octree: what views colour by.
  std::vector<std::uint8_t> triangle_levels() const;
  // Levels a view may colour: the octree's depth + 1 or the DAG's rounds.
  int levels() const;

 private:
  const LodModel* model_;
  LodStructure structure_;
  LevelCut cut_;
  std::unique_ptr<StructureLevels> levels_;  // the structure's own, with its scratch and tables
};

// A self-contained mesh of one level's triangles: only the vertices they use.
TriangleMesh compact_level(const LodModel& model, const std::vector<Triangle>& triangles);

// The box around every vertex any level can use.
Aabb model_bounds(const LodModel& model);

// What each structure holds, for `info` and summaries.
struct OctreeSummary {
  int resolution = 0, depth = 0;
  double cube_size = 0;
  Vec3d origin = Vec3d::Zero();
  std::size_t nodes = 0, leaves = 0, expansions = 0, pinned = 0;
  std::int64_t pinned_triangles = 0, full_triangles = 0;
  std::size_t offered_levels = 0;        // monotone_priorities' count
  std::int64_t coarsest_triangles = 0;   // of the coarsest offered level
  std::vector<std::size_t> nodes_per_level;
};
struct ClusterSummary {
  std::size_t clusters = 0, groups = 0, stored_triangles = 0;
  int levels = 0;
  std::int64_t full_triangles = 0, coarsest_triangles = 0;
};
// Throw InputError unless the model holds that structure.
OctreeSummary describe_octree(const LodModel& model);
ClusterSummary describe_clusters(const LodModel& model);

// A model's stored levels at the given percentages (cluster cuts not refined
// to the count), for tables and plots: triangles and distinct vertices of
// each.
struct LevelSummary {
  double percent = 0;
  std::size_t priority = 0;    // octree
  double error = 0;            // clusters
  std::size_t triangles = 0, vertices = 0, clusters = 0;
};
std::vector<LevelSummary> summarize_levels(const LodModel& model, LodStructure structure,
                                           const std::vector<double>& percents);

}  // namespace scan2lod
