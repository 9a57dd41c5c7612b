// Robustness sweep of the LOD model: is every level crack-free, on shapes and
// scans other than the one bunny the other benchmarks use?
//
// One case per run: the points of a case (virtual scans of an Open3D shape or
// of a mesh, real range scans, or a mesh's own vertices) are built into a
// model with both structures as `scan2lod build` does (bench/model_build.h),
// and each structure is checked on its own.
//
// The octree: every offered level (monotone_priorities) is walked with a
// LodCursor and measured; past 1500 offered levels, the coarsest 300 and 1200
// more spread evenly over the rest. The viewer slider's levels at 1, 5, 10,
// 20, 30, ..., 100 % (priority_for_percent) are extracted and judged too. It
// passes when, at every checked level:
//   loops     boundary loops <= the full mesh's (a new loop is a crack)
//   nm        0 non-manifold edges
//   comps     components (through shared vertices) <= the full mesh's
//   degen     0 degenerate triangles
//   accum     the accumulation table's count == the measured count; also at
//             40 sampled offered and 20 sampled arbitrary priorities
//   monotone  counts never fall, over the checked levels, the percent levels
//             and all offered priorities
//   closed    only for shapes with a known answer (--expect-components and
//             --expect-euler): 0 boundary edges and at most that many
//             components; χ is information only (a coarse level may close a
//             handle, and only the full mesh's χ is known)
// and levels go all the way down:
//   down      the coarsest offered level has at most 1 % of the full
//             triangles (judged from 20 000 full triangles on)
//   budget    priority_for_budget(500, 1000, 2000, 5000, 20000; those
//             under half the full count) gives a level within 10 % of the
//             budget (lod/level_budget.h)
// Folded edges (interior edges whose triangles face opposite ways) and
// singular vertices (pinches: more than one fan of triangles) at the percent
// levels, and the checked levels without the full mesh's topology, are
// reported as information only.
//
// The cluster hierarchy ("sound", and "crack-free from any view"): every
// uniform cut of cluster_cut_table with at least 1000 triangles (every cut of
// a mesh under 10 000) at its error, and the cut of each of 50 cameras (half
// outside the box, half inside) at 0.5, 1, 2, 4 and 8 pixels, are measured as
// index buffers into the model's vertices. It passes when:
//   cl_loops  every judged uniform cut of 1000 triangles or more: boundary
//             loops <= the full mesh's
//   cl_nm     ... 0 non-manifold edges
//   cl_comps  every judged uniform cut: components <= the full mesh's
//   cl_count  ... the table's triangle count == the extracted count
// Cuts under 1000 triangles (judged on a small mesh) may lose handles but not
// pieces, as the hierarchy's last step clusters with the topology free
// (lod/clusters/group_clustering.h): their loops and non-manifold edges are
// counted as information (*coarse failing*).
//   cl_view   every view cut: the same three topology rules
// The full mesh is the full-detail cut. The coarsest cut (flagged above 256
// triangles), the storage ratio, the hierarchy's build time and the coarser
// cuts that would fail are reported as information.
//
// Output: one line per checked octree level, budget, uniform cut and pixel
// error, then a tab-separated `RESULT key=value ...` line. `--table FILE`
// turns the RESULT lines collected in FILE into the markdown report instead;
// bench/lod/sweep.sh runs every case and does that.
//
//   build/bin/scan2lod_bench_sweep --name NAME --resolution R
//       (--shape S [--gap-cells G] | --scan-mesh FILE [--size P] [--views V]
//        | --scans NAME,... | --input FILE...)
//       [--expect-components C --expect-euler X] [--shared DIR]
//   build/bin/scan2lod_bench_sweep --table RESULTS [--command TEXT] [--load-at-start TEXT]

#include <scan2lod/acquisition/lattice_normals.h>
#include <scan2lod/acquisition/load_inputs.h>
#include <scan2lod/acquisition/range_grid_ply.h>
#include <scan2lod/acquisition/virtual_scanner.h>
#include <scan2lod/bench/bench_support.h>
#include <scan2lod/bench/library_meshes.h>
#include <scan2lod/bench/model_build.h>
#include <scan2lod/core/progress.h>
#include <scan2lod/io/mesh_file.h>
#include <scan2lod/lod/lod_model.h>
#include <scan2lod/lod/octree/extract.h>
#include <scan2lod/lod/octree/lod_array.h>
#include <scan2lod/lod/octree/lod_cursor.h>
#include <scan2lod/measure/topology.h>

#include <CLI/CLI.hpp>
#include <omp.h>
#include <open3d/geometry/TriangleMesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace fs = std::filesystem;
using namespace scan2lod;
using namespace scan2lod::bench;
using O3Mesh = open3d::geometry::TriangleMesh;

namespace {

constexpr std::array<double, 12> kPercents = {1, 5, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100};

// ---------------------------------------------------------------------------
// Inputs.

O3Mesh translated(const std::shared_ptr<O3Mesh>& mesh, double x) {
  mesh->Translate(Eigen::Vector3d(x, 0, 0));
  return *mesh;
}

// The shapes are chosen for what they stress: sharp creases and faces on
// lattice planes (box, plate, cone), thin parts (plate, thin cylinder), an
// open non-orientable surface (mobius), two pieces close together
// (two_spheres, gap_cells cells apart at this resolution), a one-point
// contact (sphere_touch) and holes (genus2, genus3: crossing tori).
TriangleMesh make_shape(const std::string& shape, double gap_cells, int resolution) {
  if (shape == "box") return from_open3d(*O3Mesh::CreateBox(1, 1, 1));
  if (shape == "plate") return from_open3d(*O3Mesh::CreateBox(1, 1, 0.03));
  if (shape == "cylinder") return from_open3d(*O3Mesh::CreateCylinder(0.5, 2.0, 80, 8));
  if (shape == "thin_cylinder") return from_open3d(*O3Mesh::CreateCylinder(0.01, 2.0, 40, 8));
  if (shape == "cone") return from_open3d(*O3Mesh::CreateCone(0.5, 1.5, 80, 4));
  if (shape == "arrow") return from_open3d(*O3Mesh::CreateArrow(0.2, 0.4, 1.6, 0.8, 60, 4, 2));
  if (shape == "icosahedron") return from_open3d(*O3Mesh::CreateIcosahedron(1.0));
  if (shape == "mobius") return from_open3d(*O3Mesh::CreateMobius(120, 20, 1, 1, 1, 0.6, 1));
  if (shape == "two_spheres") {
    // The pair is about 4 wide and the reconstruction pads 4 cells per side,
    // so a cell is about 4 / (R - 8).
    const double gap = gap_cells * 4.0 / (resolution - 8);
    O3Mesh mesh = translated(O3Mesh::CreateSphere(1.0, 100), -(1 + gap / 2));
    mesh += translated(O3Mesh::CreateSphere(1.0, 100), 1 + gap / 2);
    return from_open3d(mesh);
  }
  if (shape == "sphere_touch") {
    O3Mesh mesh = *O3Mesh::CreateSphere(1.0, 120);
    mesh += translated(O3Mesh::CreateSphere(0.25, 60), 1.25);
    return from_open3d(mesh);
  }
  if (shape == "genus2" || shape == "genus3") {
    // Tori of radius 1, 1.6 apart: neighbouring tubes cross, one hole per torus.
    const int tori = shape == "genus2" ? 2 : 3;
    O3Mesh mesh;
    for (int i = 0; i < tori; ++i) mesh += translated(O3Mesh::CreateTorus(1.0, 0.4, 160, 60), 1.6 * (i - (tori - 1) / 2.0));
    return from_open3d(mesh);
  }
  throw std::invalid_argument("unknown shape '" + shape + "'");
}

// The scans of `conf` named in `stems` (file names without .ply), in the
// .conf's order and each with its pose: what load_oriented_points makes of a
// .conf holding only those lines, without writing one.
OrientedPoints conf_subset_points(const fs::path& conf, const std::vector<std::string>& stems) {
  OrientedPoints points;
  std::size_t found = 0;
  for (const ConfEntry& entry : read_conf(conf.string())) {
    if (std::find(stems.begin(), stems.end(), fs::path(entry.file).stem().string()) == stems.end()) continue;
    points.append(range_image_to_points(read_range_grid_ply(entry.file), entry.pose));
    ++found;
  }
  if (found != stems.size()) throw std::invalid_argument("not every --scans name is a scan of " + conf.string());
  return points;
}

// ---------------------------------------------------------------------------
// Measures beyond mesh_topology.

Vec3d triangle_normal(const TriangleMesh& mesh, const Triangle& t) {
  const Vec3f& a = mesh.positions[t[0]];
  return Vec3d((mesh.positions[t[1]] - a).cast<double>().cross((mesh.positions[t[2]] - a).cast<double>()));
}

// Interior edges (exactly two triangles) whose triangles face opposite ways.
std::size_t folded_edges(const TriangleMesh& mesh) {
  std::vector<std::pair<std::uint64_t, std::int32_t>> edges;  // (edge, triangle)
  edges.reserve(3 * mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      edges.push_back({edge_key(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3]), std::int32_t(t)});
  std::sort(edges.begin(), edges.end());
  std::size_t folded = 0;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 2 && triangle_normal(mesh, mesh.triangles[edges[i].second])
                              .dot(triangle_normal(mesh, mesh.triangles[edges[i + 1].second])) < 0)
      ++folded;
    i = j;
  }
  return folded;
}

