// LOD benchmark: scan2lod's prioritized marching-cube octree (Lee 2007, §5-6)
// against the mesh simplifiers a user would otherwise reach for, on the same
// mesh and at the same triangle counts (the Stanford bunny scans by default).
//
// What is measured, each timed case in its own forked child process:
//   1. Model build, --runs times (median), as `scan2lod build` runs it
//      (bench/model_build.h): reconstruct(); build_mc_octree(reconstruction),
//      whose coarse corners take the distance to the finished mesh;
//      number_nodes(). "Model build" = octree + numbering. Peak MiB: the
//      child's ru_maxrss.
//   2. Extraction at 100, 80, 60, 40, 20, 5 and 1 % of the LOD array
//      (priority_for_percent): extract_lod() alone, repeated at least --reps
//      times and for at least 0.25 s with the scratch vectors reused, median
//      and range; output triangles; triangles per second; and extract_lod() +
//      compact_level() (a self-contained mesh), median over as many repetitions.
//   3. Peers, each simplifying the SAME full mesh (compact_level of the 100 %
//      extraction) to the triangle count of each scan2lod level below 100 %:
//      meshopt_simplify and meshopt_simplifySloppy (meshoptimizer), OpenMesh
//      Decimater + ModQuadricT, VTK vtkQuadricDecimation and
//      vtkQuadricClustering, Open3D SimplifyQuadricDecimation and
//      SimplifyVertexClustering. Seconds are the library call alone: copying
//      the mesh into the library's types and back is outside the timer. A
//      peer with no triangle-count target (vtkQuadricClustering divisions,
//      Open3D voxel size) has its setting searched in its first run, outside
//      the timer, for the count closest to the target; later runs reuse it.
//      A case whose first run took under --repeat-under seconds runs --runs
//      times (median); every run is killed after --timeout seconds, and a
//      failed, crashed or killed peer is reported as such.
//   4. Fidelity, in the parent after every child is done: two-sided mean
//      surface distance (compare_surfaces, fixed seed, --samples per
//      direction) of each scan2lod level and each peer's output to the full
//      mesh, i.e. the mean of the two directions' means, in 1e-3 of the full
//      mesh's bounding-box diagonal; and mesh_topology (boundary loops,
//      non-manifold edges, components) of each.
//   5. Ratios, all from this run: meshopt_simplify seconds / extract_lod
//      seconds at each level (goal >= 100), scan2lod error / peer error (goal:
//      below 1 against every vertex-clustering peer, at most 1.5 against every
//      quadric edge-collapse peer); and the report says which goals are met.
//   6. The cluster hierarchy (lod/clusters/cluster_hierarchy.h), built in the same
//      model-build children (add_cluster_hierarchy over the reconstruction's
//      mesh, as `scan2lod build` does) and read through the LOD face only
//      (lod/lod_model.h: LevelExtractor, compact_level): the uniform cut at
//      budgets of 1k to 200k triangles (LevelRequest::at_triangles), each
//      peer run once on the same full mesh at the cut's actual count, and the
//      octree's finest level with at most as many triangles; the errors as in
//      4. Also: the hierarchy's build alone on the full mesh (its own child,
//      --runs times: seconds and peak RSS) against meshopt_simplify of that
//      mesh to 1 % (same run, same mesh); stored triangles / full; the
//      coarsest cut; view-dependent selection (LevelRequest::for_camera, 1
//      pixel, at 48 cameras around the model: LevelCut::select_seconds, per
//      camera the median of --reps, then the median over the cameras); and
//      extraction rates (triangles / LevelCut::extract_seconds) at full
//      detail and at every budget. Goals from issue 12.
//
// Children get the work by fork() without exec (bench/bench_support.h), so the parent never runs
// OpenMP (reconstruct, load_oriented_points, compare_surfaces) before the last
// child is done: libgomp's thread pool does not survive fork. Points are
// loaded in a child, the model is built in children and handed back through a
// .mco file, and the parent only measures once every timed case has finished.
//
// Output: a markdown report on stdout (and, with --write, in
// bench/lod/REPORT.md); progress on stderr.

#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/bench/bench_support.h>
#include <scan2lod/bench/library_meshes.h>
#include <scan2lod/bench/model_build.h>
#include <scan2lod/core/error.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/core/types.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/model_file.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/mc_octree.h>
#include <scan2lod/lod/octree/octree_order.h>
#include <scan2lod/measure/surface_distance.h>
#include <scan2lod/measure/topology.h>
#include <scan2lod/reconstruct/marching_cubes.h>

#include <CLI/CLI.hpp>
// OpenMesh's properties grow by pushing a default VectorT, which leaves its
// values uninitialised on purpose; GCC 12 warns where that is inlined here.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <meshoptimizer.h>
#include <omp.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/utility/Logging.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkQuadricClustering.h>
#include <vtkQuadricDecimation.h>
#include <vtkSmartPointer.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace scan2lod;
using namespace scan2lod::bench;

