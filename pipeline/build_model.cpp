#include <scan2lod/pipeline/build_model.h>

#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/core/vertex_order.h>
#include <scan2lod/distributed/message.h>
#include <scan2lod/distributed/work_sharing.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/lod/clusters/hierarchy_ranks.h>
#include <scan2lod/lod/clusters/triangle_spool.h>
#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/mc_octree.h>
#include <scan2lod/lod/octree/octree_order.h>
#include <scan2lod/pipeline/build_progress.h>
#include <scan2lod/reconstruct/resolution_guard.h>

#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>
#include <functional>

namespace scan2lod {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// The process's peak resident memory so far.
double peak_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) * 1024.0;
}

// The process's resident memory now.
double resident_bytes() {
  long pages = 0, resident = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    std::fclose(f);
  }
  return double(resident) * double(sysconf(_SC_PAGESIZE));
}

// The cluster stage's peak over the memory resident when it starts (which
// holds the mesh), measured in bricks at 23fe5ae (the bunny's scans at
// R = 256, 0.43 M triangles; the pair's 16 at R = 1024, 3.27 M; 9.8 M points
// at R = 2048, 13.1 M): a fixed 17 MiB (threads and their scratch), and
// - built whole, 119 bytes a triangle of the full mesh;
// - in blocks, 36 bytes a triangle (the per-vertex tables, the vertices the
//   collapses place, the triangles carried from pass to pass), 30 bytes a
//   triangle of the block each lane works on, and 14 bytes a triangle more
//   when the finished clusters stay in memory, not in a spool.
// (Before, thread-local tables of every vertex, filled anew every round, cost
// about 400 bytes a block triangle.) The rest of the budget sizes the
// blocks, never below kSmallestBlock: a budget too small for that is warned
// of, since the surface is made by then.
constexpr double kClusterFixedBytes = 17.0 * (1 << 20);
constexpr double kWholeBytesPerTriangle = 119.0;
constexpr double kBlockedBytesPerTriangle = 36.0;
constexpr double kBlockBytesPerTriangle = 30.0;
constexpr double kHeldClusterBytesPerTriangle = 14.0;
constexpr std::int64_t kSmallestBlock = 65536;
// The mesh the stage starts from: 12 bytes a triangle, and half a vertex a
// triangle with its position and normal.
constexpr double kMeshBytesPerTriangle = 12.0 + 0.5 * 24.0;

// The cluster stage's peak built whole, and in blocks of `block` triangles.
double whole_cluster_bytes(std::size_t triangles) {
  return resident_bytes() + kClusterFixedBytes + kWholeBytesPerTriangle * double(triangles);
}
double blocked_cluster_bytes(std::size_t triangles, std::int64_t block) {
  return resident_bytes() + kClusterFixedBytes + kBlockedBytesPerTriangle * double(triangles) +
         kBlockBytesPerTriangle * double(block);
}

std::int64_t cluster_block_for(double budget, std::size_t triangles, BuildReport* report) {
  const double without_block = blocked_cluster_bytes(triangles, 0);
  const std::int64_t block = std::int64_t((budget - without_block) / kBlockBytesPerTriangle);
  if (block < kSmallestBlock)
    report->warnings.push_back("the cluster hierarchy of " + std::to_string(triangles) + " triangles needs about " +
                               binary_size(blocked_cluster_bytes(triangles, kSmallestBlock)) +
                               " in its smallest blocks, over the budget of " + binary_size(budget));
  return std::max(block, kSmallestBlock);
}