// Vertices whose triangles form more than one fan (triangles joined through
// edges at the vertex): surfaces that touch at a single point.
std::size_t singular_vertices(const TriangleMesh& mesh) {
  std::vector<std::vector<std::int32_t>> around(mesh.positions.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;  // no surface
    for (int k = 0; k < 3; ++k) around[tri[k]].push_back(std::int32_t(t));
  }
  std::size_t singular = 0;
  std::vector<int> parent;
  std::vector<std::pair<std::int32_t, int>> spokes;  // (other end of an edge at v, local triangle)
  for (std::size_t v = 0; v < around.size(); ++v) {
    const std::vector<std::int32_t>& fan = around[v];
    if (fan.size() < 2) continue;
    parent.resize(fan.size());
    for (std::size_t i = 0; i < fan.size(); ++i) parent[i] = int(i);
    const auto root = [&](int i) {
      while (parent[i] != i) i = parent[i] = parent[parent[i]];
      return i;
    };
    spokes.clear();
    for (std::size_t i = 0; i < fan.size(); ++i)
      for (const std::int32_t w : mesh.triangles[fan[i]])
        if (w != std::int32_t(v)) spokes.push_back({w, int(i)});
    std::sort(spokes.begin(), spokes.end());
    for (std::size_t i = 1; i < spokes.size(); ++i)
      if (spokes[i].first == spokes[i - 1].first) parent[root(spokes[i].second)] = root(spokes[i - 1].second);
    int fans = 0;
    for (std::size_t i = 0; i < fan.size(); ++i) fans += root(int(i)) == int(i);
    singular += fans > 1;
  }
  return singular;
}

// ---------------------------------------------------------------------------
// One case.

struct Level {
  double percent = 0;
  std::size_t priority = 0;
  MeshTopology topology;
  std::size_t folded = 0, singular = 0;
  std::int64_t accumulated = 0;  // the table's count
  std::size_t extracted = 0;     // extract_lod's
};

struct Expectation {
  std::size_t components = 0;
  long euler = 0;
};

// The octree's rules, then the cluster hierarchy's (from kClusterLoops on):
// each structure passes or fails on its own rules.
enum Rule {
  kLoops, kNonManifold, kComponents, kDegenerate, kAccumulation, kMonotone, kClosed, kDown, kBudget,
  kClusterLoops, kClusterNonManifold, kClusterComponents, kClusterCount, kClusterView,
  kRuleCount
};
constexpr Rule kFirstClusterRule = kClusterLoops;
constexpr std::array<const char*, kRuleCount> kRuleKeys = {
    "loops", "nm",    "comps",    "degen",    "accum",    "monotone", "closed",
    "down",  "budget", "cl_loops", "cl_nm", "cl_comps", "cl_count", "cl_view"};

// Where each rule first failed and what was seen there; per structure, the
// first of its rules to fail.
struct Verdict {
  std::array<std::string, kRuleCount> failure;  // "" while the rule holds
  std::string first, cluster_first;

  void fail(Rule rule, const std::string& where_and_what) {
    if (!failure[rule].empty()) return;
    failure[rule] = where_and_what;
    std::string& f = rule >= kFirstClusterRule ? cluster_first : first;
    if (f.empty()) f = kRuleKeys[rule];
  }
  bool pass() const { return first.empty(); }
  bool cluster_pass() const { return cluster_first.empty(); }
};

template <typename F>
std::string joined(const std::vector<Level>& levels, F value) {
  std::string out;
  for (const Level& l : levels) out += (out.empty() ? "" : "/") + std::to_string(value(l));
  return out;
}

template <typename F>
std::size_t largest(const std::vector<Level>& levels, F value) {
  std::size_t most = 0;
  for (const Level& l : levels) most = std::max<std::size_t>(most, value(l));
  return most;
}

// ---------------------------------------------------------------------------
// The cluster hierarchy: its uniform cuts, and cuts seen from cameras, are
// checked as the octree's levels are ("sound" and "crack-free from any view").

// Uniform cuts of at least kJudgedCutTriangles triangles are judged, every cut
// when the full mesh has fewer than kSmallMesh; the coarser cuts of larger
// meshes are measured and counted, not judged.
constexpr std::int64_t kJudgedCutTriangles = 1000;
constexpr std::int64_t kSmallMesh = 10000;
// A coarsest cut larger than this is flagged (information): simplification stalled.
constexpr std::int64_t kCoarsestFlag = 256;
constexpr int kCameras = 50;
constexpr std::array<double, 5> kPixelErrors = {0.5, 1, 2, 4, 8};
constexpr int kViewHeight = 720;

// `n` cameras: the first half outside the box, looking at its centre from
// directions spread over the sphere (a Fibonacci lattice) at 0.6 to 3
// diagonals from it (spread by the golden ratio, so that distance and
// direction do not go together); the second half at random points inside the
// box (fixed seed), looking at the centre. Selection depends only on the
// eye's distance to each group, so where a camera looks matters to a viewer
// only.
std::vector<CameraView> sweep_cameras(const Aabb& box, int n) {
  const Vec3f center = 0.5f * (box.min + box.max);
  const float diagonal = std::max(box.diagonal(), 1e-6f);
  const float golden = float(M_PI) * (3.0f - std::sqrt(5.0f));
  const int outside = n / 2;
  std::vector<CameraView> cameras;
  const auto look = [&](const Vec3f& eye, const Vec3f& target) {
    CameraView c;
    c.eye = eye;
    c.target = target;
    c.up = std::abs((target - eye).normalized().y()) > 0.99f ? Vec3f(1, 0, 0) : Vec3f(0, 1, 0);
    c.height = kViewHeight;
    cameras.push_back(c);
  };
  for (int i = 0; i < outside; ++i) {
    const float y = 1.0f - 2.0f * (float(i) + 0.5f) / float(outside), r = std::sqrt(std::max(0.0f, 1.0f - y * y));
    const Vec3f direction(r * std::cos(golden * float(i)), y, r * std::sin(golden * float(i)));
    const double spread = std::fmod((i + 0.5) * 0.6180339887498949, 1.0);
    look(center + float(0.6 + 2.4 * spread) * diagonal * direction, center);
  }
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> unit(0, 1);
  for (int i = outside; i < n; ++i) {
    Vec3f eye;
    for (int k = 0; k < 3; ++k) eye[k] = box.min[k] + unit(rng) * box.extent()[k];
    look(eye, (eye - center).norm() > 1e-3f * diagonal ? center : Vec3f(eye + Vec3f(1, 0, 0)));
  }
  return cameras;
}

// What the cluster checks measured, beyond the verdict.
struct ClusterResult {
  MeshTopology full;                          // the full-detail cut (the table's first entry)
  bool full_same_as_octree = false;           // that cut has the octree's 100 % triangles, loops, comps and χ
  std::size_t cuts = 0, judged = 0;           // uniform cuts in the table; those judged
  std::size_t unjudged_bad = 0;               // coarse cuts not judged that would fail a rule
  std::int64_t smallest_judged = 0;           // triangles of the coarsest judged cut
  std::int64_t coarsest = 0;                  // triangles of the coarsest cut
  double storage = 0;                         // stored triangles / full
  int levels = 0;
  std::size_t clusters = 0, groups = 0;
  std::size_t max_loops = 0, max_comps = 0, max_nm = 0, max_degen = 0;  // over the judged uniform cuts
  std::size_t views = 0, view_max_loops = 0, view_max_comps = 0, view_max_nm = 0;
  std::size_t view_min_triangles = 0, view_max_triangles = 0;
  double view_median_triangles = 0;
  double check_seconds = 0;
};