namespace {

// ---------------------------------------------------------------------------
// The peers. Each takes the full mesh and a target triangle count, copies the
// mesh into its library's types (untimed) and returns the simplified mesh.

struct PeerRun {
  double seconds = 0;  // the simplification call alone
  // The searched setting (divisions, voxel size): in, a previous run's, which
  // skips the search (NaN: search); out, the one used. Other peers report a
  // number of their own here (meshopt's error estimate).
  double setting = std::numeric_limits<double>::quiet_NaN();
  double rejected = 0;  // input triangles the library refused (OpenMesh)
};

using PeerWork = std::function<TriangleMesh(const TriangleMesh& full, std::int64_t target, PeerRun* run)>;

// The integer in [lo, cap] whose count is closest to target, for a count that
// grows with it: doubling up from lo (a trial's cost grows with the integer,
// so the cap is tried only if nothing smaller reaches the target), then
// bisection and the better neighbour.
int search_increasing(const std::function<std::int64_t(int)>& count, int lo, int cap, std::int64_t target) {
  if (count(lo) >= target) return lo;
  int hi = lo;
  std::int64_t at_hi = 0;
  do {
    lo = hi;
    hi = std::min(2 * hi, cap);
    at_hi = count(hi);
  } while (at_hi < target && hi < cap);
  if (at_hi <= target) return hi;
  while (hi - lo > 1) {  // invariant: count(lo) < target < count(hi)
    const int mid = lo + (hi - lo) / 2;
    const std::int64_t c = count(mid);
    if (c == target) return mid;
    (c < target ? lo : hi) = mid;
  }
  return std::llabs(count(lo) - target) <= std::llabs(count(hi) - target) ? lo : hi;
}

// meshopt_simplify (edge collapse under a quadric error, keeping the topology)
// or meshopt_simplifySloppy (vertex clustering on a searched grid). A target
// error of 1 (the whole mesh's extent) lets the count decide where they stop.
TriangleMesh run_meshopt(const TriangleMesh& full, std::int64_t target, bool sloppy, PeerRun* run) {
  std::vector<unsigned int> indices;
  indices.reserve(3 * full.triangles.size());
  for (const Triangle& t : full.triangles)
    for (int k = 0; k < 3; ++k) indices.push_back(unsigned(t[k]));
  std::vector<unsigned int> out(indices.size());
  const float* positions = full.positions[0].data();
  auto sloppy_count = [&](std::size_t asked) {
    float e = 0;
    return meshopt_simplifySloppy(out.data(), indices.data(), indices.size(), positions, full.positions.size(),
                                  sizeof(Vec3f), 3 * asked, 1.0f, &e) / 3;
  };
  // Sloppy stops at the grid whose count is at most the one asked, often
  // well under it (804 triangles for 992 on the bunny): the count asked is
  // searched in the first run for the result closest to the target.
  if (sloppy && std::isnan(run->setting))
    run->setting = search_increasing([&](int asked) { return std::int64_t(sloppy_count(std::size_t(asked))); },
                                     int(target), int(std::min<std::int64_t>(4 * target, full.triangles.size())),
                                     target);
  const std::size_t target_indices = 3 * std::size_t(sloppy ? run->setting : double(target));
  float error = 0;
  const auto start = Clock::now();
  const std::size_t n =
      sloppy ? meshopt_simplifySloppy(out.data(), indices.data(), indices.size(), positions,
                                      full.positions.size(), sizeof(Vec3f), target_indices, 1.0f, &error)
             : meshopt_simplify(out.data(), indices.data(), indices.size(), positions,
                                full.positions.size(), sizeof(Vec3f), target_indices, 1.0f, 0, &error);
  run->seconds = seconds_since(start);
  if (!sloppy) run->setting = error;
  TriangleMesh mesh;
  mesh.positions = full.positions;  // indices refer to the input's vertices
  mesh.triangles.resize(n / 3);
  for (std::size_t i = 0; i < n / 3; ++i)
    mesh.triangles[i] = {std::int32_t(out[3 * i]), std::int32_t(out[3 * i + 1]), std::int32_t(out[3 * i + 2])};
  return mesh;
}

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

// OpenMesh DecimaterT with ModQuadricT alone (Garland-Heckbert quadrics,
// no error bound), collapsing until `target` faces remain.
TriangleMesh run_openmesh(const TriangleMesh& full, std::int64_t target, PeerRun* run) {
  OmMesh mesh;
  std::vector<OmMesh::VertexHandle> handles;
  handles.reserve(full.positions.size());
  for (const Vec3f& p : full.positions) handles.push_back(mesh.add_vertex(OmMesh::Point(p.x(), p.y(), p.z())));
  omerr().disable();  // one "complex edge" line per refused face otherwise
  for (const Triangle& t : full.triangles)
    if (!mesh.add_face(handles[t[0]], handles[t[1]], handles[t[2]]).is_valid()) run->rejected += 1;
  omerr().enable();

  using Decimater = OpenMesh::Decimater::DecimaterT<OmMesh>;
  using Quadric = OpenMesh::Decimater::ModQuadricT<OmMesh>::Handle;
  const auto start = Clock::now();
  {
    Decimater decimater(mesh);
    Quadric quadric;
    decimater.add(quadric);
    decimater.module(quadric).unset_max_err();
    if (!decimater.initialize()) throw std::runtime_error("OpenMesh Decimater::initialize() failed");
    decimater.decimate_to_faces(0, std::size_t(target));
    // Inside the scope: the Decimater's destructor releases the status flags
    // that tell garbage_collection() what was deleted.
    mesh.garbage_collection();
  }
  run->seconds = seconds_since(start);

  TriangleMesh out;
  out.positions.reserve(mesh.n_vertices());
  for (const auto v : mesh.vertices()) {
    const OmMesh::Point& p = mesh.point(v);
    out.positions.emplace_back(p[0], p[1], p[2]);
  }
  out.triangles.reserve(mesh.n_faces());
  for (const auto f : mesh.faces()) {
    Triangle t{};
    int k = 0;
    for (const auto v : mesh.fv_range(f)) t[k++] = v.idx();
    out.triangles.push_back(t);
  }
  return out;
}

// vtkQuadricDecimation (Garland-Heckbert edge collapse) with the reduction
// that leaves `target` of the input's triangles.
TriangleMesh run_vtk_decimation(const TriangleMesh& full, std::int64_t target, PeerRun* run) {
  const vtkSmartPointer<vtkPolyData> input = to_vtk(full);
  vtkNew<vtkQuadricDecimation> filter;
  filter->SetInputData(input);
  filter->SetTargetReduction(1.0 - double(target) / double(full.triangles.size()));
  const auto start = Clock::now();
  filter->Update();
  run->seconds = seconds_since(start);
  return from_vtk(filter->GetOutput());
}

// vtkQuadricClustering's divisions per axis for `n` along the box's longest
// axis: cells as close to cubes as whole numbers allow.
std::array<int, 3> clustering_divisions(const Aabb& box, int n) {
  const Vec3f e = box.extent();
  std::array<int, 3> d{};
  for (int k = 0; k < 3; ++k) d[k] = std::max(1, int(std::lround(n * e[k] / e.maxCoeff())));
  return d;
}

// VTK 9.1 allocates one quadric (88 bytes) per bin of the whole grid, not per
// occupied bin; divisions are capped so that array stays under 4 GiB.
int max_clustering_divisions(const Aabb& box) {
  int n = 8;
  const auto bytes = [&](int m) {
    const auto d = clustering_divisions(box, m);
    return 88.0 * d[0] * d[1] * d[2];
  };
  while (bytes(n + 8) < 4.0 * (1 << 30)) n += 8;
  return n;
}

// One vtkQuadricClustering pass with n divisions along the longest axis;
// *seconds, if given, receives the time of the filter alone.
TriangleMesh vtk_clustering(vtkPolyData* input, const Aabb& box, int n, double* seconds = nullptr) {
  vtkNew<vtkQuadricClustering> filter;
  filter->SetInputData(input);
  filter->AutoAdjustNumberOfDivisionsOff();  // use exactly the divisions asked for
  const auto d = clustering_divisions(box, n);
  filter->SetNumberOfDivisions(d[0], d[1], d[2]);
  const auto start = Clock::now();
  filter->Update();
  if (seconds) *seconds = seconds_since(start);
  return from_vtk(filter->GetOutput());
}

// vtkQuadricClustering (Lindstrom 2000: one vertex per occupied grid cell at
// its quadric's minimum) with the divisions whose output is closest to target.
TriangleMesh run_vtk_clustering(const TriangleMesh& full, std::int64_t target, PeerRun* run) {
  const vtkSmartPointer<vtkPolyData> input = to_vtk(full);
  const Aabb box = bounds(full.positions);
  if (std::isnan(run->setting)) {
    const auto count = [&](int n) { return std::int64_t(vtk_clustering(input, box, n).triangles.size()); };
    run->setting = search_increasing(count, 8, max_clustering_divisions(box), target);
  }
  return vtk_clustering(input, box, int(run->setting), &run->seconds);
}

// Open3D SimplifyQuadricDecimation (Garland-Heckbert) with the Python API's
// defaults: no error bound, boundary weight 1.
TriangleMesh run_open3d_decimation(const TriangleMesh& full, std::int64_t target, PeerRun* run) {
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  const open3d::geometry::TriangleMesh input = to_open3d(full);
  const auto start = Clock::now();
  const auto out = input.SimplifyQuadricDecimation(int(target), std::numeric_limits<double>::infinity(), 1.0);
  run->seconds = seconds_since(start);
  return from_open3d(*out);
}

// Open3D SimplifyVertexClustering (average of each voxel's vertices) with the
// voxel size whose output is closest to target: bisection on log(size), the
// count falling as the voxels grow.
TriangleMesh run_open3d_clustering(const TriangleMesh& full, std::int64_t target, PeerRun* run) {
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  const open3d::geometry::TriangleMesh input = to_open3d(full);
  if (std::isnan(run->setting)) {
    const double diagonal = bounds(full.positions).diagonal();
    double lo = diagonal / 8192, hi = diagonal / 4;  // count(lo) high, count(hi) low
    double best = lo;
    std::int64_t best_miss = std::numeric_limits<std::int64_t>::max();
    for (int i = 0; i < 40 && best_miss > target / 500; ++i) {
      const double mid = std::sqrt(lo * hi);
      const std::int64_t c = std::int64_t(input.SimplifyVertexClustering(mid)->triangles_.size());
      if (std::llabs(c - target) < best_miss) best_miss = std::llabs(c - target), best = mid;
      (c > target ? lo : hi) = mid;
    }
    run->setting = best;
  }
  const auto start = Clock::now();
  const auto out = input.SimplifyVertexClustering(run->setting);
  run->seconds = seconds_since(start);
  return from_open3d(*out);
}

// ---------------------------------------------------------------------------
// Cases.

struct Peer {
  std::string name;
  bool clustering = false;  // vertex clustering (goal: beat it), else edge collapse (goal: within 1.5x)
  bool searched = false;    // PeerRun::setting is searched in the first run and reused
  PeerWork work;
  std::string setup;        // how it was set up, for the notes
  std::function<std::string(double)> describe;  // PeerRun::setting in words, or null
};

std::vector<Peer> make_peers() {
  const auto estimate = [](double e) { return "result_error " + format("%.2g", e) + " (relative)"; };
  std::vector<Peer> peers(7);
  peers[0].name = "meshopt_simplify";
  peers[0].work = [](const TriangleMesh& m, std::int64_t t, PeerRun* r) { return run_meshopt(m, t, false, r); };
  peers[0].setup = "meshoptimizer 0.18 `meshopt_simplify(…, target_index_count = 3 × target, target_error = 1, "
                   "options = 0)`: quadric edge collapse that keeps the topology, so it may stop above the target";
  peers[0].describe = estimate;

  peers[1].name = "OpenMesh ModQuadric";
  peers[1].work = run_openmesh;
  peers[1].setup = "OpenMesh 9.0 `DecimaterT` with `ModQuadricT` alone (`unset_max_err()`), "
                   "`decimate_to_faces(0, target)` and `garbage_collection()`, timed together with `initialize()`";

  peers[2].name = "VTK QuadricDecimation";
  peers[2].work = run_vtk_decimation;
  peers[2].setup = "VTK 9.1 `vtkQuadricDecimation` with `SetTargetReduction(1 − target / full)`, other settings "
                   "default (no volume preservation, no attribute error)";

  peers[3].name = "Open3D QuadricDecimation";
  peers[3].work = run_open3d_decimation;
  peers[3].setup = "Open3D 0.16 `SimplifyQuadricDecimation(target, maximum_error = ∞, boundary_weight = 1)`";

  peers[4].name = "meshopt_simplifySloppy";
  peers[4].work = [](const TriangleMesh& m, std::int64_t t, PeerRun* r) { return run_meshopt(m, t, true, r); };
  peers[4].clustering = peers[4].searched = true;
  peers[4].setup = "meshoptimizer 0.18 `meshopt_simplifySloppy(…, target_index_count = 3 × asked, "
                   "target_error = 1)`: vertex clustering on a grid it searches itself for at most the asked "
                   "count; the count asked searched by bisection in the first run (untimed) for the result "
                   "closest to the target";
  peers[4].describe = [](double asked) { return "asked for " + fixed(asked, 0); };

  peers[5].name = "VTK QuadricClustering";
  peers[5].clustering = peers[5].searched = true;
  peers[5].work = run_vtk_clustering;
  peers[5].setup = "VTK 9.1 `vtkQuadricClustering`, `AutoAdjustNumberOfDivisionsOff()`, n divisions along the "
                   "longest axis and proportionally fewer along the others (near-cubic cells), n searched by "
                   "bisection in the first run (untimed) for the count closest to the target";
  peers[5].describe = [](double n) { return "n = " + fixed(n, 0); };

  peers[6].name = "Open3D VertexClustering";
  peers[6].clustering = peers[6].searched = true;
  peers[6].work = run_open3d_clustering;
  peers[6].setup = "Open3D 0.16 `SimplifyVertexClustering(voxel_size)` (contraction Average), the voxel size "
                   "searched by bisection on its logarithm in the first run (untimed) for the count closest to "
                   "the target";
  peers[6].describe = [](double v) { return "voxel " + fixed(v * 1e3, 3) + " mm"; };
  return peers;
}

struct PeerCase {
  const Peer* peer = nullptr;
  std::vector<Outcome> runs;
  std::string mesh_path;
  double setting = std::numeric_limits<double>::quiet_NaN();
  double rejected = 0;
  // measured afterwards in the parent
  std::optional<MeshTopology> topology;
  std::optional<SurfaceComparison> fidelity;
  std::string measure_error;

  bool all_ok() const { return bench::all_ok(runs); }
  double seconds() const { return median_seconds(runs); }
  double peak_mib() const { return bench::peak_mib(runs); }
};

// A mesh's two-sided mean distance to the full mesh: the mean of both
// directions' means, in 1e-3 of the full mesh's diagonal.
double error_1e3(const SurfaceComparison& c) {
  return 1e3 * 0.5 * (c.a_to_b.mean + c.b_to_a.mean) / c.diagonal;
}

// An error in 1e-3 of the diagonal: four decimals, since the finest peers'
// errors at high levels are below 1e-3 of that unit.
std::string error_text(double e) { return fixed(e, 4); }

// A ratio: two decimals near 1, whole numbers once it is far from it.
std::string ratio_text(double r) { return fixed(r, r < 10 ? 2 : 0); }

// The larger direction's 95th percentile and maximum, in 1e-3 of the diagonal:
// whether an error is spread evenly or comes from a few gross misses.
std::string tail_cell(const SurfaceComparison& c) {
  return fixed(1e3 * std::max(c.a_to_b.p95, c.b_to_a.p95) / c.diagonal, 2) + " / " +
         fixed(1e3 * std::max(c.a_to_b.max, c.b_to_a.max) / c.diagonal, 1);
}

struct Level {
  double percent = 0;
  std::int64_t budget = 0;  // a budget level: LevelRequest::at_triangles(budget), as --triangles; else 0
  std::size_t priority = 0;
  std::int64_t triangles = 0;
  std::int64_t accumulated = 0;  // the accumulation table's count at `priority`, which should equal it
  std::size_t vertices = 0;
  Outcome extraction;  // values: see measure_extraction
  TriangleMesh mesh;   // compact_level of the level
  MeshTopology topology;
  std::optional<SurfaceComparison> fidelity;
  std::string measure_error;
  std::vector<PeerCase> peers;  // empty at 100 %
  // The same octree cut without crack patching, at about the same count
  // (open_cut): what the error would be if transitions cost nothing.
  std::size_t open_priority = 0;
  std::int64_t open_triangles = 0;
  std::optional<SurfaceComparison> open_fidelity;