// The hierarchy's blocks (0: whole): as asked, else those of every build
// (block_triangles_for), unless the budget cannot hold them; then the
// largest it holds, no larger than the usual blocks, and the hierarchy is
// not the one a larger budget makes.
std::int64_t choose_cluster_block(std::int64_t asked, std::size_t triangles, double budget, BuildReport* report) {
  if (asked > 0) return asked;
  const std::int64_t block = block_triangles_for(kAutomaticBlocks, triangles);
  const double needs = block > 0 ? blocked_cluster_bytes(triangles, block) : whole_cluster_bytes(triangles);
  if (needs <= budget) return block;
  const std::int64_t held = std::min(cluster_block_for(budget, triangles, report), kBlockTriangles);
  if (block > 0 && held >= block) return block;
  report->warnings.push_back("the budget of " + binary_size(budget) + " holds cluster blocks of " +
                             std::to_string(held) + " triangles, not " +
                             (block > 0 ? std::to_string(block) : "the whole mesh") +
                             ": the hierarchy differs from the one a build with more memory makes");
  return held;
}

// A reconstruction touches about 1.9 triangles a cube (the pair's scans:
// 13.1 M triangles over 6.95 M estimated cubes at R = 2048, 52.5 M over
// 28.0 M at 4096).
constexpr double kTrianglesPerCube = 1.9;

// The weld and the cluster hierarchy still hold the whole surface, whatever
// the budget: where they need more than the machine has, the build is
// refused before its bricks, not killed for want of memory hours into it.
// The surface grows with R^2, so the message names the finest power-of-two
// resolution they would fit.
void refuse_what_the_machine_cannot_hold(const BrickPlan& plan, const BuildOptions& options) {
  const double machine = machine_memory_bytes();
  const double triangles = kTrianglesPerCube * plan.cubes;
  const double hierarchy =
      options.clusters ? blocked_cluster_bytes(std::size_t(triangles), kSmallestBlock) + kMeshBytesPerTriangle * triangles
                       : 0.0;
  const double needs = std::max(plan.weld_bytes, hierarchy);
  if (needs <= machine) return;
  int fits = options.reconstruct.resolution;
  double at = needs;
  while (fits > 64 && at > machine) fits /= 2, at /= 4;
  throw InputError("", "resolution " + std::to_string(options.reconstruct.resolution) +
                           " makes a surface of about " + std::to_string(std::llround(triangles / 1e6)) +
                           " M triangles, whose weld needs about " + binary_size(plan.weld_bytes) +
                           (options.clusters ? " and whose cluster hierarchy about " + binary_size(hierarchy) : "") +
                           ", more than this machine's " + binary_size(machine) +
                           ": those stages hold the whole surface in memory (the bricks keep to the budget); "
                           "--resolution " + std::to_string(fits) + " would need about " + binary_size(at));
}

// A build under a budget: every array of a megabyte or more in a mapping of
// its own from here on, so that freed it goes back to the system at once.
// glibc's default raises that threshold to 32 MiB as large blocks are freed,
// and the arrays the weld and the hierarchy grow by doubling then fragment
// the heap: the pair's 1 M points at R = 1024 under 400M peaked at 347 MiB,
// against 285 MiB with this, for 0.75 M more page faults (1 s of the 2
// cores' 35 s). Set from the start when a budget is given (the points'
// arrays freed raise the threshold first), else once bricks are chosen. The
// setting is the process's, and stays.
void hand_large_arrays_back_when_freed() { mallopt(M_MMAP_THRESHOLD, 1 << 20); }

// Phase 2: the strategy, from the in-core estimate against the budget.
// Spooled points go by bricks: they took a quarter of the budget alone.
bool choose_bricks(const OrientedPoints* points, const BuildOptions& options, double budget, BuildReport* report) {
  if (!points) return true;
  report->estimated_bytes = estimate_reconstruction(*points, options.reconstruct.resolution, options.reconstruct.threads).bytes;
  switch (options.strategy) {
    case BuildStrategy::kInCore: return false;
    case BuildStrategy::kBricks: return true;
    case BuildStrategy::kAutomatic: break;
  }
  return report->estimated_bytes > budget;
}