// Checks every judged uniform cut of the hierarchy (cl_loops, cl_nm,
// cl_comps: as the octree's loops and nm, and no more components than the
// full mesh; cl_count: the cut has the table's count) and the cut of every
// camera at every pixel error (cl_view: the same three topology rules). Cuts
// are measured as index buffers into the model's vertices, as they are drawn.
ClusterResult check_clusters(const LodModel& model, const MeshTopology& octree_full, Verdict* verdict) {
  const auto start = Clock::now();
  const ClusterHierarchy& h = *model.clusters;
  const ClusterCutTable table = cluster_cut_table(h);
  LevelExtractor extractor(model, LodStructure::kClusters);
  TriangleMesh mesh;
  mesh.positions.assign(model.vertices.positions.begin(), model.vertices.positions.end());
  const auto measure = [&](const LevelCut& cut) {
    mesh.triangles = cut.triangles;
    return mesh_topology(mesh);
  };

  ClusterResult c;
  c.cuts = table.ranks.size();
  c.coarsest = table.triangles.back();
  c.storage = h.full_triangles ? double(h.triangles.size()) / double(h.full_triangles) : 0;
  c.levels = h.levels();
  c.clusters = h.size();
  c.groups = h.groups.size();
  c.full = measure(extractor.extract(LevelRequest::at_error(0)));
  const MeshTopology& full = c.full;
  c.full_same_as_octree = full.triangles == octree_full.triangles && full.boundary_loops == octree_full.boundary_loops &&
                          full.components == octree_full.components &&
                          full.euler_characteristic == octree_full.euler_characteristic;
  c.smallest_judged = h.full_triangles;

  const bool small = h.full_triangles < kSmallMesh;
  for (std::size_t i = 0; i < table.ranks.size(); ++i) {
    LevelRequest stored = LevelRequest::at_most_triangles(table.triangles[i]);
    stored.refine = false;  // every stored cut itself
    const LevelCut& cut = extractor.extract(stored);
    const MeshTopology t = measure(cut);
    const bool judged = small || table.triangles[i] >= kJudgedCutTriangles;
    std::printf("cut %zu rank=%.6g tris=%zu table=%lld clusters=%zu loops=%zu bedges=%zu nm=%zu degen=%zu comps=%zu "
                "euler=%ld%s\n",
                i, double(table.ranks[i]), t.triangles, (long long)table.triangles[i], cut.clusters, t.boundary_loops,
                t.boundary_edges, t.non_manifold_edges, t.degenerate_triangles, t.components, t.euler_characteristic,
                judged ? "" : " (not judged)");
    const bool bad = t.boundary_loops > full.boundary_loops || t.non_manifold_edges > 0 ||
                     t.components > full.components || std::int64_t(t.triangles) != table.triangles[i];
    if (!judged) {
      c.unjudged_bad += bad;
      continue;
    }
    ++c.judged;
    c.smallest_judged = std::min(c.smallest_judged, table.triangles[i]);
    c.max_comps = std::max(c.max_comps, t.components);
    c.max_degen = std::max(c.max_degen, t.degenerate_triangles);
    // The table's short form is what comes before " (".
    const std::string at = format("%lld-triangle cut (cut %zu, rank %.3g): ", (long long)table.triangles[i], i,
                                  double(table.ranks[i]));
    if (table.triangles[i] < kJudgedCutTriangles) {  // pieces only (see the top of the file)
      c.unjudged_bad += t.boundary_loops > full.boundary_loops || t.non_manifold_edges > 0;
    } else {
      c.max_loops = std::max(c.max_loops, t.boundary_loops);
      c.max_nm = std::max(c.max_nm, t.non_manifold_edges);
      if (t.boundary_loops > full.boundary_loops)
        verdict->fail(kClusterLoops,
                      at + format("%zu boundary loops, the full mesh %zu", t.boundary_loops, full.boundary_loops));
      if (t.non_manifold_edges > 0)
        verdict->fail(kClusterNonManifold, at + format("%zu non-manifold edges", t.non_manifold_edges));
    }
    if (t.components > full.components)
      verdict->fail(kClusterComponents, at + format("%zu components, the full mesh %zu", t.components, full.components));
    if (std::int64_t(t.triangles) != table.triangles[i])
      verdict->fail(kClusterCount, at + format("extracted %zu, the table %lld", t.triangles, (long long)table.triangles[i]));
  }

  const Aabb box = model_bounds(model);
  const Vec3f center = 0.5f * (box.min + box.max);
  const std::vector<CameraView> cameras = sweep_cameras(box, kCameras);
  std::vector<double> triangles;
  for (const double pixel_error : kPixelErrors) {
    std::size_t fewest = SIZE_MAX, most = 0, loops = 0, comps = 0, nm = 0;
    for (std::size_t k = 0; k < cameras.size(); ++k) {
      const LevelCut& cut = extractor.extract(LevelRequest::for_camera(cameras[k], pixel_error));
      const MeshTopology t = measure(cut);
      triangles.push_back(double(t.triangles));
      fewest = std::min(fewest, t.triangles);
      most = std::max(most, t.triangles);
      loops = std::max(loops, t.boundary_loops);
      comps = std::max(comps, t.components);
      nm = std::max(nm, t.non_manifold_edges);
      std::string problem;
      if (t.boundary_loops > full.boundary_loops)
        problem += format(", %zu boundary loops (the full mesh %zu)", t.boundary_loops, full.boundary_loops);
      if (t.non_manifold_edges > 0) problem += format(", %zu non-manifold edges", t.non_manifold_edges);
      if (t.components > full.components)
        problem += format(", %zu components (the full mesh %zu)", t.components, full.components);
      if (problem.empty()) continue;
      const std::string where = format("%g px, camera %zu (%s, %.2f diagonals from the centre; %zu triangles)",
                                       pixel_error, k, k < cameras.size() / 2 ? "outside" : "inside",
                                       (cameras[k].eye - center).norm() / std::max(box.diagonal(), 1e-6f),
                                       t.triangles);
      std::printf("view FAIL %s%s\n", where.c_str(), problem.c_str());
      verdict->fail(kClusterView, where + ":" + problem.substr(1));
    }
    std::printf("views at %g px: %zu cameras, tris %zu-%zu, max loops=%zu comps=%zu nm=%zu\n", pixel_error,
                cameras.size(), fewest, most, loops, comps, nm);
    c.view_max_loops = std::max(c.view_max_loops, loops);
    c.view_max_comps = std::max(c.view_max_comps, comps);
    c.view_max_nm = std::max(c.view_max_nm, nm);
  }
  c.views = triangles.size();
  c.view_min_triangles = std::size_t(*std::min_element(triangles.begin(), triangles.end()));
  c.view_max_triangles = std::size_t(*std::max_element(triangles.begin(), triangles.end()));
  c.view_median_triangles = median(triangles);
  c.check_seconds = seconds_since(start);
  return c;
}

// ---------------------------------------------------------------------------
// The octree's offered levels, walked with a LodCursor.

// Every offered level is checked up to kWalkAll of them; beyond, the coarsest
// kWalkCoarsest (where the coarsening does most of its work) and kWalkSpread
// more spread evenly over the rest, the finest among them.
constexpr std::size_t kWalkAll = 1500, kWalkCoarsest = 300, kWalkSpread = 1200;
// Budgets for priority_for_budget; only those under half the full count are judged.
constexpr std::array<std::int64_t, 5> kBudgets = {500, 1000, 2000, 5000, 20000};
// From this many full triangles on, the coarsest offered level must have at most 1 % of them.
constexpr std::int64_t kDownFrom = 20000;