  double extract_seconds() const { return extraction.values[0]; }
};

// The first cut of the LOD array whose nodes' own triangles (no transitions,
// so cracks stay open: Lee's mesh before its projection) number at least
// `target`, with the hole patches extract_lod would show there.
// An octree diagnostic, so it reads the octree's arrays (model.octree) rather
// than going through LevelExtractor.
TriangleMesh open_cut(const LodModel& model, std::int64_t target, std::size_t* priority) {
  const McOctree& tree = model.octree->tree;
  const LodArray& lod = model.octree->lod;
  std::int64_t count = tree.nodes.triangle_counts[0];
  std::size_t p = 0;
  for (; p < lod.full() && count < target; ++p) {
    const std::int32_t node = lod.order[p];
    count += tree.children_triangles(std::size_t(node)) - tree.nodes.triangle_counts[node];
  }
  std::vector<std::uint8_t> flags(tree.size(), 0);
  mark_cut(tree, lod, p, flags.data());
  std::vector<Triangle> triangles;
  for (std::size_t n = 0; n < tree.size(); ++n)
    if (flags[n] == 2) {
      const Triangle* own = tree.triangles.data() + tree.nodes.first_triangle[n];
      triangles.insert(triangles.end(), own, own + tree.nodes.triangle_counts[n]);
    }
  for (std::size_t g = 0; g < tree.patch_groups(); ++g) {
    bool shown = true;
    for (std::int32_t k = tree.patches.needs_first[g]; k < tree.patches.needs_first[g + 1]; ++k)
      shown = shown && flags[tree.patches.needs[k]] == 1;
    if (shown)
      triangles.insert(triangles.end(), tree.patches.triangles.begin() + tree.patches.group_first[g],
                       tree.patches.triangles.begin() + tree.patches.group_first[g + 1]);
  }
  *priority = p;
  return compact_level(model, triangles);
}

// The octree's level at `priority` (LevelExtractor, LevelRequest::at_priority:
// extract_lod), repeated at least `reps` times and for at least 0.25 s, the
// extractor's scratch reused. Values: extract median, min, max; extract +
// compact_level median; repetitions; triangles.
Values measure_extraction(const LodModel& model, std::size_t priority, int reps) {
  LevelExtractor extractor(model, LodStructure::kOctree);
  const LevelRequest request = LevelRequest::at_priority(priority);
  extractor.extract(request);  // warm-up: sizes the scratch
  std::vector<double> alone, with_compact;
  std::size_t triangles = 0;
  const auto begin = Clock::now();
  for (int i = 0; i < 100000 && (i < reps || seconds_since(begin) < 0.25); ++i) {
    const auto start = Clock::now();
    triangles = extractor.extract(request).triangles.size();
    alone.push_back(seconds_since(start));
  }
  const auto begin_compact = Clock::now();
  for (std::size_t i = 0; i < alone.size() && (int(i) < reps || seconds_since(begin_compact) < 0.25); ++i) {
    const auto start = Clock::now();
    const LevelCut& cut = extractor.extract(request);
    const TriangleMesh mesh = compact_level(model, cut.triangles);
    with_compact.push_back(seconds_since(start));
    if (mesh.triangles.size() != cut.triangles.size()) throw std::runtime_error("compact_level lost triangles");
  }
  return {median(alone), *std::min_element(alone.begin(), alone.end()),
          *std::max_element(alone.begin(), alone.end()), median(with_compact), double(alone.size()),
          double(triangles), 0, 0};
}

// ---------------------------------------------------------------------------
// The cluster hierarchy, through the LOD face (lod/lod_model.h) only.

// Budgets of the uniform cuts (LevelRequest::at_triangles).
const std::vector<std::int64_t> kClusterBudgets = {1000, 2000, 5000, 10000, 20000, 50000, 100000, 200000};

// Goal windows of issue 12: error against meshopt_simplify up to this budget,
// against the vertex-clustering peers up to that one; extraction rate at full
// detail and at budgets from this one up.
constexpr std::int64_t kSimplifyGoalMax = 100000, kClusteringGoalMax = 20000, kRateGoalMin = 50000;

struct ClusterLevel {
  std::int64_t budget = 0;     // asked for; 0: full detail (LevelRequest::at_percent(100))
  std::int64_t triangles = 0;  // the cut's
  std::size_t clusters = 0;
  double threshold = 0;        // LevelCut::error, the uniform object-space error
  TriangleMesh mesh;           // compact_level of the cut
  MeshTopology topology;
  Outcome extraction;          // values: see measure_cluster_extraction
  std::optional<SurfaceComparison> fidelity;
  std::string measure_error;
  // The octree's finest level with at most as many triangles (its coarsest when none is).
  std::int64_t octree_triangles = 0;
  TriangleMesh octree_mesh;
  std::optional<SurfaceComparison> octree_fidelity;
  // Where the cut was refined to the count (LevelCut::refined_from), the
  // stored cut the budget gets unrefined (LevelRequest::refine = false).
  std::int64_t refined_from = 0;
  double refine_seconds = 0;  // LevelCut::extract_seconds of the refined cut, once
  std::int64_t stored_triangles = 0;
  TriangleMesh stored_mesh;
  std::optional<SurfaceComparison> stored_fidelity;
  std::vector<PeerCase> peers;  // empty at full detail and for a budget the full mesh is under

