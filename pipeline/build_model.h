// The one way a LOD model is built: inputs -> oriented points ->
// reconstruction -> the LOD structures. The command line, the benches and
// (later) the Python package call this; none spells the sequence out again.
//
// Two strategies stand behind it, chosen from the reconstruction's estimate
// against the memory budget: in core (reconstruct()), or brick by brick
// (reconstruct_in_bricks(), with a work folder to resume from).
#pragma once

#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/reconstruct/brick_reconstruction.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include <memory>
#include <string>
#include <vector>

namespace scan2lod {

enum class BuildStrategy { kAutomatic, kInCore, kBricks };

struct BuildOptions {
  ReconstructOptions reconstruct;
  AcquisitionOptions acquisition;
  bool octree = true;    // the prioritized marching-cube octree (Lee 2007)
  bool clusters = true;  // the cluster hierarchy (Cignoni et al. 2005)
  LodMetric metric = LodMetric::kDeviation;
  // Memory the build may take, in bytes; 0: what the machine has available,
  // less a margin (available_memory_bytes()).
  double memory_bytes = 0;
  BuildStrategy strategy = BuildStrategy::kAutomatic;
  std::string work_dir;  // where bricks are kept; required when the build runs in bricks
  int brick_cubes = 0;   // cubes per brick side; 0: from the memory budget
  // Triangles per block of the cluster hierarchy (ClusterOptions::
  // block_triangles); 0: blocks of kBlockTriangles above kWholeMeshTriangles,
  // smaller only when the budget cannot hold those.
  std::int64_t cluster_block = 0;
  // The ranks of an MPI job that share the bricks (distributed/work_sharing.h),
  // all seeing work_dir at the same path; null: this process alone. On rank
  // 0 build_model() runs the whole build; the other ranks call serve_build().
  WorkSharing* sharing = nullptr;
};

struct BuildReport {
  std::size_t points = 0;
  bool mesh_input = false;        // one mesh given: its own triangles are the clusters' full detail
  bool in_bricks = false;         // the strategy that ran
  double estimated_bytes = 0;     // the in-core reconstruction's estimate
  double budget_bytes = 0;        // the budget that held: --memory, or what was available
  BrickPlan plan;                 // when in bricks
  BrickStats bricks;              // when in bricks
  ReconstructStats reconstruct;
  AcquisitionReport acquisition;
  std::vector<std::string> warnings;
  // Memory: estimated before each stage, and the process's peak measured after it.
  double estimated_cluster_bytes = 0;  // the stage's peak: in core, or in blocks (then the process's)
  std::int64_t cluster_block = 0;  // triangles per block of the hierarchy; 0: built in core
  int cluster_lanes = 0;           // blocks of a pass run side by side (ClusterOptions::lanes)
  ClusterBuildStats cluster_blocks;  // blocks made, here and on the other ranks
  double peak_bytes_reconstruct = 0, peak_bytes_octree = 0, peak_bytes_clusters = 0;
  std::size_t full_triangles = 0;  // the reconstruction's (or the mesh input's)
  // Wall-clock seconds per stage; the octree's build is seconds_octree, of
  // which seconds_numbering is the priority numbering.
  double seconds_read = 0, seconds_reconstruct = 0, seconds_octree = 0, seconds_numbering = 0, seconds_clusters = 0;
};

// On a rank other than 0 of options.sharing: its share of the build that
// rank 0 runs with the same inputs and options: it reads its share of the
// input files (load_within_budget()), bins them when the points go by
// bricks from every rank, and runs the bricks it is handed out; returns when
// its part is over. It writes nothing but its spool, its bins and bricks in
// options.work_dir.
void serve_build(const std::vector<std::string>& inputs, const BuildOptions& options);

// @param[in] inputs  what load_oriented_points() takes
// Throws InputError for unreadable input, for no surface, for a budget that
// no strategy fits (naming the minimum), and for the octree in bricks (it
// needs the in-core reconstruction's leaf cubes).
LodModel build_model(const std::vector<std::string>& inputs, const BuildOptions& options,
                     BuildReport* report = nullptr);

// The inputs' oriented points: in memory while they take less than a quarter
// of the budget (past that the in-core reconstruction cannot fit), else
// spooled to options.work_dir as the files are read, a few at a time; always
// spooled when the strategy is bricks. Collective under options.sharing of
// several ranks: each reads a share of the files into a spool of its own;
// points that fit as above are then rank 0's in memory, else each rank's
// spool is its share of the job's (PointSpool::join). The report is of
// every rank's files, on every rank.
struct InputPoints {
  OrientedPoints points;              // in memory
  std::unique_ptr<PointSpool> spool;  // or on disk (closed)
  std::string made_folder;            // the work folder the spool made, removed with it when left empty
  // When the spool is a share of a job's points: rank 0's budget, which
  // every rank plans the bricks with (free memory differs between ranks).
  double job_budget = 0;
  std::size_t size() const { return spool ? spool->job_census().count : points.size(); }
  void release() { points = OrientedPoints(), spool.reset(); }
  InputPoints() = default;
  InputPoints(InputPoints&&) = default;
  ~InputPoints();
};
InputPoints load_within_budget(const std::vector<std::string>& inputs, const BuildOptions& options,
                               AcquisitionReport* report = nullptr);

// The reconstruction build_model() makes: in core when its estimate fits
// options.memory_bytes, else brick by brick in options.work_dir (then the
// octree is refused, and `leaves` is empty); spooled points always go by
// bricks. Frees the points (memory or spool) once it is done with them:
// in bricks, as soon as they are binned. Fills the report's strategy,
// estimate, plan and brick counts.
Reconstruction reconstruct_within_budget(InputPoints* points, const BuildOptions& options,
                                         BuildReport* report = nullptr);

// The same from points already loaded (benches, tests); `mesh`, when not
// null, is the one mesh input whose triangles the clusters keep.
LodModel build_model(const OrientedPoints& points, const TriangleMesh* mesh, const BuildOptions& options,
                     BuildReport* report = nullptr);

}  // namespace scan2lod