// Indices into `offered` of the levels the walk checks, ascending.
std::vector<std::size_t> walked_levels(std::size_t offered) {
  std::vector<std::size_t> walked;
  if (offered <= kWalkAll) {
    for (std::size_t i = 0; i < offered; ++i) walked.push_back(i);
    return walked;
  }
  for (std::size_t i = 0; i < kWalkCoarsest; ++i) walked.push_back(i);
  const std::size_t rest = offered - kWalkCoarsest;
  for (std::size_t k = 1; k <= kWalkSpread; ++k) walked.push_back(kWalkCoarsest + k * rest / kWalkSpread - 1);
  return walked;
}

// The soundness rules at one offered level: loops, nm, comps, degen, and for
// shapes with a known answer closed (no boundary, no more pieces than
// expected; χ is not judged, as a coarse level may close a handle).
void judge_level(const MeshTopology& t, const MeshTopology& full, const std::optional<Expectation>& expect,
                 const std::string& at, Verdict* verdict) {
  if (t.boundary_loops > full.boundary_loops)
    verdict->fail(kLoops, at + format("%zu boundary loops, the full mesh %zu", t.boundary_loops, full.boundary_loops));
  if (t.non_manifold_edges > 0) verdict->fail(kNonManifold, at + format("%zu non-manifold edges", t.non_manifold_edges));
  if (t.components > full.components)
    verdict->fail(kComponents, at + format("%zu components, the full mesh %zu", t.components, full.components));
  if (t.degenerate_triangles > 0)
    verdict->fail(kDegenerate, at + format("%zu degenerate triangles", t.degenerate_triangles));
  if (expect && (t.boundary_edges != 0 || t.components > expect->components))
    verdict->fail(kClosed, at + format("%zu boundary edges, %zu components, χ %ld (expected 0, ≤ %zu; χ %ld)",
                                       t.boundary_edges, t.components, t.euler_characteristic, expect->components,
                                       expect->euler));
}

// What the walk over the offered levels measured, beyond the verdict.
struct Walk {
  std::size_t offered = 0, checked = 0;
  std::size_t max_loops = 0, max_comps = 0, max_nm = 0, max_degen = 0;
  long min_euler = 0, max_euler = 0;
  std::size_t other_topology = 0;  // checked levels without the full mesh's components or (closed) χ
  double seconds = 0;
};