// The reconstruction from points in memory or spooled (one of the two);
// release() once they are not needed any more.
Reconstruction reconstruct_budgeted(const OrientedPoints* points, const PointSpool* spool, const BuildOptions& options,
                                    BuildReport* report, const std::function<void()>& release) {
  const double budget = options.memory_bytes > 0 ? options.memory_bytes : available_memory_bytes();
  report->budget_bytes = budget;
  report->in_bricks = choose_bricks(points, options, budget, report);
  if (spool && options.strategy == BuildStrategy::kInCore)
    throw InputError("", "the points alone take over a quarter of the budget of " + binary_size(budget) +
                             ": an in-core reconstruction cannot fit; leave the strategy to the budget");
  // The octree needs every leaf cube at once. With no budget given, a build
  // that fits the machine (the limit before bricks existed) stays in core.
  if (points && report->in_bricks && options.octree && options.strategy == BuildStrategy::kAutomatic &&
      options.memory_bytes <= 0 && report->estimated_bytes <= machine_memory_bytes()) {
    report->in_bricks = false;
    report->warnings.push_back("the reconstruction needs about " + binary_size(report->estimated_bytes) +
                               " in core, more than the " + binary_size(budget) +
                               " available now; it runs in core for the octree (--structure clusters runs in bricks)");
  }
  if (!report->in_bricks) {
    release_brick_workers(options.sharing);
    ReconstructOptions in_core = options.reconstruct;
    if (in_core.memory_limit <= 0 && options.memory_bytes > 0) in_core.memory_limit = options.memory_bytes;
    Reconstruction r = reconstruct(*points, in_core);
    release();
    return r;
  }
  BrickOptions bricks;
  bricks.work_dir = options.work_dir;
  bricks.memory_bytes = budget;
  bricks.brick_cubes = options.brick_cubes;
  bricks.points_binned = release;
  bricks.sharing = options.sharing;
  if (options.octree)
    throw InputError("", (spool ? "the points alone take over a quarter of the budget of " + binary_size(budget)
                                : "the reconstruction needs about " + binary_size(report->estimated_bytes) +
                                      " in core and the budget is " + binary_size(budget)) +
                             ": in bricks only the cluster hierarchy can be built (--structure clusters), since "
                             "the octree needs every leaf cube at once");
  if (options.work_dir.empty()) throw InputError("", "a build in bricks needs a work folder");
  report->plan = spool ? plan_bricks(*spool, options.reconstruct, bricks) : plan_bricks(*points, options.reconstruct, bricks);
  if (spool) report->estimated_bytes = report->plan.estimated_bytes;
  refuse_what_the_machine_cannot_hold(report->plan, options);
  // The bricks hold the budget; the weld after them does not yet: say so.
  if (report->plan.weld_bytes > budget)
    report->warnings.push_back("the welded surface will need about " + binary_size(report->plan.weld_bytes) +
                               ", over the budget of " + binary_size(budget) +
                               ": the bricks keep to it, the weld of their surfaces is not out of core yet");
  hand_large_arrays_back_when_freed();
  return spool ? reconstruct_in_bricks(*spool, options.reconstruct, bricks, &report->bricks, &report->plan)
               : reconstruct_in_bricks(*points, options.reconstruct, bricks, &report->bricks, &report->plan);
}

// Points in memory take about this much each (positions, normals, spacing,
// confidence; colours) on their way in, merged.
constexpr double kInputBytesPerPoint = 36.0;

}  // namespace

InputPoints::~InputPoints() {
  spool.reset();
  std::error_code ec;  // a folder that holds finished bricks stays, to resume from
  if (!made_folder.empty()) std::filesystem::remove(made_folder, ec);
}