  std::string label() const { return budget == 0 ? "100 %" : format("%lldk", (long long)(budget / 1000)); }
  double extract_seconds() const { return extraction.values[0]; }
  const PeerCase* peer(const std::string& name) const {
    for (const PeerCase& c : peers)
      if (c.peer->name == name) return &c;
    return nullptr;
  }
};

LevelRequest cluster_request(const ClusterLevel& l) {
  return l.budget == 0 ? LevelRequest::at_percent(100) : LevelRequest::at_triangles(l.budget);
}

// The cluster cut of `request`, repeated at least `reps` times and for at least
// 0.25 s, the extractor's tables and scratch reused. Values: extract_seconds
// median, min, max; select_seconds median; repetitions; triangles; extract +
// compact_level median.
Values measure_cluster_extraction(const LodModel& model, const LevelRequest& request, int reps) {
  LevelExtractor extractor(model, LodStructure::kClusters);
  extractor.extract(request);  // warm-up: sizes the scratch
  std::vector<double> extract, select, with_compact;
  std::size_t triangles = 0;
  const auto begin = Clock::now();
  for (int i = 0; i < 100000 && (i < reps || seconds_since(begin) < 0.25); ++i) {
    const LevelCut& cut = extractor.extract(request);
    extract.push_back(cut.extract_seconds);
    select.push_back(cut.select_seconds);
    triangles = cut.triangles.size();
  }
  const auto begin_compact = Clock::now();
  for (std::size_t i = 0; i < extract.size() && (int(i) < reps || seconds_since(begin_compact) < 0.25); ++i) {
    const auto start = Clock::now();
    const LevelCut& cut = extractor.extract(request);
    const TriangleMesh mesh = compact_level(model, cut.triangles);
    with_compact.push_back(seconds_since(start));
    if (mesh.triangles.size() != cut.triangles.size()) throw std::runtime_error("compact_level lost triangles");
  }
  return {median(extract), *std::min_element(extract.begin(), extract.end()),
          *std::max_element(extract.begin(), extract.end()), median(select), double(extract.size()),
          double(triangles), median(with_compact), 0};
}

// `n` cameras looking at the model's centre from directions spread evenly over
// the sphere (a Fibonacci lattice), at 1.5, 3 and 6 times the box's half
// diagonal in turn: close views keep the near side fine, far ones coarsen all.
std::vector<CameraView> orbit_cameras(const Aabb& box, int n) {
  const Vec3f center = 0.5f * (box.min + box.max);
  const float radius = 0.5f * box.diagonal();
  const float golden = float(M_PI) * (3.0f - std::sqrt(5.0f));
  const float distances[3] = {1.5f, 3.0f, 6.0f};
  std::vector<CameraView> cameras;
  for (int i = 0; i < n; ++i) {
    const float y = 1.0f - 2.0f * (float(i) + 0.5f) / float(n), r = std::sqrt(std::max(0.0f, 1.0f - y * y));
    const Vec3f direction(r * std::cos(golden * float(i)), y, r * std::sin(golden * float(i)));
    CameraView c;
    c.eye = center + distances[i % 3] * radius * direction;
    c.target = center;
    c.up = std::abs(y) > 0.99f ? Vec3f(1, 0, 0) : Vec3f(0, 1, 0);
    cameras.push_back(c);
  }
  return cameras;
}

// LevelRequest::for_camera at `pixel_error` from every camera, `reps` times
// each (after one untimed call). Values: median over the cameras of each
// camera's median select_seconds; the largest of those; the median of the
// cameras' median extract_seconds; median, min and max triangles; cameras.
Values measure_view_selection(const LodModel& model, const std::vector<CameraView>& cameras, double pixel_error,
                              int reps) {
  LevelExtractor extractor(model, LodStructure::kClusters);
  std::vector<double> select, extract, triangles;
  for (const CameraView& c : cameras) {
    const LevelRequest request = LevelRequest::for_camera(c, pixel_error);
    extractor.extract(request);
    std::vector<double> s, e;
    for (int i = 0; i < reps; ++i) {
      const LevelCut& cut = extractor.extract(request);
      s.push_back(cut.select_seconds);
      e.push_back(cut.extract_seconds);
      if (i == 0) triangles.push_back(double(cut.triangles.size()));
    }
    select.push_back(median(s));
    extract.push_back(median(e));
  }
  return {median(select), *std::max_element(select.begin(), select.end()), median(extract), median(triangles),
          *std::min_element(triangles.begin(), triangles.end()), *std::max_element(triangles.begin(), triangles.end()),
          double(cameras.size()), 0};
}

// Whether two index buffers hold the same triangles, each up to rotation,
// in any order.
bool same_triangles(std::vector<Triangle> a, std::vector<Triangle> b) {
  if (a.size() != b.size()) return false;
  const auto canonical = [](std::vector<Triangle>* v) {
    for (Triangle& t : *v) {
      while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
    }
    std::sort(v->begin(), v->end());
  };
  canonical(&a);
  canonical(&b);
  return a == b;
}

struct Settings {
  std::string input;
  int resolution = 256;
  bool quick = false;
  int runs = 3;
  double repeat_under = 10;
  double timeout = 300;
  int reps = 50;
  std::size_t samples = 200000;
  std::uint64_t seed = 1;
  std::string only;  // run only the peers whose name contains this
  bool write = false;
  std::vector<std::int64_t> cut_budgets = kClusterBudgets;
};

struct RunInfo {
  std::string command_line, load_at_start, load_at_end;
  std::size_t points = 0;
  double baseline_mib = 0;
  double total_seconds = 0;
  std::vector<Outcome> builds;  // values: reconstruct, octree, numbering, mesh triangles
  std::size_t nodes = 0, leaves = 0, expansions = 0, full_triangles = 0, full_vertices = 0;
  double diagonal = 0;
  int depth = 0;
  int clustering_cap = 0;  // max_clustering_divisions of the full mesh
  // The cluster hierarchy.
  std::size_t clusters = 0, stored_triangles = 0;
  int cluster_levels = 0;
  std::int64_t cluster_full = 0, coarsest = 0;
  bool same_full = false;               // its full detail holds the octree's full-detail triangles
  std::vector<Outcome> cluster_builds;  // add_cluster_hierarchy alone on the full mesh: seconds, stored, clusters
  std::vector<Outcome> simplify_1;      // meshopt_simplify of the same mesh to 1 %: seconds, triangles
  Outcome view;                         // measure_view_selection
  double pixel_error = 1;
  int view_reps = 0;
};

// ---------------------------------------------------------------------------
// The report.

std::string status_cell(const std::vector<Outcome>& runs) {
  for (const Outcome& o : runs)
    if (o.status != Outcome::ok) return o.message;
  return {};
}

// "1.23 (1.20–1.30, 3 runs)" of values[k] over runs, scaled.
std::string spread_cell(const std::vector<Outcome>& runs, int k, double scale, int digits) {
  if (const std::string failed = status_cell(runs); !failed.empty()) return failed;
  std::vector<double> v;
  for (const Outcome& o : runs) v.push_back(o.values[k] * scale);
  std::string cell = fixed(median(v), digits);
  if (v.size() > 1)
    cell += " (" + fixed(*std::min_element(v.begin(), v.end()), digits) + "–" +
            fixed(*std::max_element(v.begin(), v.end()), digits) + ", " + std::to_string(v.size()) + " runs)";
  else
    cell += " (1 run)";
  return cell;
}

std::string percent_label(const Level& l) {
  if (l.budget > 0) return "budget " + std::to_string(l.budget / 1000) + "k";
  return fixed(l.percent, 0) + " %";
}

class Report {
 public:
  void add(const char* fmt, ...) __attribute__((format(printf, 2, 3))) {
    va_list args;
    va_start(args, fmt);
    char buf[8192];
    std::vsnprintf(buf, sizeof buf, fmt, args);
    va_end(args);
    text_ += buf;
  }
  void add_text(const std::string& s) { text_ += s; }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

// A goal's verdict, with the cases that miss it.
struct Goal {
  std::string statement;
  std::vector<std::string> misses;
  bool measured = false;
};

void report_build(Report& r, const RunInfo& info) {
  r.add("## Model build (each run in its own process)\n\n");
  r.add("| stage | seconds (median, range) |\n|---|---:|\n");
  r.add("| `reconstruct()` | %s |\n", spread_cell(info.builds, 0, 1, 3).c_str());
  r.add("| `build_mc_octree(reconstruction)` (with the distance field of the finished mesh) | %s |\n",
        spread_cell(info.builds, 1, 1, 3).c_str());
  r.add("| `number_nodes()` | %s |\n", spread_cell(info.builds, 2, 1, 3).c_str());
  std::vector<Outcome> model = info.builds, total = info.builds;
  for (Outcome& o : model) o.values[0] = o.values[1] + o.values[2];
  for (Outcome& o : total) o.values[0] += o.values[1] + o.values[2];
  r.add("| **model build** = octree + numbering | **%s** |\n", spread_cell(model, 0, 1, 3).c_str());
  r.add("| points → model (all three) | %s |\n", spread_cell(total, 0, 1, 3).c_str());
  std::vector<Outcome> with_clusters = info.builds;
  for (Outcome& o : with_clusters) o.values[0] += o.values[1] + o.values[2] + o.values[4];
  r.add("| `add_cluster_hierarchy(model, reconstruction mesh)` (the cluster hierarchy, all threads) | %s |\n",
        spread_cell(info.builds, 4, 1, 3).c_str());
  r.add("| points → model with both structures (as `scan2lod build`) | %s |\n",
        spread_cell(with_clusters, 0, 1, 3).c_str());
  double peak = 0;
  for (const Outcome& o : info.builds) peak = std::max(peak, o.peak_mib);
  r.add("\nPeak RSS of a build process: %.0f MiB (an idle child of this benchmark peaks at %.0f MiB: "
        "what every child inherits). Model: resolution %d (depth %d), %zu nodes, %zu leaves, %zu "
        "expansions (LOD array entries); the full mesh has %zu triangles and %zu vertices, "
        "bounding-box diagonal %.4f.\n\n",
        peak, info.baseline_mib, 1 << info.depth, info.depth, info.nodes, info.leaves, info.expansions,
        info.full_triangles, info.full_vertices, info.diagonal);
}

void report_extraction(Report& r, const std::vector<Level>& levels, std::size_t full_priority) {
  r.add("## Extraction by reference\n\n");
  r.add("| level | priority (%% of the array) | triangles | vertices | `extract_lod` ms (median; min–max; reps) | M triangles/s "
        "| `extract_lod` + `compact_level` ms (median) | boundary loops | non-manifold edges | components "
        "| error to full (1e-3 diag) | p95 / max (1e-3 diag) |\n");
  r.add("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Level& l : levels) {
    const Values& v = l.extraction.values;
    const std::string error = l.fidelity ? error_text(error_1e3(*l.fidelity)) : l.measure_error.empty() ? "—" : "failed";
    const std::string tail = l.fidelity ? tail_cell(*l.fidelity) : "—";
    if (l.extraction.status != Outcome::ok) {
      r.add("| %s | %zu | %lld | %zu | %s | — | — | %zu | %zu | %zu | %s | %s |\n", percent_label(l).c_str(),
            l.priority, (long long)l.triangles, l.vertices, l.extraction.message.c_str(), l.topology.boundary_loops,
            l.topology.non_manifold_edges, l.topology.components, error.c_str(), tail.c_str());
      continue;
    }
    r.add("| %s | %zu (%.2f %%) | %lld | %zu | %.3f (%.3f–%.3f; %.0f) | %.1f | %.3f | %zu | %zu | %zu | %s | %s |\n",
          percent_label(l).c_str(), l.priority, 100.0 * double(l.priority) / double(full_priority), (long long)l.triangles, l.vertices, v[0] * 1e3, v[1] * 1e3,
          v[2] * 1e3, v[4], double(l.triangles) / v[0] / 1e6, v[3] * 1e3, l.topology.boundary_loops,
          l.topology.non_manifold_edges, l.topology.components, error.c_str(), tail.c_str());
  }
  r.add("\n");
}

std::string peer_error_cell(const PeerCase& c) {
  if (!c.runs.empty() && c.runs[0].status != Outcome::ok) return "—";
  if (c.fidelity) return error_text(error_1e3(*c.fidelity));
  return c.measure_error.empty() ? "—" : "failed";
}

void report_peers(Report& r, const std::vector<Level>& levels, double timeout) {
  r.add("## Peers at scan2lod's triangle counts, on the same full mesh\n\n");
  r.add("Error: two-sided mean distance to the full mesh, 1e-3 of its diagonal (out→full / full→out in "
        "parentheses). Time ratio: the peer's seconds / scan2lod's `extract_lod` seconds at that level. "
        "p95 / max: the larger direction's 95th percentile and maximum distance. Error ratio: scan2lod's error / the "
        "peer's (below 1: scan2lod is closer).\n\n");
  for (const Level& l : levels) {
    if (l.peers.empty()) continue;
    r.add("### %s%s: %lld triangles\n\n", percent_label(l).c_str(), l.budget > 0 ? " (`--triangles`)" : " of the LOD array",
          (long long)l.triangles);
    r.add("| method | kind | triangles | seconds (median, range) | time ratio | error (1e-3 diag) | p95 / max "
          "| error ratio | boundary loops | non-manifold edges | components | peak MiB | setting |\n");
    r.add("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
    const std::string own_error = l.fidelity ? error_text(error_1e3(*l.fidelity)) : "—";
    const std::string own_detail =
        l.fidelity ? " (" + error_text(1e3 * l.fidelity->a_to_b.mean / l.fidelity->diagonal) + " / " +
                         error_text(1e3 * l.fidelity->b_to_a.mean / l.fidelity->diagonal) + ")"
                   : "";
    r.add("| **scan2lod `extract_lod`** | octree cut | %lld | %s | 1 | **%s**%s | %s | 1 | %zu | %zu | %zu | %.0f | "
          "priority %zu |\n",
          (long long)l.triangles,
          l.extraction.status == Outcome::ok ? fixed(l.extract_seconds(), 6).c_str() : l.extraction.message.c_str(),
          own_error.c_str(), own_detail.c_str(), l.fidelity ? tail_cell(*l.fidelity).c_str() : "—", l.topology.boundary_loops, l.topology.non_manifold_edges,
          l.topology.components, l.extraction.peak_mib, l.priority);
    for (const PeerCase& c : l.peers) {
      const Peer& p = *c.peer;
      const char* kind = p.clustering ? "vertex clustering" : "edge collapse";
      if (c.runs.empty()) {
        r.add("| %s | %s | — | skipped (--only) | — | — | — | — | — | — | — | — | |\n", p.name.c_str(), kind);
        continue;
      }
      const bool ok = c.all_ok();
      std::string time_ratio = "—", error = peer_error_cell(c), error_ratio = "—", detail;
      if (ok && l.extraction.status == Outcome::ok) time_ratio = fixed(c.seconds() / l.extract_seconds(), 0);
      if (c.runs[0].status == Outcome::timed_out && l.extraction.status == Outcome::ok)
        time_ratio = "> " + fixed(timeout / l.extract_seconds(), 0);
      if (c.fidelity) {
        detail = " (" + error_text(1e3 * c.fidelity->a_to_b.mean / c.fidelity->diagonal) + " / " +
                 error_text(1e3 * c.fidelity->b_to_a.mean / c.fidelity->diagonal) + ")";
        if (l.fidelity) error_ratio = ratio_text(error_1e3(*l.fidelity) / error_1e3(*c.fidelity));
      }
      std::string setting;
      if (p.describe && !std::isnan(c.setting)) setting = p.describe(c.setting);
      if (c.rejected > 0) setting += (setting.empty() ? "" : "; ") + fixed(c.rejected, 0) + " input faces refused";
      const std::string tri = c.topology ? std::to_string(c.topology->triangles) : "—";
      r.add("| %s | %s | %s | %s | %s | %s%s | %s | %s | %s | %s | %s | %.0f | %s |\n", p.name.c_str(), kind,
            tri.c_str(), spread_cell(c.runs, 0, 1, 3).c_str(), time_ratio.c_str(), error.c_str(), detail.c_str(),
            c.fidelity ? tail_cell(*c.fidelity).c_str() : "—", error_ratio.c_str(), c.topology ? std::to_string(c.topology->boundary_loops).c_str() : "—",
            c.topology ? std::to_string(c.topology->non_manifold_edges).c_str() : "—",
            c.topology ? std::to_string(c.topology->components).c_str() : "—", c.peak_mib(), setting.c_str());
    }
    r.add("\n");
  }
}

// The header of a right-aligned table: `first` columns, then one per peer.
void peer_columns(Report& r, std::initializer_list<const char*> first, const std::vector<Peer>& peers) {
  std::string names = "|", rule = "|";
  for (const char* column : first) names += std::string(" ") + column + " |";
  for (const Peer& p : peers) names += " " + p.name + " |";
  for (std::size_t i = 0; i < first.size() + peers.size(); ++i) rule += "---:|";
  r.add("%s\n%s\n", names.c_str(), rule.c_str());
}

// Where scan2lod's error comes from: its level against the same octree cut
// with no crack patching, and against the best edge-collapse peer.
void report_open_cut(Report& r, const std::vector<Level>& levels) {
  r.add("## Where the error comes from\n\n"
        "The same LOD array's cut with every node emitting its own marching-cubes triangles and no "
        "transitions (cracks left open, as in the seed before its projection), taken at the first priority "
        "where it has at least the level's triangles. If it is about as far from the full mesh as the "
        "level, crack patching costs no accuracy at equal size, and the gap to edge collapse is the cut's "
        "own: marching cubes on octree cells, with vertices on the cells' edges.\n\n"
        "| level | triangles | scan2lod | open cut: priority, triangles | open cut error | best edge collapse "
        "| scan2lod / best | open cut / best |\n|---:|---:|---:|---:|---:|---|---:|---:|\n");
  for (const Level& l : levels) {
    if (!l.open_fidelity || !l.fidelity) continue;
    double best = 0;
    std::string best_name;
    for (const PeerCase& c : l.peers) {
      if (!c.peer || c.peer->clustering || !c.fidelity) continue;
      const double e = error_1e3(*c.fidelity);
      if (best_name.empty() || e < best) best = e, best_name = c.peer->name;
    }
    const double own = error_1e3(*l.fidelity), open = error_1e3(*l.open_fidelity);
    r.add("| %s | %lld | %s | %zu, %lld | %s | %s | %s | %s |\n", percent_label(l).c_str(), (long long)l.triangles,
          error_text(own).c_str(), l.open_priority, (long long)l.open_triangles, error_text(open).c_str(),
          best_name.empty() ? "—" : (best_name + " " + error_text(best)).c_str(),
          best > 0 ? ratio_text(own / best).c_str() : "—", best > 0 ? ratio_text(open / best).c_str() : "—");
  }
  r.add("\n");
}

// Error and time of every method at every level in two compact tables.
void report_matrices(Report& r, const std::vector<Level>& levels, const std::vector<Peer>& peers) {
  r.add("## At a glance\n\n");
  r.add("Error, two-sided mean to the full mesh in 1e-3 of its diagonal (a peer's achieved triangle count "
        "in brackets where it is more than 1 %% off scan2lod's):\n\n");
  peer_columns(r, {"level", "triangles", "scan2lod"}, peers);
  for (const Level& l : levels) {
    if (l.peers.empty()) continue;
    r.add("| %s | %lld | **%s** |", percent_label(l).c_str(), (long long)l.triangles,
          l.fidelity ? error_text(error_1e3(*l.fidelity)).c_str() : "—");
    for (const PeerCase& c : l.peers) {
      std::string cell = c.runs.empty() ? "skipped" : !c.all_ok() ? c.runs[0].message : peer_error_cell(c);
      if (c.topology && std::abs(double(c.topology->triangles) - double(l.triangles)) > 0.01 * double(l.triangles))
        cell += " [" + std::to_string(c.topology->triangles) + "]";
      r.add(" %s |", cell.c_str());
    }
    r.add("\n");
  }
  r.add("\nSeconds (scan2lod: `extract_lod` alone; peers: the simplification call, median):\n\n");
  peer_columns(r, {"level", "scan2lod"}, peers);
  for (const Level& l : levels) {
    if (l.peers.empty()) continue;
    r.add("| %s | **%s** |", percent_label(l).c_str(),
          l.extraction.status == Outcome::ok ? fixed(l.extract_seconds(), 5).c_str() : "failed");
    for (const PeerCase& c : l.peers)
      r.add(" %s |", c.runs.empty() ? "skipped" : c.all_ok() ? fixed(c.seconds(), 3).c_str() : c.runs[0].message.c_str());
    r.add("\n");
  }
  r.add("\n");
}

std::vector<Goal> evaluate_goals(const std::vector<Level>& levels, const RunInfo& info) {
  std::vector<Goal> goals(6);
  goals[0].statement = "Model build (`build_mc_octree` + `number_nodes`) under 1 s";
  {
    std::vector<double> v;
    for (const Outcome& o : info.builds)
      if (o.status == Outcome::ok) v.push_back(o.values[1] + o.values[2]);
    goals[0].measured = !v.empty() && v.size() == info.builds.size();
    if (goals[0].measured && median(v) >= 1.0) goals[0].misses.push_back("median " + fixed(median(v), 2) + " s");
  }
  goals[1].statement = "`extract_lod` at ≥ 50 M triangles/s at every level";
  goals[2].statement = "`extract_lod` ≥ 100× faster than `meshopt_simplify` at the same count, at every level";
  goals[3].statement = "scan2lod's error below every vertex-clustering peer's, at every level";
  goals[4].statement = "scan2lod's error within 1.5× of every quadric edge-collapse peer's, at every level";
  goals[5].statement = "Octree at the budget levels (`--triangles`): error below Open3D VertexClustering's and "
                       "meshopt_simplifySloppy's at the same count";
  for (const Level& l : levels) {
    const std::string at = percent_label(l);
    if (l.extraction.status == Outcome::ok) {
      goals[1].measured = true;
      const double rate = double(l.triangles) / l.extract_seconds() / 1e6;
      if (rate < 50) goals[1].misses.push_back(at + ": " + fixed(rate, 1) + " M/s");
    } else {
      goals[1].misses.push_back(at + ": extraction " + l.extraction.message);
    }
    for (const PeerCase& c : l.peers) {
      if (c.peer->name == "meshopt_simplify" && c.all_ok() && l.extraction.status == Outcome::ok) {
        goals[2].measured = true;
        const double ratio = c.seconds() / l.extract_seconds();
        if (ratio < 100) goals[2].misses.push_back(at + ": " + fixed(ratio, 0) + "×");
      }
      if (!c.fidelity || !l.fidelity) continue;
      const double ratio = error_1e3(*l.fidelity) / error_1e3(*c.fidelity);
      if (l.budget > 0 && (c.peer->name == "Open3D VertexClustering" || c.peer->name == "meshopt_simplifySloppy")) {
        goals[5].measured = true;
        if (ratio >= 1) goals[5].misses.push_back(at + " vs " + c.peer->name + ": " + ratio_text(ratio) + "×");
      }
      Goal& g = goals[c.peer->clustering ? 3 : 4];
      g.measured = true;
      if (c.peer->clustering ? ratio >= 1 : ratio > 1.5)
        g.misses.push_back(at + " vs " + c.peer->name + ": " + ratio_text(ratio) + "×");
    }
  }
  return goals;
}

void report_goals(Report& r, const std::vector<Goal>& goals) {
  r.add("## Goals\n\n");
  for (const Goal& g : goals) {
    if (!g.measured) {
      r.add("- **not measured**: %s.\n", g.statement.c_str());
    } else if (g.misses.empty()) {
      r.add("- **met**: %s.\n", g.statement.c_str());
    } else {
      std::string list;
      for (const std::string& m : g.misses) list += (list.empty() ? "" : "; ") + m;
      r.add("- **not met**: %s. Misses (%zu): %s.\n", g.statement.c_str(), g.misses.size(), list.c_str());
    }
  }
  r.add("\n");
}

void report_notes(Report& r, const Settings& s, const RunInfo& info, const std::vector<Peer>& peers,
                  const std::vector<Level>& levels) {
  r.add("## Notes\n\n");
  r.add("- Every timed case ran in its own forked process. Build and peer cases: %s; killed after %.0f s. "
        "Peak MiB is the process's `ru_maxrss`, including what it inherits from the parent (points, model, "
        "full mesh): an idle child peaks at %.0f MiB.\n",
        s.runs == 1 ? "one run each"
                    : (std::to_string(s.runs) + " runs (median, range) when the first took under " +
                       fixed(s.repeat_under, 0) + " s, else one")
                          .c_str(),
        s.timeout, info.baseline_mib);
  r.add("- scan2lod: default `ReconstructOptions` apart from R = %d, all %ld threads for `reconstruct()` and the "
        "octree's field; `number_nodes` is single-threaded, `extract_lod` runs on all of them from 1,024 expansions "
        "on (ordered chunks, the same output as one thread). Levels are `priority_for_percent(p)`, "
        "i.e. the largest offered priority (`monotone_priorities`) at or below p %% of the LOD array, and the "
        "budget levels `LevelRequest::at_triangles(b)`, what `--triangles b` gives (within 10 %% of b, "
        "lod/level_budget.h). "
        "`extract_lod` was timed at least %d times and for at least 0.25 s per level with its scratch vectors "
        "reused (the first, sizing call untimed); `compact_level` adds building a self-contained mesh. The peers' "
        "times compare with `extract_lod` alone because their outputs, too, are index buffers or meshes the "
        "library already holds.\n",
        s.resolution, sysconf(_SC_NPROCESSORS_ONLN), s.reps);
  r.add("- Peers simplify the full mesh (the model's 100 %% level, `compact_level`, %zu triangles) to each "
        "level's triangle count. Their times exclude copying the mesh into the library's types and back.\n",
        info.full_triangles);
  for (const Peer& p : peers) r.add("- %s: %s.\n", p.name.c_str(), p.setup.c_str());
  r.add("- Fidelity: `compare_surfaces(output, full mesh)` with %zu samples per direction and seed %llu; error = "
        "(mean out→full + mean full→out) / 2 / the full mesh's bounding-box diagonal (%.4f), in 1e-3. Topology "
        "from `mesh_topology` on the output's index buffer (no welding).\n",
        s.samples, (unsigned long long)s.seed, info.diagonal);
  for (const Level& l : levels) {
    if (!l.measure_error.empty())
      r.add("- scan2lod at %s: measuring failed: %s\n", percent_label(l).c_str(), l.measure_error.c_str());
    for (const PeerCase& c : l.peers) {
      if (!c.measure_error.empty())
        r.add("- %s at %s: measuring failed: %s\n", c.peer->name.c_str(), percent_label(l).c_str(),
              c.measure_error.c_str());
      if (c.topology && c.topology->degenerate_triangles > 0)
        r.add("- %s at %s: %zu degenerate triangles (no samples on them).\n", c.peer->name.c_str(),
              percent_label(l).c_str(), c.topology->degenerate_triangles);
      if (c.peer->name == "VTK QuadricClustering" && int(c.setting) == info.clustering_cap && c.topology &&
          std::int64_t(c.topology->triangles) < l.triangles)
        r.add("- %s at %s: n reached its cap of %d (VTK 9.1 allocates a 88-byte quadric for every bin of the "
              "grid; the cap keeps that under 4 GiB), so the count stayed below the target.\n",
              c.peer->name.c_str(), percent_label(l).c_str(), info.clustering_cap);
    }
    if (l.accumulated != l.triangles)
      r.add("- scan2lod at %s: the accumulation table says %lld triangles, `extract_lod` gave %lld.\n",
            percent_label(l).c_str(), (long long)l.accumulated, (long long)l.triangles);
    if (l.extraction.status == Outcome::ok && l.extraction.values[5] != double(l.triangles))
      r.add("- scan2lod at %s: the timed extraction gave %.0f triangles, not %lld.\n", percent_label(l).c_str(),
            l.extraction.values[5], (long long)l.triangles);
    if (l.topology.degenerate_triangles > 0)
      r.add("- scan2lod at %s: %zu degenerate triangles.\n", percent_label(l).c_str(), l.topology.degenerate_triangles);
  }
  r.add("- Whole benchmark: %.0f s wall time.\n", info.total_seconds);
}

// An error cell of the cluster table: the peer's error, with its count in
// brackets where it is more than 1 % off the cut's.
std::string cluster_peer_cell(const PeerCase& c, std::int64_t triangles) {
  std::string cell = c.runs.empty() ? "skipped" : !c.all_ok() ? c.runs[0].message : peer_error_cell(c);
  if (c.topology && std::abs(double(c.topology->triangles) - double(triangles)) > 0.01 * double(triangles))
    cell += " [" + std::to_string(c.topology->triangles) + "]";
  return cell;
}

double cluster_build_ratio(const RunInfo& info) {
  if (!all_ok(info.cluster_builds) || !all_ok(info.simplify_1)) return 0;
  return median_seconds(info.cluster_builds) / median_seconds(info.simplify_1);
}

void report_clusters(Report& r, const RunInfo& info, const std::vector<ClusterLevel>& levels,
                     const std::vector<Peer>& peers) {
  r.add("## Cluster hierarchy beside the octree\n\n");
  r.add("The model's second structure (Cignoni et al., *Batched Multi-Triangulation*, 2005; "
        "lod/clusters/cluster_hierarchy.h), read through the LOD face (`LevelExtractor`, `compact_level`): %zu clusters "
        "in %d levels over %lld triangles at full detail%s. Budgets at or above the full count are left out.\n\n",
        info.clusters, info.cluster_levels, (long long)info.cluster_full,
        info.same_full ? ", the same triangles as the octree's full detail (the peers' full mesh)"
                       : ", NOT the octree's full-detail triangles (errors are still to the octree's full mesh)");
  r.add("| cluster hierarchy | value |\n|---|---:|\n");
  r.add("| build in the model build (`add_cluster_hierarchy`, s, median, range) | %s |\n",
        spread_cell(info.builds, 4, 1, 3).c_str());
  r.add("| build alone on the full mesh (own process, s) | %s |\n", spread_cell(info.cluster_builds, 0, 1, 3).c_str());
  r.add("| `meshopt_simplify` of the same mesh to 1 %% (s) | %s |\n", spread_cell(info.simplify_1, 0, 1, 3).c_str());
  const double ratio = cluster_build_ratio(info);
  r.add("| build alone / `meshopt_simplify` to 1 %% | %s |\n", ratio > 0 ? (ratio_text(ratio) + "×").c_str() : "—");
  const double peak = bench::peak_mib(info.cluster_builds);
  r.add("| peak RSS of the build alone (MiB; over an idle child's %.0f) | %.0f (+%.0f) |\n", info.baseline_mib, peak,
        std::max(0.0, peak - info.baseline_mib));
  r.add("| stored triangles / full | %zu / %lld = %s× |\n", info.stored_triangles, (long long)info.cluster_full,
        ratio_text(double(info.stored_triangles) / double(info.cluster_full)).c_str());
  r.add("| coarsest cut (triangles) | %lld |\n", (long long)info.coarsest);
  const Outcome& v = info.view;
  if (v.status == Outcome::ok) {
    r.add("| view-dependent selection, %.0f cameras, %.0f px (`select_seconds`, ms: median; slowest camera) "
          "| %.4f; %.4f |\n",
          v.values[6], info.pixel_error, v.values[0] * 1e3, v.values[1] * 1e3);
    r.add("| view-dependent cut: `extract_seconds` ms (median); triangles (median; min–max) | %.3f; %.0f (%.0f–%.0f) |\n",
          v.values[2] * 1e3, v.values[3], v.values[4], v.values[5]);
  } else {
    r.add("| view-dependent selection | %s |\n", v.message.c_str());
  }
  r.add("\n");

  r.add("Uniform cuts (`LevelRequest::at_triangles(budget)`) against every peer at the cut's count, on the same "
        "full mesh: error, two-sided mean to the full mesh in 1e-3 of its diagonal (a peer's count in brackets "
        "where it is more than 1 %% off the cut's). Octree: its finest level with at most the cut's "
        "triangles (its coarsest when none has), count in brackets. Ratio: the cut's error / meshopt_simplify's "
        "(goal ≤ 1.25 up to %lldk); most faithful peer and cut / it: from the unrounded errors.\n\n",
        (long long)(kSimplifyGoalMax / 1000));
  peer_columns(r, {"budget", "cut triangles", "clusters", "threshold (1e-3 diag)", "cluster cut", "cut / meshopt_simplify",
                   "most faithful peer", "cut / it", "octree"},
               peers);
  for (const ClusterLevel& l : levels) {
    if (l.peers.empty()) continue;
    const std::string own = l.fidelity ? error_text(error_1e3(*l.fidelity)) : l.measure_error.empty() ? "—" : "failed";
    std::string to_simplify = "—";
    if (const PeerCase* m = l.peer("meshopt_simplify"); m && m->fidelity && l.fidelity)
      to_simplify = ratio_text(error_1e3(*l.fidelity) / error_1e3(*m->fidelity));
    const std::string octree =
        l.octree_fidelity ? error_text(error_1e3(*l.octree_fidelity)) + " [" + std::to_string(l.octree_triangles) + "]"
                          : "—";
    // The most faithful peer from unrounded errors (the finest cuts' round to 0).
    const PeerCase* best = nullptr;
    for (const PeerCase& c : l.peers)
      if (c.fidelity && (!best || error_1e3(*c.fidelity) < error_1e3(*best->fidelity))) best = &c;
    const std::string best_name = best ? best->peer->name : "—";
    const std::string to_best =
        best && l.fidelity && error_1e3(*best->fidelity) > 0 ? ratio_text(error_1e3(*l.fidelity) / error_1e3(*best->fidelity))
                                                             : "—";
    r.add("| %s | %lld | %zu | %s | **%s** | %s | %s | %s | %s |", l.label().c_str(), (long long)l.triangles, l.clusters,
          fixed(1e3 * l.threshold / info.diagonal, 4).c_str(), own.c_str(), to_simplify.c_str(), best_name.c_str(),
          to_best.c_str(), octree.c_str());
    for (const PeerCase& c : l.peers) r.add(" %s |", cluster_peer_cell(c, l.triangles).c_str());
    r.add("\n");
  }
  r.add("\nCuts refined to the count (lod/clusters/cut_refinement.h: a stored cut of at most 1.25x the budget, "
        "collapsed to it), against the stored cut the budget gets without refining (`LevelRequest::refine = false`): "
        "error in 1e-3 of the diagonal; most faithful peer at the refined cut's count.\n\n"
        "| budget | refined from | cut triangles | refined cut | extract ms | stored cut triangles | stored cut | stored / most faithful peer |\n"
        "|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const ClusterLevel& l : levels) {
    if (l.refined_from == 0 || !l.fidelity || !l.stored_fidelity) continue;
    const PeerCase* best = nullptr;
    for (const PeerCase& c : l.peers)
      if (c.fidelity && (!best || error_1e3(*c.fidelity) < error_1e3(*best->fidelity))) best = &c;
    r.add("| %s | %lld | %lld | %s | %.1f | %lld | %s | %s |\n", l.label().c_str(), (long long)l.refined_from,
          (long long)l.triangles, error_text(error_1e3(*l.fidelity)).c_str(), l.refine_seconds * 1e3,
          (long long)l.stored_triangles,
          error_text(error_1e3(*l.stored_fidelity)).c_str(),
          best && error_1e3(*best->fidelity) > 0 ? ratio_text(error_1e3(*l.stored_fidelity) / error_1e3(*best->fidelity)).c_str() : "—");
  }
  r.add("\nTopology and tails of the cuts (`mesh_topology` on the index buffer; p95 / max: the larger direction's, "
        "1e-3 diag):\n\n");
  r.add("| budget | cut triangles | vertices | boundary loops | non-manifold edges | components | p95 / max |\n"
        "|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const ClusterLevel& l : levels)
    r.add("| %s | %lld | %zu | %zu | %zu | %zu | %s |\n", l.label().c_str(), (long long)l.triangles,
          l.mesh.positions.size(), l.topology.boundary_loops, l.topology.non_manifold_edges, l.topology.components,
          l.fidelity ? tail_cell(*l.fidelity).c_str() : "—");
  r.add("\nExtraction of the stored cuts, by reference (`LevelRequest::refine = false`; each level in its own "
        "process; `LevelCut::extract_seconds` and `select_seconds`, median over at least --reps repetitions and "
        "0.25 s; a refined cut's time is in the table above):\n\n");
  r.add("| cut | triangles | extract ms (median; min–max; reps) | select ms | M triangles/s "
        "| extract + `compact_level` ms |\n|---:|---:|---:|---:|---:|---:|\n");
  for (const ClusterLevel& l : levels) {
    const Values& x = l.extraction.values;
    if (l.extraction.status != Outcome::ok) {
      r.add("| %s | — | %s | — | — | — |\n", l.label().c_str(), l.extraction.message.c_str());
      continue;
    }
    r.add("| %s | %.0f | %.3f (%.3f–%.3f; %.0f) | %.4f | %.1f | %.3f |\n", l.label().c_str(), x[5], x[0] * 1e3,
          x[1] * 1e3, x[2] * 1e3, x[4], x[3] * 1e3, x[5] / x[0] / 1e6, x[6] * 1e3);
  }
  r.add("\n");
}

std::vector<Goal> evaluate_cluster_goals(const std::vector<ClusterLevel>& levels, const RunInfo& info) {
  std::vector<Goal> goals(7);
  goals[0].statement = "Clusters: uniform cut's error ≤ 1.25× meshopt_simplify's at every budget from 1k to " +
                       std::to_string(kSimplifyGoalMax / 1000) + "k";
  goals[1].statement = "Clusters: uniform cut's error below meshopt_simplifySloppy's, VTK QuadricClustering's and "
                       "Open3D VertexClustering's at every budget from 1k to " +
                       std::to_string(kClusteringGoalMax / 1000) + "k";
  for (const ClusterLevel& l : levels) {
    if (l.budget == 0 || !l.fidelity) continue;
    for (const PeerCase& c : l.peers) {
      if (!c.fidelity) continue;
      const double ratio = error_1e3(*l.fidelity) / error_1e3(*c.fidelity);
      if (c.peer->name == "meshopt_simplify" && l.budget <= kSimplifyGoalMax) {
        goals[0].measured = true;
        if (ratio > 1.25) goals[0].misses.push_back(l.label() + ": " + ratio_text(ratio) + "×");
      }
      if (c.peer->clustering && l.budget <= kClusteringGoalMax) {
        goals[1].measured = true;
        if (ratio >= 1) goals[1].misses.push_back(l.label() + " vs " + c.peer->name + ": " + ratio_text(ratio) + "×");
      }
    }
  }
  goals[2].statement = "Clusters: coarsest cut ≤ 256 triangles";
  goals[2].measured = info.coarsest > 0;
  if (info.coarsest > 256) goals[2].misses.push_back(std::to_string(info.coarsest) + " triangles");
  goals[3].statement = "Clusters: build ≤ 6× meshopt_simplify of the same mesh to 1 %";
  const double build = cluster_build_ratio(info);
  goals[3].measured = build > 0;
  if (build > 6) goals[3].misses.push_back(ratio_text(build) + "×");
  goals[4].statement = "Clusters: stored triangles ≤ 2.4× the full mesh's";
  goals[4].measured = info.cluster_full > 0;
  const double storage = double(info.stored_triangles) / double(std::max<std::int64_t>(1, info.cluster_full));
  if (storage > 2.4) goals[4].misses.push_back(ratio_text(storage) + "×");
  goals[5].statement = "Clusters: view-dependent selection ≤ 0.1 ms (median over the cameras)";
  goals[5].measured = info.view.status == Outcome::ok;
  if (goals[5].measured && info.view.values[0] > 1e-4)
    goals[5].misses.push_back(fixed(info.view.values[0] * 1e3, 3) + " ms");
  goals[6].statement = "Clusters: extraction ≥ 200 M triangles/s at full detail and at every budget from " +
                       std::to_string(kRateGoalMin / 1000) + "k";
  for (const ClusterLevel& l : levels) {
    if (l.budget != 0 && l.budget < kRateGoalMin) continue;
    if (l.extraction.status != Outcome::ok) {
      goals[6].misses.push_back(l.label() + ": " + l.extraction.message);
      continue;
    }
    goals[6].measured = true;
    const double rate = l.extraction.values[5] / l.extract_seconds() / 1e6;  // the stored cut's
    if (rate < 200) goals[6].misses.push_back(l.label() + ": " + fixed(rate, 1) + " M/s");
  }
  return goals;
}

std::string make_report(const Settings& s, const RunInfo& info, const std::vector<Level>& levels,
                        const std::vector<ClusterLevel>& cluster_levels, const std::vector<Peer>& peers) {
  Report r;
  r.add("# LOD benchmark: scan2lod's marching-cube octree and cluster hierarchy against mesh simplifiers\n\n");
  r.add_text(run_header_line(info.load_at_start, info.load_at_end) + "\n\n");
  r.add("Command: `%s`  \n", info.command_line.c_str());
  r.add_text(openmp_line());
  const std::string revision = source_revision();
  if (!revision.empty()) r.add("Source: %s (at run time)  \n", revision.c_str());
  r.add("Input: `%s` (%zu oriented points), R = %d\n\n", s.input.c_str(), info.points, s.resolution);
  report_build(r, info);
  report_extraction(r, levels, info.expansions);
  std::vector<Goal> goals = evaluate_goals(levels, info);
  for (Goal& g : evaluate_cluster_goals(cluster_levels, info)) goals.push_back(std::move(g));
  report_goals(r, goals);
  report_matrices(r, levels, peers);
  report_clusters(r, info, cluster_levels, peers);
  report_open_cut(r, levels);
  report_peers(r, levels, s.timeout);
  report_notes(r, s, info, peers, levels);
  return r.text();
}

// Each peer's output that ran: its topology and distance to the full mesh.
void measure_peers(std::vector<PeerCase>* peers, const TriangleMesh& full, const CompareOptions& compare) {
  for (PeerCase& c : *peers) {
    if (c.runs.empty() || c.runs[0].status != Outcome::ok) continue;
    try {
      const TriangleMesh mesh = undump_mesh(c.mesh_path);
      c.topology = mesh_topology(mesh);
      c.fidelity = compare_surfaces(mesh, full, compare);
    } catch (const std::exception& e) {
      c.measure_error = e.what();
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Times scan2lod's LOD model (build, extraction) against mesh simplifiers at the same triangle "
               "counts and measures every result's distance to the full mesh; prints a markdown report"};
  Settings s;
  s.input = default_input();
  app.add_option("--input", s.input, "Scans to build the model from (.conf, range-grid PLYs, a mesh, ...)");
  app.add_option("--resolution", s.resolution, "Leaf cubes per side (a power of two)");
  app.add_flag("--quick", s.quick, "R = 128, levels 100/20/5 %, one run each: an end-to-end check");
  app.add_option("--runs", s.runs, "Runs of a build or peer case (median)")->check(CLI::PositiveNumber);
  app.add_option("--repeat-under", s.repeat_under, "Repeat a peer only if its first run took under this many seconds");
  app.add_option("--timeout", s.timeout, "Kill a case after this many seconds (0: never)");
  app.add_option("--reps", s.reps, "Minimum repetitions of each extraction (median)")->check(CLI::PositiveNumber);
  app.add_option("--samples", s.samples, "Metro samples per direction for fidelity");
  app.add_option("--seed", s.seed, "Seed of the Metro sampling");
  app.add_option("--only", s.only, "Run only the peers whose name contains this; the others are listed as skipped");
  app.add_flag("--write", s.write, "Also write the report to bench/lod/REPORT.md in the source tree");
  app.add_option("--cut-budgets", s.cut_budgets,
                 "Triangle budgets of the cluster hierarchy's uniform cuts (default 1000 ... 200000)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  if (s.input.empty()) {
    std::fprintf(stderr, "no input: neither %s/data/bunny/bun.conf nor ../shared/data/bunny exists; pass --input\n",
                 SCAN2LOD_SOURCE_DIR);
    return 2;
  }
  if (s.quick) {
    if (app.count("--resolution") == 0) s.resolution = 128;
    if (app.count("--runs") == 0) s.runs = 1;
    if (app.count("--reps") == 0) s.reps = 20;
  }
  const std::vector<double> percents =
      s.quick ? std::vector<double>{100, 20, 5} : std::vector<double>{100, 80, 60, 40, 20, 5, 1};
  // The coarse end as users ask for it: `--triangles` budgets.
  const std::vector<std::int64_t> budgets =
      s.quick ? std::vector<std::int64_t>{1000, 5000} : std::vector<std::int64_t>{20000, 5000, 2000, 1000};
  Progress::set_quiet(true);
  const auto benchmark_start = Clock::now();

  RunInfo info;
  info.load_at_start = load_average();
  info.command_line = command_line("scan2lod_bench_lod", argc, argv);

  const ScratchDir work_dir("scan2lod_bench_lod");
  const auto work_path = [&](const std::string& name) { return work_dir.path(name); };

  std::fprintf(stderr, "loading %s\n", s.input.c_str());
  OrientedPoints points;
  try {
    points = load_points_in_child(s.input, work_path("points.bin"));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "loading failed: %s\n", e.what());
    return 1;
  }
  info.points = points.size();

  // 1. Model builds; the first one also saves the model for the parent.
  const std::string model_path = work_path("model.mco");
  for (int run = 0; run < s.runs; ++run) {
    std::fprintf(stderr, "build %d/%d at R=%d\n", run + 1, s.runs, s.resolution);
    const Outcome o = run_in_child([&] {
      const TimedModel t = build_model_timed(points, s.resolution);
      if (run == 0) save_model(model_path, t.model);
      return Values{t.reconstruct_seconds, t.octree_seconds, t.numbering_seconds,
                    double(t.full_triangles), t.cluster_seconds, 0, 0, 0};
    }, s.timeout);
    std::fprintf(stderr, "  %s, peak %.0f MiB\n",
                 o.status == Outcome::ok
                     ? format("reconstruct %.2f s, octree %.2f s, numbering %.2f s, clusters %.2f s", o.values[0],
                              o.values[1], o.values[2], o.values[4]).c_str()
                     : o.message.c_str(),
                 o.peak_mib);
    info.builds.push_back(o);
    if (run == 0 && o.status != Outcome::ok) {
      std::fprintf(stderr, "the first build failed; nothing to measure\n");
      return 1;
    }
  }
  const LodModel model = load_model(model_path);
  require_structure(model, LodStructure::kOctree, model_path);
  require_structure(model, LodStructure::kClusters, model_path);
  {
    const McOctree& tree = model.octree->tree;  // counts for the report
    info.depth = tree.depth;
    info.nodes = tree.size();
    info.expansions = model.octree->lod.full();
    for (std::size_t n = 0; n < tree.size(); ++n) info.leaves += tree.is_leaf(n);
  }

  // The levels, and the full mesh every peer starts from, on one thread:
  // extract_lod runs big levels on an OpenMP team otherwise, and the parent
  // must not start libgomp's pool before its last fork.
  std::vector<Level> levels;
  TriangleMesh full;
  std::vector<Triangle> octree_full;  // the octree's full detail, into the model's vertices
  {
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const LodArray& lod = model.octree->lod;
    LevelExtractor octree(model, LodStructure::kOctree);
    auto take = [&](Level l, const LevelRequest& request) {
      const LevelCut& cut = octree.extract(request);
      l.priority = cut.priority;
      if (l.budget > 0) l.percent = cut.percent;
      l.triangles = std::int64_t(cut.triangles.size());
      l.accumulated = lod.accumulated[l.priority];
      l.mesh = compact_level(model, cut.triangles);
      l.vertices = l.mesh.positions.size();
      l.topology = mesh_topology(l.mesh);
      if (l.priority == lod.full()) full = l.mesh, octree_full = cut.triangles;
      levels.push_back(std::move(l));
    };
    for (const double p : percents) {
      Level l;
      l.percent = p;
      take(std::move(l), LevelRequest::at_percent(p));
    }
    for (const std::int64_t b : budgets) {
      if (b * 2 >= lod.accumulated.back()) continue;
      Level l;
      l.budget = b;
      take(std::move(l), LevelRequest::at_triangles(b));
    }
    if (full.triangles.empty()) {
      octree_full = octree.extract(LevelRequest::at_priority(lod.full())).triangles;
      full = compact_level(model, octree_full);
    }
    omp_set_num_threads(threads);  // for the children; no thread has started here
  }
  info.full_triangles = full.triangles.size();
  info.full_vertices = full.positions.size();
  info.diagonal = bounds(full.positions).diagonal();
  info.clustering_cap = max_clustering_divisions(bounds(full.positions));

  // The cluster hierarchy's cuts, through the face; its full detail as a mesh
  // (with normals and colours) for building it alone. No OpenMP in any of it.
  std::vector<ClusterLevel> cluster_levels;
  TriangleMesh cluster_full_mesh;
  {
    LevelExtractor clusters(model, LodStructure::kClusters);
    info.clusters = model.clusters->size();
    info.cluster_levels = clusters.levels();
    info.stored_triangles = model.clusters->triangles.size();
    info.cluster_full = clusters.full_triangles();
    info.coarsest = clusters.coarsest_triangles();
    const std::vector<Triangle> cluster_full = clusters.extract(LevelRequest::at_percent(100)).triangles;
    info.same_full = same_triangles(cluster_full, octree_full);
    cluster_full_mesh = compact_level(model, cluster_full);
    LevelExtractor octree(model, LodStructure::kOctree);
    std::vector<std::int64_t> budgets = {0};
    for (const std::int64_t b : s.cut_budgets)
      if (b < info.cluster_full) budgets.push_back(b);
    for (const std::int64_t b : budgets) {
      ClusterLevel l;
      l.budget = b;
      const LevelCut& cut = clusters.extract(cluster_request(l));
      l.triangles = std::int64_t(cut.triangles.size());
      l.clusters = cut.clusters;
      l.threshold = cut.error;
      l.refined_from = std::int64_t(cut.refined_from);
      l.refine_seconds = cut.extract_seconds;
      l.mesh = compact_level(model, cut.triangles);
      l.topology = mesh_topology(l.mesh);
      if (l.refined_from > 0) {
        LevelRequest stored = cluster_request(l);
        stored.refine = false;
        const LevelCut& s_cut = clusters.extract(stored);
        l.stored_triangles = std::int64_t(s_cut.triangles.size());
        l.stored_mesh = compact_level(model, s_cut.triangles);
      }
      if (b != 0) {
        const int threads = omp_get_max_threads();
        omp_set_num_threads(1);  // extract_lod: no OpenMP team in the parent
        const LevelCut& o = octree.extract(LevelRequest::at_most_triangles(l.triangles));
        l.octree_triangles = std::int64_t(o.triangles.size());
        l.octree_mesh = compact_level(model, o.triangles);
        omp_set_num_threads(threads);
      }
      cluster_levels.push_back(std::move(l));
    }
  }
  info.baseline_mib = run_in_child([] { return Values{}; }, 0).peak_mib;

  // 2. Extraction, one child per level.
  for (Level& l : levels) {
    std::fprintf(stderr, "extract %s (priority %zu, %lld triangles)\n", percent_label(l).c_str(), l.priority,
                 (long long)l.triangles);
    l.extraction = run_in_child([&] { return measure_extraction(model, l.priority, s.reps); }, s.timeout);
    if (l.extraction.status == Outcome::ok)
      std::fprintf(stderr, "  %.3f ms, %.1f M triangles/s\n", l.extract_seconds() * 1e3,
                   double(l.triangles) / l.extract_seconds() / 1e6);
    else
      std::fprintf(stderr, "  %s\n", l.extraction.message.c_str());
  }

  // 3. Peers at every level below full detail.
  const std::vector<Peer> peers = make_peers();
  for (Level& l : levels) {
    if (l.priority == model.octree->lod.full()) continue;
    for (const Peer& p : peers) {
      PeerCase c;
      c.peer = &p;
      c.mesh_path = work_path("peer" + std::to_string(&l - levels.data()) + "_" + std::to_string(&p - peers.data()) + ".bin");
      if (p.name.find(s.only) == std::string::npos) {
        l.peers.push_back(std::move(c));
        continue;
      }
      std::fprintf(stderr, "%s at %s (%lld triangles)\n", p.name.c_str(), percent_label(l).c_str(),
                   (long long)l.triangles);
      c.runs = run_repeated(
          [&](int run) {
            PeerRun pr;
            if (p.searched && run > 0) pr.setting = c.setting;  // skip the search
            const TriangleMesh out = p.work(full, l.triangles, &pr);
            if (run == 0) dump_mesh(c.mesh_path, out);
            return Values{pr.seconds, pr.setting, pr.rejected, double(out.triangles.size()), 0, 0, 0, 0};
          },
          s.runs, s.repeat_under, s.timeout,
          [&](int run, const Outcome& o) {
            if (run == 0 && o.status == Outcome::ok) c.setting = o.values[1], c.rejected = o.values[2];
            std::fprintf(stderr, "  run %d: %s, peak %.0f MiB\n", run + 1,
                         o.status == Outcome::ok ? format("%.3f s, %.0f triangles", o.values[0], o.values[3]).c_str()
                                                 : o.message.c_str(),
                         o.peak_mib);
          });
      l.peers.push_back(std::move(c));
    }
  }
  // 3b. The cluster hierarchy: build alone, meshopt_simplify to 1 %, extraction,
  // view-dependent selection, and the peers at every cut's count (one run each:
  // what is compared is their error).
  std::fprintf(stderr, "cluster hierarchy alone on the full mesh (%zu triangles)\n", cluster_full_mesh.triangles.size());
  info.cluster_builds = run_repeated(
      [&](int) {
        LodModel alone;
        const auto start = Clock::now();
        add_cluster_hierarchy(&alone, cluster_full_mesh, /*shares_vertices=*/false, ClusterOptions{});
        const double seconds = seconds_since(start);
        return Values{seconds, double(alone.clusters->triangles.size()), double(alone.clusters->size()), 0, 0, 0, 0, 0};
      },
      s.runs, s.repeat_under, s.timeout, [](int run, const Outcome& o) {
        std::fprintf(stderr, "  run %d: %s, peak %.0f MiB\n", run + 1,
                     o.status == Outcome::ok ? format("%.3f s", o.values[0]).c_str() : o.message.c_str(), o.peak_mib);
      });
  std::fprintf(stderr, "meshopt_simplify of the same mesh to 1 %%\n");
  info.simplify_1 = run_repeated(
      [&](int) {
        PeerRun pr;
        const TriangleMesh out =
            run_meshopt(cluster_full_mesh, std::int64_t(cluster_full_mesh.triangles.size() / 100), false, &pr);
        return Values{pr.seconds, double(out.triangles.size()), 0, 0, 0, 0, 0, 0};
      },
      s.runs, s.repeat_under, s.timeout, [](int run, const Outcome& o) {
        std::fprintf(stderr, "  run %d: %s\n", run + 1,
                     o.status == Outcome::ok ? format("%.3f s", o.values[0]).c_str() : o.message.c_str());
      });
  for (ClusterLevel& l : cluster_levels) {
    std::fprintf(stderr, "clusters: extract %s (%lld triangles)\n", l.label().c_str(), (long long)l.triangles);
    LevelRequest stored = cluster_request(l);
    stored.refine = false;  // the cut by reference; refining is timed on its own (ClusterLevel::refine_seconds)
    l.extraction = run_in_child([&] { return measure_cluster_extraction(model, stored, s.reps); },
                                s.timeout);
    if (l.extraction.status == Outcome::ok)
      std::fprintf(stderr, "  %.3f ms, %.1f M triangles/s\n", l.extract_seconds() * 1e3,
                   double(l.triangles) / l.extract_seconds() / 1e6);
    else
      std::fprintf(stderr, "  %s\n", l.extraction.message.c_str());
  }
  {
    const std::vector<CameraView> cameras = orbit_cameras(model_bounds(model), 48);
    info.view_reps = std::max(5, s.reps / 5);
    std::fprintf(stderr, "clusters: view-dependent selection at %zu cameras\n", cameras.size());
    info.view = run_in_child([&] { return measure_view_selection(model, cameras, info.pixel_error, info.view_reps); },
                             s.timeout);
    if (info.view.status == Outcome::ok)
      std::fprintf(stderr, "  select %.4f ms median, %.4f ms slowest; %.0f triangles median\n",
                   info.view.values[0] * 1e3, info.view.values[1] * 1e3, info.view.values[3]);
    else
      std::fprintf(stderr, "  %s\n", info.view.message.c_str());
  }
  for (ClusterLevel& l : cluster_levels) {
    if (l.budget == 0) continue;
    for (const Peer& p : peers) {
      PeerCase c;
      c.peer = &p;
      c.mesh_path = work_path("cluster" + std::to_string(&l - cluster_levels.data()) + "_" +
                              std::to_string(&p - peers.data()) + ".bin");
      if (p.name.find(s.only) == std::string::npos) {
        l.peers.push_back(std::move(c));
        continue;
      }
      std::fprintf(stderr, "%s at the %s cut (%lld triangles)\n", p.name.c_str(), l.label().c_str(),
                   (long long)l.triangles);
      c.runs = run_repeated(
          [&](int) {
            PeerRun pr;
            const TriangleMesh out = p.work(full, l.triangles, &pr);
            dump_mesh(c.mesh_path, out);
            return Values{pr.seconds, pr.setting, pr.rejected, double(out.triangles.size()), 0, 0, 0, 0};
          },
          1, 0, s.timeout, [&](int, const Outcome& o) {
            if (o.status == Outcome::ok) c.setting = o.values[1], c.rejected = o.values[2];
            std::fprintf(stderr, "  %s, peak %.0f MiB\n",
                         o.status == Outcome::ok ? format("%.3f s, %.0f triangles", o.values[0], o.values[3]).c_str()
                                                 : o.message.c_str(),
                         o.peak_mib);
          });
      l.peers.push_back(std::move(c));
    }
  }
  info.load_at_end = load_average();

  // 4. Measuring, in this process: no more forks from here on.
  CompareOptions compare;
  compare.samples = s.samples;
  compare.seed = s.seed;
  for (Level& l : levels) {
    std::fprintf(stderr, "measuring %s\n", percent_label(l).c_str());
    try {
      l.fidelity = compare_surfaces(l.mesh, full, compare);
      if (!l.peers.empty()) {
        const TriangleMesh open = open_cut(model, l.triangles, &l.open_priority);
        l.open_triangles = std::int64_t(open.triangles.size());
        l.open_fidelity = compare_surfaces(open, full, compare);
      }
    } catch (const std::exception& e) {
      l.measure_error = e.what();
    }
    measure_peers(&l.peers, full, compare);
  }
  for (ClusterLevel& l : cluster_levels) {
    if (l.budget == 0) continue;  // the full detail: error 0
    std::fprintf(stderr, "measuring the %s cluster cut\n", l.label().c_str());
    try {
      l.fidelity = compare_surfaces(l.mesh, full, compare);
      l.octree_fidelity = compare_surfaces(l.octree_mesh, full, compare);
      if (l.refined_from > 0) l.stored_fidelity = compare_surfaces(l.stored_mesh, full, compare);
    } catch (const std::exception& e) {
      l.measure_error = e.what();
    }
    measure_peers(&l.peers, full, compare);
  }
  info.total_seconds = seconds_since(benchmark_start);

  const std::string report = make_report(s, info, levels, cluster_levels, peers);
  std::fwrite(report.data(), 1, report.size(), stdout);
  if (s.write) {
    const fs::path path = fs::path(SCAN2LOD_SOURCE_DIR) / "bench" / "lod" / "REPORT.md";
    write_file_atomically(path, report);
    std::fprintf(stderr, "wrote %s\n", path.c_str());
  }
  return 0;
}