// Measures the walked levels, each thread with its own cursor moving up
// through every thread-count-th of them (moves stay short and the threads'
// shares alike), then judges them in order, so the first failure is the
// coarsest.
// mesh_topology's counts (but the largest component) for a mesh whose
// vertices are all used (as compact_live makes them), in buffers kept from one
// level to the next: the walk measures hundreds of levels of up to a million
// triangles, and fresh arrays per level (page faults) were most of
// mesh_topology's cost there. Edges are bucketed under their smaller vertex
// (a counting sort). run_case checks it against mesh_topology at the slider's
// levels.
class LevelMeasure {
 public:
  MeshTopology operator()(const TriangleMesh& mesh) {
    const std::size_t n = mesh.positions.size();
    MeshTopology topo;
    topo.vertices = n;
    topo.triangles = mesh.triangles.size();
    first_.assign(n + 1, 0);
    referenced_.assign(n, 0);
    std::size_t surface = 0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Triangle& tri = mesh.triangles[t];
      if (triangle_is_degenerate(mesh, t)) ++topo.degenerate_triangles;
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
      ++surface;
      for (int k = 0; k < 3; ++k) {
        ++first_[std::size_t(std::min(tri[k], tri[(k + 1) % 3])) + 1];
        referenced_[std::size_t(tri[k])] = 1;
      }
    }
    for (std::size_t v = 0; v < n; ++v) first_[v + 1] += first_[v];
    other_.resize(first_[n]);
    fill_ = first_;
    for (const Triangle& tri : mesh.triangles) {
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
      for (int k = 0; k < 3; ++k) {
        const std::int32_t a = tri[k], b = tri[(k + 1) % 3];
        other_[fill_[std::size_t(std::min(a, b))]++] = std::max(a, b);
      }
    }
    count_edges(n, &topo);
    for (std::size_t v = 0; v < n; ++v) topo.referenced_vertices += referenced_[v];
    topo.euler_characteristic = long(topo.referenced_vertices) - long(topo.edges) + long(surface);
    return topo;
  }

 private:
  // Union-find with path halving over `parent`.
  static std::uint32_t find(std::vector<std::uint32_t>& parent, std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  static void unite(std::vector<std::uint32_t>& parent, std::uint32_t a, std::uint32_t b) {
    a = find(parent, a), b = find(parent, b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  static void reset(std::vector<std::uint32_t>& parent, std::size_t n) {
    parent.resize(n);
    for (std::size_t v = 0; v < n; ++v) parent[v] = std::uint32_t(v);
  }

  // Edges, boundary edges and loops, non-manifold edges (runs of equal ends
  // in each vertex's bucket), and components: vertices joined by edges are
  // triangles joined through shared vertices.
  void count_edges(std::size_t n, MeshTopology* topo) {
    reset(pieces_, n);
    reset(loops_, n);
    on_boundary_.assign(n, 0);
    for (std::size_t a = 0; a < n; ++a) {
      const auto begin = other_.begin() + std::ptrdiff_t(first_[a]), end = other_.begin() + std::ptrdiff_t(first_[a + 1]);
      std::sort(begin, end);
      for (auto i = begin; i != end;) {
        auto j = i;
        while (j != end && *j == *i) ++j;
        ++topo->edges;
        unite(pieces_, std::uint32_t(a), std::uint32_t(*i));
        if (j - i == 1) {
          ++topo->boundary_edges;
          unite(loops_, std::uint32_t(a), std::uint32_t(*i));
          on_boundary_[a] = on_boundary_[std::size_t(*i)] = 1;
        } else if (j - i > 2) {
          ++topo->non_manifold_edges;
        }
        i = j;
      }
    }
    for (std::size_t v = 0; v < n; ++v) {
      topo->boundary_loops += on_boundary_[v] && find(loops_, std::uint32_t(v)) == v;
      topo->components += referenced_[v] && find(pieces_, std::uint32_t(v)) == v;
    }
  }

  std::vector<std::size_t> first_, fill_;
  std::vector<std::int32_t> other_;
  std::vector<std::uint32_t> pieces_, loops_;  // union-find parents: components, boundary loops
  std::vector<std::uint8_t> referenced_, on_boundary_;
};

// Copies the live triangles of `cursor` into `level` with only the vertices
// they use, renumbered: measuring a coarse level then costs its size, not the
// model's vertex count. `remap` (one entry per model vertex, -1 between calls)
// is reused across calls.
void compact_live(const LodCursor& cursor, ArrayView<Vec3f> positions, std::vector<std::int32_t>* remap,
                  std::vector<Triangle>* live, TriangleMesh* level) {
  cursor.live_triangles(live);
  level->positions.clear();
  level->triangles.resize(live->size());
  for (std::size_t t = 0; t < live->size(); ++t)
    for (int k = 0; k < 3; ++k) {
      std::int32_t& id = (*remap)[std::size_t((*live)[t][k])];
      if (id < 0) {
        id = std::int32_t(level->positions.size());
        level->positions.push_back(positions[std::size_t((*live)[t][k])]);
      }
      level->triangles[t][k] = id;
    }
  for (const Triangle& t : *live)
    for (const std::int32_t v : t) (*remap)[std::size_t(v)] = -1;
}

std::vector<MeshTopology> measure_walked(const LodModel& model, const std::vector<std::size_t>& offered,
                                         const std::vector<std::size_t>& walked) {
  std::vector<MeshTopology> measured(walked.size());
  std::string error;
#pragma omp parallel
  {
    try {
      const std::size_t threads = std::size_t(omp_get_num_threads()), me = std::size_t(omp_get_thread_num());
      LodCursor cursor(model.octree->tree, model.octree->lod);
      std::vector<std::int32_t> remap(model.vertices.positions.size(), -1);
      std::vector<Triangle> live;
      TriangleMesh level;
      LevelMeasure measure;
      for (std::size_t i = me; i < walked.size(); i += threads) {
        cursor.move_to(offered[walked[i]]);
        compact_live(cursor, model.vertices.positions, &remap, &live, &level);
        measured[i] = measure(level);
      }
    } catch (const std::exception& e) {
#pragma omp critical
      error = e.what();
    }
  }
  if (!error.empty()) throw std::runtime_error(error);
  return measured;
}

Walk walk_offered_levels(const LodModel& model, const std::vector<std::size_t>& offered, const MeshTopology& full,
                         const std::optional<Expectation>& expect, Verdict* verdict) {
  const auto start = Clock::now();
  const LodArray& lod = model.octree->lod;
  const std::vector<std::size_t> walked = walked_levels(offered.size());
  const std::vector<MeshTopology> measured = measure_walked(model, offered, walked);
  Walk w;
  w.offered = offered.size();
  w.checked = walked.size();
  w.min_euler = w.max_euler = full.euler_characteristic;
  for (std::size_t i = 0; i < walked.size(); ++i) {
    const MeshTopology& t = measured[i];
    const std::size_t priority = offered[walked[i]];
    std::printf("offered %zu p=%zu tris=%zu loops=%zu bedges=%zu nm=%zu degen=%zu comps=%zu euler=%ld\n", walked[i],
                priority, t.triangles, t.boundary_loops, t.boundary_edges, t.non_manifold_edges,
                t.degenerate_triangles, t.components, t.euler_characteristic);
    const std::string at = format("offered level %zu (priority %zu, %zu triangles): ", walked[i], priority, t.triangles);
    judge_level(t, full, expect, at, verdict);
    if (std::int64_t(t.triangles) != lod.accumulated[priority])
      verdict->fail(kAccumulation, at + format("the table %lld", (long long)lod.accumulated[priority]));
    if (i > 0 && t.triangles < measured[i - 1].triangles)
      verdict->fail(kMonotone, at + format("%zu at offered level %zu", measured[i - 1].triangles, walked[i - 1]));
    w.max_loops = std::max(w.max_loops, t.boundary_loops);
    w.max_comps = std::max(w.max_comps, t.components);
    w.max_nm = std::max(w.max_nm, t.non_manifold_edges);
    w.max_degen = std::max(w.max_degen, t.degenerate_triangles);
    w.min_euler = std::min(w.min_euler, t.euler_characteristic);
    w.max_euler = std::max(w.max_euler, t.euler_characteristic);
    w.other_topology += t.components != full.components ||
                        (full.boundary_edges == 0 && t.euler_characteristic != full.euler_characteristic);
  }
  w.seconds = seconds_since(start);
  return w;
}

// Levels all the way down: the coarsest offered level (rule down) and the
// level priority_for_budget picks for each budget (rule budget: within 10 %
// of the budget).
struct Down {
  std::int64_t coarsest = 0;
  double share = 0;        // of the full count, in %
  std::string budgets;     // per budget, the level's triangles or "–" (not judged)
  std::string worst;       // the budget farthest from its level, relatively: "500 → 214 (−57.2 %)"
  bool worst_fails = false;
  std::string largest_step;  // the largest rise between neighbouring offered levels: "5 → 29662"
};

Down check_down(const LodArray& lod, const std::vector<std::size_t>& offered, Verdict* verdict) {
  Down d;
  const std::int64_t full = lod.accumulated.back();
  d.coarsest = lod.accumulated[offered.front()];
  d.share = full > 0 ? 100.0 * double(d.coarsest) / double(full) : 0;
  if (full >= kDownFrom && d.coarsest * 100 > full)
    verdict->fail(kDown, format("offered level 0 (priority %zu): %lld triangles, %.2f %% of the full %lld",
                                offered.front(), (long long)d.coarsest, d.share, (long long)full));
  double worst_miss = -1;
  for (const std::int64_t budget : kBudgets) {
    d.budgets += d.budgets.empty() ? "" : "/";
    if (2 * budget >= full) {
      d.budgets += "–";
      continue;
    }
    const std::size_t priority = priority_for_budget(lod, budget);
    const std::int64_t got = lod.accumulated[priority];
    d.budgets += std::to_string(got);
    const bool fails = 10 * got > 11 * budget || 10 * got < 9 * budget;
    const std::string what = format("%lld → %lld (%+.1f %%)", (long long)budget, (long long)got,
                                    100.0 * double(got - budget) / double(budget));
    std::printf("budget %s at priority %zu%s\n", what.c_str(), priority, fails ? " FAIL" : "");
    if (fails) verdict->fail(kBudget, format("budget %lld (priority %zu): %lld triangles", (long long)budget, priority,
                                              (long long)got));
    const double miss = std::abs(double(got - budget)) / double(budget);
    if (miss > worst_miss) worst_miss = miss, d.worst = what, d.worst_fails = fails;
  }
  if (d.worst.empty()) d.worst = "–";
  std::size_t step = 0;
  for (std::size_t i = 1; i < offered.size(); ++i)
    if (lod.accumulated[offered[i]] - lod.accumulated[offered[i - 1]] >
        lod.accumulated[offered[step]] - lod.accumulated[offered[step > 0 ? step - 1 : 0]])
      step = i;
  d.largest_step = step == 0 ? "–"
                             : format("%lld → %lld", (long long)lod.accumulated[offered[step - 1]],
                                      (long long)lod.accumulated[offered[step]]);
  return d;
}

// The walk's counts must be mesh_topology's: a mismatch is the sweep's bug,
// not the model's.
void check_measure(const MeshTopology& fast, const MeshTopology& t, double percent) {
  if (fast.triangles != t.triangles || fast.boundary_edges != t.boundary_edges ||
      fast.boundary_loops != t.boundary_loops || fast.non_manifold_edges != t.non_manifold_edges ||
      fast.components != t.components || fast.degenerate_triangles != t.degenerate_triangles ||
      fast.euler_characteristic != t.euler_characteristic)
    throw std::logic_error(format("LevelMeasure disagrees with mesh_topology at %g %%", percent));
}

// The viewer slider's levels (priority_for_percent), extracted as the viewer
// does and judged by the same rules; measured beyond them: folded edges and
// singular vertices.
std::vector<Level> check_percent_levels(const LodModel& model, const std::optional<Expectation>& expect,
                                        Verdict* verdict) {
  const LodArray& lod = model.octree->lod;
  LevelExtractor extractor(model, LodStructure::kOctree);
  LevelMeasure measure;
  std::vector<Level> levels;
  for (const double percent : kPercents) {
    Level l;
    l.percent = percent;
    const LevelCut& cut = extractor.extract(LevelRequest::at_percent(percent));
    l.priority = cut.priority;
    l.extracted = cut.triangles.size();
    l.accumulated = lod.accumulated[l.priority];
    const TriangleMesh mesh = compact_level(model, cut.triangles);
    l.topology = mesh_topology(mesh);
    check_measure(measure(mesh), l.topology, percent);
    l.folded = folded_edges(mesh);
    l.singular = singular_vertices(mesh);
    levels.push_back(l);
  }
  const MeshTopology& full = levels.back().topology;
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const Level& l = levels[i];
    const MeshTopology& t = l.topology;
    std::printf("%5.0f %% p=%zu tris=%zu loops=%zu bedges=%zu nm=%zu degen=%zu comps=%zu euler=%ld folded=%zu "
                "singular=%zu accum=%lld\n",
                l.percent, l.priority, t.triangles, t.boundary_loops, t.boundary_edges, t.non_manifold_edges,
                t.degenerate_triangles, t.components, t.euler_characteristic, l.folded, l.singular,
                (long long)l.accumulated);
    const std::string at = fixed(l.percent, 0) + " % (priority " + std::to_string(l.priority) + "): ";
    judge_level(t, full, expect, at, verdict);
    if (l.accumulated != std::int64_t(l.extracted))
      verdict->fail(kAccumulation, at + format("table %lld, extracted %zu", (long long)l.accumulated, l.extracted));
    if (i > 0 && t.triangles < levels[i - 1].topology.triangles)
      verdict->fail(kMonotone, at + format("%zu triangles, %zu at %s %%", t.triangles, levels[i - 1].topology.triangles,
                                           fixed(levels[i - 1].percent, 0).c_str()));
  }
  return levels;
}

// Offered priorities never lose triangles, and the table holds at sampled
// priorities, offered or not (fixed seed), as extract_lod counts them.
std::size_t check_table(const LodModel& model, const std::vector<std::size_t>& offered, Verdict* verdict) {
  const LodArray& lod = model.octree->lod;
  for (std::size_t i = 1; i < offered.size(); ++i)
    if (lod.accumulated[offered[i]] < lod.accumulated[offered[i - 1]])
      verdict->fail(kMonotone, format("offered priority %zu: %lld triangles, %lld at offered priority %zu", offered[i],
                                      (long long)lod.accumulated[offered[i]],
                                      (long long)lod.accumulated[offered[i - 1]], offered[i - 1]));
  LevelExtractor extractor(model, LodStructure::kOctree);
  std::mt19937 rng(1);
  std::vector<std::size_t> sampled;
  for (int i = 0; i < 40 && !offered.empty(); ++i) sampled.push_back(offered[rng() % offered.size()]);
  for (int i = 0; i < 20; ++i) sampled.push_back(rng() % (lod.full() + 1));
  for (const std::size_t priority : sampled) {
    const std::size_t extracted = extractor.extract(LevelRequest::at_priority(priority)).triangles.size();
    if (std::int64_t(extracted) != lod.accumulated[priority])
      verdict->fail(kAccumulation, format("sampled priority %zu: table %lld, extracted %zu", priority,
                                          (long long)lod.accumulated[priority], extracted));
  }
  return sampled.size();
}

int run_case(const std::string& name, int resolution, const OrientedPoints& points, double load_seconds,
             const std::optional<Expectation>& expect) {
  // Both structures, as `scan2lod build` makes them; the cluster hierarchy's
  // build is timed on its own.
  const TimedModel timed = build_model_timed(points, resolution, /*clusters=*/true);
  const LodModel& model = timed.model;
  const double build_seconds = load_seconds + timed.reconstruct_seconds + timed.octree_model_seconds();
  const LodArray& lod = model.octree->lod;
  const std::vector<std::size_t> offered = monotone_priorities(lod);
  if (offered.empty()) throw std::runtime_error("the octree offers no level");

  // The walk's failures come first, so each rule's first failure is at the
  // coarsest level walked; the slider's add the rules the walk did not fail.
  Verdict verdict, slider;
  const std::vector<Level> levels = check_percent_levels(model, expect, &slider);
  const MeshTopology& full = levels.back().topology;
  const Walk walk = walk_offered_levels(model, offered, full, expect, &verdict);
  for (int r = 0; r < kFirstClusterRule; ++r)
    if (!slider.failure[r].empty()) verdict.fail(Rule(r), slider.failure[r]);
  const Down down = check_down(lod, offered, &verdict);
  const std::size_t sampled = check_table(model, offered, &verdict);
  const ClusterResult cl = check_clusters(model, full, &verdict);

  std::printf("RESULT\tname=%s\tR=%d\tpass=%d\tfirst_fail=%s", name.c_str(), resolution, int(verdict.pass()),
              verdict.pass() ? "-" : verdict.first.c_str());
  std::printf("\tcl_pass=%d\tcl_first_fail=%s", int(verdict.cluster_pass()),
              verdict.cluster_pass() ? "-" : verdict.cluster_first.c_str());
  for (int r = 0; r < kRuleCount; ++r)
    if (!verdict.failure[r].empty()) std::printf("\tfail.%s=%s", kRuleKeys[r], verdict.failure[r].c_str());
  std::printf("\texpect=%s", expect ? format("%zu/%ld", expect->components, expect->euler).c_str() : "–");
  std::printf("\tfull=%zu/%zu/%zu/%ld", full.triangles, full.boundary_loops, full.components, full.euler_characteristic);
  const std::string euler_range = walk.min_euler == walk.max_euler
                                      ? std::to_string(walk.min_euler)
                                      : format("%ld to %ld", walk.min_euler, walk.max_euler);
  std::printf("\toffered=%zu\tchecked=%zu\twalk_max=%zu/%zu/%zu/%zu\twalk_euler=%s\tother_topology=%zu\twalk_s=%.1f",
              walk.offered, walk.checked, walk.max_loops, walk.max_comps, walk.max_nm, walk.max_degen,
              euler_range.c_str(), walk.other_topology, walk.seconds);
  std::printf("\tcoarsest=%lld\tcoarsest_share=%.2f\tbudgets=%s\tworst_budget=%s\tworst_budget_fails=%d"
              "\tlargest_step=%s",
              (long long)down.coarsest, down.share, down.budgets.c_str(), down.worst.c_str(), int(down.worst_fails),
              down.largest_step.c_str());
  std::printf("\ttris=%s", joined(levels, [](const Level& l) { return l.topology.triangles; }).c_str());
  std::printf("\teuler=%s", joined(levels, [](const Level& l) { return l.topology.euler_characteristic; }).c_str());
  std::printf("\tmax_folded=%zu\tmax_singular=%zu", largest(levels, [](const Level& l) { return l.folded; }),
              largest(levels, [](const Level& l) { return l.singular; }));
  std::printf("\tnodes=%zu\tsampled=%zu\tbuild_s=%.1f", model.octree->tree.size(), sampled, build_seconds);
  std::printf("\tcl_full=%zu/%zu/%zu/%ld\tcl_full_same=%d", cl.full.triangles, cl.full.boundary_loops,
              cl.full.components, cl.full.euler_characteristic, int(cl.full_same_as_octree));
  std::printf("\tcl_cuts=%zu/%zu\tcl_unjudged_bad=%zu\tcl_smallest_judged=%lld", cl.judged, cl.cuts,
              cl.unjudged_bad, (long long)cl.smallest_judged);
  std::printf("\tcl_max_loops=%zu\tcl_max_comps=%zu\tcl_max_nm=%zu\tcl_max_degen=%zu", cl.max_loops, cl.max_comps,
              cl.max_nm, cl.max_degen);
  std::printf("\tcl_views=%zu\tcl_view_tris=%zu/%.0f/%zu\tcl_view_max_loops=%zu\tcl_view_max_comps=%zu"
              "\tcl_view_max_nm=%zu",
              cl.views, cl.view_min_triangles, cl.view_median_triangles, cl.view_max_triangles, cl.view_max_loops,
              cl.view_max_comps, cl.view_max_nm);
  std::printf("\tcl_coarsest=%lld\tcl_coarsest_flag=%d\tcl_storage=%.2f\tcl_levels=%d\tcl_clusters=%zu"
              "\tcl_groups=%zu\tcl_build_s=%.1f\tcl_check_s=%.1f\n",
              (long long)cl.coarsest, int(cl.coarsest > kCoarsestFlag), cl.storage, cl.levels, cl.clusters, cl.groups,
              timed.cluster_seconds, cl.check_seconds);
  return 0;
}

// ---------------------------------------------------------------------------
// The report, from the RESULT lines of every case.

using Result = std::map<std::string, std::string>;

std::vector<Result> read_results(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::vector<Result> results;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("RESULT\t", 0) != 0) continue;
    Result r;
    std::istringstream fields(line.substr(7));
    std::string field;
    while (std::getline(fields, field, '\t')) {
      const std::size_t eq = field.find('=');
      if (eq != std::string::npos) r[field.substr(0, eq)] = field.substr(eq + 1);
    }
    results.push_back(std::move(r));
  }
  return results;
}