namespace {

// The work folder, made if missing; returns it when this call made it.
std::string make_work_folder(const std::string& work_dir) {
  std::error_code ec;
  const bool existed = std::filesystem::exists(work_dir, ec);
  std::filesystem::create_directories(work_dir, ec);
  if (ec && !std::filesystem::is_directory(work_dir, ec))
    throw InputError(work_dir, "cannot make the work folder: " + ec.message());
  return existed ? "" : work_dir;
}

// The spool and the bins each take a record a point: refused when the disk
// cannot hold them for `points` points.
void check_spool_room(const std::string& work_dir, double points) {
  std::error_code ec;
  const double need = 2.0 * double(sizeof(PointRecord)) * points;
  const std::filesystem::space_info space = std::filesystem::space(work_dir, ec);
  if (!ec && double(space.available) < need)
    throw InputError(work_dir, "the input points (about " + std::to_string(std::llround(points / 1e6)) +
                                   " M) need about " + binary_size(need) + " of disk in the work folder and " +
                                   binary_size(double(space.available)) + " are free there");
}

void put_text(MessageWriter* out, const std::string& text) { out->put(std::vector<char>(text.begin(), text.end())); }
std::string get_text(MessageReader* in) {
  std::vector<char> text;
  in->get(&text);
  return std::string(text.begin(), text.end());
}

std::string spool_path(const std::string& work_dir, int rank) {
  return (std::filesystem::path(work_dir) / ("points." + std::to_string(rank) + ".spool")).string();
}

// Under a job of several ranks: each reads its share of the input files into
// a spool of its own, and all learn every share's census and report. Points
// that rank 0 can hold (as load_within_budget() decides for one process) are
// then read back by it from every spool, in rank order; else each rank's
// spool joins the job (PointSpool::join) and every rank bins its own share.
InputPoints load_shares(const std::vector<std::string>& inputs, const BuildOptions& options, AcquisitionReport* report) {
  WorkSharing& job = *options.sharing;
  if (options.work_dir.empty())
    throw InputError("", "a build on several ranks needs a work folder: each rank spools the inputs it reads there");
  InputPoints loaded;
  const std::string made = make_work_folder(options.work_dir);
  if (job.rank() == 0) loaded.made_folder = made;
  loaded.spool = std::make_unique<PointSpool>(spool_path(options.work_dir, job.rank()));
  AcquisitionReport mine;
  bool checked = false;
  stream_oriented_points(inputs, options.acquisition, &mine, [&](OrientedPoints&& part, double read_share) {
    if (!checked) check_spool_room(options.work_dir, double(part.size()) / std::max(read_share, 1e-9)), checked = true;
    loaded.spool->add(part);
    part = OrientedPoints();
  }, InputShare{job.rank(), job.ranks()});
  loaded.spool->close();

  // Rank 0's budget decides for all: what is available differs between machines.
  MessageWriter out;
  put_text(&out, census_bytes(loaded.spool->census()));
  out.put(options.memory_bytes > 0 ? options.memory_bytes : available_memory_bytes());
  out.put(std::uint64_t(mine.range_images)), out.put(std::uint64_t(mine.meshes));
  out.put(std::uint64_t(mine.clouds)), out.put(std::uint64_t(mine.clouds_estimated));
  for (const std::vector<std::string>* list : {&mine.files, &mine.warnings}) {
    out.put(std::uint64_t(list->size()));
    for (const std::string& text : *list) put_text(&out, text);
  }
  std::vector<PointCensus> shares;
  double budget = 0;
  AcquisitionReport all;
  all.origin = mine.origin;  // every rank's: the first LAS input's, whoever reads it
  for (const std::string& bytes : job.gather_all(out.bytes())) {
    MessageReader in(bytes);
    shares.push_back(census_from_bytes(get_text(&in)));
    double rank_budget = 0;
    in.get(&rank_budget);
    if (shares.size() == 1) budget = rank_budget;
    std::uint64_t counts[4] = {};
    for (std::uint64_t& c : counts) in.get(&c);
    all.range_images += counts[0], all.meshes += counts[1], all.clouds += counts[2], all.clouds_estimated += counts[3];
    for (std::vector<std::string>* list : {&all.files, &all.warnings}) {
      std::uint64_t n = 0;
      in.get(&n);
      for (std::uint64_t k = 0; k < n; ++k) list->push_back(get_text(&in));
    }
  }
  if (report) *report = all;
  const PointCensus census = merge_censuses(shares);
  if (options.strategy != BuildStrategy::kBricks && kInputBytesPerPoint * double(census.count) <= 0.25 * budget) {
    // The others keep their spools until rank 0 has read them: they wait
    // for its brick plan (serve_bricks()), which comes after.
    if (job.rank() != 0) return loaded;
    OrientedPoints& points = loaded.points;
    points.positions.reserve(census.count);
    points.normals.reserve(census.count);
    for (int r = 0; r < job.ranks(); ++r)
      for_each_spooled(spool_path(options.work_dir, r), shares[std::size_t(r)].count,
                       [&](const PointRecord* records, std::size_t n) { append_records(records, n, census, &points); });
    loaded.spool.reset();
    return loaded;
  }
  std::size_t first = 0;
  for (int r = 0; r < job.rank(); ++r) first += shares[std::size_t(r)].count;
  loaded.spool->join(census, first);
  loaded.job_budget = budget;
  return loaded;
}

}  // namespace