std::string get(const Result& r, const std::string& key) {
  const auto it = r.find(key);
  return it == r.end() ? "" : it->second;
}

// "a/b/c" stays as it is unless every entry is the same: then just that one.
std::string per_level(const std::string& list) {
  const std::string first = list.substr(0, list.find('/'));
  std::string same;
  for (std::size_t i = 0; i < 12; ++i) same += (i ? "/" : "") + first;
  return list == same ? first : list;
}

// "a/b/c" as "a / b / c".
std::string spaced(std::string list) {
  for (std::size_t p = list.find('/'); p != std::string::npos; p = list.find('/', p + 3)) list.replace(p, 1, " / ");
  return list;
}

// Rows grouped by case name (in the order names first appear), then by R.
void sort_cases(std::vector<Result>* results) {
  std::vector<std::string> names;
  for (const Result& r : *results)
    if (std::find(names.begin(), names.end(), get(r, "name")) == names.end()) names.push_back(get(r, "name"));
  const auto rank = [&](const Result& r) {
    return std::pair(std::find(names.begin(), names.end(), get(r, "name")) - names.begin(), std::stoi(get(r, "R")));
  };
  std::stable_sort(results->begin(), results->end(),
                   [&](const Result& a, const Result& b) { return rank(a) < rank(b); });
}

// One structure's failed rules (kRuleKeys[from, to)), the first to fail (the
// RESULT key `first_key` names it) first, each with the short form of where:
// "closed @ 1 %, degen @ 60 %".
std::string failed_rules(const Result& r, const std::string& first_key, int from, int to) {
  std::vector<std::string> rules = {get(r, first_key)};
  for (int i = from; i < to; ++i)
    if (kRuleKeys[i] != rules.front()) rules.push_back(kRuleKeys[i]);
  std::string failed;
  for (const std::string& rule : rules) {
    const std::string f = get(r, "fail." + rule);
    if (f.empty()) continue;
    if (!failed.empty()) failed += ", ";
    failed += rule + " @ " + f.substr(0, f.find(" ("));
  }
  return failed.empty() ? "–" : failed;
}

// One structure's failures in full: "*first* at where. Also *other* at where".
std::string failures_in_full(const Result& r, const std::string& first_key, int from, int to) {
  const std::string first = get(r, first_key);
  std::string out = "*" + first + "* at " + get(r, "fail." + first);
  std::string others;
  for (int i = from; i < to; ++i) {
    const std::string rule = kRuleKeys[i];
    if (rule != first && !get(r, "fail." + rule).empty())
      others += (others.empty() ? "" : "; ") + ("*" + rule + "* at " + get(r, "fail." + rule));
  }
  return others.empty() ? out : out + ". Also " + others;
}

std::string outcome(const std::string& pass) { return pass == "1" ? "pass" : pass == "0" ? "**FAIL**" : "–"; }