InputPoints load_within_budget(const std::vector<std::string>& inputs, const BuildOptions& options,
                               AcquisitionReport* report) {
  if (options.sharing && options.sharing->ranks() > 1) return load_shares(inputs, options, report);
  const double budget = options.memory_bytes > 0 ? options.memory_bytes : available_memory_bytes();
  InputPoints loaded;
  std::vector<OrientedPoints> parts;
  double held = 0;
  stream_oriented_points(inputs, options.acquisition, report, [&](OrientedPoints&& part, double read_share) {
    if (!loaded.spool && options.strategy != BuildStrategy::kBricks &&
        held + kInputBytesPerPoint * double(part.size()) <= 0.25 * budget) {
      held += kInputBytesPerPoint * double(part.size());
      parts.push_back(std::move(part));
      return;
    }
    if (!loaded.spool) {
      if (options.work_dir.empty())
        throw InputError("", "a build in bricks needs a work folder: the points go there as they are read");
      loaded.made_folder = make_work_folder(options.work_dir);
      // Projected from the points so far over the share of the input bytes they came from.
      check_spool_room(options.work_dir,
                       (held / kInputBytesPerPoint + double(part.size())) / std::max(read_share, 1e-9));
      loaded.spool = std::make_unique<PointSpool>((std::filesystem::path(options.work_dir) / "points.spool").string());
      for (OrientedPoints& held_part : parts) loaded.spool->add(held_part), held_part = OrientedPoints();
      parts.clear();
    }
    loaded.spool->add(part);
    part = OrientedPoints();
  });
  if (loaded.spool) loaded.spool->close();
  else loaded.points = merge_parts(&parts);
  return loaded;
}

Reconstruction reconstruct_within_budget(InputPoints* points, const BuildOptions& options, BuildReport* report_out) {
  BuildReport local;
  BuildReport* report = report_out ? report_out : &local;
  return reconstruct_budgeted(points->spool ? nullptr : &points->points, points->spool.get(), options, report,
                              [points] { points->release(); });
}