int print_table(const std::string& path, const std::string& command, const std::string& load_at_start) {
  std::vector<Result> results = read_results(path);
  sort_cases(&results);
  std::size_t passed = 0, cluster_passed = 0, both = 0;
  for (const Result& r : results) {
    passed += get(r, "pass") == "1";
    cluster_passed += get(r, "cl_pass") == "1";
    both += get(r, "pass") == "1" && get(r, "cl_pass") == "1";
  }

  std::printf("# LOD robustness sweep: crack-freeness beyond the bunny\n\n");
  std::printf("%s  \n", run_header_line(load_at_start, load_average()).c_str());
  if (!command.empty()) std::printf("Command: `%s`  \n", command.c_str());
  std::printf("%s", openmp_line().c_str());
  const std::string revision = source_revision();
  if (!revision.empty()) std::printf("Source: %s (at run time)  \n", revision.c_str());
  std::printf("Tool: `scan2lod_bench_sweep` (bench/lod/shape_sweep.cpp), one process per case\n\n");
  std::printf("**Octree: %zu of %zu cases pass. Cluster hierarchy: %zu of %zu cases pass.** Both: %zu.\n\n", passed,
              results.size(), cluster_passed, results.size(), both);

  std::printf(
      "Each case is built as `scan2lod build` builds it, at resolution R, with both structures.\n\n"
      "**Octree.** Every offered level (`monotone_priorities`) is walked with a `LodCursor` and measured by "
      "`mesh_topology`; a case with more than %zu offered levels has its coarsest %zu and %zu more spread evenly over "
      "the rest checked (the finest among them; *offered (checked)*). The 12 levels of the viewer's slider (1, 5, 10, "
      "20, 30, …, 100 %%, `priority_for_percent`) are extracted as the viewer does and judged the same way. It passes "
      "when at every checked level: boundary loops ≤ the full mesh's (*loops*; a new loop is a crack), 0 "
      "non-manifold edges (*nm*), components (through shared vertices) ≤ the full mesh's (*comps*), 0 degenerate "
      "triangles (*degen*), the accumulation table's count = the measured count, also at 60 sampled priorities, "
      "offered or not (*accum*), and counts never fall over the checked levels and the table's offered priorities "
      "(*monotone*). Shapes with a known answer (the *expected* column: components / χ) must also have 0 boundary "
      "edges and at most that many components at every checked level (*closed*); χ is information only, as a "
      "coarse level may close a handle (it may not open one, but only the full mesh's χ is known). Levels go all "
      "the way down: from %lld full triangles on, the coarsest offered level has at most 1 %% of them (*down*), and "
      "`priority_for_budget` (what `--triangles` uses) gives for each budget of %s under half the full count a "
      "level within 10 %% of it (*budget*; *worst budget miss*: the budget farthest from its level, "
      "relatively, **bold** when it fails; *largest step*: the largest rise in triangles between neighbouring "
      "offered levels, information).\n\n",
      kWalkAll, kWalkCoarsest, kWalkSpread, (long long)kDownFrom, "500, 1000, 2000, 5000 and 20000");
  std::printf(
      "**Cluster hierarchy.** Every uniform cut of `cluster_cut_table` with at least %lld triangles (every cut when "
      "the full mesh has fewer than %lld) is extracted at its error (`LevelRequest::at_error`), and so is the cut of "
      "each of %d cameras at %s pixels of error (`LevelRequest::for_camera`, %d pixels high, 45°): half outside the "
      "box at 0.6 to 3 diagonals from its centre, looking at it, half at random points inside the box. Cuts are "
      "measured as drawn, as index buffers into the model's vertices. The hierarchy passes when every judged "
      "uniform cut has components ≤ the full mesh's (*cl_comps*) and the table's triangle count (*cl_count*), "
      "every judged uniform cut of at least %lld triangles also boundary loops ≤ the full mesh's (*cl_loops*) and "
      "0 non-manifold edges (*cl_nm*), and every view cut the same three topology rules (*cl_view*): coarser cuts "
      "may lose handles but not pieces, since the hierarchy's last step clusters with the topology free. The full "
      "mesh is the full-detail cut. Coarser uniform cuts are measured and the ones that would fail the loops or "
      "non-manifold rule are counted (*coarse failing*, information), as are degenerate triangles; a "
      "coarsest cut above %lld triangles is marked **bold** (simplification stalled). *Storage*: triangles "
      "stored / full.\n\n",
      (long long)kJudgedCutTriangles, (long long)kSmallMesh, kCameras,
      "0.5, 1, 2, 4 and 8", kViewHeight, (long long)kJudgedCutTriangles, (long long)kCoarsestFlag);
  std::printf(
      "Shapes are Open3D's, scanned by the virtual scanner from 14 views at 256² (*virtual P*: the bunny mesh at "
      "P²); `bun_sub2` and `bun_sub3` are bun000 + bun045 and bun000 + bun090 + bun180 of `bun.conf`. *Max "
      "loops / comps / nm / degen* and *χ* (its range) are over the checked levels; *other topology*: checked "
      "levels without the full mesh's components or (closed full meshes) its χ, information only. Over the "
      "slider's 12 levels, as information: their χ (shown once when all equal), folded edges (interior edges whose "
      "triangles face opposite ways) and singular vertices (pinches). *s*: scanning + octree build; *walk s*: "
      "the walk over the offered levels (both cores).\n\n");

  const int octree_rules = kFirstClusterRule, all_rules = kRuleCount;
  std::printf("| case | R | octree | clusters | octree: failed rules (first level) | expected | "
              "full: triangles / loops / comps / χ | offered (checked) | coarsest: triangles (%% of full) | "
              "budgets 500 / 1000 / 2000 / 5000 / 20000 | worst budget miss | largest step | max loops / comps / nm / degen | χ | "
              "other topology | slider χ | max folded | max singular | s | walk s |\n");
  std::printf("|---|--:|---|---|---|---|---|--:|--:|---|---|---|---|---|--:|---|--:|--:|--:|--:|\n");
  for (const Result& r : results) {
    if (get(r, "pass").empty()) {
      std::printf("| %s | %s | **%s** | | | | | | | | | | | | | | | | | |\n", get(r, "name").c_str(),
                  get(r, "R").c_str(), get(r, "status").c_str());
      continue;
    }
    const std::string worst =
        get(r, "worst_budget_fails") == "1" ? "**" + get(r, "worst_budget") + "**" : get(r, "worst_budget");
    std::printf("| %s | %s | %s | %s | %s | %s | %s | %s (%s) | %s (%s %%) | %s | %s | %s | %s | %s | %s | %s | %s | "
                "%s | %s | %s |\n",
                get(r, "name").c_str(), get(r, "R").c_str(), outcome(get(r, "pass")).c_str(),
                outcome(get(r, "cl_pass")).c_str(), failed_rules(r, "first_fail", 0, octree_rules).c_str(),
                get(r, "expect").c_str(), spaced(get(r, "full")).c_str(), get(r, "offered").c_str(),
                get(r, "checked").c_str(), get(r, "coarsest").c_str(), get(r, "coarsest_share").c_str(),
                spaced(get(r, "budgets")).c_str(), worst.c_str(), get(r, "largest_step").c_str(),
                spaced(get(r, "walk_max")).c_str(),
                get(r, "walk_euler").c_str(), get(r, "other_topology").c_str(), per_level(get(r, "euler")).c_str(),
                get(r, "max_folded").c_str(), get(r, "max_singular").c_str(), get(r, "build_s").c_str(),
                get(r, "walk_s").c_str());
  }

  std::printf("\n## The cluster hierarchy\n\n");
  std::printf("*Uniform cuts*: judged / all (triangles of the coarsest judged one); maxima over the judged cuts. "
              "*Full = octree*: the full-detail cut has the octree's 100 %% counts. *Views*: maxima over the %d "
              "view cuts. *Build s*: the hierarchy's build alone (all cores); *check s*: these checks.\n\n",
              kCameras * int(kPixelErrors.size()));
  std::printf("| case | R | clusters | failed rules (first cut or view) | full: triangles / loops / comps / χ | "
              "full = octree | uniform cuts | max loops / comps / nm / degen | coarse failing | "
              "view triangles: min / median / max | views: max loops / comps / nm | coarsest | storage | levels | "
              "build s | check s |\n");
  std::printf("|---|--:|---|---|---|---|---|---|--:|---|---|--:|--:|--:|--:|--:|\n");
  for (const Result& r : results) {
    if (get(r, "cl_pass").empty()) {
      std::printf("| %s | %s | **%s** | | | | | | | | | | | | | |\n", get(r, "name").c_str(), get(r, "R").c_str(),
                  get(r, "status").empty() ? "not run" : get(r, "status").c_str());
      continue;
    }
    const std::string coarsest =
        get(r, "cl_coarsest_flag") == "1" ? "**" + get(r, "cl_coarsest") + "**" : get(r, "cl_coarsest");
    std::printf("| %s | %s | %s | %s | %s | %s | %s (%s) | %s / %s / %s / %s | %s | %s | %s / %s / %s | %s | %s | "
                "%s | %s | %s |\n",
                get(r, "name").c_str(), get(r, "R").c_str(), outcome(get(r, "cl_pass")).c_str(),
                failed_rules(r, "cl_first_fail", octree_rules, all_rules).c_str(), spaced(get(r, "cl_full")).c_str(),
                get(r, "cl_full_same") == "1" ? "yes" : "**no**", spaced(get(r, "cl_cuts")).c_str(),
                get(r, "cl_smallest_judged").c_str(), get(r, "cl_max_loops").c_str(), get(r, "cl_max_comps").c_str(),
                get(r, "cl_max_nm").c_str(), get(r, "cl_max_degen").c_str(), get(r, "cl_unjudged_bad").c_str(),
                spaced(get(r, "cl_view_tris")).c_str(), get(r, "cl_view_max_loops").c_str(),
                get(r, "cl_view_max_comps").c_str(), get(r, "cl_view_max_nm").c_str(), coarsest.c_str(),
                get(r, "cl_storage").c_str(), get(r, "cl_levels").c_str(), get(r, "cl_build_s").c_str(),
                get(r, "cl_check_s").c_str());
  }

  std::printf("\n## Failing cases: first failing rule and where\n\n");
  if (both == results.size()) std::printf("None.\n");
  for (const Result& r : results) {
    if (get(r, "pass") == "1" && get(r, "cl_pass") == "1") continue;
    if (get(r, "pass").empty()) {
      std::printf("- **%s R=%s**: %s (sweep.sh --logs DIR keeps its output)\n", get(r, "name").c_str(), get(r, "R").c_str(),
                  get(r, "status").c_str());
      continue;
    }
    std::printf("- **%s R=%s**:", get(r, "name").c_str(), get(r, "R").c_str());
    if (get(r, "pass") != "1") std::printf(" octree: %s.", failures_in_full(r, "first_fail", 0, octree_rules).c_str());
    if (get(r, "cl_pass") == "0")
      std::printf(" Clusters: %s.", failures_in_full(r, "cl_first_fail", octree_rules, all_rules).c_str());
    else if (get(r, "cl_pass").empty())
      std::printf(" Clusters: not checked.");
    std::printf("\n");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Checks every level of the LOD model of one case (a shape, scans or a mesh) for cracks and "
               "topology errors; or, with --table, makes the markdown report of collected RESULT lines"};
  std::string name, shape, scan_mesh, table, command, load_at_start = load_average();
  std::string shared = (fs::path(SCAN2LOD_SOURCE_DIR) / ".." / "shared").lexically_normal().string();
  std::vector<std::string> inputs, scans;
  double gap_cells = 0;
  int resolution = 64, views = 14, size = 256;
  std::optional<std::size_t> expect_components;
  std::optional<long> expect_euler;
  app.add_option("--name", name, "The case's name in the RESULT line");
  app.add_option("--resolution,-r", resolution, "Leaf cubes per side (a power of two)");
  auto* shape_option = app.add_option("--shape", shape,
                                      "An Open3D shape, virtually scanned: box, plate, cylinder, thin_cylinder, cone, "
                                      "arrow, icosahedron, mobius, two_spheres, sphere_touch, genus2, genus3");
  app.add_option("--gap-cells", gap_cells, "two_spheres: the gap between them in cells at this resolution")
      ->needs(shape_option);
  auto* scan_mesh_option =
      app.add_option("--scan-mesh", scan_mesh, "A mesh to scan virtually (relative to <shared>/data/bunny)");
  app.add_option("--views", views, "Virtual scans per shape or mesh")->check(CLI::PositiveNumber);
  app.add_option("--size", size, "Pixels per side of each virtual scan")->check(CLI::PositiveNumber);
  auto* scans_option = app.add_option("--scans", scans, "Scans of <shared>/data/bunny/data/bun.conf, by name "
                                                        "(bun000,bun045): that subset with its poses")
                           ->delimiter(',');
  auto* input_option =
      app.add_option("--input", inputs, "Inputs as `scan2lod build` takes them (relative to <shared>/data/bunny)");
  shape_option->excludes(scan_mesh_option)->excludes(scans_option)->excludes(input_option);
  scan_mesh_option->excludes(scans_option)->excludes(input_option);
  scans_option->excludes(input_option);
  auto* components_option =
      app.add_option("--expect-components", expect_components, "The shape's components, for the closed rule");
  app.add_option("--expect-euler", expect_euler, "The shape's Euler characteristic, for the closed rule")
      ->needs(components_option);
  components_option->needs("--expect-euler");
  app.add_option("--shared", shared, "The shared data folder (default: ../shared beside the source tree)");
  app.add_option("--table", table, "Print the markdown report of the RESULT lines in this file and exit");
  app.add_option("--command", command, "--table: the command to name in the report's header");
  app.add_option("--load-at-start", load_at_start, "--table: the load average when the sweep started");
  CLI11_PARSE(app, argc, argv);
  Progress::set_quiet(true);

  try {
    if (!table.empty()) return print_table(table, command, load_at_start);
    const fs::path bunny = fs::path(shared) / "data" / "bunny";
    const auto start = Clock::now();
    OrientedPoints points;
    if (!shape.empty()) {
      points = virtual_scan_points(make_shape(shape, gap_cells, resolution), {views, size, size});
    } else if (!scan_mesh.empty()) {
      points = virtual_scan_points(read_mesh((bunny / scan_mesh).string()), {views, size, size});
    } else if (!scans.empty()) {
      points = conf_subset_points(bunny / "data" / "bun.conf", scans);
    } else if (!inputs.empty()) {
      for (std::string& input : inputs) input = (bunny / input).string();
      points = load_oriented_points(inputs);
    } else {
      std::fprintf(stderr, "no case: give --shape, --scan-mesh, --scans or --input (see --help)\n");
      return 2;
    }
    std::optional<Expectation> expect;
    if (expect_components) expect = Expectation{*expect_components, *expect_euler};
    return run_case(name.empty() ? "case" : name, resolution, points, seconds_since(start), expect);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scan2lod_bench_sweep: %s\n", e.what());
    return 1;
  }
}