namespace {

// From points in memory or spooled (one of the two); release() frees them
// once the reconstruction is done with them (they are the largest thing a
// big build holds).
LodModel build_from_points(const OrientedPoints* points, const PointSpool* spool, const TriangleMesh* mesh,
                           const BuildOptions& options, BuildReport* report_out, const std::string& source,
                           const std::function<void()>& release, BuildProgress* outer = nullptr) {
  if (!options.octree && !options.clusters) throw InputError("", "no LOD structure asked for");
  BuildReport local;
  BuildReport& report = report_out ? *report_out : local;
  report.points = spool ? spool->job_census().count : points->size();
  report.mesh_input = mesh != nullptr;
  const bool reconstructs = options.octree || !mesh;
  // One progress for the whole build (reconstruction-relative shares).
  std::unique_ptr<BuildProgress> own;
  if (!outer) own = std::make_unique<BuildProgress>(0.0, options.octree ? 4.0 : 0.0,
                                                    options.clusters ? (reconstructs ? 1.6 : 1.0) : 0.0);
  BuildProgress& progress = outer ? *outer : *own;
  auto stage = Clock::now();
  Reconstruction r;
  if (!reconstructs) release_brick_workers(options.sharing);
  if (reconstructs) {
    r = reconstruct_budgeted(points, spool, options, &report, release);
    report.reconstruct = r.stats;
    report.warnings.insert(report.warnings.end(), r.warnings.begin(), r.warnings.end());
    if (r.mesh.triangles.empty())
      throw InputError(source, no_surface_message(r, options.reconstruct.resolution, "--resolution"));
  }
  release();
  report.seconds_reconstruct = seconds_since(stage);
  report.peak_bytes_reconstruct = peak_bytes();
  report.full_triangles = mesh && !options.octree ? mesh->triangles.size() : r.mesh.triangles.size();

  stage = Clock::now();
  LodModel model;
  if (options.octree) {
    progress.octree_started();
    OctreeOptions octree;
    octree.metric = options.metric;
    McOctree tree = build_mc_octree(r, octree);
    const auto numbering = Clock::now();
    LodArray lod = number_nodes(tree);
    model = model_from_octree(std::move(tree), std::move(lod));
    report.seconds_numbering = seconds_since(numbering);
    progress.octree_finished();
  }
  report.seconds_octree = seconds_since(stage);
  report.peak_bytes_octree = peak_bytes();

  stage = Clock::now();
  // What the stages before freed goes back to the system: the threads'
  // heaps keep some otherwise (34 MiB after a 7.2 M-triangle weld).
  malloc_trim(0);
  if (options.clusters) {
    report.estimated_cluster_bytes = whole_cluster_bytes(report.full_triangles);
    const double budget = report.budget_bytes > 0 ? report.budget_bytes : available_memory_bytes();
    report.cluster_block = choose_cluster_block(options.cluster_block, report.full_triangles, budget, &report);
    if (report.cluster_block > 0 && report.full_triangles > std::size_t(report.cluster_block))
      report.estimated_cluster_bytes = blocked_cluster_bytes(report.full_triangles, report.cluster_block);
    Progress bar("clusters", 1000);
    ClusterOptions clusters;
    clusters.threads = options.reconstruct.threads;
    clusters.block_triangles = report.cluster_block;
    clusters.sharing = options.sharing;  // the other ranks make blocks too
    clusters.stats = &report.cluster_blocks;
    // Finished clusters go to a spool on disk only where memory cannot hold
    // them too: writing them cost 4 % of an in-core build's cluster stage.
    const bool blocked = report.cluster_block > 0 && report.full_triangles > std::size_t(report.cluster_block);
    // Blocks side by side, a thread each, where the budget holds a block's
    // working memory per thread (the pair at R = 1024: 387 MiB with one
    // block at a time, 415 MiB with two); else one after another, which
    // makes the same model.
    if (blocked) {
      const int threads = options.reconstruct.threads > 0 ? options.reconstruct.threads
                                                          : int(std::max(1u, std::thread::hardware_concurrency()));
      const double per_lane = double(report.cluster_block) * kBlockBytesPerTriangle;
      clusters.lanes = std::max(1, std::min(threads, int((budget - report.estimated_cluster_bytes) / per_lane) + 1));
      report.estimated_cluster_bytes += double(clusters.lanes - 1) * per_lane;
      report.cluster_lanes = clusters.lanes;
    }
    const double held = kHeldClusterBytesPerTriangle * double(report.full_triangles);
    if (blocked && (options.work_dir.empty() || report.estimated_cluster_bytes + held <= budget))
      report.estimated_cluster_bytes += held;
    else if (blocked) {
      std::filesystem::create_directories(options.work_dir);
      clusters.spool = std::make_shared<TriangleSpool>(
          (std::filesystem::path(options.work_dir) / "cluster_triangles.spool").string());
    }
    clusters.progress = [&bar, done = std::size_t(0)](double share) mutable {
      const std::size_t now = std::size_t(share * 1000);
      if (now > done) bar.advance(now - done), done = now;
    };
    if (mesh) add_cluster_hierarchy(&model, *mesh, false, clusters);
    else if (options.octree) add_cluster_hierarchy(&model, r.mesh, true, clusters);
    else {
      // Meshlet walks and collapses break ties by vertex number: one order
      // of the vertices makes the hierarchy of a surface welded from bricks
      // that of the same surface made in core. (A mesh input keeps its own.)
      order_vertices(&r.mesh);
      add_cluster_hierarchy(&model, std::move(r.mesh), false, clusters);
    }
    bar.finish();
  } else {
    release_hierarchy_ranks(options.sharing);
  }
  report.seconds_clusters = seconds_since(stage);
  report.peak_bytes_clusters = peak_bytes();
  return model;
}

}  // namespace

void serve_build(const std::vector<std::string>& inputs, const BuildOptions& options) {
  AcquisitionReport report;
  if (options.memory_bytes > 0) hand_large_arrays_back_when_freed();
  InputPoints points = load_within_budget(inputs, options, &report);
  BrickOptions bricks;
  bricks.work_dir = options.work_dir;
  bricks.memory_bytes = options.memory_bytes > 0 ? options.memory_bytes
                        : points.job_budget > 0  ? points.job_budget
                                                 : available_memory_bytes();
  bricks.brick_cubes = options.brick_cubes;
  bricks.sharing = options.sharing;
  // As build_model() decides on rank 0: one mesh given for its clusters alone is not reconstructed.
  const bool mesh_only = report.meshes == 1 && report.files.size() == 1 && options.clusters && !options.octree;
  if (points.spool && points.spool->shared() && !mesh_only) {
    bricks.points_binned = [&points] { points.release(); };
    serve_bricks(*points.spool, options.reconstruct, bricks);
  } else {
    serve_bricks(options.reconstruct, bricks);
  }
  points.release();
  malloc_trim(0);  // what the bricks freed, before the mesh and the hierarchy's tables come
  serve_cluster_hierarchy(*options.sharing, options.reconstruct.threads);
}

LodModel build_model(const OrientedPoints& points, const TriangleMesh* mesh, const BuildOptions& options,
                     BuildReport* report) {
  return build_from_points(&points, nullptr, mesh, options, report, "", [] {});
}

LodModel build_model(const std::vector<std::string>& inputs, const BuildOptions& options, BuildReport* report_out) {
  BuildReport local;
  BuildReport& report = report_out ? *report_out : local;
  const auto start = Clock::now();
  BuildProgress progress(0.05, options.octree ? 4.0 : 0.0, options.clusters ? 1.6 : 0.0);
  if (options.memory_bytes > 0) hand_large_arrays_back_when_freed();
  InputPoints points = load_within_budget(inputs, options, &report.acquisition);
  // Ranks that bin their shares plan with one budget: rank 0's, as measured when they met.
  BuildOptions planned = options;
  if (planned.memory_bytes <= 0 && points.job_budget > 0) planned.memory_bytes = points.job_budget;
  report.warnings = report.acquisition.warnings;
  report.mesh_input = report.acquisition.meshes == 1 && report.acquisition.files.size() == 1;
  TriangleMesh mesh;
  if (report.mesh_input && options.clusters) mesh = read_mesh(inputs[0]);
  report.seconds_read = seconds_since(start);
  const AcquisitionReport acquisition = report.acquisition;
  const double read = report.seconds_read;
  std::string names;
  for (const std::string& input : inputs) names += (names.empty() ? "" : ", ") + input;
  LodModel model = build_from_points(points.spool ? nullptr : &points.points, points.spool.get(),
                                     report.mesh_input && options.clusters ? &mesh : nullptr, planned, &report, names,
                                     [&points] { points.release(); },
                                     &progress);
  report.acquisition = acquisition;
  report.seconds_read = read;
  model.origin = acquisition.origin;  // a LAS input's local origin: outputs go back to its frame
  return model;
}

}  // namespace scan2lod
